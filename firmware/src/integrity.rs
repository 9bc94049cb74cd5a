//! Start-up integrity checks of the MCU itself: the program memory (a CRC-32 over the flash image)
//! and the variable memory (a March C- test of the RAM), as ISO 13849-1 Table E.1 lists them for the
//! logic ("invariable memory: signature of one word", "variable memory: RAM test ... March"; IEC
//! 60730-1 Table H.11.12.7 and IEC 61508-7 A.4/A.5 describe the same tests).
//!
//! Both run once at start-up, before the outputs can be energised; a failure latches
//! [`Cause::SelfCheck`](crate::Cause::SelfCheck) and the board never builds its `Firmware` (no
//! reset press can clear it: only a start with good memory runs). They are not repeated during
//! operation (the March test is destructive); the watchdogs, the tick supervision and the fault
//! handlers cover the running program.
//!
//! The routines are generic so that the host tests can inject faults: [`Cells`] is the memory under
//! test (the board's implementation uses volatile accesses to a raw RAM range).

/// CRC-32 (IEEE 802.3 / ISO-HDLC: reflected polynomial 0xEDB88320, initial value and final XOR
/// 0xFFFFFFFF; `crc32(b"123456789") == 0xCBF43926`), four bits at a time from a 16-entry table
/// (64 bytes of flash).
#[derive(Copy, Clone, Debug)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A fresh computation.
    pub const fn new() -> Self {
        Crc32(0xFFFF_FFFF)
    }

    /// A computation whose register starts at `seed` instead of 0xFFFFFFFF (see [`Seed`]).
    pub const fn with_seed(seed: u32) -> Self {
        Crc32(seed)
    }

    /// Feed `bytes`.
    #[inline(never)]
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u32::from(b);
            for _ in 0..2 {
                // `& 0xF` keeps the index inside the 16 entries.
                let nibble = NIBBLE_TABLE.get((self.0 & 0xF) as usize).copied().unwrap_or(0);
                self.0 = (self.0 >> 4) ^ nibble;
            }
        }
    }

    /// Feed `n` zero bytes (the stored CRC word itself counts as zeros).
    pub fn update_zeros(&mut self, n: usize) {
        for _ in 0..n {
            self.update(&[0]);
        }
    }

    /// The checksum of everything fed.
    pub const fn finish(self) -> u32 {
        !self.0
    }
}

/// The CRC of each 4-bit value, bitwise from the reflected polynomial at compile time.
// Evaluated by the compiler: an out-of-range index or overflow here fails the build, not the MCU.
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
const NIBBLE_TABLE: [u32; 16] = {
    let mut t = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 { (c >> 1) ^ 0xEDB8_8320 } else { c >> 1 };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}

/// Which build an image's stored CRC belongs to: the CRC register's initial value.
///
/// The `qemu-io` build of the board binary (its pins are RAM words a bench drives, so it must never
/// run a machine) is patched with [`Seed::QemuBench`]; the production board build checks with
/// [`Seed::Production`]. For any image the two seeds give different CRCs (the CRC is affine in its
/// initial value: the results differ by a fixed non-zero term for a given length), so a bench
/// image's stored word fails the production check, and `cargo xtask` (`patch_flash_crc`) and the
/// host test `a_bench_image_fails_the_production_check` hold each build to its own seed.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Seed {
    /// The production board build: the standard CRC-32 initial value.
    Production = 0xFFFF_FFFF,
    /// The `qemu-io` bench build ("QEMU" in ASCII, inverted).
    QemuBench = !0x5145_4D55,
}

/// The CRC of a flash image whose word at byte offset `crc_at` holds the stored CRC: that word is
/// counted as four zero bytes. `crc_at` outside the image (or not 4 bytes inside it) counts nothing
/// as the stored word, so the result will not match a stored value and the check fails safe.
/// The production build's seed ([`Seed::Production`]).
pub fn image_crc(image: &[u8], crc_at: usize) -> u32 {
    image_crc_seeded(image, crc_at, Seed::Production)
}

/// [`image_crc`] for the build `seed` names.
pub fn image_crc_seeded(image: &[u8], crc_at: usize, seed: Seed) -> u32 {
    let mut c = Crc32::with_seed(seed as u32);
    match (image.get(..crc_at), crc_at.checked_add(4).and_then(|end| image.get(end..))) {
        (Some(head), Some(tail)) => {
            c.update(head);
            c.update_zeros(4);
            c.update(tail);
        }
        _ => {
            c.update(image);
            c.update(&[0xA5]); // never equal to a CRC computed with the word skipped
        }
    }
    c.finish()
}

/// Words of memory under test.
pub trait Cells {
    /// How many words.
    fn len(&self) -> usize;
    /// Read word `i` (`i < len()`).
    fn read(&mut self, i: usize) -> u32;
    /// Write word `i` (`i < len()`).
    fn write(&mut self, i: usize, v: u32);
    /// No words.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Where a RAM test found memory not holding what was written.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct RamFault {
    /// Word index in the range under test.
    pub index: usize,
    /// What the March element expected to read.
    pub expected: u32,
    /// What it read.
    pub read: u32,
}

