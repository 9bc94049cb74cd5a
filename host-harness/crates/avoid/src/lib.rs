//! Collision avoidance (Ch. 5): RBF interpolation of depth images and the potential field.
//!
//! `depth` reads 16-bit depth images, generates synthetic ones and pre-processes them (5.1); `rbf`
//! fits the Gaussian grid, filters the weights and evaluates the field and its gradient (5.2);
//! `calib` removes the robot by calibration (5.2.1); `path` closes the loop with the firmware's
//! potential-field step (5.3), `engine` gives it its commands and `verdict` judges the run; `scene` reads `[avoid]` scene files; `plot` draws Fig. 88-90.
//! `flinch avoid SCENE.toml` is [`run`].

pub mod board_engine;
pub mod calib;
pub mod camera;
pub mod compare;
pub mod depth;
pub mod drive;
pub mod engine;
pub mod link;
pub mod path;
#[cfg(test)]
mod path_tests;
pub mod result;
pub mod sensing;
pub mod setup;
pub mod plot;
pub mod rbf;
pub mod recorded;
pub mod scene;
pub mod verdict;

use std::path::PathBuf;

use path::{Engine, PathResult, Setup};
pub use result::PflSummary;

/// `flinch avoid`: simulate an avoidance scene and report the path.
#[derive(clap::Args, Debug)]
pub struct AvoidArgs {
    /// Scene file with an `[avoid]` table (see docs/avoidance.md).
    pub scene: PathBuf,
    /// Draw the path over the interpolated field (`.svg` or `.png`).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print the metrics as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Run the firmware step as the board builds it (its number type `BoardReal`: f32, or I16F16 with
    /// the feature avoid-fixed; lookup-table Gaussian, serial frames) instead of the f64 reference.
    #[arg(long)]
    pub mcu: bool,
    /// Use this robot calibration file instead of running the calibration pass.
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Save the calibration used to this file.
    #[arg(long, value_name = "FILE")]
    pub save_calibration: Option<PathBuf>,
    /// Compare every number type and Gaussian of the firmware step with the f64 reference, on this
    /// grid and on the other of 15 x 15 / 30 x 30 (slow: about a minute).
    #[arg(long)]
    pub compare: bool,
    /// The thesis's law alone (eq 74-79): the speed and separation monitor off (`safety.mode =
    /// "off"`), for comparison. Not safe near a person.
    #[arg(long)]
    pub thesis: bool,
    /// Write the path, one row per control step (`t_s,x_m,y_m,vx_mps,vy_mps,separation_m,
    /// speed_limit_mps,state,swept_separation_m,ssm_bound_mps`); `-` is standard output.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the first synthetic depth frame (16-bit, `.png` or `.pgm`) to this file.
    #[arg(long, value_name = "FILE")]
    pub save_depth: Option<PathBuf>,
    /// Run on recorded depth frames instead of the synthetic camera: one 16-bit PNG/PGM, or a
    /// directory of them (times from `index.csv` or the file names); the scene's
    /// `[avoid.depth_camera]` gives the pinhole camera and `depth_scale_m` (docs/avoidance.md).
    #[arg(long, value_name = "FILE|DIR")]
    pub depth: Option<PathBuf>,
    /// With `--depth`: the robot's tool point over time (`t_s,x_m,y_m`, the frames' clock), to
    /// remove the robot from each frame; without it the robot is an obstacle.
    #[arg(long, value_name = "CSV", requires = "depth")]
    pub robot_poses: Option<PathBuf>,
}

/// The receiver's frame counters (MCU engine), counts.
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct RxCounts {
    /// Frames applied.
    pub good: u32,
    /// Frames with a wrong CRC.
    pub bad_crc: u32,
    /// Headers out of range.
    pub bad_header: u32,
    /// Frames cut off mid-frame.
    pub short: u32,
    /// Whole, correct frames refused as old.
    pub stale: u32,
    /// Bytes skipped while looking for a frame start.
    pub skipped_bytes: u32,
    /// Bytes lost because the receiver's ring was full (each one forgets the weights: stop).
    pub overrun_bytes: u32,
    /// Frames accepted from a new session (a restarted host, after the weights went stale).
    pub new_sessions: u32,
    /// Whole, correct frames of another session refused (weights not yet stale, or a session
    /// applied before).
    pub old_session: u32,
    /// Times the weights were forgotten because a byte waited longer than the age bound unparsed.
    pub backlog: u32,
}

