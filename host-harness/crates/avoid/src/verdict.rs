//! The run's own verdict, from the ground truth of the scene: the SSM bound of ISO/TS 15066 5.5.4
//! at the TRUE separation ([`SsmVerdict`]), the swept distance over each control step
//! ([`swept_min_m`]), the obstacles' true speed ([`obstacle_speed_mps`]), and how a run ended
//! ([`Status`], [`Reason`], [`VerdictBasis`], and the exit class [`Verdict`]).

use flinch_firmware::avoidance::{SafeController, SsmParams};

use crate::engine::ssm_params;
use crate::scene::Avoid;

/// The speed the SSM bound of ISO/TS 15066 5.5.4 allows at a TRUE separation `s_m` (from the tool's
/// surface to the obstacles' true footprint, m), m/s: the largest `v_r` with
/// `S_p(v_r) = K (T_r + T_s) + v_r (T_r + T_s / 2) + C + Z_d + Z_r + clearance <= s_m`, at most the
/// cap (`T_s` is the stopping time from the cap; `K` by ISO 13855:2010 6.2 from the scene's `v_h`:
/// `max(2.0 m/s, v_h)` where that gives a stop separation within 0.5 m, else `v_h` with at least
/// 0.5 m, as the monitor computes it: [`SafeController::approach_speed_mps`]). The same function the firmware's monitor applies
/// to its sensed lower bound ([`SafeController::speed_limit`]); here it is given the ground truth,
/// so a sensing chain that overstates the separation (a hidden hand, a hand faster than `v_h`, an
/// age not counted) shows. The sensing latency is not added to `T_r`: the verdict uses the true
/// separation at the instant the command is given, so no sensing delay stands between the person's
/// position and the check (the monitor counts it in the frame's age).
///
/// `v_h` is never less than how fast the scene's obstacles truly move ([`SsmVerdict::bound_at_mps`]):
/// the monitor must assume a speed, the verdict knows it.
pub struct SsmVerdict(SafeController<f64>, SsmParams<f64>);

impl SsmVerdict {
    /// For a scene.
    pub fn new(scene: &Avoid) -> Self {
        let p = ssm_params(scene);
        SsmVerdict(SafeController::new(p), p)
    }
    /// The bound at true separation `s_m`, m/s (0: only standing still is allowed).
    pub fn bound_mps(&self, s_m: f64) -> f64 {
        self.0.speed_limit(s_m)
    }
    /// The bound at a fixture's true separation `s_m` (issue 29 item 2): the robot's own stop only,
    /// `v (T_r + T_s / 2) + margin <= s_m` (a fixture does not move: no `K`), m/s.
    pub fn fixture_bound_mps(&self, s_m: f64) -> f64 {
        self.0.fixture_speed_limit(s_m)
    }
    /// The bound at true separation `s_m` with the obstacles truly approaching at up to
    /// `obstacle_mps` (taken as `v_h` when faster than the scene's), m/s.
    pub fn bound_at_mps(&self, s_m: f64, obstacle_mps: f64) -> f64 {
        if obstacle_mps.is_finite() && obstacle_mps > self.1.human_speed_mps {
            SafeController::new(SsmParams { human_speed_mps: obstacle_mps, ..self.1 }).speed_limit(s_m)
        } else {
            self.0.speed_limit(s_m)
        }
    }
}

/// A commanded speed above the SSM bound by more than this counts as a violation, m/s (the monitor
/// scales to at most its limit; this absorbs rounding only).
pub const SSM_TOL_MPS: f64 = 1e-6;

/// The step of the one-sided difference in [`approach_speed_mps`], m.
pub const APPROACH_STEP_M: f64 = 1e-5;

