//! What happens after the MCU resets: never "go" by itself.
//!
//! IEC 60204-1 7.5 asks that a machine does not restart by itself when power returns, and ISO 13849-1
//! 5.2.2 asks that a manual reset is a deliberate act: a separate device, acting on the *release* of
//! the button, not possible while a stop condition persists, and a stuck button must not reset. So:
//!
//! * **Every start is latched** ([`StartPolicy::ManualReset`], the default): whatever reset the part
//!   (power-on, brown-out, watchdog, a fault handler, the NRST pin, software), the firmware comes up in
//!   [`State::Fault`](crate::State::Fault)`(`[`Cause::Reset`]`)` with both outputs de-energised, and
//!   only a reset press-and-release ([`ResetPress`]) starts the self-test that arms it.
//! * [`StartPolicy::AutoAfterPowerOn`] relaxes this for one case only: a *clean* power-on (the reset
//!   flags say power-on and nothing else, and no valid latched record survived). Watchdog, brown-out,
//!   software and pin resets, an unknown cause and a retained latch always wait for a person.
//! * **The latch survives the reset.** [`Retained`] is four words the board keeps in RAM that the
//!   start-up code does not clear (backup SRAM or a `.uninit` section): a magic number, the latched
//!   cause (a trip, a fault, or a fault handler that ran just before the reset), a boot counter and a
//!   CRC-32 over the three. A record whose CRC fails is treated as no record, which can only make the
//!   start *more* latched: without a valid record a non-power-on reset is latched anyway.
//! * The reset cause is logged as an event ([`Cause::Reset`], its [`ResetCause`] code in the flags),
//!   and a retained latch as a second one ([`FLAG_RETAINED`](crate::event_log::FLAG_RETAINED)).
//!
//! The reset cause comes from the reset-flag register: [`ResetCause::from_rcc_csr`] decodes the
//! STM32F4's `RCC_CSR` (RM0090 7.3.21); the board clears the flags afterwards (RMVF) so the next reset
//! reads only its own.

use crate::clock::Micros;
use crate::event_log::Cause;
use crc::{Crc, NoTable, CRC_32_ISO_HDLC};

/// Why the MCU (re)started.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum ResetCause {
    /// Power-on / power-down reset, nothing else flagged.
    PowerOn = 1,
    /// Supply dropped below the brown-out level (BOR) without a full power cycle.
    BrownOut = 2,
    /// The independent or the window watchdog expired.
    Watchdog = 3,
    /// Software reset (SYSRESETREQ), e.g. from a fault handler.
    Software = 4,
    /// The NRST pin alone (an external reset, a debugger).
    Pin = 5,
    /// Low-power management reset.
    LowPower = 6,
    /// The flags were unreadable or empty: treated like the worst of the above.
    Unknown = 7,
}

impl ResetCause {
    /// Decode the STM32F4 `RCC_CSR` reset flags (RM0090 7.3.21): LPWRRSTF bit 31, WWDGRSTF 30,
    /// IWDGRSTF 29, SFTRSTF 28, PORRSTF 27, PINRSTF 26, BORRSTF 25. The most serious flag wins. A
    /// power-on also sets BORRSTF and PINRSTF (the internal reset drives NRST), so it is recognised by
    /// PORRSTF; a brown-out sets BORRSTF and PINRSTF without PORRSTF; any reset sets PINRSTF.
    pub const fn from_rcc_csr(csr: u32) -> ResetCause {
        const LPWR: u32 = 1 << 31;
        const WWDG: u32 = 1 << 30;
        const IWDG: u32 = 1 << 29;
        const SFT: u32 = 1 << 28;
        const POR: u32 = 1 << 27;
        const PIN: u32 = 1 << 26;
        const BOR: u32 = 1 << 25;
        if csr & (WWDG | IWDG) != 0 {
            ResetCause::Watchdog
        } else if csr & LPWR != 0 {
            ResetCause::LowPower
        } else if csr & SFT != 0 {
            ResetCause::Software
        } else if csr & POR != 0 {
            ResetCause::PowerOn
        } else if csr & BOR != 0 {
            ResetCause::BrownOut
        } else if csr & PIN != 0 {
            ResetCause::Pin
        } else {
            ResetCause::Unknown
        }
    }