/// `flinch avoid --json`: the metrics of one run (docs/schema/avoid.json). Names carry their unit
/// (docs/conventions.md).
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct AvoidMetrics {
    /// Version of this document's schema.
    pub schema_version: u32,
    /// "reference-f64", or "mcu-" and the board's number type (`avoidance::BoardReal`): "mcu-f32"
    /// (default build) or "mcu-i16f16" (built with the feature `avoid-fixed`).
    pub engine: &'static str,
    /// The speed and separation monitor: "ssm" or "off".
    pub monitor: &'static str,
    /// How the run ended: `reached` (exit 0); `stopped` (safely, before the goal: exit 4);
    /// `too_close`, `collision` (the tool's surface entered an obstacle, over any step's swept
    /// segment), `ssm_violation` (never inside, but faster than the SSM bound at the true
    /// separation at some step) or `fault` (a non-finite command) (all exit 1);
    /// `reached_unverified` or `stopped_unverified` (on recorded frames: the verdict was judged
    /// against the scene file's model operator, not the recording, see `verdict_basis`: exit 5).
    /// Only `reached` exits 0.
    pub status: &'static str,
    /// What the verdict (signed distance, SSM bound) was judged against: `scene_model` (the scene
    /// file's operator, which also drew every frame: ground truth) or `scene_model_not_recording`
    /// (`--depth`: the frames came from a recording whose true geometry is unknown; a favourable
    /// outcome is then `reached_unverified` or `stopped_unverified`, never `reached`).
    pub verdict_basis: &'static str,
    /// Why it stopped before the goal, if it did: `stalled`, `no_path`, `no_room`, `blocked`,
    /// `stale_weights`, `timeout`, `left_view`, `contact_stop` (a contact within the PFL speeds:
    /// the module's switch stopped the robot) or `non_finite_command` (with `fault`).
    pub reason: Option<&'static str>,
    /// Why `reason` is null.
    pub reason_null_reason: Option<&'static str>,
    /// The tool entered the operator's true footprint, or the robot's link entered a person or
    /// an obstacle tall enough to reach it.
    pub collided: bool,
    /// The tool got to the goal (a plain fact, whatever the verdict: `status` says whether the
    /// run was safe; only `status` = `reached` is a goal reached safely).
    pub goal_reached: bool,
    /// Time at which the goal was reached, s.
    pub time_to_goal_s: Option<f64>,
    /// Why `time_to_goal_s` is null.
    pub time_to_goal_null_reason: Option<&'static str>,
    /// Smallest signed distance from the tool's surface to the operator's true footprint, m
    /// (negative inside), over the whole path: each control step's segment is checked, the
    /// obstacles moving meanwhile (a lower bound within 0.1 mm of the true minimum).
    pub min_signed_distance_m: f64,
    /// The clearance the scene asks for, m.
    pub clearance_m: f64,
    /// `min_signed_distance_m` is at least `clearance_m`.
    pub clearance_kept: bool,
    /// Control steps whose commanded speed exceeded the speed and separation bound (ISO/TS 15066
    /// 5.5.4) computed from the TRUE separation at the step's start (ground truth, not the sensed
    /// image; the scene's `v_h`, `T_r`, `T_s`, `C`, `Z_d`, `Z_r`, clearance and cap), count. Any
    /// makes `status` `ssm_violation` (unless `collision`) and `flinch avoid` exit 1.
    pub ssm_violations: usize,
    /// Largest excess of the commanded speed over that bound, m/s (0 when none).
    pub max_speed_over_ssm_mps: f64,
    /// End of the first step that exceeded it, s.
    pub first_ssm_violation_s: Option<f64>,
    /// Why `first_ssm_violation_s` is null.
    pub first_ssm_violation_null_reason: Option<&'static str>,
    /// Time with the tool inside the operator, s.
    pub time_inside_s: f64,
    /// Largest commanded speed, m/s.
    pub max_speed_mps: f64,
    /// Largest commanded speed within `near_operator_m` of the operator, m/s.
    pub max_speed_near_operator_mps: f64,
    /// The distance that counts as near the operator, m.
    pub near_operator_m: f64,
    /// Turns of the commanded direction by more than 90 degrees, count.
    pub heading_reversals: usize,
    /// Length of the path, m.
    pub path_length_m: f64,
    /// Stall episodes (local minima away from the goal), count.
    pub stalls: usize,
    /// Control steps, count.
    pub steps: usize,
    /// Camera frames fitted, count.
    pub frames: usize,
    /// The tool's last position [x, y], m.
    pub final_m: Option<[f64; 2]>,
    /// Receiver counters (MCU engine only).
    pub rx: Option<RxCounts>,
    /// The PFL speeds the monitor and the verdict used, with their provenance; null without
    /// `[avoid.pfl]` (SSM alone, no contact permitted).
    pub pfl: Option<PflSummary>,
    /// Why `pfl` is null.
    pub pfl_null_reason: Option<&'static str>,
    /// Control steps beyond the SSM bound but within the PFL speeds, count.
    pub steps_in_pfl: usize,
    /// Largest commanded speed on such a step, m/s.
    pub max_speed_in_pfl_mps: f64,
    /// Smallest signed distance from the robot's link (base to tool, 3-D: a part lower than the
    /// link's underside passes beneath it) to a person or obstacle, over every step, m (negative:
    /// the arm entered it, a `collision`); null when nothing reaches the link's height.
    pub link_min_signed_distance_m: Option<f64>,
    /// Why `link_min_signed_distance_m` is null.
    pub link_min_signed_distance_null_reason: Option<&'static str>,
    /// Contacts at a tool velocity within the PFL speeds, count (each ends the run: `reason`
    /// `contact_stop`).
    pub contacts_within_pfl: usize,
    /// The tool's speed at the contact, m/s (0 without one; the person's own speed is not in it).
    pub max_contact_speed_mps: f64,
    /// What the input looked wrong in, each naming why (also on stderr): a recording whose frames
    /// are mis-timed (median interval over 1 s) or mis-scaled (most valid points under the work
    /// plane). Empty when nothing was.
    pub warnings: Vec<String>,
}