/// The tool's speed towards the person at `p` (time `t_s`), commanded `v`, m/s (0 when moving
/// away): ISO/TS 15066 5.5.4.2.3's directed `v_r`. The one-sided rate at which the true signed
/// distance falls along `v`: where two points of the footprint are equally near, the larger of
/// their approach speeds (the derivative of a minimum along a direction is the minimum of the
/// derivatives). A finite difference over [`APPROACH_STEP_M`]: on a curved boundary it is off by
/// at most that step over the curvature radius (a 40 mm hand: 0.03 %).
pub fn approach_speed_mps(scene: &Avoid, t_s: f64, p: [f64; 2], v: [f64; 2]) -> f64 {
    approach_rate_mps(&|q| scene.signed_distance_m(t_s, q), p, v)
}

/// [`approach_speed_mps`] towards the people only (not the fixtures), m/s.
pub fn person_approach_speed_mps(scene: &Avoid, t_s: f64, p: [f64; 2], v: [f64; 2]) -> f64 {
    approach_rate_mps(&|q| scene.person_signed_distance_m(t_s, q), p, v)
}

/// [`approach_speed_mps`] towards the fixtures only, m/s.
pub fn fixture_approach_speed_mps(scene: &Avoid, p: [f64; 2], v: [f64; 2]) -> f64 {
    approach_rate_mps(&|q| scene.fixture_signed_distance_m(q), p, v)
}

/// The one-sided rate at which the signed distance `d` falls along `v` at `p`, within `[0, |v|]`.
pub fn approach_rate_mps(d: &dyn Fn([f64; 2]) -> f64, p: [f64; 2], v: [f64; 2]) -> f64 {
    let speed = v[0].hypot(v[1]);
    if !(speed > 0.0) {
        return 0.0;
    }
    let h = APPROACH_STEP_M;
    let q = [p[0] + h * v[0] / speed, p[1] + h * v[1] / speed];
    let fall = (d(p) - d(q)) / h;
    if !fall.is_finite() {
        // Nothing there (an infinite distance): no approach.
        return 0.0;
    }
    (fall * speed).clamp(0.0, speed)
}

/// Within the PFL speeds of `pfl` (the module's axis, along and across), to rounding.
pub fn within_pfl(pfl: &flinch_firmware::avoidance::Pfl<f64>, v: [f64; 2]) -> bool {
    let along = (v[0] * pfl.axis[0] + v[1] * pfl.axis[1]).abs();
    let across = (v[0] * pfl.axis[1] - v[1] * pfl.axis[0]).abs();
    along <= pfl.along_mps + SSM_TOL_MPS && across <= pfl.across_mps + SSM_TOL_MPS
}

/// The swept distance's resolution: over each control step the signed distance is bounded from
/// below to within this of the true minimum over the step's segment, m.
pub const SWEPT_TOL_M: f64 = 1e-4;

/// The most samples [`swept_min_m`] takes over one step (a hand at 1.6 m/s and the tool at 0.25 m/s
/// with 10 ms steps need 93).
pub const SWEPT_MAX_SAMPLES: usize = 2048;

/// The fastest any part of the operator or an obstacle moves, m/s: the largest speed between
/// consecutive key frames of the hand (the forearm's segment follows its end, no faster) and of
/// every moving obstacle.
pub fn max_obstacle_speed_mps(scene: &Avoid) -> f64 {
    obstacle_speed_mps(scene, f64::NEG_INFINITY, f64::INFINITY)
}

/// [`max_obstacle_speed_mps`] over the key-frame segments that overlap the times `[t0, t1]` (held
/// positions before the first and after the last key frame do not move), m/s.
pub fn obstacle_speed_mps(scene: &Avoid, t0: f64, t1: f64) -> f64 {
    let seg = |a: (f64, [f64; 2]), b: (f64, [f64; 2])| {
        let d = (b.1[0] - a.1[0]).hypot(b.1[1] - a.1[1]);
        if d == 0.0 || b.0 <= t0 || a.0 >= t1 {
            0.0
        } else if b.0 > a.0 {
            d / (b.0 - a.0)
        } else {
            f64::INFINITY
        }
    };
    let hand = scene.operator.keyframes.windows(2).map(|w| seg((w[0].t_s, w[0].hand_m), (w[1].t_s, w[1].hand_m))).fold(0.0, f64::max);
    scene
        .operator
        .obstacles
        .iter()
        .flat_map(|o| o.keyframes.windows(2).map(|w| seg((w[0].t_s, [w[0].x_m, w[0].y_m]), (w[1].t_s, [w[1].x_m, w[1].y_m]))))
        .fold(hand, f64::max)
}