    /// Decode the code stored in an event's flags.
    pub const fn from_u8(v: u8) -> Option<ResetCause> {
        Some(match v {
            1 => ResetCause::PowerOn,
            2 => ResetCause::BrownOut,
            3 => ResetCause::Watchdog,
            4 => ResetCause::Software,
            5 => ResetCause::Pin,
            6 => ResetCause::LowPower,
            7 => ResetCause::Unknown,
            _ => return None,
        })
    }

    /// A short name, for reports.
    pub const fn name(self) -> &'static str {
        match self {
            ResetCause::PowerOn => "power-on",
            ResetCause::BrownOut => "brown-out",
            ResetCause::Watchdog => "watchdog",
            ResetCause::Software => "software",
            ResetCause::Pin => "pin",
            ResetCause::LowPower => "low-power",
            ResetCause::Unknown => "unknown",
        }
    }
}

/// Whether a start needs a person.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum StartPolicy {
    /// Every start, power-on included, waits for a reset press and release (the default).
    ManualReset,
    /// A clean power-on with no retained latch starts the self-test by itself; every other reset
    /// waits for a person. For a cell whose robot controller has its own start interlock.
    AutoAfterPowerOn,
}

/// What counts as a deliberate reset press (ISO 13849-1 5.2.2: the reset acts on the release).
///
/// The button must go from released to pressed *while the firmware is latched*, stay pressed at least
/// `min_us` and at most `max_us`, and the reset happens on its release. A shorter press is a glitch; a
/// longer one is a stuck button or a jammed contact, refused until it is released and pressed again.
/// A button already held when the latch began never resets it (its press did not start in the latch).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ResetPress {
    /// Shortest press accepted, microseconds.
    pub min_us: u32,
    /// Longest press accepted, microseconds (below 2^31 so that wrap-safe time measures it).
    pub max_us: u32,
}

impl ResetPress {
    /// 50 ms to 5 s, the range common safety relays use for a monitored manual reset.
    pub const DEFAULT: ResetPress = ResetPress { min_us: 50_000, max_us: 5_000_000 };
}

/// Tracks the reset button: presses start while latched, resets act on release.
///
/// A new tracker (after every MCU reset) takes the button as *pressed*: only a released-to-pressed
/// edge it has itself observed starts a press. A button found held at boot (a press begun before a
/// watchdog reset, a jammed contact) must first be seen released, so its release never counts.
#[derive(Copy, Clone, Debug)]
pub struct ResetButton {
    prev: bool,
    pressed_since: Option<Micros>,
}

impl Default for ResetButton {
    fn default() -> ResetButton {
        // `prev = true`: until a released level is seen, no rising edge can be observed.
        ResetButton { prev: true, pressed_since: None }
    }
}

impl ResetButton {
    /// Forget a press in progress: a press that began before a new latch does not count.
    pub fn cancel(&mut self) {
        self.pressed_since = None;
    }

    /// Feed the button's level at `now`; returns `true` on the release of a press that started while
    /// tracked and lasted between `press.min_us` and `press.max_us`.
    pub fn released(&mut self, press: ResetPress, now: Micros, level: bool) -> bool {
        let rising = level && !self.prev;
        let falling = !level && self.prev;
        self.prev = level;
        if rising {
            self.pressed_since = Some(now);
            return false;
        }
        let Some(since) = self.pressed_since else { return false };
        let held = now.since(since);
        if level {
            if held > press.max_us {
                self.pressed_since = None; // stuck: refused until released and pressed again
            }
            return false;
        }
        if falling {
            self.pressed_since = None;
            return held >= press.min_us && held <= press.max_us;
        }
        false
    }