impl AvoidMetrics {
    /// The metrics of `res`.
    pub fn new(res: &PathResult, engine: Engine, monitor: bool) -> Self {
        let reason = res.status.reason().map(|r| r.name());
        Self {
            schema_version: flinch_output::SCHEMA_VERSION,
            engine: match engine {
                Engine::Reference => "reference-f64",
                Engine::Mcu => match path::board_real_name() {
                    "f32" => "mcu-f32",
                    "I16F16" => "mcu-i16f16",
                    _ => "mcu-unknown",
                },
            },
            monitor: if monitor { "ssm" } else { "off" },
            status: res.status.name(),
            verdict_basis: res.verdict_basis.name(),
            reason,
            reason_null_reason: reason.is_none().then_some("reached the goal"),
            collided: res.min_signed_distance_m < 0.0 || res.link_min_signed_distance_m < 0.0,
            goal_reached: res.time_to_goal_s.is_some(),
            time_to_goal_s: res.time_to_goal_s,
            time_to_goal_null_reason: res.time_to_goal_s.is_none().then_some("the goal was not reached"),
            min_signed_distance_m: res.min_signed_distance_m,
            clearance_m: res.clearance_m,
            clearance_kept: res.min_signed_distance_m >= res.clearance_m,
            ssm_violations: res.ssm_violations,
            max_speed_over_ssm_mps: res.max_speed_over_ssm_mps,
            first_ssm_violation_s: res.first_ssm_violation_s,
            first_ssm_violation_null_reason: res.first_ssm_violation_s.is_none().then_some("the speed stayed within the bound at every step"),
            time_inside_s: res.time_inside_s,
            max_speed_mps: res.max_speed_mps,
            max_speed_near_operator_mps: res.max_speed_near_operator_mps,
            near_operator_m: path::NEAR_OPERATOR_M,
            heading_reversals: res.heading_reversals,
            path_length_m: res.path_length_m,
            stalls: res.stalls,
            steps: res.points.len().saturating_sub(1),
            frames: res.frames,
            final_m: res.points.last().copied(),
            rx: res.rx.map(|s| RxCounts {
                good: s.good,
                bad_crc: s.bad_crc,
                bad_header: s.bad_header,
                short: s.short,
                stale: s.stale,
                skipped_bytes: s.skipped_bytes,
                overrun_bytes: s.overrun,
                new_sessions: s.new_sessions,
                old_session: s.old_session,
                backlog: s.backlog,
            }),
            pfl: res.pfl.clone(),
            pfl_null_reason: res.pfl.is_none().then_some("the scene has no [avoid.pfl]: no contact permitted, SSM alone"),
            steps_in_pfl: res.steps_in_pfl,
            max_speed_in_pfl_mps: res.max_speed_in_pfl_mps,
            contacts_within_pfl: res.contacts_within_pfl,
            max_contact_speed_mps: res.max_contact_speed_mps,
            link_min_signed_distance_m: res.link_min_signed_distance_m.is_finite().then_some(res.link_min_signed_distance_m),
            link_min_signed_distance_null_reason: (!res.link_min_signed_distance_m.is_finite()).then_some("no person or obstacle reaches the height of the link's underside"),
            warnings: res.warnings.clone(),
        }
    }
}

