//! The avoidance step as the board runs it: weights frames in (through a [`Receiver`]), one step per
//! control period, a velocity frame with a status word out.
//!
//! Kept in the library (not in the board binary) so that the host tests the whole step, the status
//! and the velocity frame; the board binary (`src/bin/support/board_avoid.rs`) only moves bytes between the
//! USART and this type and runs [`Link::step_with`] on a timer, with the detection firmware's latch.
//!
//! Each step: the receiver is ticked and serviced (at most `budget_bytes` parsed), the field and its
//! gradient are sampled at the tool, the command of eq 74-78 is formed with the weights-age watchdog
//! factor, capped at `speed_cap_mps` (the length bound `max + min / 2`, never below the true speed),
//! and classified:
//!
//! | status | when | command |
//! |---|---|---|
//! | `ok` | fresh weights, the field below `slow_height_m` | as computed |
//! | `slowed` | the weights older than `slow_after_ms`, or the field above `slow_height_m` | scaled down |
//! | `stopped: stale` | no good frame yet, or the weights at least `stop_after_ms` old | zero |
//! | `stopped: no path` | the field at the tool at or above `stop_height_m`, or no command away from the goal (a local minimum) | zero |
//! | `stopped: latched` | the detection firmware holds the robot stopped ([`Link::step_with`] with `latched`: on the board every state but armed, i.e. the collision latch after a trip, a fault, the start latch after a reset, and the self-test after a reset press); before every other status | zero |
//!
//! While latched the receiver still takes and applies frames (so the weights are current when the
//! latch is released) and the step number counts on, but the command is zero and the dead-reckoned
//! position does not move: the robot is held, whatever the field says.
//!
//! The tool position is dead-reckoned from the commands (eq 79, `p += v dt`: the robot is assumed
//! to follow the command), from `start_m`. The velocity frame reports it, so the host can check it
//! against the robot's.
//!
//! Velocity frame (board to host), little-endian, [`VEL_LEN`] bytes:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 2 | sync `5A A5` (the weights frame's reversed) |
//! | 2 | 1 | version 1 |
//! | 3 | 1 | status: 0 `ok`, 1 `slowed`, 2 `stopped: stale`, 3 `stopped: no path`, 4 `stopped: latched` (a reader that does not know a code refuses the frame: [`decode_velocity`]) |
//! | 4 | 4 | step number u32 (wrapping) |
//! | 8 | 4 | `seq` of the weights in use u32 (0: none) |
//! | 12 | 4 | `vx`, i32 micrometres per second |
//! | 16 | 4 | `vy`, i32 um/s |
//! | 20 | 4 | `x`, i32 micrometres (dead-reckoned tool position) |
//! | 24 | 4 | `y`, i32 um |
//! | 28 | 2 | good frames u16 (saturating) |
//! | 30 | 2 | refused frames u16: bad CRC + bad header + short + stale (saturating) |
//! | 32 | 4 | CRC-32/ISO-HDLC of bytes 2..32 |

use super::control::{Controller, Gains, Repulsion, Watchdog};
use super::field::sample;
use super::frame::CRC;
use super::gauss::GaussLut;
use super::num::Real;
use super::receiver::Receiver;

/// Bytes of a velocity frame.
pub const VEL_LEN: usize = 36;
/// First sync byte of a velocity frame.
pub const VEL_SYNC0: u8 = 0x5A;
/// Second sync byte of a velocity frame.
pub const VEL_SYNC1: u8 = 0xA5;
/// Velocity frame version.
pub const VEL_VERSION: u8 = 1;

/// What the step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The command as computed.
    Ok = 0,
    /// Scaled down (old weights, or the field above the slow height).
    Slowed = 1,
    /// Zero: no weights yet, or too old.
    StoppedStale = 2,
    /// Zero: the field at the tool at or above the stop height, or no command away from the goal.
    StoppedNoPath = 3,
    /// Zero: the detection firmware holds the robot stopped (its collision latch, a fault, the start
    /// latch, the self-test); only a person's reset press at the module ends it.
    StoppedLatched = 4,
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
            _ => None,
        }
    }
}

