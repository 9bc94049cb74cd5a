//! The checks of an avoidance scene that need several keys at once (every value already in its
//! range): the points inside the image, the heights in order, the work caps, the firmware's window.

use crate::scene::check::{approx, num, Ctx, Tab};
use crate::avoid::scene::Avoid;
use super::{keys::*, values::*};

/// The tables cross-checks name.
pub(crate) struct Tabs<'a, 'd> {
    pub(crate) avoid: &'a Tab<'d>,
    pub(crate) camera: &'a Tab<'d>,
    pub(crate) fit: &'a Tab<'d>,
    pub(crate) robot: &'a Tab<'d>,
    pub(crate) operator: &'a Tab<'d>,
}

pub(crate) fn cross_checks(cx: &mut Ctx, s: &Avoid, tabs: &Tabs) {
    let (w, h, px, cam_h) = (s.camera.width_px as f64, s.camera.height_px as f64, s.camera.m_per_px, s.camera.camera_height_m);
    let pixels = w * h;
    if w.max(h) * px > MAX_EXTENT_M {
        cx.bad(tabs.camera, M_PER_PX.name, format!(
            "the image covers {} m x {} m on the plane (width_px x m_per_px); allowed at most {MAX_EXTENT_M} m across ({PLANE}), got m_per_px = {}",
            approx(w * px), approx(h * px), num(px)
        ));
        return;
    }
    // Every height below the camera.
    let r = &s.robot;
    let o = &s.operator;
    for (tab, key, v) in [
        (tabs.avoid, &LATCH, s.latch_height_m),
        (tabs.avoid, &SLOW, s.slow_height_m),
        (tabs.avoid, &STOP, s.stop_height_m),
        (tabs.robot, &ROBOT_KEYS[2], r.wrist_height_m),
        (tabs.robot, &ROBOT_KEYS[4], r.link_height_m),
        (tabs.robot, &THRESHOLD, r.calibration_threshold_m),
        (tabs.operator, &OPERATOR_KEYS[2], o.hand_height_m),
        (tabs.operator, &OPERATOR_KEYS[4], o.forearm_height_m),
    ] {
        debug_assert!(key.span().is_some_and(|sp| sp.source == HEIGHT), "{}", key.name);
        if v >= cam_h {
            cx.bad(tab, key.name, format!("must be below the camera (camera.camera_height_m = {} m): a height above the work plane, got {}", num(cam_h), num(v)));
        }
    }
    if s.stop_height_m <= s.slow_height_m {
        cx.bad(tabs.avoid, STOP.name, format!("must be above slow_height_m = {} m (the speed falls from 1 at slow_height_m to 0 at stop_height_m), got {}", num(s.slow_height_m), num(s.stop_height_m)));
    }
    // Start and goal inside the image, and inside the edge margin the steering keeps the tool's
    // centre from the view's edges (robot.wrist_radius_m, issue 29 item 7): a start or goal in the
    // margin is a run that cannot start cleanly or end at all.
    let (ew, eh) = s.extent_m();
    let m = s.robot.wrist_radius_m;
    for (key, p) in [(&START, s.start_m), (&GOAL, s.goal_m)] {
        if !(0.0..=ew).contains(&p[0]) || !(0.0..=eh).contains(&p[1]) {
            cx.bad(tabs.avoid, key.name, format!("must be inside the image, [0, {}] x [0, {}] m (width_px x m_per_px, height_px x m_per_px), got [{}, {}]", approx(ew), approx(eh), num(p[0]), num(p[1])));
        } else if !(m..=ew - m).contains(&p[0]) || !(m..=eh - m).contains(&p[1]) {
            cx.bad(tabs.avoid, key.name, format!(
                "must be at least robot.wrist_radius_m = {} m inside the image's edges (the steering keeps the tool's centre that far in: the edge margin), [{}, {}] x [{}, {}] m, got [{}, {}]",
                num(m), approx(m), approx(ew - m), approx(m), approx(eh - m), num(p[0]), num(p[1])
            ));
        }
    }
    // Obstacles inside the image (a moving one's every key frame).
    if let Some(obs) = tables(cx, tabs.operator, &OBSTACLES) {
        for (ob, ot) in s.operator.obstacles.iter().zip(obs.iter()) {
            if ob.keyframes.is_empty() {
                let c = ob.center_m;
                if !(0.0..=ew).contains(&c[0]) || !(0.0..=eh).contains(&c[1]) {
                    cx.bad(ot, OB_CENTER.name, format!("must be inside the image, [0, {}] x [0, {}] m, got [{}, {}]", approx(ew), approx(eh), num(c[0]), num(c[1])));
                }
            }
            let frames = tables(cx, ot, &OB_KEYFRAMES).unwrap_or_default();
            for (k, ft) in ob.keyframes.iter().zip(frames.iter()) {
                for (name, v, extent) in [("x_m", k.x_m, ew), ("y_m", k.y_m, eh)] {
                    if !(0.0..=extent).contains(&v) {
                        cx.bad(ft, name, format!("must be inside the image, [0, {}] m, got {}", approx(extent), num(v)));
                    }
                }
            }
        }
    }
    if s.progress_window_s > s.max_time_s.max(1.0) * 100.0 {
        cx.bad(tabs.avoid, PROGRESS_WINDOW.name, format!("must be at most 100 x max_time_s (at least 100 s), here {} s, got {}", num(s.max_time_s.max(1.0) * 100.0), num(s.progress_window_s)));
    }
    let (dt, max_time, frame) = (s.dt_s, s.max_time_s, s.frame_period_s);
    // T_r holds at least the control period: a command stands for a whole step before the next one
    // can stop the robot (ISO/TS 15066 5.5.4.2.3: T_r includes the detection and the control's cycle).
    if s.safety.reaction_time_s < dt {
        let safety = tables_one(cx, tabs.avoid, &SAFETY);
        cx.bad(safety.as_ref().unwrap_or(tabs.avoid), "reaction_time_s", format!(
            "T_r must cover at least one control period (dt_s = {} s: a command stands for a whole step; ISO/TS 15066 5.5.4.2.3), got {}",
            num(dt), num(s.safety.reaction_time_s)
        ));
    }
    if max_time / dt > MAX_STEPS {
        cx.bad(tabs.avoid, DT.name, format!(
            "max_time_s / dt_s = {} control steps; allowed at most {} (bounds the run time), got dt_s = {}",
            approx(max_time / dt), num(MAX_STEPS), num(dt)
        ));
    }
    let frames = (max_time / frame).ceil() + 1.0;
    if frames * pixels > MAX_FRAME_PIXELS {
        cx.bad(tabs.avoid, FRAME.name, format!(
            "{} frames (max_time_s / frame_period_s) of {} px each: {} pixels rendered and fitted; allowed at most {} (bounds the run time: the shipped scene does 1.6e7), got frame_period_s = {}",
            approx(frames), num(pixels), approx(frames * pixels), num(MAX_FRAME_PIXELS), num(frame)
        ));
    }
    sigma_within_window(cx, tabs.fit, s.fit.sigma_factor, s.fit.eval_sigma_factor);
    let (step, threshold, dilate) = (r.calibration_step_m, r.calibration_threshold_m, r.calibration_dilate_m);
    if threshold <= s.fit.offset_m {
        cx.bad(tabs.robot, THRESHOLD.name, format!(
            "must be above fit.offset_m = {} m: the image is raised by it before the fit, so a lower cut marks the whole plane as robot; got {}",
            num(s.fit.offset_m), num(threshold)
        ));
    }
    if dilate > step {
        cx.bad(tabs.robot, DILATE.name, format!(
            "must be at most calibration_step_m = {} m: the nearest stored position is within d / sqrt 2 of the robot, so a larger growth only clears more of what is near it; got {}",
            num(step), num(dilate)
        ));
    }
    if step < px {
        cx.bad(tabs.robot, STEP.name, format!("must be at least one pixel (camera.m_per_px = {} m), got {}", num(px), num(step)));
    }
    if !cx.issues.is_empty() {
        return;
    }
    // The zig-zag of `avoid::calib::zigzag` from d/2 to extent - d/2: this is the work of the
    // calibration pass, which runs with robot.removal = "calibration" and with `--thesis`.
    let count = |extent: f64| ((extent - step) / step).floor().max(0.0) + 1.0;
    let positions = count(w * px) * count(h * px);
    let why = "the calibration pass runs with robot.removal = \"calibration\" and with --thesis";
    if positions * pixels > MAX_CALIBRATION_PIXELS {
        cx.bad(tabs.robot, STEP.name, format!(
            "the calibration zig-zag has {} positions of {} px each ({} pixels rendered and fitted); allowed at most {} ({why}; the shipped scene does 1.9e7), got calibration_step_m = {}",
            num(positions), num(pixels), approx(positions * pixels), num(MAX_CALIBRATION_PIXELS), num(step)
        ));
        return;
    }
    let rad = (dilate / px).round();
    let disc = std::f64::consts::PI * rad * rad + 1.0;
    if positions * pixels * disc > MAX_DILATION_WORK {
        cx.bad(tabs.robot, DILATE.name, format!(
            "growing {} masks of {} px by {} px ({} m) is up to {} pixel writes; allowed at most {} ({why}; the shipped scene: 2.9e9), got calibration_dilate_m = {}",
            num(positions), num(pixels), num(rad), num(dilate), approx(positions * pixels * disc), num(MAX_DILATION_WORK), num(dilate)
        ));
    }
}