/// Metrics of one run, as printed by `--json`.
pub fn metrics_json(res: &PathResult, engine: Engine, monitor: bool) -> serde_json::Value {
    serde_json::to_value(AvoidMetrics::new(res, engine, monitor)).unwrap_or_default()
}

/// The CSV's header (docs/avoidance.md).
pub const CSV_HEADER: &str = "t_s,x_m,y_m,vx_mps,vy_mps,separation_m,speed_limit_mps,state,swept_separation_m,ssm_bound_mps";

/// Writes the path, one row per control step: [`CSV_HEADER`] (`separation_m`: signed distance to
/// the operator's true footprint at the step's end; `swept_separation_m`: its lower bound over the
/// step's segment; `speed_limit_mps`: the monitor's limit from what it sensed; `ssm_bound_mps`:
/// the SSM bound at the true separation at the step's start, which the speed must not exceed).
pub fn write_csv(res: &PathResult, out: &std::path::Path) -> Result<(), String> {
    use flinch_output::output;
    let mut w = output::create(out).map_err(|f| f.message)?;
    let mut body = format!("{CSV_HEADER}\n");
    for r in &res.rows {
        body.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{}\n",
            r.t_s, r.p_m[0], r.p_m[1], r.v_mps[0], r.v_mps[1], r.separation_m, r.speed_limit_mps, r.state, r.swept_separation_m, r.ssm_bound_mps
        ));
    }
    std::io::Write::write_all(&mut w, body.as_bytes())
        .and_then(|_| std::io::Write::flush(&mut w))
        .map_err(|e| output::write_error(out, &e).message)
}

/// Entry point of `flinch avoid`: the verdict, whose [`path::Verdict::code`] is the exit code:
/// 0 when the tool reached the goal without ever entering the operator, keeping the clearance and
/// the SSM bound at every step (judged against the frames' ground truth); 1 unsafe (a collision,
/// an SSM violation, too close, a fault); 4 stopped safely before the goal; 5 unverified (recorded
/// frames: the verdict is the scene model's, not the recording's).
pub fn run(args: &AvoidArgs) -> Result<path::Verdict, String> {
    run_scene(args, scene::Avoid::load(&args.scene)?)
}

