//! `flinch avoid --mcu`: the board's avoidance step itself ([`Link`], the type the board binary
//! runs), in the board's number type, configured from the scene by [`link_config`] (the one function
//! that also makes the board's shipped configuration, `flinch_firmware::avoidance::cell`, as a test
//! checks), fed protocol-v3 weights frames over a simulated serial line and answered by velocity
//! frames whose integers are the command the robot receives.
//!
//! Each frame carries what the monitor needs: the separations per sector from the tool's surface at
//! capture (persons and fixtures), the tool's position and the nearest point at capture, and the echo
//! of the MCU's clock: the `t_ms` of the newest velocity frame the host had read before the image was
//! captured. Here the velocity frames reach the host the instant they are made, so that is the
//! newest step at or before the capture (the first frame, captured before any step: the step's
//! clock at boot, 0). The board's age of the separations is therefore up to one control period more
//! than the reference engine's (which takes the capture time itself): conservative.
//!
//! The robot's measured position goes to the step ([`Link::step_at`]): in the simulation the robot's
//! true motion (the loop's), as a robot interface would report it.

use std::collections::VecDeque;

use flinch_firmware::avoidance::frame::{mm_of_m, FrameHeader};
use flinch_firmware::avoidance::link::{decode_velocity, encode_velocity, LinkConfig, Status};
use flinch_firmware::avoidance::{BoardReal, Link, Real, RxStats, Sensed, Steer, Watchdog};
use flinch_hal_sim::serial::SimSerial;

use crate::engine::{gains, ssm, steer_barrier_m, Cmd, StepEngine, STEER_BAND_M};
use crate::rbf::Field;
use crate::scene::Avoid;

/// The fewest milliseconds the board's receiver lets an image be old ([`max_age_ms`]).
pub const MIN_MAX_AGE_MS: u16 = 200;

/// The oldest image the board's receiver accepts for a scene, ms: its capture-to-controller delay
/// plus two frame periods and two control steps, at least [`MIN_MAX_AGE_MS`] (older frames are
/// refused as stale: the robot stops). The monitor does not rely on it: it bounds the age from the
/// clock echo.
pub fn max_age_ms(scene: &Avoid) -> Result<u16, String> {
    let s = crate::link::frame_delay_s(scene)? + 2.0 * scene.frame_period_s + 2.0 * scene.dt_s;
    Ok(((s * 1e3).ceil().min(f64::from(u16::MAX)) as u16).max(MIN_MAX_AGE_MS))
}
/// The longest gap between two bytes of one frame, ms.
pub const BYTE_TIMEOUT_MS: u32 = 20;
/// The fewest bytes parsed per control step: 256 (115,200 baud brings 115 bytes in 10 ms).
pub const MIN_BUDGET_BYTES: usize = 256;

/// Bytes the board parses per control step for a scene: a quarter more than its frames bring per
/// step on average (`frame length x dt / frame period`), in whole 32-byte blocks, at least
/// [`MIN_BUDGET_BYTES`]; less and a backlog builds until the receiver forgets the weights (the
/// robot stops). The line must carry the same: 15 x 15 frames (988 bytes) at 30 Hz are 296,400
/// bit/s (8N1), 30 x 30 ones (3,688 bytes) at 30 Hz 1.1 Mbit/s.
pub fn budget_bytes(scene: &Avoid) -> usize {
    let n = scene.fit.grid;
    let len = flinch_firmware::avoidance::frame_len(n, n).unwrap_or(flinch_firmware::avoidance::frame::MAX_FRAME) as f64;
    let per_step = len * scene.dt_s / scene.frame_period_s * 1.25;
    ((per_step / 32.0).ceil() as usize * 32).max(MIN_BUDGET_BYTES)
}

/// The board's avoidance settings for a scene, in `f64` (the board converts them to its number
/// type): the gains, the weights watchdog (from the clock echo: the capture-to-controller delay, then slowing after 3 frame periods and stopping after 10), the
/// start and goal, the cap, the control period (the scene's `dt_s`, whole milliseconds), the
/// receiver's limits ([`budget_bytes`]), and the monitor with its PFL speeds and its steering barrier as the reference
/// engine builds them. A scene whose `dt_s` is not a whole number of milliseconds is refused.
pub fn link_config(scene: &Avoid) -> Result<LinkConfig<f64>, String> {
    let period_ms = (scene.dt_s * 1e3).round();
    if !(1.0..=60_000.0).contains(&period_ms) || (scene.dt_s * 1e3 - period_ms).abs() > 1e-9 {
        return Err(format!("avoid.dt_s = {}: the board's step runs on whole milliseconds (1 ms to 60 s)", scene.dt_s));
    }
    let params = ssm::<f64>(scene);
    let delay = crate::link::frame_delay_s(scene)?;
    let steer = match &params {
        None => None,
        Some(p) => {
            let (w, h) = scene.extent_m();
            // As the reference engine's monitor: with PFL the barrier keeps only the clearance.
            let barrier = if p.pfl.is_some() { scene.clearance_m } else { steer_barrier_m(scene)? };
            Some(Steer { barrier_m: barrier, band_m: STEER_BAND_M, view_m: [0.0, 0.0, w, h], edge_margin_m: scene.robot.wrist_radius_m })
        }
    };
    Ok(LinkConfig {
        gains: gains::<f64>(scene)?,
        // The watchdog counts from the clock echo (before capture): the delay to the controller,
        // then 3 frame periods to slowing and 10 to a stop.
        watchdog: Watchdog { slow_after_ms: ((delay + 3.0 * scene.frame_period_s) * 1e3).ceil() as u32, stop_after_ms: ((delay + 10.0 * scene.frame_period_s) * 1e3).ceil() as u32 },
        start_m: scene.start_m,
        goal_m: scene.goal_m,
        speed_cap_mps: scene.speed_mps,
        period_ms: period_ms as u32,
        max_age_ms: max_age_ms(scene)?,
        byte_timeout_ms: BYTE_TIMEOUT_MS,
        budget_bytes: budget_bytes(scene),
        // Not the reference engine's steering round the fixtures: on the board it costs 205
        // instructions a step, 5,192 at 15 x 15 and 10 Hz against the 5,000 budget (avoid-cost's
        // avoid_board line). The monitor's fixture bound is the same on both; only the steering
        // differs (open: make room in the step, then set `fixture_barrier_m(scene)` here).
        fixture_barrier_m: None,
        ssm: params,
        steer,
    })
}