    /// Track the level without accepting anything (while armed or in the self-test), so that a
    /// button held across a trip is not a new press.
    pub fn track(&mut self, level: bool) {
        self.prev = level;
        self.pressed_since = None;
    }
}

/// `Retained::words[0]` of a valid record.
pub const RETAINED_MAGIC: u32 = 0x464C_4E43; // "FLNC"

const CRC32: Crc<u32, NoTable> = Crc::<u32, NoTable>::new(&CRC_32_ISO_HDLC);

/// The latch that survives a reset: `[magic, latched cause (0 = none), boot count, CRC-32]`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
#[repr(C)]
pub struct Retained {
    /// The raw words, as stored in backup SRAM.
    pub words: [u32; 4],
}

impl Retained {
    /// A valid record holding `latched` and `boots`.
    pub fn new(latched: Option<Cause>, boots: u32) -> Retained {
        let cause = match latched {
            Some(c) => c as u32,
            None => 0,
        };
        let crc = Self::crc(RETAINED_MAGIC, cause, boots);
        Retained { words: [RETAINED_MAGIC, cause, boots, crc] }
    }

    fn crc(magic: u32, cause: u32, boots: u32) -> u32 {
        let mut b = [0u8; 12];
        let (m, rest) = b.split_at_mut(4);
        let (c, n) = rest.split_at_mut(4);
        m.copy_from_slice(&magic.to_le_bytes());
        c.copy_from_slice(&cause.to_le_bytes());
        n.copy_from_slice(&boots.to_le_bytes());
        CRC32.checksum(&b)
    }

    /// `Some((latched, boots))` for a record whose magic and CRC hold and whose cause decodes; `None`
    /// otherwise (power-on garbage, a torn write, a flipped bit).
    pub fn decode(&self) -> Option<(Option<Cause>, u32)> {
        let [magic, cause, boots, crc] = self.words;
        if magic != RETAINED_MAGIC || crc != Self::crc(magic, cause, boots) {
            return None;
        }
        let latched = match cause {
            0 => None,
            c => Some(Cause::from_u8(u8::try_from(c).ok()?)?),
        };
        Some((latched, boots))
    }
}

/// Everything the firmware needs to know about the reset it starts from.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Boot {
    /// Why the MCU started.
    pub cause: ResetCause,
    /// The record that survived in retained RAM (garbage after a power cycle: it is checked).
    pub retained: Retained,
}

impl Boot {
    /// The start of a firmware whose reset cause is not known: always latched.
    pub const UNKNOWN: Boot = Boot { cause: ResetCause::Unknown, retained: Retained { words: [0; 4] } };

    /// A power-on with nothing retained (a simulation's first start).
    pub const POWER_ON: Boot = Boot { cause: ResetCause::PowerOn, retained: Retained { words: [0; 4] } };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rcc_csr_flags_decode_most_serious_first() {
        let (lpwr, wwdg, iwdg, sft, por, pin, bor) = (1 << 31, 1 << 30, 1 << 29, 1 << 28, 1 << 27, 1 << 26, 1 << 25);
        assert_eq!(ResetCause::from_rcc_csr(por | pin | bor), ResetCause::PowerOn);
        assert_eq!(ResetCause::from_rcc_csr(pin | bor), ResetCause::BrownOut);
        assert_eq!(ResetCause::from_rcc_csr(iwdg | pin), ResetCause::Watchdog);
        assert_eq!(ResetCause::from_rcc_csr(wwdg | pin), ResetCause::Watchdog);
        assert_eq!(ResetCause::from_rcc_csr(iwdg | por | pin | bor), ResetCause::Watchdog);
        assert_eq!(ResetCause::from_rcc_csr(sft | pin), ResetCause::Software);
        assert_eq!(ResetCause::from_rcc_csr(lpwr | pin), ResetCause::LowPower);
        assert_eq!(ResetCause::from_rcc_csr(pin), ResetCause::Pin);
        assert_eq!(ResetCause::from_rcc_csr(0), ResetCause::Unknown);
        for c in 1..=7u8 {
            assert_eq!(ResetCause::from_u8(c).map(|r| r as u8), Some(c));
        }
    }