/// The data backgrounds each March C- pass uses (and their complements): all-zero finds stuck-at,
/// transition, address-decoder and coupling faults between words; the other three also couple
/// neighbouring bits inside a word (bit i against bit i+1, i+2, i+4).
pub const BACKGROUNDS: [u32; 4] = [0x0000_0000, 0x5555_5555, 0x3333_3333, 0x0F0F_0F0F];

/// March C- (van de Goor): {⇕(w0); ⇑(r0,w1); ⇑(r1,w0); ⇓(r0,w1); ⇓(r1,w0); ⇕(r0)}, 10 operations
/// per word, once per data background (`0` = the background, `1` = its complement). Destructive:
/// the memory ends holding zeros. Every loop is bounded by `len()`.
#[inline(never)]
pub fn march_c_minus<M: Cells>(m: &mut M, backgrounds: &[u32]) -> Result<(), RamFault> {
    let n = m.len();
    for &zero in backgrounds {
        let one = !zero;
        for i in 0..n {
            m.write(i, zero);
        }
        for i in 0..n {
            check(m, i, zero)?;
            m.write(i, one);
        }
        for i in 0..n {
            check(m, i, one)?;
            m.write(i, zero);
        }
        for i in (0..n).rev() {
            check(m, i, zero)?;
            m.write(i, one);
        }
        for i in (0..n).rev() {
            check(m, i, one)?;
            m.write(i, zero);
        }
        for i in 0..n {
            check(m, i, zero)?;
        }
    }
    for i in 0..n {
        m.write(i, 0);
    }
    Ok(())
}

fn check<M: Cells>(m: &mut M, index: usize, expected: u32) -> Result<(), RamFault> {
    let read = m.read(index);
    if read == expected {
        Ok(())
    } else {
        Err(RamFault { index, expected, read })
    }
}

/// A raw RAM range under test with volatile accesses (the board's RAM).
pub struct RawRam {
    base: *mut u32,
    len: usize,
}

impl RawRam {
    /// The `len` words from `base`.
    ///
    /// # Safety
    /// `base..base + len` must be RAM that nothing else uses while the test runs (no live reference,
    /// not the stack in use, not the retained latch), word-aligned; its contents are destroyed.
    pub unsafe fn new(base: *mut u32, len: usize) -> Self {
        RawRam { base, len }
    }
}