/// [`run`] on a scene already read (`args.scene` names it in messages; it is not read again, so
/// `-` works).
pub fn run_scene(args: &AvoidArgs, mut scene: scene::Avoid) -> Result<path::Verdict, String> {
    if args.thesis {
        scene.thesis_mode();
    }
    let cal = match &args.calibration {
        Some(p) => Some(calib::Calibration::load(p)?),
        None => None,
    };
    let setup = Setup::new(&scene, cal).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    if let Some(p) = &args.save_calibration {
        if scene.robot.removal != "calibration" {
            return Err("--save-calibration: this scene removes the robot by its height model (robot.removal = \"model\"), no calibration is run; use --thesis or robot.removal = \"calibration\"".into());
        }
        setup.calibration.save(p)?;
    }
    if let Some(p) = &args.save_depth {
        let mut rng = depth::Rng::new(scene.camera.seed);
        let img = depth::render(
            &scene.camera(),
            Some((&scene.robot_shape(), scene.start_m)),
            Some((&scene.operator_shape(), scene.hand_at(0.0))),
            &mut rng,
        );
        img.save(p)?;
    }
    if args.compare {
        return run_compare(&scene, &setup, &args.scene).map(|_| path::Verdict::Good);
    }
    let engine = if args.mcu { Engine::Mcu } else { Engine::Reference };
    let (res, recorded) = match &args.depth {
        None => (path::simulate(&scene, &setup, engine).map_err(|e| format!("{}: {e}", args.scene.display()))?, None),
        Some(d) => {
            let (r, stats) = recorded::simulate(&scene, &setup, engine, d, args.robot_poses.as_deref())?;
            (r, Some(stats))
        }
    };
    for w in &res.warnings {
        eprintln!("warning: {}: {w}", args.scene.display());
    }
    if let Some(p) = &args.plot {
        plot::plot(&scene, &res, p)?;
    }
    if let Some(p) = &args.csv {
        write_csv(&res, p)?;
    }
    if args.json {
        print!("{}", flinch_output::to_json(&AvoidMetrics::new(&res, engine, scene.safety.on())));
    } else {
        let name = args.scene.display();
        if args.mcu {
            // Whether this scene is the cell the board ships for (its settings the board's constant).
            let shipped = path::link_config(&scene).is_ok_and(|c| c == flinch_firmware::avoidance::BOARD_CELL);
            println!(
                "avoid {name}: engine mcu (the board's step: {}, LUT, protocol-v3 frames, velocity frames; {})",
                path::board_real_name(),
                if shipped { "the board's shipped configuration".to_string() } else { format!("this scene's configuration; the board ships {}", flinch_firmware::avoidance::cell::BOARD_CELL_SCENE) }
            );
        } else {
            println!("avoid {name}: engine reference (f64)");
        }
        let sf = &scene.safety;
        let monitor = flinch_firmware::avoidance::SafeController::new(path::ssm_params::<f64>(&scene));
        if sf.on() {
            println!(
                "  monitor           speed and separation (ISO/TS 15066 5.5.4): v_h {} m/s, K {} m/s (ISO 13855 6.2: stop separation {:.3} m), T_r {} s, T_s {} s, C {:.4} m (detection capability {:.1} mm), Z {} m, clearance {} m, latency {} s, cap {} m/s",
                sf.human_speed_mps,
                monitor.approach_speed_mps(),
                monitor.stop_separation_m(),
                sf.reaction_time_s,
                sf.stopping_time_s,
                sf.intrusion_used_m(scene.camera.m_per_px),
                sf.detection_capability_m(scene.camera.m_per_px) * 1e3,
                sf.sensor_uncertainty_m + sf.robot_uncertainty_m,
                scene.clearance_m,
                scene.latency_s,
                scene.speed_mps
            );
        } else {
            println!("  monitor           OFF (the thesis's law alone; latency {} s)", scene.latency_s);
        }
        match &res.pfl {
            Some(p) => println!(
                "  PFL (5.5.5)       {:.3} m/s along the module's axis [{:.3}, {:.3}] ({}, {:.0} N, {}), {:.3} m/s across it (rigid tool, {}); module {} sha256 {}...; {} steps in PFL (max {:.3} m/s), {} contacts within it",
                p.pfl_speed_along_axis_mps,
                p.axis[0],
                p.axis[1],
                p.along_region,
                p.force_limit_n,
                p.contact,
                p.pfl_speed_across_axis_mps,
                p.across_region,
                p.module,
                p.module_sha256.get(..12).unwrap_or(""),
                res.steps_in_pfl,
                res.max_speed_in_pfl_mps,
                res.contacts_within_pfl
            ),
            None => println!("  PFL (5.5.5)       none: no contact permitted (no [avoid.pfl])"),
        }
        println!(
            "  robot removal     {}; raised plane {}",
            if scene.robot.removal == "model" { "by the robot's height model" } else { "by calibration masks (thesis 5.2.1)" },
            if scene.fit.remove_plane { "subtracted before eq 71" } else { "kept (thesis)" }
        );
        println!(
            "  grid {} x {}, fit sigma = {:.3} x spacing/2, eval sigma x {:.2}; {} frames, {} steps of {} s",
            setup.fitter.grid.nx,
            setup.fitter.grid.ny,
            scene.fit.sigma_factor,
            scene.fit.eval_sigma_factor,
            res.frames,
            res.points.len() - 1,
            res.dt_s
        );
        let verdict = match res.status {
            path::Status::Reached => "reached the goal, never inside the operator".to_string(),
            path::Status::Stopped(r) => format!("stopped before the goal: {}", r.name()),
            path::Status::TooClose => format!("TOO CLOSE: reached the goal but came closer to the operator than clearance_m = {} m", res.clearance_m),
            path::Status::Collision(e) => format!(
                "COLLISION: {} (then {})",
                match (res.min_signed_distance_m < 0.0, res.link_min_signed_distance_m < 0.0) {
                    (true, true) => "the tool and the robot's link entered the operator",
                    (false, true) => "the robot's link entered a person or an obstacle (the tool did not)",
                    _ => "the tool entered the operator",
                },
                e.map_or("reached the goal".to_string(), |r| format!("stopped: {}", r.name()))
            ),
            path::Status::Fault => "FAULT: the command source gave a non-finite command (NaN or infinite); the tool was held where it was".to_string(),
            path::Status::Unverified(None) => "UNVERIFIED: the tool reached the goal on recorded frames, but the verdict was judged against the scene file's model operator, not against the people in the recording: the clearance and the SSM bound are not known to have been kept".to_string(),
            path::Status::Unverified(Some(r)) => format!("UNVERIFIED: stopped before the goal ({}) on recorded frames; the verdict was judged against the scene file's model operator, not against the people in the recording: not known to be safe", r.name()),
            path::Status::SsmViolation(e) => format!(
                "SSM VIOLATION: {} steps faster than ISO/TS 15066 5.5.4 allows at the true separation, by up to {:.3} m/s (first at t = {:.2} s); then {}",
                res.ssm_violations,
                res.max_speed_over_ssm_mps,
                res.first_ssm_violation_s.unwrap_or(0.0),
                e.map_or("reached the goal".to_string(), |r| format!("stopped: {}", r.name()))
            ),
        };
        println!("  status            {} ({verdict})", res.status.name());
        println!(
            "  verdict basis     {}",
            match res.verdict_basis {
                path::VerdictBasis::SceneModel => "the scene file's operator, which drew every frame (ground truth)",
                path::VerdictBasis::SceneModelNotRecording => "the scene file's operator, NOT the recording: unverified",
            }
        );
        match res.time_to_goal_s {
            Some(t) => println!("  time to goal      {t:.3} s"),
            None => println!("  time to goal      not reached (final {:?})", res.points.last()),
        }
        if res.link_min_signed_distance_m.is_finite() {
            println!("  robot's link      {:.1} mm from the nearest person or obstacle that reaches its height (negative = inside)", res.link_min_signed_distance_m * 1e3);
        }
        println!(
            "  min signed dist.  {:.1} mm from the tool's surface (at t = {:.2} s; clearance asked {:.0} mm; negative = inside the operator, {:.2} s inside)",
            res.min_signed_distance_m * 1e3,
            res.snapshot.t_s,
            res.clearance_m * 1e3,
            res.time_inside_s
        );
        println!(
            "  max speed         {:.3} m/s, {:.3} m/s within {:.0} mm of the operator; {} heading reversals",
            res.max_speed_mps,
            res.max_speed_near_operator_mps,
            path::NEAR_OPERATOR_M * 1e3,
            res.heading_reversals
        );
        println!("  path length       {:.3} m (straight line {:.3} m)", res.path_length_m, {
            let (a, b) = (scene.start_m, scene.goal_m);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        });
        println!("  stalls            {}", res.stalls);
        if let (Some(st), Some(d)) = (&recorded, &args.depth) {
            println!(
                "  recorded frames   {} used from {}; robot {}; unknown (obstacle) at most {:.1} % of the plane in a frame, at most {} cells filled",
                st.frames_used,
                d.display(),
                if args.robot_poses.is_some() { "removed at its recorded poses" } else { "not removed (no --robot-poses): an obstacle" },
                st.max_unknown_fraction * 100.0,
                st.max_filled_cells
            );
        }
        if let Some(s) = res.rx {
            println!(
                "  frames received   {} good, {} bad CRC, {} bad header, {} short, {} stale, {} of another session; {} bytes overrun, {} backlogs, {} new sessions",
                s.good, s.bad_crc, s.bad_header, s.short, s.stale, s.old_session, s.overrun, s.backlog, s.new_sessions
            );
        }
        if let Some(p) = &args.plot {
            flinch_output::output::note(&format!("wrote {} (plot)", p.display()));
        }
    }
    Ok(res.status.verdict())
}

