//! The closed loop of section 5.3: every camera frame the scene is rendered (robot at the tool, operator
//! at its key-framed position), pre-processed, cleared of the robot with the calibration, fitted and
//! filtered; every control step the field is sampled at the tool and eq 74-79 move it.
//!
//! Two engines share the firmware's [`Controller`]: [`Engine::Reference`] samples the field in `f64`
//! with the full (untruncated) sum; [`Engine::Mcu`] runs the firmware exactly as on the target: each
//! fit is encoded into a serial frame, fed to a [`Receiver`] in `I16F16`, and the step uses the
//! lookup-table Gaussian over the truncated window plus the weights-age watchdog.

use flinch_firmware::avoidance::{self as fw, Controller, Gains, Real, Receiver, RxStats, Watchdog};
use flinch_firmware::avoidance::num::I16F16;

use super::calib::{preprocess, zigzag, Calibration};
use super::depth::{render, Rng};
use super::rbf::{filter_weights, Field, Fitter, RbfGrid};
use super::scene::Avoid;

/// Which implementation computes the command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// `f64`, full sum.
    Reference,
    /// The firmware step in `I16F16` behind the serial frame protocol.
    Mcu,
}

/// What is computed once per scene: the pseudo-inverses and the calibration.
pub struct Setup {
    /// Separable fitter.
    pub fitter: Fitter,
    /// Robot masks.
    pub calibration: Calibration,
}

impl Setup {
    /// Compute the pseudo-inverse and run the calibration pass (or use a loaded calibration).
    pub fn new(scene: &Avoid, calibration: Option<Calibration>) -> Result<Self, String> {
        let cam = scene.camera();
        let grid = RbfGrid::new(cam.width_px, cam.height_px, scene.fit.grid, cam.m_per_px, scene.fit.sigma_factor)?;
        let fitter = Fitter::new(grid)?;
        let calibration = match calibration {
            Some(c) => {
                if (c.width, c.height) != (cam.width_px, cam.height_px) {
                    return Err(format!(
                        "calibration is for {} x {} px images, the scene's camera is {} x {}",
                        c.width, c.height, cam.width_px, cam.height_px
                    ));
                }
                c
            }
            None => {
                let (w, h) = scene.extent_m();
                let d = scene.robot.calibration_step_m;
                let pos = zigzag([d / 2.0, d / 2.0], [w - d / 2.0, h - d / 2.0], d);
                let mut rng = Rng::new(scene.camera.seed ^ 0xCA11);
                Calibration::run(
                    &cam,
                    &scene.robot_shape(),
                    &fitter,
                    &pos,
                    scene.fit.offset_m,
                    scene.robot.calibration_threshold_m,
                    scene.robot.calibration_dilate_m,
                    &mut rng,
                )
            }
        };
        Ok(Setup { fitter, calibration })
    }
}

/// The state of the scene at the moment of minimum clearance, for the plot.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Time, s.
    pub t_s: f64,
    /// Tool, m.
    pub tool_m: [f64; 2],
    /// Hand, m.
    pub hand_m: [f64; 2],
    /// The field in use.
    pub field: Field,
}

/// A simulated path and its metrics.
#[derive(Clone, Debug)]
pub struct PathResult {
    /// Tool positions, one per control step (the first is the start), m.
    pub points: Vec<[f64; 2]>,
    /// Clearance to the operator's footprint at each point, m.
    pub clearance_m: Vec<f64>,
    /// Smallest clearance, m.
    pub min_clearance_m: f64,
    /// Length of the path, m.
    pub path_length_m: f64,
    /// Time at which the goal was reached, s.
    pub time_to_goal_s: Option<f64>,
    /// Stall episodes: local minima away from the goal.
    pub stalls: usize,
    /// Camera frames fitted.
    pub frames: usize,
    /// Control step `dt`, s.
    pub dt_s: f64,
    /// Receiver counters (MCU engine).
    pub rx: Option<RxStats>,
    /// Scene at the minimum clearance.
    pub snapshot: Snapshot,
}

/// The field fitted to one frame (robot at `tool`, hand at `hand`).
pub fn fit_frame(scene: &Avoid, setup: &Setup, tool: [f64; 2], hand: [f64; 2], rng: &mut Rng) -> Field {
    let cam = scene.camera();
    let robot = scene.robot_shape();
    let op = scene.operator_shape();
    let img = render(&cam, Some((&robot, tool)), Some((&op, hand)), rng);
    let map = preprocess(&img, &cam, scene.fit.offset_m, Some((&setup.calibration, tool)));
    let mut w = setup.fitter.weights(&map);
    filter_weights(&mut w);
    Field::new(&setup.fitter.grid, w, scene.fit.eval_sigma_factor)
}

/// The firmware gains of a scene.
pub fn gains<R: Real>(scene: &Avoid) -> Result<Gains<R>, String> {
    Ok(Gains {
        repulsion: scene.repulsion_law()?,
        k_att: R::from_f64(scene.speed_mps),
        k_rep: R::from_f64(scene.k_rep),
        capture_radius_m: R::from_f64(scene.capture_radius_m),
        latch_height_m: R::from_f64(scene.latch_height_m),
        slow_height_m: R::from_f64(scene.slow_height_m),
        stop_height_m: R::from_f64(scene.stop_height_m),
    })
}

