//! The velocity frame: what one avoidance step ([`super::link::Link`]) sends back to the host and
//! the robot, defined once (the board encodes with [`encode_velocity`], the host and xtask decode
//! with [`decode_velocity`]).
//!
//! Little-endian, [`VEL_LEN`] bytes:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 2 | sync `5A A5` (the weights frame's reversed) |
//! | 2 | 1 | version 2 |
//! | 3 | 1 | status ([`Status`]: 0 `ok`, 1 `slowed`, 2 `stopped: stale`, 3 `stopped: no path`, 4 `stopped: latched`, 5 `stopped: protective`; a reader that does not know a code refuses the frame) |
//! | 4 | 4 | step number u32 (wrapping) |
//! | 8 | 4 | `seq` of the weights in use u32 (0: none) |
//! | 12 | 4 | `vx`, i32 micrometres per second |
//! | 16 | 4 | `vy`, i32 um/s |
//! | 20 | 4 | `x`, i32 micrometres (the tool position the step used) |
//! | 24 | 4 | `y`, i32 um |
//! | 28 | 2 | good frames u16 (saturating) |
//! | 30 | 2 | refused frames u16: bad CRC + bad header + short + stale (saturating) |
//! | 32 | 4 | `t_ms`, u32: the MCU's clock at this step (wrapping); the host echoes it in the weights frames it captures after reading it (`frame`: `echo_ms`), so the MCU bounds their age from above |
//! | 36 | 1 | `boot`: this boot of the MCU (echoed with `t_ms`: a clock of an earlier boot is not used) |
//! | 37 | 1 | the monitor ([`Monitor`]: 0 `run`, 1 `slow`, 2 `protective_stop`, 3 `no_data`, 4 `pfl`, 5 `off`, 6 `not_run`) |
//! | 38 | 2 | the speed limit that applied, u16 mm/s (rounded down, saturating) |
//! | 40 | 4 | CRC-32/ISO-HDLC of bytes 2..40 |

use super::frame::CRC;
use super::num::Real;

/// Bytes of a velocity frame.
pub const VEL_LEN: usize = 44;
/// First sync byte of a velocity frame.
pub const VEL_SYNC0: u8 = 0x5A;
/// Second sync byte of a velocity frame.
pub const VEL_SYNC1: u8 = 0xA5;
/// Velocity frame version (2: the MCU clock, the boot byte and the monitor's state and limit).
pub const VEL_VERSION: u8 = 2;
/// Bytes covered by the CRC end here.
const BODY_END: usize = 40;

/// What the step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The command as computed.
    Ok = 0,
    /// Scaled down (old weights, the field above the slow height, or the speed and separation
    /// monitor's bound).
    Slowed = 1,
    /// Zero: no weights yet, or too old, or no sensed separation the monitor may use.
    StoppedStale = 2,
    /// Zero: the field at the tool at or above the stop height, or no command away from the goal.
    StoppedNoPath = 3,
    /// Zero: the detection firmware holds the robot stopped (its collision latch, a fault, the start
    /// latch, the self-test); only a person's reset press at the module ends it.
    StoppedLatched = 4,
    /// Zero: the speed and separation monitor's protective stop (a person within the protective
    /// separation, and no PFL speed in the asked direction); it resumes by itself when the separation
    /// grows (ISO 10218-1:2011, 5.10.6).
    StoppedProtective = 5,
}

impl Status {
    /// The status word as the velocity frame's reader prints it.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Slowed => "slowed",
            Status::StoppedStale => "stopped: stale",
            Status::StoppedNoPath => "stopped: no path",
            Status::StoppedLatched => "stopped: latched",
            Status::StoppedProtective => "stopped: protective",
        }
    }

    /// From the frame's status byte.
    pub fn from_code(c: u8) -> Option<Status> {
        match c {
            0 => Some(Status::Ok),
            1 => Some(Status::Slowed),
            2 => Some(Status::StoppedStale),
            3 => Some(Status::StoppedNoPath),
            4 => Some(Status::StoppedLatched),
            5 => Some(Status::StoppedProtective),
            _ => None,
        }
    }
}

