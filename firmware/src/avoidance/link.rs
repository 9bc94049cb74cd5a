//! The avoidance step as the board runs it: weights frames in (through a [`Receiver`]), one step per
//! control period, a velocity frame ([`super::velocity`]) out. The same type is the host's
//! `flinch avoid --mcu` engine, so the board and the host run one monitor from one configuration
//! ([`super::cell`]).
//!
//! Kept in the library (not in the board binary) so that the host tests the whole step, the status
//! and the velocity frame; the board binary (`src/bin/support/board_avoid.rs`) only moves bytes
//! between the USART and this type and runs [`Link::step_with`] on a timer, with the detection
//! firmware's latch.
//!
//! Each step: the receiver is ticked and serviced (at most `budget_bytes` parsed), the field and its
//! gradient are sampled at the tool, the command of eq 74-78 is formed with the weights-age watchdog
//! factor, then (with [`LinkConfig::ssm`]) steered round the sensed obstacles and limited by the
//! speed and separation monitor with its power and force limits ([`super::safe`], ISO/TS 15066
//! 5.5.4 and 5.5.5) from the separations the frame carries, their age bounded from above by the
//! frame's echo of this MCU's clock; without a monitor (host comparisons only) capped at
//! `speed_cap_mps`. Classified:
//!
//! | status | when | command |
//! |---|---|---|
//! | `ok` | fresh weights, the field below `slow_height_m`, the monitor passed it | as computed |
//! | `slowed` | the weights older than `slow_after_ms`, the field above `slow_height_m`, or the monitor scaled it (SSM or PFL) | scaled down |
//! | `stopped: stale` | no good frame yet, the weights at least `stop_after_ms` old, or no separation the monitor may use (the frame's clock echo is of another boot, or ahead of this clock) | zero |
//! | `stopped: no path` | the field at the tool at or above `stop_height_m`, or no command away from the goal (a local minimum) | zero |
//! | `stopped: protective` | the monitor's protective stop | zero |
//! | `stopped: latched` | the detection firmware holds the robot stopped ([`Link::step_with`] with `latched`: on the board every state but armed, i.e. the collision latch after a trip, a fault, the start latch after a reset, and the self-test after a reset press); before every other status | zero |
//!
//! While latched the receiver still takes and applies frames (so the weights are current when the
//! latch is released) and the step number counts on, but the command is zero and the dead-reckoned
//! position does not move: the robot is held, whatever the field says.
//!
//! **Position.** The board dead-reckons the tool from its commands (eq 79, `p += v dt`: the robot is
//! assumed to follow the command), from `start_m`; the velocity frame reports it, so the host can
//! check it against the robot's. Where the robot's measured position is available (the host's
//! simulation; on a cell, a robot interface: not yet on the board) [`Link::step_at`] takes it
//! instead. The monitor's term for the tool's motion since capture does not use absolute positions
//! (a dead-reckoned position need not agree with the frame's tool at capture: an offset of a few
//! millimetres would hide motion): it is the tool's own path length since the step that started at
//! or before the echoed clock ([`Link::moved_since_m`], a ring of [`PATH_STEPS`] steps).
//!
//! **Age.** The age of the frame in use, for the monitor's separations and for the weights
//! watchdog alike, is `now - echo_ms`: the frame echoes a velocity frame's `t_ms` that the host read
//! before the image was captured, so this bounds the age from above, whatever the host and the line
//! delayed; never less than the receiver's own arrival-based lower bound (the frame's first byte
//! less its `age_ms`), which also refuses frames too old on arrival and forgets the weights on a
//! backlog. An echo of another boot (`boot`, [`Link::set_boot`]) or ahead of this clock makes the
//! frame unusable: `stopped: stale`. **Open:** the boot byte is the backup SRAM's boot count, which
//! a power-on (no VBAT) resets to 0, so two power-ons share it; a frame of the earlier one is still
//! refused unless its clock echo is behind the new clock and its `seq` newer than every frame since
//! (the receiver's order check), and a per-boot random nonce (the RNG, which needs the PLL's 48 MHz)
//! is not done.
//!
//! **Fixtures.** The frame's fixture separations go to the monitor as fixtures: the robot's own stop
//! and clearance from them, no human approach speed (`safe`'s fixture bound).

