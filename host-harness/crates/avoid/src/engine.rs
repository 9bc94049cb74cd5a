//! The command sources of the loop ([`StepEngine`]): the `f64` reference ([`RefEngine`]) and the
//! firmware as the board runs it ([`FwEngine`]: frames over a simulated serial line into the
//! firmware's [`Receiver`], the board's number type, the lookup-table Gaussian, the weights
//! watchdog), both behind the firmware's speed and separation monitor with the steering barrier.

use flinch_firmware::avoidance::{self as fw, Controller, Gains, Pfl, Real, Receiver, RxStats, SafeController, SafeState, Sensed, SsmParams, Steer, Watchdog};
use flinch_firmware::avoidance::{num::I16F16, BoardReal};
use flinch_hal_sim::serial::SimSerial;

use crate::link::frame_delay_s;
use crate::rbf::Field;
use crate::scene::Avoid;

/// Which implementation computes the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// `f64`, full sum.
    Reference,
    /// The firmware step in the board's number type ([`BoardReal`]) behind the serial frame protocol.
    Mcu,
}

/// The name of the board's number type ([`BoardReal`], which the `--mcu` engine runs): `"f32"` (the
/// M4F default), or `"I16F16"` when the firmware is built with the feature `avoid-fixed`
/// (`cargo build -p flinch-harness --features avoid-fixed` forwards it).
pub fn board_real_name() -> &'static str {
    use core::any::TypeId;
    if TypeId::of::<BoardReal>() == TypeId::of::<f32>() {
        "f32"
    } else if TypeId::of::<BoardReal>() == TypeId::of::<I16F16>() {
        "I16F16"
    } else {
        "unknown"
    }
}

/// A command source for [`simulate_with`](crate::path::simulate_with): gets every new field, answers every control step.
pub trait StepEngine {
    /// The monitor's part of the next frame: the separations sensed at capture (`sensed.age_s` is
    /// not used) and the capture time, s. Called before [`StepEngine::new_field`] for the same frame;
    /// the engines that get the separations with every command ignore it.
    fn capture(&mut self, _sensed: &Sensed<f64>, _capture_s: f64) {}
    /// A new fit is available (frame `seq` at `now_ms`).
    fn new_field(&mut self, field: &Field, seq: u32, now_ms: u32) -> Result<(), String>;
    /// Velocity command at `p`, after the speed and separation monitor when `sensed` is given (the
    /// last frame's separation, tool position and age): what the drive receives.
    fn command(&mut self, p: [f64; 2], goal: [f64; 2], now_ms: u32, sensed: Option<&Sensed<f64>>) -> Cmd;
    /// Receiver counters, if there is a receiver.
    fn rx_stats(&self) -> Option<RxStats> {
        None
    }
}

/// One command as the drive receives it.
#[derive(Clone, Copy, Debug)]
pub struct Cmd {
    /// Velocity, m/s.
    pub v: [f64; 2],
    /// Speed limit that applied, m/s.
    pub limit_mps: f64,
    /// `run`, `slow`, `protective_stop`, `no_data` (the monitor) or `field` (monitor off).
    pub state: &'static str,
}

fn state_name(s: SafeState) -> &'static str {
    match s {
        SafeState::Run => "run",
        SafeState::Slow => "slow",
        SafeState::ProtectiveStop => "protective_stop",
        SafeState::NoData => "no_data",
        SafeState::Pfl => "pfl",
    }
}

/// The monitor's parameters for a scene (`None`: monitor off).
pub fn ssm<R: Real>(scene: &Avoid) -> Option<SsmParams<R>> {
    scene.safety.on().then(|| ssm_params(scene))
}

/// The scene's speed and separation parameters (ISO/TS 15066 5.5.4), whether the monitor is on or
/// not: what the monitor uses, and what the run's verdict checks every step against.
pub fn ssm_params<R: Real>(scene: &Avoid) -> SsmParams<R> {
    let s = &scene.safety;
    SsmParams {
        human_speed_mps: R::from_f64(s.human_speed_mps),
        reaction_time_s: R::from_f64(s.reaction_time_s),
        stopping_time_s: R::from_f64(s.stopping_time_s),
        margin_m: R::from_f64(s.intrusion_used_m(scene.camera.m_per_px) + s.sensor_uncertainty_m + s.robot_uncertainty_m + scene.clearance_m),
        speed_cap_mps: R::from_f64(scene.speed_mps),
        whole_body_only: s.whole_body_only,
        pfl: pfl_params(scene),
    }
}

/// The PFL speeds of a scene's `[avoid.pfl]` once resolved (`None` without it, or while it is not
/// resolved: [`check_pfl_resolved`] refuses such a run).
pub fn pfl_params<R: Real>(scene: &Avoid) -> Option<Pfl<R>> {
    let p = scene.pfl.as_ref()?;
    let r = p.resolved.as_ref()?;
    Some(Pfl { axis: [R::from_f64(p.axis[0]), R::from_f64(p.axis[1])], along_mps: R::from_f64(r.along_mps), across_mps: R::from_f64(r.across_mps) })
}