/// What the speed and separation monitor did in the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Monitor {
    /// The command passed unchanged.
    Run = 0,
    /// Scaled to the SSM bound (or the cap).
    Slow = 1,
    /// The protective separation is not kept: zero.
    ProtectiveStop = 2,
    /// No sensed separation it may use (none, or its clock echo from another boot or the future).
    NoData = 3,
    /// Beyond the SSM bound, within the PFL speeds.
    Pfl = 4,
    /// No monitor configured (the thesis's law: host comparisons only; the board ships one).
    Off = 5,
    /// The step stopped before the monitor (latched, stale weights, no path).
    NotRun = 6,
}

impl Monitor {
    /// The name the host's run rows use.
    pub fn name(self) -> &'static str {
        match self {
            Monitor::Run => "run",
            Monitor::Slow => "slow",
            Monitor::ProtectiveStop => "protective_stop",
            Monitor::NoData => "no_data",
            Monitor::Pfl => "pfl",
            Monitor::Off => "field",
            Monitor::NotRun => "not_run",
        }
    }

    /// From the frame's byte.
    pub fn from_code(c: u8) -> Option<Monitor> {
        match c {
            0 => Some(Monitor::Run),
            1 => Some(Monitor::Slow),
            2 => Some(Monitor::ProtectiveStop),
            3 => Some(Monitor::NoData),
            4 => Some(Monitor::Pfl),
            5 => Some(Monitor::Off),
            6 => Some(Monitor::NotRun),
            _ => None,
        }
    }
}

/// One step's output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Velocity<R> {
    /// Step number (wrapping).
    pub step: u32,
    /// `seq` of the weights in use (0: none).
    pub seq: u32,
    /// What the step did.
    pub status: Status,
    /// Command, m/s.
    pub vx: R,
    /// Command, m/s.
    pub vy: R,
    /// The tool position the step used (dead-reckoned, or the robot's when given), m.
    pub x: R,
    /// See `x`.
    pub y: R,
    /// Frames applied.
    pub good: u32,
    /// Frames refused (bad CRC, bad header, short, stale).
    pub refused: u32,
    /// The MCU's clock at the step, ms.
    pub t_ms: u32,
    /// The MCU's boot byte.
    pub boot: u8,
    /// What the monitor did.
    pub monitor: Monitor,
    /// The speed limit that applied, m/s (0 when stopped).
    pub limit_mps: R,
}

/// Metres (per second) to whole micrometres (per second), saturating ([`Real::to_micro`]).
fn micro<R: Real>(v: R) -> i32 {
    v.to_micro()
}

/// The velocity frame of one step. Built as one array (no per-field copies: in QEMU's instruction
/// count the field-by-field version cost 1,180 instructions a frame, most of them `memcpy` calls).
pub fn encode_velocity<R: Real>(v: &Velocity<R>) -> [u8; VEL_LEN] {
    let sat16 = |n: u32| u16::try_from(n).unwrap_or(u16::MAX);
    // mm/s from um/s, rounded down; a negative (never produced) or NaN limit is 0.
    let limit_mmps = sat16(u32::try_from(micro(v.limit_mps).max(0)).unwrap_or(0) / 1000);
    let [a0, a1, a2, a3] = v.step.to_le_bytes();
    let [b0, b1, b2, b3] = v.seq.to_le_bytes();
    let [c0, c1, c2, c3] = micro(v.vx).to_le_bytes();
    let [d0, d1, d2, d3] = micro(v.vy).to_le_bytes();
    let [e0, e1, e2, e3] = micro(v.x).to_le_bytes();
    let [f0, f1, f2, f3] = micro(v.y).to_le_bytes();
    let [g0, g1] = sat16(v.good).to_le_bytes();
    let [h0, h1] = sat16(v.refused).to_le_bytes();
    let [t0, t1, t2, t3] = v.t_ms.to_le_bytes();
    let [l0, l1] = limit_mmps.to_le_bytes();
    #[rustfmt::skip]
    let body: [u8; BODY_END] = [
        VEL_SYNC0, VEL_SYNC1, VEL_VERSION, v.status as u8,
        a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3, e0, e1, e2, e3, f0, f1, f2, f3,
        g0, g1, h0, h1, t0, t1, t2, t3, v.boot, v.monitor as u8, l0, l1,
    ];
    let [k0, k1, k2, k3] = CRC.checksum(body.get(2..).unwrap_or(&[])).to_le_bytes();
    let mut b = [0u8; VEL_LEN];
    let (head, tail) = b.split_at_mut(BODY_END);
    head.copy_from_slice(&body);
    tail.copy_from_slice(&[k0, k1, k2, k3]);
    b
}