use super::control::{Controller, Gains, Watchdog};
use super::field::sample;
use super::frame::{FrameHeader, FRAME_SECTORS, NOTHING_MM};
use super::gauss::GaussLut;
use super::num::Real;
use super::receiver::Receiver;
use super::safe::{SafeController, SafeState, Sensed, SsmParams, Steer, SECTORS};
pub use super::velocity::{decode_velocity, encode_velocity, Monitor, Status, Velocity, VelocityFrame, VEL_LEN, VEL_SYNC0, VEL_SYNC1, VEL_VERSION};

const _: () = assert!(FRAME_SECTORS == SECTORS);

/// The installation's avoidance settings.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// The speed and separation monitor with its PFL speeds (`None`: the thesis's law alone, for
    /// host comparisons; the board ships one).
    pub ssm: Option<SsmParams<R>>,
    /// The steering barrier before the monitor (`None`: none).
    pub steer: Option<Steer<R>>,
    /// The separation the steering holds from fixtures, m (`SafeController::with_fixture_barrier`;
    /// `None`: none).
    pub fixture_barrier_m: Option<R>,
}

impl LinkConfig<f64> {
    /// The same settings in the number type `R` (each value through [`Real::from_f64`]).
    pub fn to_real<R: Real>(&self) -> LinkConfig<R> {
        let q = R::from_f64;
        let g = &self.gains;
        LinkConfig {
            gains: Gains {
                repulsion: g.repulsion,
                k_att: q(g.k_att),
                k_rep: q(g.k_rep),
                capture_radius_m: q(g.capture_radius_m),
                latch_height_m: q(g.latch_height_m),
                slow_height_m: q(g.slow_height_m),
                stop_height_m: q(g.stop_height_m),
                bounded: g.bounded,
            },
            watchdog: self.watchdog,
            start_m: self.start_m.map(q),
            goal_m: self.goal_m.map(q),
            speed_cap_mps: q(self.speed_cap_mps),
            period_ms: self.period_ms,
            max_age_ms: self.max_age_ms,
            byte_timeout_ms: self.byte_timeout_ms,
            budget_bytes: self.budget_bytes,
            ssm: self.ssm.map(|p| SsmParams {
                human_speed_mps: q(p.human_speed_mps),
                reaction_time_s: q(p.reaction_time_s),
                stopping_time_s: q(p.stopping_time_s),
                margin_m: q(p.margin_m),
                speed_cap_mps: q(p.speed_cap_mps),
                whole_body_only: p.whole_body_only,
                pfl: p.pfl.map(|f| super::safe::Pfl { axis: f.axis.map(q), along_mps: q(f.along_mps), across_mps: q(f.across_mps) }),
            }),
            steer: self.steer.map(|s| Steer { barrier_m: q(s.barrier_m), band_m: q(s.band_m), view_m: s.view_m.map(q), edge_margin_m: q(s.edge_margin_m) }),
            fixture_barrier_m: self.fixture_barrier_m.map(q),
        }
    }
}

/// The board's control period, ms: one avoidance step every ten 1 ms ticks.
pub const BOARD_PERIOD_MS: u32 = 10;

/// The receiver and the step.
pub struct Link<R> {
    rx: Receiver<R>,
    ctl: Controller<R>,
    safe: Option<SafeController<R>>,
    gauss: GaussLut<R>,
    cfg: LinkConfig<R>,
    dt_s: R,
    /// `1 / 1000`: mm to m, ms to s.
    milli: R,
    x: R,
    y: R,
    step: u32,
    boot: u8,
    /// The tool's path length since start (a bound: each step's move by `max + min / 2`), m, and
    /// its value at the start of each of the last [`PATH_STEPS`] steps (a ring, the newest at
    /// `path_head`).
    path_m: R,
    path_ring: [R; PATH_STEPS],
    path_head: usize,
    /// The position at the previous step's start (`None` before the first).
    last_pos: Option<[R; 2]>,
}