/// A lower bound of the signed distance (tool surface to the true footprint) over a control step:
/// the tool moving at constant velocity from `p0` (time `t0`) to `p1` (time `t1`), the operator and
/// the obstacles moving on their key frames meanwhile; m. Along the step the signed distance is
/// Lipschitz with constant `L = |p1 - p0| + v_o (t1 - t0)` per unit of the step's fraction (the
/// footprint's signed distance is 1-Lipschitz in the point, and changes by no more than its parts
/// move, at most `v_o`: [`obstacle_speed_mps`] over the step, or any larger value). Sampled at `n`
/// equal parts, each part's minimum is at least `(d_a + d_b - L / n) / 2`; `n` is chosen so that
/// this is within [`SWEPT_TOL_M`] of the samples, at most [`SWEPT_MAX_SAMPLES`] (beyond, the bound
/// stays conservative and is looser: within `L / (2 n)`). Never above the distance at either end.
pub fn swept_min_m(scene: &Avoid, v_o: f64, (t0, p0): (f64, [f64; 2]), (t1, p1): (f64, [f64; 2])) -> f64 {
    let d0 = scene.signed_distance_m(t0, p0);
    let d1 = scene.signed_distance_m(t1, p1);
    let l = (p1[0] - p0[0]).hypot(p1[1] - p0[1]) + v_o * (t1 - t0).max(0.0);
    if !(l > 0.0) || !l.is_finite() {
        // Nothing moves (or a key frame jumps: the end points are all that is known; a jump is
        // refused by the loader).
        return d0.min(d1);
    }
    let n = (l / (2.0 * SWEPT_TOL_M)).ceil().clamp(1.0, SWEPT_MAX_SAMPLES as f64) as usize;
    let (mut lower, mut prev) = (d0.min(d1), d0);
    for i in 1..=n {
        let s = i as f64 / n as f64;
        let d = if i == n { d1 } else { scene.signed_distance_m(t0 + s * (t1 - t0), [p0[0] + s * (p1[0] - p0[0]), p0[1] + s * (p1[1] - p0[1])]) };
        lower = lower.min(0.5 * (prev + d - l / n as f64));
        prev = d;
    }
    lower
}

/// [`swept_min_m`] along any motion over `[t0, t1]`: the tool at `at(t)`, never faster than
/// `max_speed_mps` (the drive's braking ramps: [`crate::drive::Motion`]), m. The Lipschitz constant
/// per unit of the step's fraction is `(max_speed + v_o) (t1 - t0)`; the same sampling and bound.
pub fn swept_min_along(scene: &Avoid, v_o: f64, t0: f64, t1: f64, at: &dyn Fn(f64) -> [f64; 2], max_speed_mps: f64) -> f64 {
    swept_min_by(&|t, p| scene.signed_distance_m(t, p), v_o, t0, t1, at, max_speed_mps)
}

/// [`swept_min_along`] for any signed distance `dist(t, p)` (1-Lipschitz in `p`, changing by no
/// more than `v_o` in `t`): the fixtures' alone, for one.
pub fn swept_min_by(dist: &dyn Fn(f64, [f64; 2]) -> f64, v_o: f64, t0: f64, t1: f64, at: &dyn Fn(f64) -> [f64; 2], max_speed_mps: f64) -> f64 {
    let (p0, p1) = (at(t0), at(t1));
    let d0 = dist(t0, p0);
    let d1 = dist(t1, p1);
    let l = (max_speed_mps + v_o) * (t1 - t0).max(0.0);
    if !(l > 0.0) || !l.is_finite() {
        return d0.min(d1);
    }
    let n = (l / (2.0 * SWEPT_TOL_M)).ceil().clamp(1.0, SWEPT_MAX_SAMPLES as f64) as usize;
    let (mut lower, mut prev) = (d0.min(d1), d0);
    for i in 1..=n {
        let t = t0 + (t1 - t0) * i as f64 / n as f64;
        let d = if i == n { d1 } else { dist(t, at(t)) };
        lower = lower.min(0.5 * (prev + d - l / n as f64));
        prev = d;
    }
    lower
}