/// A decoded velocity frame (integers as sent).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VelocityFrame {
    /// What the step did.
    pub status: Status,
    /// Step number.
    pub step: u32,
    /// Weights in use (0: none).
    pub seq: u32,
    /// Command, um/s.
    pub vx_umps: i32,
    /// Command, um/s.
    pub vy_umps: i32,
    /// Tool position, um.
    pub x_um: i32,
    /// Tool position, um.
    pub y_um: i32,
    /// Frames applied (saturating).
    pub good: u16,
    /// Frames refused (saturating).
    pub refused: u16,
    /// The MCU's clock, ms.
    pub t_ms: u32,
    /// The MCU's boot byte.
    pub boot: u8,
    /// What the monitor did.
    pub monitor: Monitor,
    /// The speed limit, mm/s.
    pub limit_mmps: u16,
}

/// Decode one velocity frame (`None`: wrong sync, version, status, monitor code or CRC, or too
/// short).
pub fn decode_velocity(b: &[u8]) -> Option<VelocityFrame> {
    let b: &[u8; VEL_LEN] = b.get(..VEL_LEN)?.try_into().ok()?;
    let [s0, s1, ver, st, ..] = *b;
    if s0 != VEL_SYNC0 || s1 != VEL_SYNC1 || ver != VEL_VERSION {
        return None;
    }
    let u32_at = |k: usize| -> Option<u32> { Some(u32::from_le_bytes(b.get(k..k.checked_add(4)?)?.try_into().ok()?)) };
    let u16_at = |k: usize| -> Option<u16> { Some(u16::from_le_bytes(b.get(k..k.checked_add(2)?)?.try_into().ok()?)) };
    if CRC.checksum(b.get(2..BODY_END)?) != u32_at(BODY_END)? {
        return None;
    }
    Some(VelocityFrame {
        status: Status::from_code(st)?,
        step: u32_at(4)?,
        seq: u32_at(8)?,
        vx_umps: u32_at(12)? as i32,
        vy_umps: u32_at(16)? as i32,
        x_um: u32_at(20)? as i32,
        y_um: u32_at(24)? as i32,
        good: u16_at(28)?,
        refused: u16_at(30)?,
        t_ms: u32_at(32)?,
        boot: *b.get(36)?,
        monitor: Monitor::from_code(*b.get(37)?)?,
        limit_mmps: u16_at(38)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_velocity_frame_round_trips_and_refuses_damage() {
        let v = Velocity { step: 7, seq: 3, status: Status::Slowed, vx: 0.125f32, vy: -0.25, x: 0.5, y: 1.0, good: 70_000, refused: 2, t_ms: 123_456, boot: 9, monitor: Monitor::Pfl, limit_mps: 0.2875 };
        let b = encode_velocity(&v);
        let d = decode_velocity(&b).unwrap();
        assert_eq!(
            d,
            VelocityFrame { status: Status::Slowed, step: 7, seq: 3, vx_umps: 125_000, vy_umps: -250_000, x_um: 500_000, y_um: 1_000_000, good: u16::MAX, refused: 2, t_ms: 123_456, boot: 9, monitor: Monitor::Pfl, limit_mmps: 287 }
        );
        for k in 0..VEL_LEN {
            let mut c = b;
            c[k] ^= 0x10;
            assert!(decode_velocity(&c).is_none(), "byte {k} flipped was accepted");
        }
        // NaN and huge values saturate; a NaN command never decodes as motion.
        let w = Velocity { vx: f32::NAN, vy: 1e30, limit_mps: f32::NAN, ..v };
        let d = decode_velocity(&encode_velocity(&w)).unwrap();
        assert_eq!((d.vx_umps, d.vy_umps, d.limit_mmps), (0, i32::MAX, 0));
        // Every status and monitor code round-trips; unknown ones are refused.
        for c in 0..=255u8 {
            assert_eq!(Status::from_code(c).map(|s| s as u8), (c <= 5).then_some(c));
            assert_eq!(Monitor::from_code(c).map(|s| s as u8), (c <= 6).then_some(c));
        }
    }
}
