//! Building the firmware: the target check, the release build (its flash CRC patched), the
//! `qemu-io` board build (its feature implies `qemu-clock`), and the firmware clippy stage.

use crate::common::{cargo, elf_path, repo_root, target_dir, TARGET};
use crate::flash::{flash_image, patch_flash_crc};
use crate::Outcome;
use flinch_firmware::integrity::Seed;
use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn target_installed() -> bool {
    // The target's standard library exists when `rustc --print target-libdir` names a real directory.
    let out = Command::new(env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .args(["--print", "target-libdir", "--target", TARGET])
        .output();
    match out {
        Ok(o) if o.status.success() => {
            let dir = String::from_utf8_lossy(&o.stdout).trim().to_string();
            fs::read_dir(&dir).map(|mut d| d.next().is_some()).unwrap_or(false)
        }
        _ => false,
    }
}

/// Build both bare-metal binaries. Run inside firmware/ so that firmware/.cargo/config.toml (linker
/// scripts, runner) applies.
pub fn build_firmware() -> Result<(), String> {
    let status = cargo()
        .args(["build", "--release", "--target", TARGET])
        .current_dir(repo_root().join("firmware"))
        .status()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if status.success() {
        patch_flash_crc(&elf_path("board"), Seed::Production).map(|_| ())
    } else {
        Err(format!("cargo build --release --target {TARGET} (in firmware/) exited with {status}"))
    }
}

/// The lints the panic-free claim rests on (`firmware/src/lib.rs`: no unwrap/expect/panic, no
/// indexing, no unchecked arithmetic in the detection modules) are only lints: this stage runs them,
/// for the target, with warnings as errors. In the release profile, as the firmware stage builds
/// it: the dependencies' metadata is then already there (issue 28; the firmware has no
/// `debug_assertions` code, so the lints see the same source).
pub fn firmware_clippy() -> Outcome {
    let args = ["clippy", "--release", "-p", "flinch-firmware", "--target", TARGET, "--", "-D", "warnings"];
    let status = cargo().args(args).current_dir(repo_root().join("firmware")).status();
    let cmd = format!("cargo {} (in firmware/)", args.join(" "));
    match status {
        Ok(s) if s.success() => Outcome::Pass(cmd),
        Ok(s) => Outcome::Fail(format!("{cmd} exited with {s}")),
        Err(e) => Outcome::Fail(format!("could not run {cmd}: {e}")),
    }
}

/// The `qemu-io` build of the board binary (`firmware/src/bin/support/board_bench.rs`): the same
/// `board.rs`, with GPIOA's input register and GPIOD's output register read from RAM that a bench in
/// thread mode drives, because QEMU 7.2 does not model the F405's GPIO. Its own target directory, so
/// the production ELF is never overwritten by it.
pub fn build_board_qemu_io() -> Result<(), String> {
    let elf = build_board_with("qemu-io", &qemu_io_dir())?;
    let stored = patch_flash_crc(&elf, Seed::QemuBench)?;
    // The bench image must fail the production build's check (it must never drive a machine).
    let b = fs::read(&elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let (image, _, crc_at) = flash_image(&b, true)?;
    if flinch_firmware::integrity::image_crc(&image, crc_at) == stored {
        return Err("the qemu-io board image passes the production flash CRC check".into());
    }
    Ok(())
}

/// The board binary built with the cargo feature `feature` into its own target directory `dir`
/// (inside firmware/, for its .cargo/config.toml); returns the ELF's path (its CRC not yet patched).
fn build_board_with(feature: &str, dir: &Path) -> Result<PathBuf, String> {
    let status = cargo()
        .args(["build", "--release", "--target", TARGET, "--bin", "board", "--features", feature, "--target-dir"])
        .arg(dir)
        .current_dir(repo_root().join("firmware"))
        .status()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if status.success() {
        Ok(dir.join(TARGET).join("release").join("board"))
    } else {
        Err(format!("cargo build --release --target {TARGET} --bin board --features {feature} exited with {status}"))
    }
}

pub fn qemu_io_dir() -> PathBuf {
    target_dir().join("board-qemu-io")
}
