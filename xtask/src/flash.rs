//! The board ELF's flash image and the start-up CRC patched into it (`patch_flash_crc`), and the
//! check the flash path makes before anything is written (`prepare_flash`). Pure functions of the
//! ELF's bytes: building the firmware, probe-rs and QEMU are `flash_run.rs`'s.

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