/// Largest evaluation sigma the MCU accepts, in units of the spacing: the firmware visits the centres
/// within 4 sigma' (`TRUNC_SIGMAS`) and holds at most `MAX_WINDOW` = 10 per axis, so
/// `2 * 4 * sigma' / s + 2 <= 10` (`Grid::set_geometry`), i.e. sigma' <= s.
pub const MAX_EVAL_SIGMA_OVER_SPACING: f64 = (flinch_firmware::avoidance::MAX_WINDOW as f64 - 2.0) / (2.0 * flinch_firmware::avoidance::TRUNC_SIGMAS);

/// sigma' = `sigma_factor * eval_sigma_factor * spacing / 2` (eq 70, Fig. 90) must fit the firmware's
/// window, or the MCU refuses every frame (`bad_header`) and the robot never moves: refused here,
/// on `fit.eval_sigma_factor`.
pub(crate) fn sigma_within_window(cx: &mut Ctx, fit: &Tab, sigma_factor: f64, eval_factor: f64) {
    let ratio = sigma_factor * eval_factor / 2.0;
    if ratio > MAX_EVAL_SIGMA_OVER_SPACING {
        cx.bad(fit, "eval_sigma_factor", format!(
            "sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = {} x spacing; the firmware evaluates centres within 4 sigma' and holds at most {} per axis, so sigma' must be at most {} x spacing (sigma_factor x eval_sigma_factor <= {}): the MCU would refuse every frame; got eval_sigma_factor = {} with sigma_factor = {}",
            approx(ratio), flinch_firmware::avoidance::MAX_WINDOW, num(MAX_EVAL_SIGMA_OVER_SPACING), num(2.0 * MAX_EVAL_SIGMA_OVER_SPACING), num(eval_factor), num(sigma_factor)
        ));
    }
}
