//! Periodic self-tests while running, in the style of IEC 60730-1 Annex H (class B, Table H.1:
//! "invariable memory: periodic checksum", "variable memory: periodic static memory test",
//! "peripherals / internal: periodic self-test"); the start-up checks are `integrity.rs`.
//!
//! Three checks, each a small step the board runs after every wake-up in thread mode (so none of
//! them runs inside an interrupt), each with a stated period (`board.rs`, firmware/README.md):
//!
//! * [`FlashCrc`]: the start-up CRC-32 of the flash image again, `chunk` bytes a step, compared with
//!   the stored word at the end of every pass. Read-only, no masking.
//! * [`march_block_transparent`]: March C- over a block of a few words of the safety state (the
//!   `Firmware` object), which it saves first and restores after, so the state is unchanged; the
//!   board runs it with the tick and the bookkeeping masked (BASEPRI), the edge (which does not
//!   touch that state) not. A different block every step, round the whole state.
//! * [`check_config`]: the safety-relevant peripheral configuration read back against what the
//!   board wrote at start-up (EXTI, NVIC priorities and enables, GPIO modes, SysTick, IWDG, RCC
//!   enable bits, the MPU guard): a table of masked registers.
//!
//! Any mismatch is a latched fault ([`Cause::Diagnostic`](crate::Cause::Diagnostic), through
//! `Firmware::diagnostic_failed`): every output drops and the watchdog starves.

use crate::integrity::{Cells, Crc32, RamFault, Seed};

/// Which check failed: the [`Cause::Diagnostic`](crate::Cause::Diagnostic) event's flags (bits 4..6).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Check {
    /// The flash CRC.
    Flash = 1,
    /// The RAM test of the safety state.
    Ram = 2,
    /// The peripheral configuration read-back.
    Config = 3,
}

/// The incremental flash CRC: one pass over the image in steps of `chunk` bytes.
#[derive(Copy, Clone, Debug)]
pub struct FlashCrc {
    crc: Crc32,
    pos: usize,
    passes: u32,
    seed: Seed,
}

impl FlashCrc {
    /// A check that starts at the image's first byte, with the build's seed.
    pub const fn new(seed: Seed) -> Self {
        FlashCrc { crc: Crc32::with_seed(seed as u32), pos: 0, passes: 0, seed }
    }

    /// Passes completed.
    pub const fn passes(&self) -> u32 {
        self.passes
    }

    /// One step: the next `chunk` bytes of `image` (the stored CRC word at `crc_at` counted as
    /// zeros, as `integrity::image_crc_seeded` does). At the end of a pass `Some(ok)`, and the next
    /// step starts a new pass; `None` meanwhile.
    pub fn step(&mut self, image: &[u8], crc_at: usize, stored: u32, chunk: usize) -> Option<bool> {
        let end = self.pos.saturating_add(chunk.max(1)).min(image.len());
        for i in self.pos..end {
            let in_word = i >= crc_at && i < crc_at.saturating_add(4);
            let b = if in_word { 0 } else { image.get(i).copied().unwrap_or(0) };
            self.crc.update(&[b]);
        }
        self.pos = end;
        if self.pos < image.len() {
            return None;
        }
        let ok = crc_at.saturating_add(4) <= image.len() && self.crc.finish() == stored;
        self.crc = Crc32::with_seed(self.seed as u32);
        self.pos = 0;
        self.passes = self.passes.wrapping_add(1);
        Some(ok)
    }
}

/// The most words [`march_block_transparent`] tests in one step.
pub const MAX_BLOCK: usize = 8;

/// March C- over words `start..start + len` of `m` (at most [`MAX_BLOCK`]) with the data
/// backgrounds `backgrounds`, saving the block first and writing it back afterwards, also when a
/// fault is found: a transparent test of memory in use. The caller keeps everything else that
/// uses the block off it meanwhile (the board masks the tick and the bookkeeping).
pub fn march_block_transparent<M: Cells>(m: &mut M, start: usize, len: usize, backgrounds: &[u32]) -> Result<(), RamFault> {
    let len = len.min(MAX_BLOCK).min(m.len().saturating_sub(start));
    let mut saved = [0u32; MAX_BLOCK];
    for (k, s) in saved.iter_mut().enumerate().take(len) {
        *s = m.read(start.saturating_add(k));
    }
    let result = crate::integrity::march_c_minus(&mut Window { m, start, len }, backgrounds);
    for (k, s) in saved.iter().enumerate().take(len) {
        m.write(start.saturating_add(k), *s);
    }
    result.map_err(|f| RamFault { index: f.index.saturating_add(start), ..f })
}