/// Steps of path length kept: 64 steps (640 ms at 10 ms), more than any usable frame's age (the
/// watchdog stops at its `stop_after_ms`); an older echo bounds the motion by the cap instead.
pub const PATH_STEPS: usize = 64;

impl<R: Real> Link<R> {
    /// A link with no weights (every step `stopped: stale` until the first good frame).
    pub fn new(cfg: LinkConfig<R>) -> Self {
        let mut rx = Receiver::new(cfg.max_age_ms, cfg.byte_timeout_ms);
        rx.budget_bytes = cfg.budget_bytes;
        // A restarted host's new session is taken once the weights watchdog has stopped the robot.
        rx.new_session_after_ms = cfg.watchdog.stop_after_ms;
        let milli = R::ONE.div(R::from_int(1000));
        let dt_s = R::from_int(cfg.period_ms.min(60_000) as i32).mul(milli);
        let safe = cfg.ssm.map(|p| {
            let c = SafeController::new(p);
            let c = match cfg.fixture_barrier_m {
                Some(b) => c.with_fixture_barrier(b),
                None => c,
            };
            match cfg.steer {
                Some(s) => c.with_steer(s),
                None => c,
            }
        });
        Link { rx, ctl: Controller::new(cfg.gains), safe, gauss: GaussLut::new(), cfg, dt_s, milli, x: cfg.start_m[0], y: cfg.start_m[1], step: 0, boot: 0, path_m: R::ZERO, path_ring: [R::ZERO; PATH_STEPS], path_head: 0, last_pos: None }
    }

    /// This boot's byte (the board: from its reset counter), sent in every velocity frame; a weights
    /// frame whose echo carries another is not used by the monitor.
    pub fn set_boot(&mut self, boot: u8) {
        self.boot = boot;
    }

    /// The receiver (to push bytes into, and for its counters).
    pub fn receiver(&mut self) -> &mut Receiver<R> {
        &mut self.rx
    }

    /// The receiver's counters.
    pub fn rx_stats(&self) -> super::receiver::RxStats {
        self.rx.stats
    }

    /// The settings.
    pub fn config(&self) -> &LinkConfig<R> {
        &self.cfg
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
        self.step_at(now_ms, latched, None)
    }

    /// The age of the frame in use from its echo of this clock, ms: `None` for an echo of another
    /// boot or one ahead of `now_ms` (or older than the receiver's expiry).
    fn echo_age_ms(&self, h: &FrameHeader, now_ms: u32) -> Option<u32> {
        let age_ms = now_ms.wrapping_sub(h.echo_ms);
        (h.echo_boot == self.boot && age_ms <= super::receiver::EXPIRE_MS).then_some(age_ms)
    }

    /// How far the tool can have moved since the frame's capture, m: its path since the step that
    /// started at or before the echoed clock (`ceil(age / period)` steps back; the capture came after
    /// the echo, on that path), a bound that needs no absolute position (the board dead-reckons,
    /// and its dead reckoning need not agree with the frame's tool position); beyond the ring, the
    /// cap times the age.
    fn moved_since_m(&self, age_ms: u32) -> R {
        let period = self.cfg.period_ms.max(1);
        // `period` is at least 1: `div_ceil` cannot divide by zero.
        let back = age_ms.div_ceil(period) as usize;
        if back < PATH_STEPS {
            let then = *self.path_ring.get(self.path_head.wrapping_add(PATH_STEPS).wrapping_sub(back) % PATH_STEPS).unwrap_or(&R::ZERO);
            self.path_m.sub(then)
        } else {
            self.cfg.speed_cap_mps.mul(R::from_int(i32::try_from(age_ms).unwrap_or(i32::MAX))).mul(self.milli)
        }
    }