/// Why a run stopped before the goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// The progress monitor tripped and the tool had barely moved: a local minimum.
    Stalled,
    /// The progress monitor tripped while the tool kept moving without getting closer: orbiting or
    /// climbing over an obstacle, no way through found.
    NoPath,
    /// Held in a protective stop (separation below the protective separation) when time ran out.
    Blocked,
    /// The weights were too old (the stale-weights stop) when time ran out.
    StaleWeights,
    /// `max_time_s` passed while moving and making progress.
    Timeout,
    /// The tool left the camera's view (the sensed workspace): stopped there.
    LeftView,
    /// With the monitor on and no PFL, the first frame shows the goal inside the protective
    /// separation at rest (`S_p(0)`, the clearance included): no path can keep it, so the tool
    /// does not move at all (instead of waiting in a protective stop or stalling to the timeout).
    /// (A start inside it is not refused: moving away is not limited.)
    NoRoom,
    /// The command source gave a non-finite command (NaN or infinite): a fault, not a stop (with
    /// the monitor on it never reaches the drive; in `--thesis` mode nothing stands in between).
    /// The tool is held where it was.
    NonFiniteCommand,
    /// The tool touched a person at a velocity within the PFL speeds (`[avoid.pfl]`): the
    /// module's switch fires and the firmware latches the stop; a person resets it (ISO 13849-1
    /// 5.2.2). Safe, and the work stops.
    ContactStop,
}

impl Reason {
    /// The name used in the JSON and the text output.
    pub fn name(self) -> &'static str {
        match self {
            Reason::Stalled => "stalled",
            Reason::NoPath => "no_path",
            Reason::Blocked => "blocked",
            Reason::StaleWeights => "stale_weights",
            Reason::Timeout => "timeout",
            Reason::LeftView => "left_view",
            Reason::NoRoom => "no_room",
            Reason::NonFiniteCommand => "non_finite_command",
            Reason::ContactStop => "contact_stop",
        }
    }
}

/// How a run ended. A run that ever put the tool inside the operator is a [`Status::Collision`]
/// whatever happened afterwards: it is never reported as reached; one that reached the goal but came
/// closer than `clearance_m` is [`Status::TooClose`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// At the goal, never inside the operator.
    Reached,
    /// Stopped before the goal, never inside the operator.
    Stopped(Reason),
    /// The tool reached the goal, never inside the operator, but its surface came closer to the
    /// operator than `clearance_m` on the way.
    TooClose,
    /// The tool entered the operator (signed distance < 0) at least once; `None`: it then reached
    /// the goal, `Some(reason)`: it then stopped for that reason.
    Collision(Option<Reason>),
    /// Never inside, but at some step the commanded speed exceeded the SSM bound computed from the
    /// TRUE separation ([`SsmVerdict`]); `None`: it then reached the goal, `Some(reason)`: it
    /// stopped for that reason. Reported in place of `reached`, `too_close` and `stopped`.
    SsmViolation(Option<Reason>),
    /// The command source failed ([`Reason::NonFiniteCommand`]), never inside before it: unsafe.
    Fault,
    /// A run on recorded frames (`--depth`) that would otherwise read `reached` (`None`) or
    /// `stopped` (`Some(reason)`): the verdict was judged against the scene file's model operator,
    /// which the recording need not show ([`VerdictBasis::SceneModelNotRecording`]), so neither the
    /// clearance nor the SSM bound is known to have been kept. Never a favourable verdict.
    Unverified(Option<Reason>),
}