/// A window of `len` words from `start` of a larger memory.
struct Window<'a, M> {
    m: &'a mut M,
    start: usize,
    len: usize,
}

impl<M: Cells> Cells for Window<'_, M> {
    fn len(&self) -> usize {
        self.len
    }
    fn read(&mut self, i: usize) -> u32 {
        if i < self.len {
            self.m.read(self.start.saturating_add(i))
        } else {
            0
        }
    }
    fn write(&mut self, i: usize, v: u32) {
        if i < self.len {
            self.m.write(self.start.saturating_add(i), v);
        }
    }
}

/// One register of the configuration read-back: the bits of `mask` must read `value`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Expect {
    /// The board's name for the register (an index into its own table of readers).
    pub reg: u8,
    /// The bits checked.
    pub mask: u32,
    /// What they must read.
    pub value: u32,
}

/// Read every register of `expected` through `read` and compare its masked bits. `Err((reg,
/// read))` names the first one that differs.
pub fn check_config(expected: &[Expect], mut read: impl FnMut(u8) -> u32) -> Result<(), (u8, u32)> {
    for e in expected {
        let v = read(e.reg);
        if v & e.mask != e.value & e.mask {
            return Err((e.reg, v));
        }
    }
    Ok(())
}

/// Which check the next step runs, and the cursor of the RAM test: the board's schedule. Every
/// step runs one flash chunk; every `ram_every`-th step one RAM block, every `config_every`-th the
/// configuration read-back.
#[derive(Copy, Clone, Debug)]
pub struct Schedule {
    step: u32,
    ram_at: usize,
    background: usize,
}

/// What one scheduled step should run besides its flash chunk.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Due {
    /// The RAM block's first word and background (index into `integrity::BACKGROUNDS`), if due.
    pub ram: Option<(usize, usize)>,
    /// The configuration read-back is due.
    pub config: bool,
}

impl Schedule {
    /// Nothing run yet.
    pub const fn new() -> Self {
        Schedule { step: 0, ram_at: 0, background: 0 }
    }

    /// The next step over a safety state of `words` words tested `block` words at a time.
    pub fn next(&mut self, words: usize, block: usize, ram_every: u32, config_every: u32, backgrounds: usize) -> Due {
        self.step = self.step.wrapping_add(1);
        let ram = if ram_every != 0 && self.step.is_multiple_of(ram_every) && words != 0 {
            let at = (self.ram_at, self.background);
            self.ram_at = self.ram_at.saturating_add(block.max(1));
            if self.ram_at >= words {
                self.ram_at = 0;
                self.background = (self.background.wrapping_add(1)).checked_rem(backgrounds.max(1)).unwrap_or(0);
            }
            Some(at)
        } else {
            None
        };
        Due { ram, config: config_every != 0 && self.step.is_multiple_of(config_every) }
    }
}

impl Default for Schedule {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::integrity::{image_crc_seeded, BACKGROUNDS};
    use std::vec::Vec;

    fn image() -> (Vec<u8>, usize, u32) {
        let mut img: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        let crc_at = 400;
        let stored = image_crc_seeded(&img, crc_at, Seed::Production);
        img[crc_at..crc_at + 4].copy_from_slice(&stored.to_le_bytes());
        (img, crc_at, stored)
    }

    /// Steps until the end of the pass under way.
    fn finish_pass(c: &mut FlashCrc, img: &[u8], crc_at: usize, stored: u32) -> bool {
        loop {
            if let Some(ok) = c.step(img, crc_at, stored, 64) {
                return ok;
            }
        }
    }

    #[test]
    fn the_incremental_flash_crc_equals_the_start_up_one_pass_after_pass() {
        let (img, crc_at, stored) = image();
        let mut c = FlashCrc::new(Seed::Production);
        for _ in 0..3 {
            assert!(finish_pass(&mut c, &img, crc_at, stored));
        }
        assert_eq!(c.passes(), 3);
    }