/// The installation's avoidance settings.
#[derive(Clone, Copy, Debug)]
pub struct LinkConfig<R> {
    /// Gains and heights of the step.
    pub gains: Gains<R>,
    /// The weights-age watchdog.
    pub watchdog: Watchdog,
    /// Where the tool starts, m.
    pub start_m: [R; 2],
    /// The goal, m.
    pub goal_m: [R; 2],
    /// Largest commanded speed, m/s.
    pub speed_cap_mps: R,
    /// The control period, ms (the step's timer).
    pub period_ms: u32,
    /// Oldest image the receiver accepts, ms.
    pub max_age_ms: u16,
    /// Longest gap inside one frame, ms.
    pub byte_timeout_ms: u32,
    /// Bytes parsed per step (more than the line brings in one period).
    pub budget_bytes: usize,
}

/// The board's control period, ms: one avoidance step every ten 1 ms ticks.
pub const BOARD_PERIOD_MS: u32 = 10;

/// The installation's avoidance settings as the board ships them: those of the demo scene
/// (`scenes/avoid_*.toml`: k_a 0.25 m/s, the thesis's vortex) on the 1.05 m work plane; replace
/// with the cell's. The one copy: the board (`src/bin/support/board_avoid.rs`) runs it and the
/// step's instruction count (`avoid-cost`, its `avoid_board` lines) measures it.
pub fn board_config() -> LinkConfig<super::num::BoardReal> {
    let r = super::num::BoardReal::from_f32;
    LinkConfig {
        gains: Gains {
            repulsion: Repulsion::Vortex { sign: 0 },
            k_att: r(0.25),
            k_rep: r(0.5),
            capture_radius_m: r(0.03),
            latch_height_m: r(0.02),
            slow_height_m: r(0.05),
            stop_height_m: r(0.15),
            bounded: false,
        },
        watchdog: Watchdog { slow_after_ms: 100, stop_after_ms: 330 },
        start_m: [r(0.2), r(0.5)],
        goal_m: [r(0.9), r(0.5)],
        speed_cap_mps: r(0.25),
        period_ms: BOARD_PERIOD_MS,
        max_age_ms: 100,
        byte_timeout_ms: 50,
        // 115,200 baud brings 115 bytes in 10 ms.
        budget_bytes: 256,
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
    /// Dead-reckoned tool position before this step's motion, m.
    pub x: R,
    /// Dead-reckoned tool position before this step's motion, m.
    pub y: R,
    /// Frames applied.
    pub good: u32,
    /// Frames refused (bad CRC, bad header, short, stale).
    pub refused: u32,
}

/// The receiver and the step.
pub struct Link<R> {
    rx: Receiver<R>,
    ctl: Controller<R>,
    gauss: GaussLut<R>,
    cfg: LinkConfig<R>,
    dt_s: R,
    x: R,
    y: R,
    step: u32,
}

impl<R: Real> Link<R> {
    /// A link with no weights (every step `stopped: stale` until the first good frame).
    pub fn new(cfg: LinkConfig<R>) -> Self {
        let mut rx = Receiver::new(cfg.max_age_ms, cfg.byte_timeout_ms);
        rx.budget_bytes = cfg.budget_bytes;
        // A restarted host's new session is taken once the weights watchdog has stopped the robot.
        rx.new_session_after_ms = cfg.watchdog.stop_after_ms;
        let dt_s = R::from_int(cfg.period_ms.min(60_000) as i32).div(R::from_int(1000));
        Link { rx, ctl: Controller::new(cfg.gains), gauss: GaussLut::new(), cfg, dt_s, x: cfg.start_m[0], y: cfg.start_m[1], step: 0 }
    }

    /// The receiver (to push bytes into, and for its counters).
    pub fn receiver(&mut self) -> &mut Receiver<R> {
        &mut self.rx
    }

    /// One control step at `now_ms` (wrap-safe: only differences of it are used), the robot not
    /// held by the detection firmware: [`Link::step_with`] with `latched` false.
    pub fn step(&mut self, now_ms: u32) -> Velocity<R> {
        self.step_with(now_ms, false)
    }

    /// One control step at `now_ms`; `latched`: the detection firmware holds the robot stopped (on
    /// the board: any state but armed). Latched, the command is zero, the status
    /// [`Status::StoppedLatched`] (before every other) and the dead-reckoned position stays where it
    /// is; the receiver is still serviced, so the weights are current when the latch is released.
    pub fn step_with(&mut self, now_ms: u32, latched: bool) -> Velocity<R> {
        self.rx.tick(now_ms);
        self.rx.service(now_ms);
        self.step = self.step.wrapping_add(1);
        let factor: R = self.cfg.watchdog.factor(self.rx.weights_age_ms(now_ms));
        let (x, y) = (self.x, self.y);
        let [gx, gy] = self.cfg.goal_m;
        let f = sample(self.rx.grid(), &self.gauss, x, y);
        let c = self.ctl.command(x, y, gx, gy, &f, factor);
        let height = self.ctl.height_scale(f.height);
        let (mut vx, mut vy) = (c.vx, c.vy);
        let speed = norm_bound(vx, vy);
        let cap = self.cfg.speed_cap_mps;
        if speed > cap && speed > R::ZERO {
            let k = cap.div(speed);
            vx = vx.mul(k);
            vy = vy.mul(k);
        }
        let away = norm_bound(gx.sub(x), gy.sub(y)) > self.cfg.gains.capture_radius_m;
        // 1 mm/s: below it a command away from the goal is no motion (a local minimum).
        let crawl = R::from_f32(0.001);
        // NaN-safe: anything not comparable stops (a factor that is not > 0 is stale).
        let status = if latched {
            Status::StoppedLatched
        } else if factor.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
            Status::StoppedStale
        } else if height.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
            Status::StoppedNoPath
        } else if norm_bound(vx, vy).partial_cmp(&crawl).is_none() {
            // Not a number (float types only): no command to trust.
            Status::StoppedNoPath
        } else if norm_bound(vx, vy) <= crawl && away {
            Status::StoppedNoPath
        } else if factor < R::ONE || height < R::ONE {
            Status::Slowed
        } else {
            Status::Ok
        };
        if matches!(status, Status::StoppedStale | Status::StoppedNoPath | Status::StoppedLatched) {
            vx = R::ZERO;
            vy = R::ZERO;
        }
        self.x = x.add(vx.mul(self.dt_s));
        self.y = y.add(vy.mul(self.dt_s));
        let s = self.rx.stats;
        let refused = s.bad_crc.saturating_add(s.bad_header).saturating_add(s.short).saturating_add(s.stale);
        Velocity { step: self.step, seq: if self.rx.weights_age_ms(now_ms).is_some() { self.rx.grid().seq } else { 0 }, status, vx, vy, x, y, good: s.good, refused }
    }
}