impl Cells for RawRam {
    fn len(&self) -> usize {
        self.len
    }
    fn read(&mut self, i: usize) -> u32 {
        if i >= self.len {
            return 0;
        }
        // SAFETY: `i < len`, and `new`'s contract makes the range ours.
        unsafe { core::ptr::read_volatile(self.base.wrapping_add(i)) }
    }
    fn write(&mut self, i: usize, v: u32) {
        if i >= self.len {
            return;
        }
        // SAFETY: as for `read`.
        unsafe { core::ptr::write_volatile(self.base.wrapping_add(i), v) }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec;
    use std::vec::Vec;

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn image_crc_skips_the_stored_word_and_sees_every_other_byte() {
        let mut img: Vec<u8> = (0..64u8).collect();
        let good = image_crc(&img, 16);
        // The stored word itself does not change the result (it holds the CRC).
        img[16..20].copy_from_slice(&good.to_le_bytes());
        assert_eq!(image_crc(&img, 16), good);
        // Every single flipped bit anywhere else does.
        for byte in (0..64).filter(|b| !(16..20).contains(b)) {
            for bit in 0..8 {
                img[byte] ^= 1 << bit;
                assert_ne!(image_crc(&img, 16), good, "flip at byte {byte} bit {bit} not seen");
                img[byte] ^= 1 << bit;
            }
        }
        // A stored word outside the image never matches.
        assert_ne!(image_crc(&img, 62), good);
        assert_ne!(image_crc(&img, 62), image_crc(&img, 16));
    }

    #[test]
    fn a_bench_image_fails_the_production_check() {
        // Images of several lengths and contents, each patched as xtask patches a qemu-io build.
        for len in [8usize, 64, 257, 4096] {
            let mut img: Vec<u8> = (0..len).map(|i| (i * 37 + len) as u8).collect();
            let at = (len / 2) & !3;
            let bench = image_crc_seeded(&img, at, Seed::QemuBench);
            img[at..at + 4].copy_from_slice(&bench.to_le_bytes());
            assert_eq!(image_crc_seeded(&img, at, Seed::QemuBench), bench, "the bench build passes its own check");
            assert_ne!(image_crc(&img, at), bench, "len {len}: a qemu-io image passed the production check");
            // And the other way round: a production image fails the bench build's check.
            let prod = image_crc(&img, at);
            img[at..at + 4].copy_from_slice(&prod.to_le_bytes());
            assert_ne!(image_crc_seeded(&img, at, Seed::QemuBench), prod);
        }
        assert_eq!(image_crc_seeded(b"123456789", 100, Seed::Production), image_crc(b"123456789", 100));
    }

    /// A memory with injected faults.
    struct Faulty {
        words: Vec<u32>,
        /// (word, bit, value): the bit always reads `value`.
        stuck: Option<(usize, u32, bool)>,
        /// Address decoder: writes to `.0` also land in `.1`.
        alias: Option<(usize, usize)>,
        /// Coupling: a write that changes word `.0` bit `.1` inverts word `.2` bit `.3`.
        coupling: Option<(usize, u32, usize, u32)>,
        /// Bridge inside word `.0`: bits `.1` and `.2` shorted, both read their OR.
        bridge: Option<(usize, u32, u32)>,
    }

    impl Faulty {
        fn new(n: usize) -> Self {
            Faulty { words: vec![0xDEAD_BEEF; n], stuck: None, alias: None, coupling: None, bridge: None }
        }
    }

    impl Cells for Faulty {
        fn len(&self) -> usize {
            self.words.len()
        }
        fn read(&mut self, i: usize) -> u32 {
            let mut v = self.words[i];
            if let Some((w, b, one)) = self.stuck {
                if w == i {
                    v = if one { v | 1 << b } else { v & !(1 << b) };
                }
            }
            if let Some((w, a, b)) = self.bridge {
                if w == i && v & (1 << a | 1 << b) != 0 {
                    v |= 1 << a | 1 << b;
                }
            }
            v
        }
        fn write(&mut self, i: usize, v: u32) {
            let flips = self.coupling.filter(|&(w, b, _, _)| w == i && (self.words[i] ^ v) & (1 << b) != 0);
            self.words[i] = v;
            if let Some((_, _, victim, vb)) = flips {
                self.words[victim] ^= 1 << vb;
            }
            if let Some((from, to)) = self.alias {
                if from == i {
                    self.words[to] = v;
                }
            }
        }
    }

    #[test]
    fn march_passes_good_memory_and_leaves_zeros() {
        let mut m = Faulty::new(37);
        assert_eq!(march_c_minus(&mut m, &BACKGROUNDS), Ok(()));
        assert!(m.words.iter().all(|&w| w == 0));
    }

    #[test]
    fn march_finds_every_stuck_bit() {
        for word in [0, 5, 36] {
            for bit in [0, 7, 31] {
                for one in [false, true] {
                    let mut m = Faulty::new(37);
                    m.stuck = Some((word, bit, one));
                    let e = march_c_minus(&mut m, &BACKGROUNDS[..1]).expect_err("stuck bit not found");
                    assert_eq!(e.index, word);
                    assert_eq!((e.expected ^ e.read), 1 << bit);
                }
            }
        }
    }

    #[test]
    fn march_finds_address_decoder_faults_both_ways() {
        for (from, to) in [(3, 20), (20, 3), (0, 36), (36, 0)] {
            let mut m = Faulty::new(37);
            m.alias = Some((from, to));
            assert!(march_c_minus(&mut m, &BACKGROUNDS[..1]).is_err(), "alias {from} -> {to} not found");
        }
    }

    #[test]
    fn march_finds_inversion_coupling_between_words_both_directions() {
        for (aggr, victim) in [(2, 30), (30, 2)] {
            let mut m = Faulty::new(37);
            m.coupling = Some((aggr, 4, victim, 9));
            assert!(march_c_minus(&mut m, &BACKGROUNDS[..1]).is_err(), "coupling {aggr} -> {victim} not found");
        }
    }

    #[test]
    fn march_finds_inversion_coupling_inside_a_word() {
        let mut m = Faulty::new(16);
        m.coupling = Some((7, 0, 7, 1));
        assert!(march_c_minus(&mut m, &BACKGROUNDS[..1]).is_err());
    }

    #[test]
    fn bridged_bits_in_one_word_need_the_extra_backgrounds() {
        // Two shorted bit lines of one word read their OR. With the all-zero background and its
        // complement both bits always hold the same value, so the short is invisible; the
        // 0x5555.../0x3333... backgrounds put different values on neighbouring bits.
        for (a, b) in [(0, 1), (0, 2), (5, 9)] {
            let mut m = Faulty::new(16);
            m.bridge = Some((7, a, b));
            assert_eq!(march_c_minus(&mut m, &BACKGROUNDS[..1]), Ok(()), "one background cannot see bits {a},{b}");
            let mut m = Faulty::new(16);
            m.bridge = Some((7, a, b));
            let e = march_c_minus(&mut m, &BACKGROUNDS).expect_err("bridge not found");
            assert_eq!(e.index, 7);
        }
    }

    #[test]
    fn empty_range_passes() {
        let mut m = Faulty::new(0);
        assert_eq!(march_c_minus(&mut m, &BACKGROUNDS), Ok(()));
    }
}