    #[test]
    fn a_flipped_flash_bit_is_found_within_two_passes_wherever_the_cursor_is() {
        let (img, crc_at, stored) = image();
        // Every bit of every 7th byte, flipped while the check is at every possible step of its pass.
        for byte in (0..img.len()).step_by(7).filter(|b| !(crc_at..crc_at + 4).contains(b)) {
            for bit in 0..8 {
                for cursor_steps in [0usize, 3, 15] {
                    let mut c = FlashCrc::new(Seed::Production);
                    for _ in 0..cursor_steps {
                        assert_eq!(c.step(&img, crc_at, stored, 64), None);
                    }
                    let mut bad = img.clone();
                    bad[byte] ^= 1 << bit;
                    let first = finish_pass(&mut c, &bad, crc_at, stored);
                    let second = finish_pass(&mut c, &bad, crc_at, stored);
                    assert!(!first || !second, "byte {byte} bit {bit} cursor {cursor_steps}: not found in two passes");
                    assert!(!second, "byte {byte} bit {bit}: the first whole pass after the flip must see it");
                }
            }
        }
    }

    /// Memory with injectable stuck bits.
    struct Ram {
        words: Vec<u32>,
        stuck: Option<(usize, u32, bool)>,
    }
    impl Cells for Ram {
        fn len(&self) -> usize {
            self.words.len()
        }
        fn read(&mut self, i: usize) -> u32 {
            let v = self.words[i];
            match self.stuck {
                Some((w, m, high)) if w == i => {
                    if high {
                        v | m
                    } else {
                        v & !m
                    }
                }
                _ => v,
            }
        }
        fn write(&mut self, i: usize, v: u32) {
            self.words[i] = v;
        }
    }

    #[test]
    fn the_ram_test_leaves_the_safety_state_as_it_was() {
        let orig: Vec<u32> = (0..40u32).map(|i| i.wrapping_mul(0x9E37_79B9)).collect();
        let mut m = Ram { words: orig.clone(), stuck: None };
        let mut s = Schedule::new();
        for _ in 0..200 {
            if let Some((at, bg)) = s.next(40, 4, 1, 0, BACKGROUNDS.len()).ram {
                assert_eq!(march_block_transparent(&mut m, at, 4, &BACKGROUNDS[bg..=bg]), Ok(()));
            }
        }
        assert_eq!(m.words, orig);
    }

    #[test]
    fn a_stuck_ram_bit_in_the_safety_state_is_found_within_one_pass() {
        for word in [0usize, 13, 39] {
            for bit in [0u32, 7, 31] {
                for high in [false, true] {
                    let mut m = Ram { words: (0..40u32).collect(), stuck: Some((word, 1 << bit, high)) };
                    let mut s = Schedule::new();
                    let mut found = None;
                    // One pass: 40 words, 4 a step, every step.
                    for step in 0..10 {
                        let (at, bg) = s.next(40, 4, 1, 0, BACKGROUNDS.len()).ram.unwrap();
                        if let Err(f) = march_block_transparent(&mut m, at, 4, &BACKGROUNDS[bg..=bg]) {
                            found = Some((step, f.index));
                            break;
                        }
                    }
                    let (_, index) = found.unwrap_or_else(|| panic!("word {word} bit {bit} high {high}: not found in a pass"));
                    assert_eq!(index, word);
                }
            }
        }
    }

    #[test]
    fn every_flipped_configuration_bit_is_found_at_the_next_check() {
        let expected = [Expect { reg: 0, mask: 0x0000_0011, value: 0x11 }, Expect { reg: 1, mask: 0xFF00_0000, value: 0x8000_0000 }];
        let good = [0x11u32 | 0xF0, 0x8012_3456];
        assert_eq!(check_config(&expected, |r| good[usize::from(r)]), Ok(()));
        for (k, e) in expected.iter().enumerate() {
            for bit in 0..32 {
                let mut regs = good;
                regs[k] ^= 1 << bit;
                let r = check_config(&expected, |r| regs[usize::from(r)]);
                if e.mask & (1 << bit) != 0 {
                    assert_eq!(r, Err((e.reg, regs[k])), "reg {k} bit {bit}");
                } else {
                    assert_eq!(r, Ok(()), "reg {k} bit {bit} is not checked");
                }
            }
        }
    }

    #[test]
    fn the_schedule_states_its_periods() {
        let mut s = Schedule::new();
        let dues: Vec<Due> = (0..32).map(|_| s.next(10, 2, 2, 16, 4)).collect();
        assert_eq!(dues.iter().filter(|d| d.config).count(), 2, "every 16th step");
        let rams: Vec<(usize, usize)> = dues.iter().filter_map(|d| d.ram).collect();
        assert_eq!(rams.len(), 16, "every 2nd step");
        assert_eq!(&rams[..6], &[(0, 0), (2, 0), (4, 0), (6, 0), (8, 0), (0, 1)], "round the state, then the next background");
    }
}