/// The `--mcu` engine for a scene.
pub fn mcu_engine(scene: &Avoid) -> Result<BoardEngine, String> {
    BoardEngine::new(scene)
}

/// The board's [`Link`] behind a simulated serial line.
pub struct BoardEngine {
    link: Box<Link<BoardReal>>,
    /// The host's end of the line and the MCU's.
    line: (SimSerial, SimSerial),
    /// The clocks of the steps so far (the newest last; a few frame periods' worth).
    steps_ms: VecDeque<u32>,
    /// The next frame's monitor header (set by [`StepEngine::capture`]).
    next: FrameHeader,
    /// The boot byte of the velocity frames (echoed with the clock).
    boot: u8,
}

impl BoardEngine {
    /// For a scene.
    pub fn new(scene: &Avoid) -> Result<Self, String> {
        let cfg = link_config(scene)?.to_real::<BoardReal>();
        Ok(BoardEngine { link: Box::new(Link::new(cfg)), line: SimSerial::pair(), steps_ms: VecDeque::new(), next: FrameHeader::default(), boot: 0 })
    }
}

fn q16(v: f64) -> i32 {
    (v * 65536.0).round().clamp(i32::MIN as f64, i32::MAX as f64) as i32
}

impl StepEngine for BoardEngine {
    fn capture(&mut self, sensed: &Sensed<f64>, capture_s: f64) {
        let capture_ms = capture_s * 1e3;
        // The newest step at or before the capture (its velocity frame was read before it).
        let echo = self.steps_ms.iter().rev().find(|&&t| f64::from(t) <= capture_ms + 1e-9).copied().unwrap_or(0);
        self.next = FrameHeader {
            echo_ms: echo,
            echo_boot: self.boot,
            // The tool at capture rounded to the nearest 1/65536 m (15 um): inside the margin's
            // robot uncertainty.
            tool_q16: [q16(sensed.tool_x_m), q16(sensed.tool_y_m)],
            nearest_q16: [q16(sensed.nearest_x_m), q16(sensed.nearest_y_m)],
            person_mm: sensed.sectors_m.map(mm_of_m),
            fixture_mm: sensed.fixture_sectors_m.map(mm_of_m),
            ..FrameHeader::default()
        };
    }
    fn new_field(&mut self, field: &Field, seq: u32, _now_ms: u32) -> Result<(), String> {
        // Sent now; the firmware reads it from the line on its next steps (at most the budget a step).
        let frame = field.to_frame_with(seq, 0, &self.next)?;
        embedded_io::Write::write_all(&mut self.line.0, &frame).map_err(|e| format!("serial line: {e:?}"))?;
        Ok(())
    }
    fn command(&mut self, p: [f64; 2], _goal: [f64; 2], now_ms: u32, _sensed: Option<&Sensed<f64>>) -> Cmd {
        // As the board: the bytes that arrived go into the receiver's ring, then one step.
        let _ = self.link.receiver().poll(&mut self.line.1, now_ms);
        let v = self.link.step_at(now_ms, false, Some([BoardReal::from_f64(p[0]), BoardReal::from_f64(p[1])]));
        self.steps_ms.push_back(now_ms);
        if self.steps_ms.len() > 256 {
            self.steps_ms.pop_front();
        }
        let bytes = encode_velocity(&v);
        // The robot receives the velocity frame: its integers are the command.
        match decode_velocity(&bytes) {
            Some(f) => {
                self.boot = f.boot;
                let stopped = !matches!(f.status, Status::Ok | Status::Slowed);
                Cmd {
                    v: if stopped { [0.0, 0.0] } else { [f64::from(f.vx_umps) * 1e-6, f64::from(f.vy_umps) * 1e-6] },
                    limit_mps: f64::from(f.limit_mmps) * 1e-3,
                    // The loop's names: a stop before the monitor is named by its cause.
                    state: match f.status {
                        Status::StoppedStale => "no_data",
                        Status::StoppedProtective => "protective_stop",
                        Status::StoppedNoPath => "no_path",
                        Status::StoppedLatched => "latched",
                        Status::Ok | Status::Slowed => f.monitor.name(),
                    },
                }
            }
            // Never: the frame was just encoded. A robot that cannot read its frame stops.
            None => Cmd { v: [0.0, 0.0], limit_mps: 0.0, state: "no_data" },
        }
    }
    fn rx_stats(&self) -> Option<RxStats> {
        Some(self.link.rx_stats())
    }
}
