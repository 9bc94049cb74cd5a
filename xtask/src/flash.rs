//! The board ELF's flash image and the start-up CRC patched into it (`patch_flash_crc`), and the
//! flash path a user runs (`cargo xtask flash`, cargo's runner `firmware/scripts/flash-runner`):
//! patch, check with the firmware's own routine, then probe-rs.

use flinch_firmware::integrity::Seed;
use std::fs;
use std::path::Path;

const FLASH_ORIGIN: u64 = 0x0800_0000;
const FLASH_END: u64 = 0x0810_0000;

/// The board ELF's flash image as the part holds it: every loaded section in flash at its address,
/// and .data at its load address `__sidata`; from the start of flash to the end of .data's load
/// image, which must be covered without gaps (the board's `flash_crc_ok` reads exactly that range).
/// Returns the image, the file offset of `FLINCH_FLASH_CRC`, and its offset in the image.
pub fn flash_image(b: &[u8], zero_gaps: bool) -> Result<(Vec<u8>, usize, usize), String> {
    use object::{Object, ObjectSection, ObjectSymbol, SectionKind};
    let elf = object::File::parse(b).map_err(|e| format!("not an ELF object: {e}"))?;
    let sym = |name: &str| {
        elf.symbols().find(|s| s.name() == Ok(name)).map(|s| s.address()).ok_or_else(|| format!("no symbol {name} in the board ELF"))
    };
    let (sidata, sdata, edata, crc) = (sym("__sidata")?, sym("__sdata")?, sym("__edata")?, sym("FLINCH_FLASH_CRC")?);
    let end = sidata + (edata - sdata);
    let mut image = vec![None::<u8>; (end - FLASH_ORIGIN) as usize];
    let mut crc_file = None;
    for sec in elf.sections() {
        if sec.size() == 0 || matches!(sec.kind(), SectionKind::UninitializedData | SectionKind::Metadata | SectionKind::Other | SectionKind::Debug) {
            continue;
        }
        let name = sec.name().unwrap_or("?");
        let at = if name == ".data" { sidata } else { sec.address() };
        if !(FLASH_ORIGIN..FLASH_END).contains(&at) {
            continue;
        }
        let data = sec.data().map_err(|e| format!("reading {name}: {e}"))?;
        for (i, &byte) in data.iter().enumerate() {
            let a = at + i as u64;
            if a >= end {
                return Err(format!("section {name} reaches past the end of .data's load image ({end:#x})"));
            }
            image[(a - FLASH_ORIGIN) as usize] = Some(byte);
        }
        if (sec.address()..sec.address() + sec.size()).contains(&crc) {
            let (off, _) = sec.file_range().ok_or("FLINCH_FLASH_CRC's section has no file data")?;
            crc_file = Some((off + (crc - sec.address())) as usize);
        }
    }
    if let Some(gap) = image.iter().position(Option::is_none).filter(|_| !zero_gaps) {
        return Err(format!("the board's flash image has a gap at {:#x}: the CRC range is not contiguous", FLASH_ORIGIN + gap as u64));
    }
    let image: Vec<u8> = image.into_iter().map(|b| b.unwrap_or(0)).collect();
    Ok((image, crc_file.ok_or("FLINCH_FLASH_CRC is not in a flash section")?, (crc - FLASH_ORIGIN) as usize))
}