/// The step's deadline, watched from the detection tick: the tick counts the ticks since the last
/// step ended and the step resets the count. Once the count reaches `limit` the deadline is missed
/// for good (latched: only a reset of the MCU clears it), and [`StepDeadline::tick`] says so, so
/// that the tick stops feeding the watchdog. Until the first step has ended the limit is
/// `first_limit` (the first step may wait for more: in QEMU its code is translated on first use;
/// a first step that never ends still trips it). Counted in ticks, not read from a timer, so it
/// holds however the timers are clocked. Atomics only: the tick and the step run at different
/// priorities.
pub struct StepDeadline {
    since: core::sync::atomic::AtomicU32,
    missed: core::sync::atomic::AtomicBool,
    started: core::sync::atomic::AtomicBool,
    limit: u32,
    first_limit: u32,
}

impl StepDeadline {
    /// A deadline of `limit` ticks between step ends, `first_limit` to the first one.
    pub const fn new(limit: u32, first_limit: u32) -> Self {
        StepDeadline {
            since: core::sync::atomic::AtomicU32::new(0),
            missed: core::sync::atomic::AtomicBool::new(false),
            started: core::sync::atomic::AtomicBool::new(false),
            limit,
            first_limit,
        }
    }

    /// One tick: `true` while every step has ended within `limit` ticks of the one before.
    pub fn tick(&self) -> bool {
        use core::sync::atomic::Ordering::Relaxed;
        let n = self.since.load(Relaxed).saturating_add(1);
        self.since.store(n, Relaxed);
        let limit = if self.started.load(Relaxed) { self.limit } else { self.first_limit };
        if n >= limit {
            self.missed.store(true, Relaxed);
        }
        !self.missed.load(Relaxed)
    }