/// A scene with `[avoid.pfl]` runs only with its speeds computed (`flinch_studies::body_design::
/// resolve_pfl`): never silently as SSM alone, never with made-up speeds.
pub fn check_pfl_resolved(scene: &Avoid) -> Result<(), String> {
    match &scene.pfl {
        Some(p) if p.resolved.is_none() => Err(format!("avoid.pfl: the PFL speeds of the module scene {} are not computed (the caller must resolve them first: flinch_studies::body_design::resolve_pfl)", p.module)),
        _ => Ok(()),
    }
}

/// Width of the steering barrier's band, m: over it the allowed approach speed rises from 0 to
/// the cap.
pub const STEER_BAND_M: f64 = 0.05;

/// The separation (from the tool's surface, at capture, less the motion since) that the steering
/// barrier holds, m: the monitor's zero-speed separation (with the clearance asked), plus what a
/// person covers at the monitor's approach speed `K` (ISO 13855 6.2: 2.0 m/s within 0.5 m) while
/// the oldest frame is in use (capture to command, one camera period, one control step), plus the
/// robot's own term at the cap, plus 10 mm. There the monitor still allows the cap, so the tool
/// goes round at its cruise speed instead of being stopped.
pub fn steer_barrier_m(scene: &Avoid) -> Result<f64, String> {
    let s = &scene.safety;
    let monitor = SafeController::new(ssm_params::<f64>(scene));
    let oldest = frame_delay_s(scene)? + scene.frame_period_s + scene.dt_s;
    Ok(monitor.stop_separation_m() + monitor.approach_speed_mps() * oldest + scene.speed_mps * (s.reaction_time_s + s.stopping_time_s / 2.0) + 0.01)
}

/// The separation from a fixture the steering barrier holds, m: where the fixture bound (no human
/// approach: the tool's own stop `cap (T_r + T_s / 2)` plus the margin) still allows the cap, plus
/// 10 mm. The tool's motion since capture is taken off by the barrier itself.
pub fn fixture_barrier_m(scene: &Avoid) -> f64 {
    let s = &scene.safety;
    ssm_params::<f64>(scene).margin_m + scene.speed_mps * (s.reaction_time_s + s.stopping_time_s / 2.0) + 0.01
}

/// The monitor with its steering barrier for a scene (`None`: monitor off, as the thesis wrote it).
pub fn safe_controller<R: Real>(scene: &Avoid) -> Result<Option<SafeController<R>>, String> {
    let Some(p) = ssm::<R>(scene) else { return Ok(None) };
    let (w, h) = scene.extent_m();
    let q = R::from_f64;
    // With PFL the monitor lets the tool pass a person along the module's axis at up to the module's
    // speed, so the barrier keeps only the clearance asked (it still goes round where it can); SSM
    // alone: where the monitor allows the cap.
    let barrier = if p.pfl.is_some() { scene.clearance_m } else { steer_barrier_m(scene)? };
    Ok(Some(SafeController::new(p).with_fixture_barrier(q(fixture_barrier_m(scene))).with_steer(Steer {
        barrier_m: q(barrier),
        band_m: q(STEER_BAND_M),
        view_m: [R::ZERO, R::ZERO, q(w), q(h)],
        edge_margin_m: q(scene.robot.wrist_radius_m),
    })))
}

fn monitored<R: Real>(safe: &mut Option<SafeController<R>>, v: [R; 2], p: [f64; 2], sensed: Option<&Sensed<f64>>, cap: f64) -> Cmd {
    match safe {
        None => Cmd { v: [v[0].to_f64(), v[1].to_f64()], limit_mps: cap, state: "field" },
        Some(c) => {
            let q = R::from_f64;
            let sn = sensed.map(|s| Sensed {
                separation_m: q(s.separation_m),
                tool_x_m: q(s.tool_x_m),
                tool_y_m: q(s.tool_y_m),
                age_s: q(s.age_s),
                nearest_x_m: q(s.nearest_x_m),
                nearest_y_m: q(s.nearest_y_m),
                sectors_m: s.sectors_m.map(q),
                fixture_sectors_m: s.fixture_sectors_m.map(q),
            });
            let (x, y) = (q(p[0]), q(p[1]));
            let (vx, vy) = c.steer(v[0], v[1], x, y, sn.as_ref());
            let out = c.limit(vx, vy, x, y, sn.as_ref());
            Cmd { v: [out.vx.to_f64(), out.vy.to_f64()], limit_mps: out.limit_mps.to_f64(), state: state_name(out.state) }
        }
    }
}

/// The `f64` reference: full-sum field, firmware controller and monitor in `f64`.
pub struct RefEngine {
    ctl: Controller<f64>,
    safe: Option<SafeController<f64>>,
    cap: f64,
    field: Option<Field>,
}

impl RefEngine {
    /// For a scene.
    pub fn new(scene: &Avoid) -> Result<Self, String> {
        Ok(RefEngine { ctl: Controller::new(gains(scene)?), safe: safe_controller(scene)?, cap: scene.speed_mps, field: None })
    }
}