/// Alignment gaps between the flash-resident load segments (e.g. 4 bytes between `.text` and an
/// 8-aligned `.rodata`) are not loaded: on the part they stay erased (0xFF), in QEMU zero, so the
/// start-up CRC over them would differ. Grow the segment before each gap over it, when the file holds
/// the gap's bytes right there and they are zeros, so that the loader (probe-rs, QEMU) writes zeros
/// on both; anything else is an error. ELF32 little-endian program headers, edited in place.
fn cover_flash_gaps(b: &mut [u8]) -> Result<(), String> {
    let rd32 = |b: &[u8], at: usize| -> Result<u32, String> {
        b.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).ok_or_else(|| "ELF truncated".to_string())
    };
    let rd16 = |b: &[u8], at: usize| -> Result<usize, String> { b.get(at..at + 2).map(|w| u16::from_le_bytes([w[0], w[1]]) as usize).ok_or_else(|| "ELF truncated".to_string()) };
    let (phoff, phentsize, phnum) = (rd32(b, 0x1C)? as usize, rd16(b, 0x2A)?, rd16(b, 0x2C)?);
    // (header offset, file offset, address, file size, memory size) of flash-resident LOAD segments.
    let mut segs = Vec::new();
    for k in 0..phnum {
        let h = phoff + k * phentsize;
        let (ty, off, vaddr, paddr, filesz, memsz) = (rd32(b, h)?, rd32(b, h + 4)?, rd32(b, h + 8)?, rd32(b, h + 12)?, rd32(b, h + 16)?, rd32(b, h + 20)?);
        if ty == 1 && vaddr == paddr && filesz == memsz && (FLASH_ORIGIN..FLASH_END).contains(&u64::from(paddr)) && filesz > 0 {
            segs.push((h, off, paddr, filesz));
        }
    }
    // Where the next loaded flash bytes start: the next flash segment, or .data's load image.
    let mut starts: Vec<u32> = segs.iter().map(|s| s.2).collect();
    for k in 0..phnum {
        let h = phoff + k * phentsize;
        let (ty, paddr, filesz) = (rd32(b, h)?, rd32(b, h + 12)?, rd32(b, h + 16)?);
        if ty == 1 && filesz > 0 && (FLASH_ORIGIN..FLASH_END).contains(&u64::from(paddr)) {
            starts.push(paddr);
        }
    }
    for &(h, off, addr, size) in &segs {
        let end = addr + size;
        let Some(&next) = starts.iter().filter(|&&a| a >= end).min() else { continue };
        let gap = next - end;
        if gap == 0 {
            continue;
        }
        if gap >= 64 {
            return Err(format!("a {gap}-byte gap in flash at {end:#x}: not an alignment gap"));
        }
        let (from, to) = ((off + size) as usize, (off + size + gap) as usize);
        match b.get(from..to) {
            Some(bytes) if bytes.iter().all(|&x| x == 0) => {}
            _ => return Err(format!("a {gap}-byte gap in flash at {end:#x} whose bytes the file does not hold as zeros")),
        }
        b[h + 16..h + 20].copy_from_slice(&(size + gap).to_le_bytes());
        b[h + 20..h + 24].copy_from_slice(&(size + gap).to_le_bytes());
    }
    Ok(())
}

/// Write the flash image's CRC-32 (`flinch_firmware::integrity::image_crc`, the routine the board
/// runs at start-up) into the ELF's `FLINCH_FLASH_CRC`. Idempotent: the word itself counts as zeros.
/// `seed`: the production build's, or the `qemu-io` bench build's own (whose image must fail the
/// production check, `flinch_firmware::integrity::Seed`).
pub fn patch_flash_crc(path: &Path, seed: Seed) -> Result<u32, String> {
    let mut b = fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    cover_flash_gaps(&mut b).map_err(|e| format!("{}: {e}", path.display()))?;
    let (image, file_off, crc_at) = flash_image(&b, true).map_err(|e| format!("{}: {e}", path.display()))?;
    let crc = flinch_firmware::integrity::image_crc_seeded(&image, crc_at, seed);
    b[file_off..file_off + 4].copy_from_slice(&crc.to_le_bytes());
    fs::write(path, &b).map_err(|e| format!("writing {}: {e}", path.display()))?;
    Ok(crc)
}

/// The chip probe-rs flashes.
pub const CHIP: &str = "STM32F407VGTx";

/// What the flash path does to an ELF before anything is written to a part: refuse what is not a
/// board image (no `FLINCH_FLASH_CRC`: the `qemu` binary), patch the start-up CRC with the
/// production seed, then read the file back and check the stored word the way the firmware's
/// `flash_crc_ok` does (`integrity::image_crc_seeded` over the image as the part holds it). Returns
/// the CRC.
pub fn prepare_flash(elf: &Path) -> Result<u32, String> {
    let b = fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    if flash_image(&b, true).is_err() {
        return Err(format!(
            "{}: not a board image (no FLINCH_FLASH_CRC): only the `board` binary is flashed; the `qemu` one runs with `cargo xtask qemu`",
            elf.display()
        ));
    }
    let crc = patch_flash_crc(elf, Seed::Production)?;
    let b = fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let (image, file_off, crc_at) = flash_image(&b, false).map_err(|e| format!("{}: {e}", elf.display()))?;
    let stored = b.get(file_off..file_off + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).ok_or("CRC word outside the file")?;
    if flinch_firmware::integrity::image_crc_seeded(&image, crc_at, Seed::Production) != stored || stored != crc {
        return Err(format!("{}: the patched image fails the firmware's own flash check", elf.display()));
    }
    Ok(crc)
}

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