/// What the verdict (signed distance, SSM bound) was judged against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VerdictBasis {
    /// The scene file's model operator, which also drew every camera frame: the verdict is checked
    /// against the ground truth of what the sensing saw.
    SceneModel,
    /// The scene file's model operator while the frames came from a recording (`--depth`): the
    /// recording's true geometry is unknown, the verdict unverified.
    SceneModelNotRecording,
}

impl VerdictBasis {
    /// The name in the JSON (`verdict_basis`).
    pub fn name(self) -> &'static str {
        match self {
            VerdictBasis::SceneModel => "scene_model",
            VerdictBasis::SceneModelNotRecording => "scene_model_not_recording",
        }
    }
}

/// What `flinch avoid` exits with (docs/conventions.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Exit 0: `reached`, judged against the frames' own ground truth.
    Good,
    /// Exit 1: unsafe: `collision`, `too_close`, `ssm_violation` or `fault`.
    Unsafe,
    /// Exit 4: `stopped` safely before the goal (never inside, the SSM bound kept), verified.
    SafeStop,
    /// Exit 5: `reached_unverified` or `stopped_unverified`: on a recording, nothing checked.
    Unverified,
}

impl Verdict {
    /// The process exit code.
    pub fn code(self) -> u8 {
        match self {
            Verdict::Good => flinch_output::output::EXIT_OK,
            Verdict::Unsafe => flinch_output::output::EXIT_VERDICT,
            Verdict::SafeStop => flinch_output::output::EXIT_SAFE_STOP,
            Verdict::Unverified => flinch_output::output::EXIT_UNVERIFIED,
        }
    }
}

impl Status {
    /// `reached`, `stopped`, `too_close`, `collision`, `ssm_violation`, `fault`,
    /// `reached_unverified` or `stopped_unverified`.
    pub fn name(self) -> &'static str {
        match self {
            Status::Reached => "reached",
            Status::Stopped(_) => "stopped",
            Status::TooClose => "too_close",
            Status::Collision(_) => "collision",
            Status::SsmViolation(_) => "ssm_violation",
            Status::Fault => "fault",
            Status::Unverified(None) => "reached_unverified",
            Status::Unverified(Some(_)) => "stopped_unverified",
        }
    }
    /// The exit class: only `reached` is [`Verdict::Good`].
    pub fn verdict(self) -> Verdict {
        match self {
            Status::Reached => Verdict::Good,
            Status::Stopped(_) => Verdict::SafeStop,
            Status::Unverified(_) => Verdict::Unverified,
            Status::TooClose | Status::Collision(_) | Status::SsmViolation(_) | Status::Fault => Verdict::Unsafe,
        }
    }
    /// The same outcome judged on a basis that is not the frames' ground truth: `reached` becomes
    /// `reached_unverified`, `stopped` `stopped_unverified`; the unsafe ones stay as they are (a
    /// collision with the model operator is still reported).
    pub fn unverified(self) -> Status {
        match self {
            Status::Reached => Status::Unverified(None),
            Status::Stopped(r) => Status::Unverified(Some(r)),
            s => s,
        }
    }
    /// Why it stopped (also after a collision), if it did not reach the goal.
    pub fn reason(self) -> Option<Reason> {
        match self {
            Status::Reached | Status::TooClose | Status::Collision(None) | Status::SsmViolation(None) | Status::Unverified(None) => None,
            Status::Stopped(r) | Status::Collision(Some(r)) | Status::SsmViolation(Some(r)) | Status::Unverified(Some(r)) => Some(r),
            Status::Fault => Some(Reason::NonFiniteCommand),
        }
    }
    /// The favourable verdict: reached the goal, never inside the operator, the clearance and the
    /// SSM bound kept, judged against the frames' ground truth.
    pub fn ok(self) -> bool {
        self == Status::Reached
    }
}