    #[test]
    fn retained_record_round_trips_and_any_flipped_bit_is_refused() {
        let r = Retained::new(Some(Cause::Trip), 7);
        assert_eq!(r.decode(), Some((Some(Cause::Trip), 7)));
        assert_eq!(Retained::new(None, 0).decode(), Some((None, 0)));
        for w in 0..4 {
            for bit in 0..32 {
                let mut bad = r;
                bad.words[w] ^= 1 << bit;
                assert_eq!(bad.decode(), None, "word {w} bit {bit}");
            }
        }
        assert_eq!(Retained::default().decode(), None, "zeroed RAM is no record");
    }

    #[test]
    fn reset_acts_on_release_of_a_press_of_the_right_length() {
        let p = ResetPress { min_us: 50_000, max_us: 5_000_000 };
        let mut b = ResetButton::default();
        assert!(!b.released(p, Micros(0), false));
        assert!(!b.released(p, Micros(1_000), true), "pressing does nothing");
        assert!(!b.released(p, Micros(40_000), false), "39 ms: too short, a glitch");
        assert!(!b.released(p, Micros(100_000), true));
        assert!(!b.released(p, Micros(150_000), true), "held: still nothing");
        assert!(b.released(p, Micros(150_001), false), "released after 50 ms: reset");
    }

    #[test]
    fn a_button_held_at_boot_must_be_seen_released_before_a_press_counts() {
        let p = ResetPress { min_us: 50_000, max_us: 5_000_000 };
        for release_us in [100_000, 1_000_000, 3_000_000] {
            let mut b = ResetButton::default(); // a fresh boot, button already held
            let mut t = 0;
            while t < release_us {
                assert!(!b.released(p, Micros(t), true));
                t += 1_000;
            }
            assert!(!b.released(p, Micros(t), false), "held through the reset, released at {release_us} us");
            // A press that begins after boot does count.
            assert!(!b.released(p, Micros(t + 10_000), true));
            assert!(b.released(p, Micros(t + 70_000), false));
        }
        // Released at boot: the first press counts.
        let mut b = ResetButton::default();
        assert!(!b.released(p, Micros(0), false));
        assert!(!b.released(p, Micros(1_000), true));
        assert!(b.released(p, Micros(61_000), false));
    }

    #[test]
    fn a_stuck_or_pre_held_button_never_resets() {
        let p = ResetPress { min_us: 50_000, max_us: 5_000_000 };
        // Held when the latch began: its release is not a reset.
        let mut b = ResetButton::default();
        b.track(true);
        assert!(!b.released(p, Micros(0), true));
        assert!(!b.released(p, Micros(100_000), false));
        // Stuck for longer than max_us: refused, even when it finally lets go.
        let mut b = ResetButton::default();
        let t0 = Micros(u32::MAX - 1_000_000); // across the wrap
        assert!(!b.released(p, t0, false));
        assert!(!b.released(p, t0.plus(1), true));
        let mut t = t0.plus(1);
        for _ in 0..60 {
            t = t.plus(100_000);
            assert!(!b.released(p, t, true));
        }
        assert!(!b.released(p, t.plus(1), false), "a 6 s press is a stuck button");
        // A fresh press afterwards works.
        assert!(!b.released(p, t.plus(10_000), true));
        assert!(b.released(p, t.plus(70_000), false));
        // A press cancelled by a new latch does not count.
        assert!(!b.released(p, t.plus(100_000), true));
        b.cancel();
        assert!(!b.released(p, t.plus(200_000), false));
    }
}