    /// The sensed separations of the frame in use as the monitor takes them, `age_ms` old, for the
    /// tool at `(x, y)`: persons and fixtures apart (the monitor keeps the robot's own stop from a
    /// fixture, with no human approach speed). The tool's motion since capture is [`Link::moved_since_m`], passed to the monitor as the tool
    /// at capture that far from `(x, y)` along x (the monitor's `|p - p_capture|` is then exactly
    /// it).
    fn sensed(&self, h: &FrameHeader, age_ms: u32, x: R, y: R) -> Sensed<R> {
        let m = |mm: u16| -> R {
            if mm == NOTHING_MM {
                // Far: nothing sensed in the sector (the host's NOTHING_SENSED_M is 10 m).
                R::from_int(10)
            } else {
                // mm to Q16.16 m, rounded down: never more than the frame says.
                R::from_q16(i32::from(mm).saturating_mul(8192) / 125)
            }
        };
        let sectors_m = h.person_mm.map(m);
        let fixture_sectors_m = h.fixture_mm.map(m);
        let mut sep = R::from_int(10);
        for &s in sectors_m.iter() {
            if s < sep {
                sep = s;
            }
        }
        Sensed {
            separation_m: sep,
            tool_x_m: x.sub(self.moved_since_m(age_ms)),
            tool_y_m: y,
            age_s: R::from_int(i32::try_from(age_ms).unwrap_or(i32::MAX)).mul(self.milli),
            nearest_x_m: R::from_q16(h.nearest_q16[0]),
            nearest_y_m: R::from_q16(h.nearest_q16[1]),
            sectors_m,
            fixture_sectors_m,
        }
    }

    /// [`Link::step_with`] with the tool at `pos` (the robot's measured position, m) when given, else
    /// at the dead-reckoned one; the dead reckoning then goes on from `pos`.
    pub fn step_at(&mut self, now_ms: u32, latched: bool, pos: Option<[R; 2]>) -> Velocity<R> {
        self.rx.tick(now_ms);
        self.rx.service(now_ms);
        self.step = self.step.wrapping_add(1);
        if let Some([x, y]) = pos {
            self.x = x;
            self.y = y;
        }
        // The path since start, at this step's start (the move since the last step's start).
        if let Some([lx, ly]) = self.last_pos {
            self.path_m = self.path_m.add(norm_bound(self.x.sub(lx), self.y.sub(ly)));
        }
        self.last_pos = Some([self.x, self.y]);
        self.path_head = self.path_head.wrapping_add(1) % PATH_STEPS;
        if let Some(slot) = self.path_ring.get_mut(self.path_head) {
            *slot = self.path_m;
        }
        // The weights' age from the frame's clock echo (an upper bound); none without weights, or
        // with an echo of another boot or ahead of this clock: stale.
        let header = self.rx.header_in_use().copied();
        // Never below the receiver's own lower bound (its first byte's arrival less its `age_ms`):
        // a host whose echo is wrong cannot make a frame younger than it arrived.
        let age_ms = header.and_then(|h| self.echo_age_ms(&h, now_ms)).map(|a| match self.rx.weights_age_ms(now_ms) {
            Some(lower) if lower > a => lower,
            _ => a,
        });
        let factor: R = self.cfg.watchdog.factor(age_ms);
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
        let mut status = if latched {
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
        let moving = matches!(status, Status::Ok | Status::Slowed);
        let (mut monitor, mut limit) = (if self.safe.is_some() { Monitor::NotRun } else { Monitor::Off }, if moving { cap } else { R::ZERO });
        if moving && self.safe.is_some() {
            let sensed = match (header, age_ms) {
                (Some(h), Some(a)) => Some(self.sensed(&h, a, x, y)),
                _ => None,
            };
            if let Some(safe) = self.safe.as_mut() {
                let (sx, sy) = safe.steer(c.vx, c.vy, x, y, sensed.as_ref());
                let out = safe.limit(sx, sy, x, y, sensed.as_ref());
                (vx, vy, limit) = (out.vx, out.vy, out.limit_mps);
                monitor = match out.state {
                    SafeState::Run => Monitor::Run,
                    SafeState::Slow => Monitor::Slow,
                    SafeState::ProtectiveStop => Monitor::ProtectiveStop,
                    SafeState::NoData => Monitor::NoData,
                    SafeState::Pfl => Monitor::Pfl,
                };
                status = match out.state {
                    SafeState::ProtectiveStop => Status::StoppedProtective,
                    SafeState::NoData => Status::StoppedStale,
                    SafeState::Slow | SafeState::Pfl => Status::Slowed,
                    SafeState::Run => status,
                };
            }
        }
        if !matches!(status, Status::Ok | Status::Slowed) {
            vx = R::ZERO;
            vy = R::ZERO;
            limit = R::ZERO;
        }
        self.x = x.add(vx.mul(self.dt_s));
        self.y = y.add(vy.mul(self.dt_s));
        let s = self.rx.stats;
        let refused = s.bad_crc.saturating_add(s.bad_header).saturating_add(s.short).saturating_add(s.stale);
        let seq = if header.is_some() { self.rx.grid().seq } else { 0 };
        Velocity { step: self.step, seq, status, vx, vy, x, y, good: s.good, refused, t_ms: now_ms, boot: self.boot, monitor, limit_mps: limit }
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
            ssm: None,
            steer: None,
            fixture_barrier_m: None,
        }
    }