/// Counts stall episodes in a path: the tool moved less than `move_m` over `window` steps while
/// farther than `tol_m` from the goal. An episode ends when it moves again.
pub fn count_stalls(points: &[[f64; 2]], goal: [f64; 2], window: usize, move_m: f64, tol_m: f64) -> usize {
    let d = |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    let mut stalls = 0;
    let mut in_stall = false;
    for k in window.max(1)..points.len() {
        let stalled = d(points[k], points[k - window.max(1)]) < move_m && d(points[k], goal) > tol_m;
        if stalled && !in_stall {
            stalls += 1;
        }
        in_stall = stalled;
    }
    stalls
}

/// Simulate the scene.
pub fn simulate(scene: &Avoid, setup: &Setup, engine: Engine) -> Result<PathResult, String> {
    let op = scene.operator_shape();
    let mut rng = Rng::new(scene.camera.seed);
    let dt = scene.dt_s;
    let steps = (scene.max_time_s / dt).ceil() as usize;
    let goal = scene.goal_m;

    let mut ctl64 = Controller::<f64>::new(gains(scene)?);
    let mut ctlq = Controller::<I16F16>::new(gains(scene)?);
    let mut rx = Box::new(Receiver::<I16F16>::new(200, 20));
    let lut = fw::GaussLut::<I16F16>::new();
    let watchdog = Watchdog { slow_after_ms: (3.0 * scene.frame_period_s * 1e3) as u32, stop_after_ms: (10.0 * scene.frame_period_s * 1e3) as u32 };

    let mut p = scene.start_m;
    let mut points = vec![p];
    let mut clearance = vec![op.clearance(scene.hand_at(0.0), p)];
    let mut field = fit_frame(scene, setup, p, scene.hand_at(0.0), &mut rng);
    let mut frames = 1;
    let mut seq: u32 = 0;
    if engine == Engine::Mcu {
        rx.feed(&field.to_frame(seq, 0)?, 0);
    }
    let mut next_frame = scene.frame_period_s;
    let mut best = Snapshot { t_s: 0.0, tool_m: p, hand_m: scene.hand_at(0.0), field: field.clone() };
    let mut min_c = clearance[0];
    let mut time_to_goal = None;

    for k in 1..=steps {
        let t = k as f64 * dt;
        let t_prev = t - dt;
        if t_prev + 1e-12 >= next_frame {
            field = fit_frame(scene, setup, p, scene.hand_at(t_prev), &mut rng);
            frames += 1;
            next_frame += scene.frame_period_s;
            if engine == Engine::Mcu {
                seq = seq.wrapping_add(1);
                rx.feed(&field.to_frame(seq, 0)?, (t_prev * 1e3) as u32);
            }
        }
        let (vx, vy) = match engine {
            Engine::Reference => {
                let (h, fx, fy) = field.sample(p[0], p[1]);
                let s = fw::FieldSample { height: h, grad_x: fx, grad_y: fy };
                let c = ctl64.command(p[0], p[1], goal[0], goal[1], &s, 1.0);
                (c.vx, c.vy)
            }
            Engine::Mcu => {
                let now = (t_prev * 1e3) as u32;
                rx.tick(now);
                let q = |v: f64| I16F16::from_f64(v);
                let s = fw::sample(rx.grid(), &lut, q(p[0]), q(p[1]));
                let wd = watchdog.factor::<I16F16>(rx.weights_age_ms(now));
                let c = ctlq.command(q(p[0]), q(p[1]), q(goal[0]), q(goal[1]), &s, wd);
                (c.vx.to_f64(), c.vy.to_f64())
            }
        };
        // Eq 79.
        p = [p[0] + vx * dt, p[1] + vy * dt];
        let hand = scene.hand_at(t);
        let c = op.clearance(hand, p);
        points.push(p);
        clearance.push(c);
        if c < min_c {
            min_c = c;
            best = Snapshot { t_s: t, tool_m: p, hand_m: hand, field: field.clone() };
        }
        let dist = ((p[0] - goal[0]).powi(2) + (p[1] - goal[1]).powi(2)).sqrt();
        if dist <= scene.goal_tolerance_m {
            time_to_goal = Some(t);
            break;
        }
    }
    let path_length_m = points.windows(2).map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt()).sum();
    let window = (scene.stall_window_s / dt).round().max(1.0) as usize;
    let stalls = count_stalls(&points, goal, window, scene.stall_move_m, scene.goal_tolerance_m);
    Ok(PathResult {
        points,
        clearance_m: clearance,
        min_clearance_m: min_c,
        path_length_m,
        time_to_goal_s: time_to_goal,
        stalls,
        frames,
        dt_s: dt,
        rx: (engine == Engine::Mcu).then_some(rx.stats),
        snapshot: best,
    })
}