impl StepEngine for RefEngine {
    fn new_field(&mut self, field: &Field, _: u32, _: u32) -> Result<(), String> {
        self.field = Some(field.clone());
        Ok(())
    }
    fn command(&mut self, p: [f64; 2], goal: [f64; 2], _: u32, sensed: Option<&Sensed<f64>>) -> Cmd {
        let (h, fx, fy) = self.field.as_ref().map_or((0.0, 0.0, 0.0), |f| f.sample(p[0], p[1]));
        let s = fw::FieldSample { height: h, grad_x: fx, grad_y: fy };
        let c = self.ctl.command(p[0], p[1], goal[0], goal[1], &s, 1.0);
        monitored(&mut self.safe, [c.vx, c.vy], p, sensed, self.cap)
    }
}

/// The firmware as on the target, in number type `R` with Gaussian `G`: frames written by the host
/// onto a `hal-sim` serial line and polled by the firmware's [`Receiver`] (as on the MCU),
/// truncated-window field, controller, weights-age watchdog.
pub struct FwEngine<R, G> {
    ctl: Controller<R>,
    safe: Option<SafeController<R>>,
    cap: f64,
    rx: Box<Receiver<R>>,
    /// The host's end of the line and the MCU's.
    line: (SimSerial, SimSerial),
    gauss: G,
    watchdog: Watchdog,
}

impl<R: Real, G: fw::Gauss<R>> FwEngine<R, G> {
    /// For a scene.
    pub fn new(scene: &Avoid, gauss: G) -> Result<Self, String> {
        let watchdog = Watchdog {
            slow_after_ms: (3.0 * scene.frame_period_s * 1e3) as u32,
            stop_after_ms: (10.0 * scene.frame_period_s * 1e3) as u32,
        };
        let mut rx = Box::new(Receiver::new(200, 20));
        // As the board's `Link::new`: a restarted host's new session is taken once the weights
        // watchdog has stopped the robot, not before.
        rx.new_session_after_ms = watchdog.stop_after_ms;
        Ok(FwEngine {
            ctl: Controller::new(gains(scene)?),
            safe: safe_controller(scene)?,
            cap: scene.speed_mps,
            rx,
            line: SimSerial::pair(),
            gauss,
            watchdog,
        })
    }
}

impl<R: Real, G: fw::Gauss<R>> StepEngine for FwEngine<R, G> {
    fn new_field(&mut self, field: &Field, seq: u32, _now_ms: u32) -> Result<(), String> {
        // Sent now; the firmware reads it from the line on its next step.
        let frame = field.to_frame(seq, 0)?;
        embedded_io::Write::write_all(&mut self.line.0, &frame).map_err(|e| format!("serial line: {e:?}"))?;
        Ok(())
    }
    fn command(&mut self, p: [f64; 2], goal: [f64; 2], now_ms: u32, sensed: Option<&Sensed<f64>>) -> Cmd {
        // Bounded per call, as on the MCU: what is left is read on the next steps.
        let _ = self.rx.poll(&mut self.line.1, now_ms);
        let q = R::from_f64;
        let s = fw::sample(self.rx.grid(), &self.gauss, q(p[0]), q(p[1]));
        let wd = self.watchdog.factor::<R>(self.rx.weights_age_ms(now_ms));
        let c = self.ctl.command(q(p[0]), q(p[1]), q(goal[0]), q(goal[1]), &s, wd);
        monitored(&mut self.safe, [c.vx, c.vy], p, sensed, self.cap)
    }
    fn rx_stats(&self) -> Option<RxStats> {
        Some(self.rx.stats)
    }
}

/// The firmware gains of a scene.
pub fn gains<R: Real>(scene: &Avoid) -> Result<Gains<R>, String> {
    Ok(Gains {
        repulsion: repulsion_law(scene)?,
        k_att: R::from_f64(scene.speed_mps),
        k_rep: R::from_f64(scene.k_rep),
        capture_radius_m: R::from_f64(scene.capture_radius_m),
        latch_height_m: R::from_f64(scene.latch_height_m),
        slow_height_m: R::from_f64(scene.slow_height_m),
        stop_height_m: R::from_f64(scene.stop_height_m),
        bounded: scene.safety.on(),
    })
}

/// The repulsion law named by `repulsion`.
pub fn repulsion_law(scene: &Avoid) -> Result<flinch_firmware::avoidance::Repulsion, String> {
    use flinch_firmware::avoidance::Repulsion;
    Ok(match scene.repulsion.as_str() {
        "vortex" => Repulsion::Vortex { sign: 0 },
        "vortex_cw" => Repulsion::Vortex { sign: 1 },
        "vortex_ccw" => Repulsion::Vortex { sign: -1 },
        "gradient" => Repulsion::Gradient,
        other => {
            return Err(format!(
                "avoid.repulsion = {other:?}: expected \"vortex\", \"vortex_cw\", \"vortex_ccw\" or \"gradient\""
            ))
        }
    })
}
