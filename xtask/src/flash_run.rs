//! The flash path a user runs (`cargo xtask flash`, cargo's runner `firmware/scripts/flash-runner`):
//! build if needed, patch and check (`flash::prepare_flash`), then probe-rs; and the stage "flash
//! image", which runs that path end to end with a stand-in probe-rs and boots what it was handed
//! in QEMU.

use crate::flash::{flash_image, prepare_flash, CHIP};
use flinch_firmware::integrity::Seed;
use std::fs;

/// `cargo xtask flash [ELF] [probe-rs arguments...]`: the ELF (cargo's runner passes the one it
/// built; without one the release board ELF is built first) patched and checked (`prepare_flash`),
/// then `probe-rs run --chip STM32F407VGTx ELF ...`: flash, reset, the defmt log over RTT.
pub fn flash(args: &[String]) -> Result<(), String> {
    let (elf, rest) = match args.first() {
        Some(a) if !a.starts_with('-') => (std::path::PathBuf::from(a), &args[1..]),
        _ => {
            crate::firmware::build_firmware()?;
            (crate::common::elf_path("board"), args)
        }
    };
    let crc = prepare_flash(&elf)?;
    eprintln!("flash: {} patched, start-up CRC {crc:#010x} checked; probe-rs run --chip {CHIP}", elf.display());
    let status = std::process::Command::new("probe-rs")
        .args(["run", "--chip", CHIP])
        .arg(&elf)
        .args(rest)
        .status()
        .map_err(|e| format!("could not run probe-rs ({e}): install it with `cargo install probe-rs-tools --locked`"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("probe-rs run exited with {status}"))
    }
}

/// The stage "flash image": the flash path a user runs, end to end, on the bytes it writes. The
/// board ELF as the linker leaves it (its CRC word zeroed) is handed to cargo's runner,
/// `firmware/scripts/flash-runner`, exactly as `cargo run --release --bin board` does (from
/// firmware/), with a stand-in `probe-rs` first on PATH that keeps the ELF it is asked to flash.
/// That ELF must be what `probe-rs run --chip STM32F407VGTx` was given, pass the firmware's own
/// flash check, and boot on QEMU's netduinoplus2 past the start-up checks to the first tick with the
/// boot trace of `firmware/qemu/board-boot.txt` (an image whose CRC is wrong stops there instead:
/// the "board ELF in QEMU" stage's corrupted copy).
pub fn check_flash_image() -> Result<String, String> {
    use crate::common::{elf_path, repo_root, target_dir};
    let dir = target_dir().join("flash-image");
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("bin")).map_err(|e| format!("{}: {e}", dir.display()))?;
    // The ELF as linked: the CRC word zero, as `cargo build` leaves it.
    let linked = dir.join("board");
    let mut b = fs::read(elf_path("board")).map_err(|e| format!("reading the board ELF: {e}"))?;
    let (_, off, _) = flash_image(&b, true)?;
    b[off..off + 4].copy_from_slice(&[0; 4]);
    fs::write(&linked, &b).map_err(|e| format!("{}: {e}", linked.display()))?;
    // The stand-in probe-rs: records its arguments and keeps the ELF it was given.
    let flashed = dir.join("flashed.elf");
    let args_log = dir.join("probe-rs.args");
    let fake = dir.join("bin/probe-rs");
    fs::write(
        &fake,
        format!("#!/bin/sh\necho \"$*\" > '{}'\nfor a in \"$@\"; do last=\"$a\"; done\ncp \"$last\" '{}'\n", args_log.display(), flashed.display()),
    )
    .map_err(|e| format!("{}: {e}", fake.display()))?;
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&fake, fs::Permissions::from_mode(0o755)).map_err(|e| format!("{}: {e}", fake.display()))?;
    }
    let path = format!("{}:{}", dir.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let status = std::process::Command::new(repo_root().join("firmware/scripts/flash-runner"))
        .arg(&linked)
        .current_dir(repo_root().join("firmware"))
        .env("PATH", path)
        .status()
        .map_err(|e| format!("could not run firmware/scripts/flash-runner: {e}"))?;
    if !status.success() {
        return Err(format!("firmware/scripts/flash-runner exited with {status}"));
    }
    let args = fs::read_to_string(&args_log).map_err(|e| format!("probe-rs was not called ({e})"))?;
    if !args.starts_with(&format!("run --chip {CHIP} ")) {
        return Err(format!("probe-rs was called as `probe-rs {}`", args.trim()));
    }
    let got = fs::read(&flashed).map_err(|e| format!("{}: {e}", flashed.display()))?;
    let (image, off, crc_at) = flash_image(&got, false)?;
    let stored = u32::from_le_bytes([got[off], got[off + 1], got[off + 2], got[off + 3]]);
    if stored == 0 || flinch_firmware::integrity::image_crc_seeded(&image, crc_at, Seed::Production) != stored {
        return Err(format!("the image handed to probe-rs fails the firmware's flash check (stored {stored:#010x})"));
    }
    let log = crate::board::run_board_elf(&flashed, "flash-image.log")?;
    let booted = crate::board::check_board_log(&log).map_err(|e| format!("the flashed image in QEMU: {e}"))?;
    // And the image as linked, without the runner, fails its check (what plain `probe-rs run` flashed).
    let (image, _, crc_at) = flash_image(&b, false)?;
    if flinch_firmware::integrity::image_crc_seeded(&image, crc_at, Seed::Production) == 0 {
        return Err("the unpatched image passes the flash check: the check cannot fail".into());
    }
    Ok(format!(
        "`cargo run --release --bin board`'s runner handed probe-rs `{}` an image with CRC {stored:#010x} that passes the firmware's flash check; in QEMU: {booted}",
        args.trim().replace(&dir.display().to_string(), "...")
    ))
}