fn run_compare(scene: &scene::Avoid, setup: &Setup, file: &std::path::Path) -> Result<(), String> {
    let ctx = |e: String| format!("{}: {e}", file.display());
    let other = if scene.fit.grid == 30 { 15 } else { 30 };
    let mut refs = Vec::new();
    for (k, n) in [scene.fit.grid, other].into_iter().enumerate() {
        let mut s = scene.clone();
        s.fit.grid = n;
        let own;
        let setup = if k == 0 {
            setup
        } else {
            own = Setup::new(&s, Some(setup.calibration.clone())).map_err(ctx)?;
            &own
        };
        let (reference, rows) = compare::compare(&s, setup).map_err(ctx)?;
        println!(
            "grid {n} x {n}: f64 reference: time to goal {}, min clearance {:.1} mm, path {:.3} m",
            reference.time_to_goal_s.map_or("not reached".to_string(), |t| format!("{t:.2} s")),
            reference.min_signed_distance_m * 1e3,
            reference.path_length_m
        );
        println!("  {:<30} {:>14} {:>14} {:>14} {:>12} {:>10}", "variant", "cmd max mm/s", "cmd rms mm/s", "path dev mm", "min clr mm", "goal s");
        for r in &rows {
            println!(
                "  {:<30} {:>14.3} {:>14.3} {:>14.3} {:>12.1} {:>10}",
                r.variant,
                r.cmd_max_err_mps * 1e3,
                r.cmd_rms_err_mps * 1e3,
                r.path_max_dev_m * 1e3,
                r.min_clearance_m * 1e3,
                r.time_to_goal_s.map_or("-".to_string(), |t| format!("{t:.2}"))
            );
        }
        refs.push(reference);
    }
    println!(
        "grid {} vs {} (both f64 reference): largest path difference {:.1} mm",
        scene.fit.grid,
        other,
        compare::path_deviation(&refs[0], &refs[1]) * 1e3
    );
    Ok(())
}