    /// A step ended.
    pub fn step_done(&self) {
        self.since.store(0, core::sync::atomic::Ordering::Relaxed);
        self.started.store(true, core::sync::atomic::Ordering::Relaxed);
    }

    /// The deadline was missed (latched).
    pub fn missed(&self) -> bool {
        self.missed.load(core::sync::atomic::Ordering::Relaxed)
    }
}

/// `max(|a|, |b|) + min(|a|, |b|) / 2`: at least the length, at most 11.8 % above.
fn norm_bound<R: Real>(a: R, b: R) -> R {
    let (a, b) = (a.abs(), b.abs());
    if a > b {
        a.add(b.halve())
    } else {
        b.add(a.halve())
    }
}

/// Metres (per second) to whole micrometres (per second), saturating ([`Real::to_micro`]).
fn micro<R: Real>(v: R) -> i32 {
    v.to_micro()
}

/// The velocity frame of one step.
pub fn encode_velocity<R: Real>(v: &Velocity<R>) -> [u8; VEL_LEN] {
    let mut b = [0u8; VEL_LEN];
    let sat16 = |n: u32| u16::try_from(n).unwrap_or(u16::MAX);
    let fields: [(usize, &[u8]); 9] = [
        (0, &[VEL_SYNC0, VEL_SYNC1, VEL_VERSION, v.status as u8]),
        (4, &v.step.to_le_bytes()),
        (8, &v.seq.to_le_bytes()),
        (12, &micro(v.vx).to_le_bytes()),
        (16, &micro(v.vy).to_le_bytes()),
        (20, &micro(v.x).to_le_bytes()),
        (24, &micro(v.y).to_le_bytes()),
        (28, &sat16(v.good).to_le_bytes()),
        (30, &sat16(v.refused).to_le_bytes()),
    ];
    for (at, bytes) in fields {
        if let Some(dst) = b.get_mut(at..at.saturating_add(bytes.len())) {
            dst.copy_from_slice(bytes);
        }
    }
    let crc = CRC.checksum(b.get(2..32).unwrap_or(&[]));
    if let Some(dst) = b.get_mut(32..36) {
        dst.copy_from_slice(&crc.to_le_bytes());
    }
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
}

