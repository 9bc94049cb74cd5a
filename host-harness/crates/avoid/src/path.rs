//! The closed loop of section 5.3: every camera frame the scene is rendered (robot at the tool, operator
//! at its key-framed position), pre-processed, cleared of the robot with the calibration, fitted and
//! filtered; every control step the field is sampled at the tool and eq 74-79 move it.
//!
//! Two engines ([`crate::engine`]) share the firmware's [`Controller`](fw::Controller): [`Engine::Reference`] samples the field in `f64`
//! with the full (untruncated) sum; [`Engine::Mcu`] runs the firmware exactly as on the target: each
//! fit is encoded into a serial frame, fed to a [`Receiver`](fw::Receiver) in the board's number type
//! ([`BoardReal`](fw::BoardReal): `f32`, or `I16F16` when the firmware is built with the feature `avoid-fixed`), and
//! the step uses the lookup-table Gaussian over the truncated window plus the weights-age watchdog.
//!
//! This file is the loop itself ([`simulate_from`]) and its frame sources; the parts it uses are in
//! `engine.rs` (the command sources), `verdict.rs`, `link.rs`, `setup.rs`, `sensing.rs` and
//! `result.rs`, re-exported here under the names the avoidance's users know.

use flinch_firmware::avoidance::{SafeController, Sensed};
// The parts of the loop live in their own modules; their names stay reachable here.
pub use crate::board_engine::{link_config, mcu_engine, BoardEngine};
pub use crate::engine::*;
pub use crate::link::*;
pub use crate::result::*;
pub use crate::sensing::*;
pub use crate::setup::*;
pub use crate::verdict::*;
use crate::depth::Rng;
use crate::rbf::Field;
use crate::scene::Avoid;

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

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// Simulate the scene with the reference or the on-target ([`BoardReal`](fw::BoardReal), lookup table) engine.
pub fn simulate(scene: &Avoid, setup: &Setup, engine: Engine) -> Result<PathResult, String> {
    match engine {
        Engine::Reference => simulate_with(scene, setup, &mut RefEngine::new(scene)?),
        Engine::Mcu => simulate_with(scene, setup, &mut mcu_engine(scene)?),
    }
}

/// Where the loop's camera frames come from: the synthetic scene ([`Synthetic`]) or a recording
/// (`avoid::recorded`).
pub trait FrameSource {
    /// The newest frame captured by loop time `t_s` with the tool at `tool`; `None` when there is no
    /// new frame since the last call.
    fn frame(&mut self, scene: &Avoid, setup: &Setup, t_s: f64, tool: [f64; 2]) -> Result<Option<Frame>, String>;
}

/// One camera frame through the pipeline.
pub struct Frame {
    /// The field fitted to it.
    pub field: Field,
    /// The separation sensed from the tool's surface, m.
    pub separation_m: f64,
    /// The nearest sensed obstacle point, m ([`NOTHING_SENSED_M`] along x from the tool when none).
    pub nearest_m: [f64; 2],
    /// Its capture time, s (at most the loop time asked for).
    pub capture_s: f64,
    /// The separation the sensor sees from the goal (the tool's surface there), m; `None` when the
    /// source does not measure it.
    pub goal_separation_m: Option<f64>,
    /// The separation per direction ([`SECTORS`] sectors of 45 degrees round the tool, from its
    /// surface), m: what the monitor's directional bound reads.
    pub sectors_m: [f64; SECTORS],
    /// The same for the pixels classed as fixtures ([`NOTHING_SENSED_M`] where none), m: the
    /// monitor's fixture bound reads them; `separation_m` and `sectors_m` are the people's.
    pub fixture_sectors_m: [f64; SECTORS],
}

/// The synthetic camera: the scene rendered at every frame, captured when asked.
pub struct Synthetic(pub Rng);