    /// A 5 x 5 grid over 1.05 m with every weight `w` (m).
    fn frame(seq: u32, w: f64, echo_ms: u32) -> heapless::Vec<u8, 256> {
        let h = FrameHeader { session: 1, nx: 5, ny: 5, seq, age_ms: 5, x0_q16: (0.105 * 65536.0) as i32, y0_q16: (0.105 * 65536.0) as i32, spacing_q16: (0.21 * 65536.0) as i32, sigma_q16: (0.105 * 65536.0) as i32, echo_ms, ..FrameHeader::default() };
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
        feed(&mut l, &frame(1, 0.5, 5), 5);
        let v = l.step(10);
        assert_eq!((v.status, v.vx, v.vy, v.seq), (Status::StoppedNoPath, 0.0, 0.0, 1));
        assert_eq!((v.x, v.y), (0.2, 0.5));
        // An empty field: ok, at the cruise speed towards the goal.
        feed(&mut l, &frame(2, 0.0, 15), 15);
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
        let mut bad = frame(3, 0.0, 360);
        bad[40] ^= 1;
        feed(&mut l, &bad, 360);
        let v = l.step(370);
        assert_eq!((v.status, v.refused, v.good), (Status::StoppedStale, 1, 2));
    }

    #[test]
    fn a_latched_step_is_zero_and_holds_the_position_and_release_resumes() {
        let mut l = Link::new(cfg());
        // Fresh weights of an empty field, the goal 0.7 m away: unlatched this is `ok` at the cap.
        feed(&mut l, &frame(1, 0.0, 0), 0);
        let v = l.step(10);
        assert_eq!(v.status, Status::Ok, "{v:?}");
        let held = l.step_with(20, false);
        // Latched: zero, `stopped: latched`, the position where it was, every step; frames still taken.
        let mut step = held.step;
        let mut at = None;
        for k in 0..20u32 {
            let now = 30 + 10 * k;
            if k % 3 == 0 {
                feed(&mut l, &frame(2 + k, 0.0, now - 5), now - 5);
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
        feed(&mut fresh, &frame(1, 0.5, 5), 5);
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
        feed(&mut l, &frame(1, 0.06, 0), 0);
        let v = l.step(10);
        assert_eq!(v.status, Status::Slowed, "{v:?}");
        // The goal at the start: no command, but not away from the goal: ok, not no path.
        let mut c = cfg();
        c.goal_m = c.start_m;
        let mut l = Link::new(c);
        feed(&mut l, &frame(1, 0.0, 0), 0);
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
}

#[cfg(test)]
mod monitor_tests;