/// Decode one velocity frame (`None`: wrong sync, version, status or CRC, or too short).
pub fn decode_velocity(b: &[u8]) -> Option<VelocityFrame> {
    let b: &[u8; VEL_LEN] = b.get(..VEL_LEN)?.try_into().ok()?;
    let [s0, s1, ver, st, ..] = *b;
    if s0 != VEL_SYNC0 || s1 != VEL_SYNC1 || ver != VEL_VERSION {
        return None;
    }
    let u32_at = |k: usize| -> Option<u32> { Some(u32::from_le_bytes(b.get(k..k.checked_add(4)?)?.try_into().ok()?)) };
    let u16_at = |k: usize| -> Option<u16> { Some(u16::from_le_bytes(b.get(k..k.checked_add(2)?)?.try_into().ok()?)) };
    if CRC.checksum(b.get(2..32)?) != u32_at(32)? {
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::avoidance::control::Repulsion;
    use crate::avoidance::frame::{encode_frame, FrameHeader};

    fn cfg() -> LinkConfig<f32> {
        LinkConfig {
            gains: Gains {
                repulsion: Repulsion::Vortex { sign: 0 },
                k_att: 0.25,
                k_rep: 0.5,
                capture_radius_m: 0.03,
                latch_height_m: 0.02,
                slow_height_m: 0.05,
                stop_height_m: 0.15,
                bounded: false,
            },
            watchdog: Watchdog { slow_after_ms: 100, stop_after_ms: 330 },
            start_m: [0.2, 0.5],
            goal_m: [0.9, 0.5],
            speed_cap_mps: 0.25,
            period_ms: 10,
            max_age_ms: 100,
            byte_timeout_ms: 50,
            budget_bytes: 256,
        }
    }

    /// A 5 x 5 grid over 1.05 m with every weight `w` (m).
    fn frame(seq: u32, w: f64) -> heapless::Vec<u8, 256> {
        let h = FrameHeader { session: 1, nx: 5, ny: 5, seq, age_ms: 5, x0_q16: (0.105 * 65536.0) as i32, y0_q16: (0.105 * 65536.0) as i32, spacing_q16: (0.21 * 65536.0) as i32, sigma_q16: (0.105 * 65536.0) as i32 };
        let ws = [(w * 65536.0) as i32; 25];
        let mut out = [0u8; 256];
        let n = encode_frame(&h, &ws, &mut out).unwrap();
        heapless::Vec::from_slice(&out[..n]).unwrap()
    }

    fn feed(l: &mut Link<f32>, b: &[u8], now: u32) {
        assert_eq!(l.receiver().push(b, now), b.len());
    }

    #[test]
    fn every_status_is_reached_and_stops_are_zero() {
        let mut l = Link::new(cfg());
        // No weights: stale, zero, the tool does not move.
        let v = l.step(0);
        assert_eq!((v.status, v.vx, v.vy, v.seq), (Status::StoppedStale, 0.0, 0.0, 0));
        // A high field everywhere: no path, zero.
        feed(&mut l, &frame(1, 0.5), 5);
        let v = l.step(10);
        assert_eq!((v.status, v.vx, v.vy, v.seq), (Status::StoppedNoPath, 0.0, 0.0, 1));
        assert_eq!((v.x, v.y), (0.2, 0.5));
        // An empty field: ok, at the cruise speed towards the goal.
        feed(&mut l, &frame(2, 0.0), 15);
        let v = l.step(20);
        assert_eq!((v.status, v.seq), (Status::Ok, 2));
        assert!((v.vx - 0.25).abs() < 1e-4 && v.vy.abs() < 1e-6, "{v:?}");
        // The line goes quiet: slowed after 100 ms, stale at 330 ms, and zero then.
        let v = l.step(20 + 200);
        assert_eq!(v.status, Status::Slowed);
        assert!(v.vx > 0.0 && v.vx < 0.25);
        let v = l.step(20 + 330);
        assert_eq!((v.status, v.vx, v.vy), (Status::StoppedStale, 0.0, 0.0));
        // A corrupted frame is refused and counted; nothing changes.
        let mut bad = frame(3, 0.0);
        bad[40] ^= 1;
        feed(&mut l, &bad, 360);
        let v = l.step(370);
        assert_eq!((v.status, v.refused, v.good), (Status::StoppedStale, 1, 2));
    }

    #[test]
    fn a_latched_step_is_zero_and_holds_the_position_and_release_resumes() {
        let mut l = Link::new(cfg());
        // Fresh weights of an empty field, the goal 0.7 m away: unlatched this is `ok` at the cap.
        feed(&mut l, &frame(1, 0.0), 0);
        let v = l.step(10);
        assert_eq!(v.status, Status::Ok, "{v:?}");
        let held = l.step_with(20, false);
        // Latched: zero, `stopped: latched`, the position where it was, every step; frames still taken.
        let mut step = held.step;
        let mut at = None;
        for k in 0..20u32 {
            let now = 30 + 10 * k;
            if k % 3 == 0 {
                feed(&mut l, &frame(2 + k, 0.0), now - 5);
            }
            let v = l.step_with(now, true);
            step += 1;
            assert_eq!((v.status, v.vx, v.vy, v.step), (Status::StoppedLatched, 0.0, 0.0, step), "{v:?}");
            let p = *at.get_or_insert((v.x, v.y));
            assert_eq!((v.x, v.y), p, "the position moved while latched");
            assert!(v.x > held.x, "{v:?}");
        }
        // Before every other status: with no weights at all, and with a field above the stop height.
        let mut fresh = Link::new(cfg());
        assert_eq!(fresh.step_with(0, true).status, Status::StoppedLatched);
        feed(&mut fresh, &frame(1, 0.5), 5);
        assert_eq!(fresh.step_with(10, true).status, Status::StoppedLatched);
        // Released: the newest frame (seq 20, taken while latched at 205 ms) is in use and the step
        // resumes from the held position.
        let v = l.step_with(240, false);
        assert_eq!((v.status, v.seq), (Status::Ok, 20), "{v:?}");
        assert_eq!(Some((v.x, v.y)), at);
        assert!((v.vx - 0.25).abs() < 1e-4, "{v:?}");
        let w = l.step(250);
        assert!(w.x > v.x, "the position does not move after the release: {v:?} {w:?}");
        // The frame carries it.
        let d = decode_velocity(&encode_velocity(&l.step_with(260, true))).unwrap();
        assert_eq!((d.status, d.vx_umps, d.vy_umps), (Status::StoppedLatched, 0, 0));
        assert_eq!(Status::from_code(4), Some(Status::StoppedLatched));
        assert_eq!(Status::StoppedLatched.name(), "stopped: latched");
    }

    #[test]
    fn slowed_by_the_field_and_no_path_in_a_local_minimum() {
        let mut c = cfg();
        // Attraction only (no vortex): a field between slow and stop slows.
        c.gains.k_rep = 0.0;
        let mut l = Link::new(c);
        feed(&mut l, &frame(1, 0.06), 0);
        let v = l.step(10);
        assert_eq!(v.status, Status::Slowed, "{v:?}");
        // The goal at the start: no command, but not away from the goal: ok, not no path.
        let mut c = cfg();
        c.goal_m = c.start_m;
        let mut l = Link::new(c);
        feed(&mut l, &frame(1, 0.0), 0);
        assert_eq!(l.step(10).status, Status::Ok);
    }

    #[test]
    fn a_missed_step_deadline_stays_missed() {
        // No first step within 1000 ticks: missed.
        let d = StepDeadline::new(15, 1000);
        for _ in 0..999 {
            assert!(d.tick());
        }
        assert!(!d.tick());
        let d = StepDeadline::new(15, 1000);
        // The first step late by the tick limit but within the first one, then steps every 10 ticks: always fed.
        for _ in 0..500 {
            assert!(d.tick());
        }
        d.step_done();
        for _ in 0..100 {
            for _ in 0..10 {
                assert!(d.tick());
            }
            d.step_done();
        }
        // 14 ticks without a step still fed, the 15th not, and never again, even after steps.
        for _ in 0..14 {
            assert!(d.tick());
        }
        assert!(!d.tick());
        d.step_done();
        assert!(!d.tick() && d.missed());
    }

    #[test]
    fn the_velocity_frame_round_trips_and_refuses_damage() {
        let v = Velocity { step: 7, seq: 3, status: Status::Slowed, vx: 0.125f32, vy: -0.25, x: 0.5, y: 1.0, good: 70_000, refused: 2 };
        let b = encode_velocity(&v);
        let d = decode_velocity(&b).unwrap();
        assert_eq!(d, VelocityFrame { status: Status::Slowed, step: 7, seq: 3, vx_umps: 125_000, vy_umps: -250_000, x_um: 500_000, y_um: 1_000_000, good: u16::MAX, refused: 2 });
        for k in 0..VEL_LEN {
            let mut c = b;
            c[k] ^= 0x10;
            assert!(decode_velocity(&c).is_none(), "byte {k} flipped was accepted");
        }
        // NaN and huge values saturate; a NaN command never decodes as motion.
        let w = Velocity { vx: f32::NAN, vy: 1e30, ..v };
        let d = decode_velocity(&encode_velocity(&w)).unwrap();
        assert_eq!((d.vx_umps, d.vy_umps), (0, i32::MAX));
    }
}