impl FrameSource for Synthetic {
    fn frame(&mut self, scene: &Avoid, setup: &Setup, t_s: f64, tool: [f64; 2]) -> Result<Option<Frame>, String> {
        let s = fit_and_sense_classed(scene, setup, tool, &scene.operator_shape_at(t_s), scene.hand_at(t_s), &mut self.0);
        Ok(Some(Frame { field: s.field, separation_m: s.separation_m, nearest_m: s.nearest_m, capture_s: t_s, goal_separation_m: Some(s.goal_separation_m), sectors_m: s.sectors_m, fixture_sectors_m: s.fixture_sectors_m }))
    }
}

/// Simulate the scene with any command source, on the synthetic camera.
pub fn simulate_with(scene: &Avoid, setup: &Setup, engine: &mut dyn StepEngine) -> Result<PathResult, String> {
    simulate_from(scene, setup, engine, &mut Synthetic(Rng::new(scene.camera.seed)))
}

/// Simulate the scene with any command source and any frame source.
///
/// Every step the tool's signed distance to the operator is measured on the true geometry. The run
/// ends at the goal, when the tool leaves the camera's view, when the progress monitor trips
/// (`progress_window_s`, `progress_m`) or at `max_time_s`; in each case the tool is stopped there.
pub fn simulate_from(scene: &Avoid, setup: &Setup, engine: &mut dyn StepEngine, source: &mut dyn FrameSource) -> Result<PathResult, String> {
    let dt = scene.dt_s;
    let steps = (scene.max_time_s / dt).ceil() as usize;
    let goal = scene.goal_m;
    let (w, h) = scene.extent_m();
    let dist_goal = |p: [f64; 2]| ((p[0] - goal[0]).powi(2) + (p[1] - goal[1]).powi(2)).sqrt();

    let mut p = scene.start_m;
    let mut points = vec![p];
    let mut signed = vec![scene.signed_distance_m(0.0, p)];
    let mut rows = Vec::with_capacity(steps.min(1 << 20));
    // Frames in flight: (time it reaches the controller, capture time, field, separation, tool at
    // capture). Each reaches the controller `latency_s` after capture.
    type InFlight = (f64, f64, Field, f64, [f64; 2], [f64; 2], Option<f64>, [f64; SECTORS], [f64; SECTORS]);
    let mut in_flight: std::collections::VecDeque<InFlight> = std::collections::VecDeque::new();
    let Some(Frame { field: f0, separation_m: sep0, nearest_m: near0, goal_separation_m: goal0, sectors_m: sec0, fixture_sectors_m: fix0, .. }) = source.frame(scene, setup, 0.0, p)? else {
        return Err("no camera frame at t = 0".into());
    };
    let mut field = f0.clone();
    // Capture to command: the latency, plus the frame's time on the line when the baud is modelled.
    let delay = frame_delay_s(scene)?;
    in_flight.push_back((delay, 0.0, f0, sep0, p, near0, goal0, sec0, fix0));
    // The verdict: the SSM bound at the true separation, and the swept distance's Lipschitz term.
    let verdict = SsmVerdict::new(scene);
    let (mut ssm_violations, mut over_max, mut first_violation) = (0usize, 0.0f64, None);
    // Power and force limiting: the steps it carried, and the contacts within it.
    check_pfl_resolved(scene)?;
    let pfl = pfl_params::<f64>(scene);
    let (mut steps_in_pfl, mut max_in_pfl, mut contacts_within_pfl, mut contact_speed) = (0usize, 0.0f64, 0usize, 0.0f64);
    let mut pfl_contact = false;
    // The robot's link (issue 29 item 3): its distance to the people at every step.
    let mut link_prev = scene.link_signed_distance_m(0.0, p);
    let mut link_min = link_prev;
    // `no_room` is the monitor's call, on the first frame it sees.
    let monitor = ssm::<f64>(scene).map(SafeController::new);
    let mut frames = 1;
    let mut seq: u32 = 0;
    let mut sensed: Option<Sensed<f64>> = None;
    let mut capture_t = 0.0;
    let mut last_state = "no_data";
    let mut next_frame = scene.frame_period_s;
    let mut best = Snapshot { t_s: 0.0, tool_m: p, hand_m: scene.hand_at(0.0), field: field.clone() };
    let mut min_s = signed[0];
    let mut time_to_goal = None;
    let mut ended: Option<Reason> = None;
    let (mut time_inside, mut vmax, mut vmax_near, mut reversals) = (0.0, 0.0f64, 0.0f64, 0usize);
    let mut last_v: Option<[f64; 2]> = None;
    // Progress monitor: best distance to the goal, and the time and path length when it last
    // improved by `progress_m`.
    let (mut best_goal, mut t_best, mut p_best) = (dist_goal(p), 0.0, p);
    let mut spread: f64 = 0.0;
    let mut path_len = 0.0;
    let mut drive = crate::drive::Drive::new(scene);
    // Fixtures (issue 29 item 2): their clearance judged without K, contact with one a collision.
    let fixtures = scene.has_fixtures();
    let mut fix_min = f64::INFINITY;
    let mut t_end = 0.0;

    for k in 1..=steps {
        let t = k as f64 * dt;
        let t_prev = t - dt;
        let now = (t_prev * 1e3).round() as u32;
        if t_prev + 1e-12 >= next_frame {
            if let Some(Frame { field: f, separation_m: sep, nearest_m: near, capture_s: tc, goal_separation_m: gs, sectors_m: sec, fixture_sectors_m: fix }) = source.frame(scene, setup, t_prev, p)? {
                // The separation was measured from the tool where it is now (`p`), so the monitor's
                // correction for the tool's motion since counts from `p` too; counting from the tool
                // at a recorded frame's (earlier) capture would be optimistic by up to v (t - tc)
                // when the tool turned back in between (review finding).
                in_flight.push_back((tc + delay, tc, f, sep, p, near, gs, sec, fix));
                frames += 1;
            }
            next_frame += scene.frame_period_s;
        }
        let mut no_room = false;
        while in_flight.front().is_some_and(|f| f.0 <= t_prev + 1e-12) {
            let Some((_, tc, f, sep, at, near, gs, sec, fix)) = in_flight.pop_front() else { break };
            if sensed.is_none() {
                if let Some(m) = &monitor {
                    // At rest and with a fresh frame the protective separation is `S_p(0)`: with
                    // the goal inside it no path can keep it (unless contact is permitted: PFL).
                    // A start inside it is not refused: moving away from the person is not
                    // limited (ISO/TS 15066 5.5.4.2.3), and where every direction is blocked the
                    // monitor holds the tool in a protective stop.
                    no_room = pfl.is_none() && gs.is_some_and(|g| m.speed_limit(g) <= 0.0);
                }
            }
            let s = Sensed { separation_m: sep, tool_x_m: at[0], tool_y_m: at[1], age_s: 0.0, nearest_x_m: near[0], nearest_y_m: near[1], sectors_m: sec, fixture_sectors_m: fix };
            engine.capture(&s, tc);
            engine.new_field(&f, seq, now)?;
            seq = seq.wrapping_add(1);
            field = f;
            capture_t = tc;
            sensed = Some(s);
        }
        if let Some(sn) = sensed.as_mut() {
            // Counted from capture: latency plus the time since it arrived.
            sn.age_s = t_prev - capture_t;
        }
        if no_room {
            ended = Some(Reason::NoRoom);
            break;
        }
        let cmd = engine.command(p, goal, now, sensed.as_ref());
        last_state = cmd.state;
        if !(cmd.v[0].is_finite() && cmd.v[1].is_finite()) {
            // A command the drive cannot carry out: a fault (the tool held where it was).
            ended = Some(Reason::NonFiniteCommand);
            break;
        }
        let [vx, vy] = cmd.v;
        // Eq 79, through the drive: the command is followed `T_r - dt` later, a slowing down at
        // no more than `cap / T_s` (`drive.rs`).
        drive.command(t_prev, [vx, vy]);
        let m = drive.advance(p, t_prev, t);
        let speed = m.max_speed_mps;
        path_len += m.length_m;
        p = m.end_m;
        t_end = t;
        let hand = scene.hand_at(t);
        let sd = scene.signed_distance_m(t, p);
        let s_start = *signed.last().unwrap_or(&sd);
        let v_obstacle = obstacle_speed_mps(scene, t_prev, t);
        let swept = swept_min_along(scene, v_obstacle, t_prev, t, &|tt| m.at(tt), m.max_speed_mps);
        let fix_swept = if fixtures { swept_min_by(&|_, q| scene.fixture_signed_distance_m(q), 0.0, t_prev, t, &|tt| m.at(tt), m.max_speed_mps) } else { f64::INFINITY };
        fix_min = fix_min.min(fix_swept);
        vmax = vmax.max(speed);
        if swept < NEAR_OPERATOR_M {
            vmax_near = vmax_near.max(speed);
        }
        if swept < 0.0 {
            time_inside += dt;
        }
        // The verdict on the command: the SSM bound at the true separation when it was given.
        // ISO/TS 15066 5.5.4.2.3: the speed towards the person; moving away is not limited.
        let p_prev = points[points.len() - 1];
        // The people's bound (with K) at their true separation; the fixtures' (the robot's own
        // stop, no K) at theirs (issue 29 item 2). Without fixtures the first is the old one.
        let (s_person, towards) = if fixtures { (scene.person_signed_distance_m(t_prev, p_prev), person_approach_speed_mps(scene, t_prev, p_prev, [vx, vy])) } else { (s_start, approach_speed_mps(scene, t_prev, p_prev, [vx, vy])) };
        let bound = verdict.bound_at_mps(s_person, v_obstacle);
        let over_fixture = if fixtures {
            let s_fix = scene.fixture_signed_distance_m(p_prev);
            let towards_fix = fixture_approach_speed_mps(scene, p_prev, [vx, vy]);
            let b = verdict.fixture_bound_mps(s_fix);
            (towards_fix > b + SSM_TOL_MPS).then_some(towards_fix - b)
        } else {
            None
        };
        let in_pfl = pfl.as_ref().is_some_and(|p| within_pfl(p, [vx, vy]));
        let beyond_ssm = if over_fixture.is_some() { Some(false) } else { (towards > bound + SSM_TOL_MPS).then_some(in_pfl) };
        if let Some(over) = over_fixture {
            // PFL permits no contact with a fixture: beyond its bound is a violation.
            ssm_violations += 1;
            over_max = over_max.max(over);
            first_violation.get_or_insert(t);
        } else if towards > bound + SSM_TOL_MPS {
            if in_pfl {
                steps_in_pfl += 1;
                max_in_pfl = max_in_pfl.max(speed);
            } else {
                ssm_violations += 1;
                over_max = over_max.max(towards - bound);
                first_violation.get_or_insert(t);
            }
        }
        // The link between the step's ends: each of its points moves no more than the tool, the
        // obstacles no more than `v_obstacle`: the swept bound of one part.
        let link_now = scene.link_signed_distance_m(t, p);
        let l_step = (m.max_speed_mps + v_obstacle) * dt;
        if link_now.is_finite() || link_prev.is_finite() {
            link_min = link_min.min(0.5 * (link_prev + link_now - l_step)).min(link_prev).min(link_now);
        }
        link_prev = link_now;
        // The contact's velocity is the drive's (it may still be braking from a faster command).
        let moved_in_pfl = pfl.as_ref().is_some_and(|p| m.velocities_mps.iter().all(|v| within_pfl(p, *v)));
        if swept < 0.0 && moved_in_pfl && min_s >= 0.0 && fix_swept >= 0.0 {
            // The first contact, within the PFL speeds: the module yields, its switch fires, the
            // robot stops (the firmware's latch); the run ends here, a stop.
            contacts_within_pfl += 1;
            contact_speed = speed;
            pfl_contact = true;
        }
        if norm(cmd.v) > 1e-3 {
            if let Some(l) = last_v {
                if l[0] * vx + l[1] * vy < 0.0 {
                    reversals += 1;
                }
            }
            last_v = Some([vx, vy]);
        }
        points.push(p);
        signed.push(sd);
        rows.push(StepRow { t_s: t, p_m: p, v_mps: [vx, vy], separation_m: sd, speed_limit_mps: cmd.limit_mps, state: cmd.state, swept_separation_m: swept, ssm_bound_mps: bound, beyond_ssm });
        if pfl_contact {
            best = Snapshot { t_s: t, tool_m: p, hand_m: hand, field: field.clone() };
            min_s = min_s.min(swept);
            ended = Some(Reason::ContactStop);
            break;
        }
        if swept < min_s {
            min_s = swept;
            best = Snapshot { t_s: t, tool_m: p, hand_m: hand, field: field.clone() };
        }
        if dist_goal(p) <= scene.goal_tolerance_m {
            time_to_goal = Some(t);
            break;
        }
        if !(0.0..=w).contains(&p[0]) || !(0.0..=h).contains(&p[1]) {
            ended = Some(Reason::LeftView);
            break;
        }
        if matches!(cmd.state, "protective_stop" | "no_data") {
            // Waiting for the person to step back is not a lack of progress.
            t_best += dt;
        } else if dist_goal(p) <= best_goal - scene.progress_m {
            (best_goal, t_best, p_best, spread) = (dist_goal(p), t, p, 0.0);
        } else {
            spread = spread.max(((p[0] - p_best[0]).powi(2) + (p[1] - p_best[1]).powi(2)).sqrt());
            if t - t_best >= scene.progress_window_s {
                // Stayed within twice the progress distance of where it last made progress (still,
                // or chattering in place): stalled; went farther without getting closer: no path.
                ended = Some(if spread < 2.0 * scene.progress_m { Reason::Stalled } else { Reason::NoPath });
                break;
            }
        }
    }
    // After any end while moving: the drive brakes to rest (the commands already on their way
    // first), and the path, the distances and the contact checks include it.
    let main_rows = rows.len();
    let tail_steps = ((drive.delay_s + scene.safety.stopping_time_s) / dt).ceil() as usize + 2;
    for k in 1..=tail_steps {
        if !drive.moving() || pfl_contact {
            break;
        }
        let (t_prev, t) = (t_end + (k - 1) as f64 * dt, t_end + k as f64 * dt);
        drive.command(t_prev, [0.0, 0.0]);
        let m = drive.advance(p, t_prev, t);
        path_len += m.length_m;
        p = m.end_m;
        let v_obstacle = obstacle_speed_mps(scene, t_prev, t);
        let swept = swept_min_along(scene, v_obstacle, t_prev, t, &|tt| m.at(tt), m.max_speed_mps);
        let fix_swept = if fixtures { swept_min_by(&|_, q| scene.fixture_signed_distance_m(q), 0.0, t_prev, t, &|tt| m.at(tt), m.max_speed_mps) } else { f64::INFINITY };
        fix_min = fix_min.min(fix_swept);
        let sd = scene.signed_distance_m(t, p);
        let s_start = *signed.last().unwrap_or(&sd);
        vmax = vmax.max(m.max_speed_mps);
        if swept < NEAR_OPERATOR_M {
            vmax_near = vmax_near.max(m.max_speed_mps);
        }
        if swept < 0.0 {
            time_inside += dt;
        }
        let link_now = scene.link_signed_distance_m(t, p);
        if link_now.is_finite() || link_prev.is_finite() {
            link_min = link_min.min(0.5 * (link_prev + link_now - (m.max_speed_mps + v_obstacle) * dt)).min(link_prev).min(link_now);
        }
        link_prev = link_now;
        let moved_in_pfl = pfl.as_ref().is_some_and(|q| m.velocities_mps.iter().all(|v| within_pfl(q, *v)));
        if swept < 0.0 && moved_in_pfl && min_s >= 0.0 && fix_swept >= 0.0 {
            contacts_within_pfl += 1;
            contact_speed = m.max_speed_mps;
            pfl_contact = true;
            if ended.is_none() {
                ended = Some(Reason::ContactStop);
            }
        }
        points.push(p);
        signed.push(sd);
        let s_person = if fixtures { scene.person_signed_distance_m(t_prev, points[points.len() - 2]) } else { s_start };
        let bound = verdict.bound_at_mps(s_person, v_obstacle);
        rows.push(StepRow { t_s: t, p_m: p, v_mps: [0.0, 0.0], separation_m: sd, speed_limit_mps: 0.0, state: "braking", swept_separation_m: swept, ssm_bound_mps: bound, beyond_ssm: None });
        if swept < min_s {
            min_s = swept;
            best = Snapshot { t_s: t, tool_m: p, hand_m: scene.hand_at(t), field: field.clone() };
        }
    }
    if time_to_goal.is_none() && ended.is_none() {
        ended = Some(match last_state {
            "protective_stop" => Reason::Blocked,
            "no_data" => Reason::StaleWeights,
            _ => Reason::Timeout,
        });
    }
    if let Some(r) = main_rows.checked_sub(1).and_then(|k| rows.get_mut(k)) {
        // The row is the step's command: `stopped` only when its command was zero (the braking
        // rows after it are `braking`).
        if ended.is_some() && r.v_mps == [0.0, 0.0] {
            r.state = "stopped";
        }
    }
    // A contact within the PFL speeds is the one permitted contact (it ended the run); any other
    // entry into a person is a collision.
    let collided = (min_s < 0.0 && !pfl_contact) || link_min < 0.0 || fix_min < 0.0;
    // Stopped runs are judged against contact only: a person may walk up to a stopped robot.
    let status = match (collided, ended) {
        (true, e) => Status::Collision(e),
        (false, Some(Reason::NonFiniteCommand)) => Status::Fault,
        (false, e) if ssm_violations > 0 => Status::SsmViolation(e),
        // With PFL every step inside the clearance was judged against the PFL speeds.
        (false, None) if min_s < scene.clearance_m && pfl.is_none() => Status::TooClose,
        (false, None) => Status::Reached,
        (false, Some(r)) => Status::Stopped(r),
    };
    let window = (scene.stall_window_s / dt).round().max(1.0) as usize;
    let stalls = count_stalls(&points, goal, window, scene.stall_move_m, scene.goal_tolerance_m);
    Ok(PathResult {
        points,
        signed_distance_m: signed,
        min_signed_distance_m: min_s,
        ssm_violations,
        max_speed_over_ssm_mps: over_max,
        first_ssm_violation_s: first_violation,
        clearance_m: scene.clearance_m,
        rows,
        status,
        verdict_basis: VerdictBasis::SceneModel,
        time_inside_s: time_inside,
        max_speed_mps: vmax,
        max_speed_near_operator_mps: vmax_near,
        heading_reversals: reversals,
        path_length_m: path_len,
        time_to_goal_s: time_to_goal,
        stalls,
        frames,
        dt_s: dt,
        rx: engine.rx_stats(),
        snapshot: best,
        steps_in_pfl,
        max_speed_in_pfl_mps: max_in_pfl,
        contacts_within_pfl,
        max_contact_speed_mps: contact_speed,
        pfl: crate::result::PflSummary::of(scene),
        link_min_signed_distance_m: link_min,
        warnings: Vec::new(),
    })
}
