//! The avoidance scene (`[avoid]`, thesis Ch. 5, docs/avoidance.md), read by the impact scenes'
//! loader machinery (`check.rs`): every key declared once in a [`Key`] table (type, unit, physical
//! range with its source, default, doc line), unknown keys refused with the list of the allowed
//! ones, wrong types, ranges, fixed-length points, increasing key frames, and the caps on the work
//! a scene can ask for (image size, calibration grid, mask growth, frames). Every problem at once,
//! each as `file:line: key: message`. [`parse`] builds `avoid::scene::Avoid`; nothing else parses
//! an avoidance scene file.
use super::check::{approx, line_at, num, Bound::*, Ctx, Key, Need, SceneError, SceneIssue, Tab, Ty};
use crate::avoid::camera::DepthCameraCfg;
use crate::avoid::depth::{Obstacle, ObstacleKeyframe};
use crate::avoid::scene::{Avoid, CameraCfg, FitCfg, Keyframe, OperatorCfg, RobotCfg, SafetyCfg};
use toml_edit::{TableLike, Value};

/// Where points may lie: the plane one camera sees.
const PLANE: &str = "a point on the work plane one ceiling camera sees, at most 10 m across (the thesis's plane: 1.05 m)";
/// Heights above the work plane.
const HEIGHT: &str = "a height above the work plane, below a ceiling camera (the thesis's camera: 1.2 m up)";
/// Sizes of the robot's and the operator's parts.
const PART: &str = "a part of an arm or a hand seen from above: up to 0.5 m across (shipped: 0.045-0.07 m)";

const fn point(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Incl(-10.0), Incl(10.0), PLANE, doc)
}

const fn height(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Excl(0.0), Incl(2.0), HEIGHT, doc)
}

const fn part(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Excl(0.0), Incl(0.5), PART, doc)
}

/// Keys holding `[x, y]` (two numbers, each in the key's range), not one number.
pub const POINTS: &[&str] = &["start_m", "goal_m", "base_m", "entry_m", "hand_m", "position_m", "center_m", "size_m"];

const START: Key = point("start_m", "[x, y] start of the tool");
const GOAL: Key = point("goal_m", "[x, y] goal of the tool");
const SPEED: Key = Key::number(
    "speed_mps",
    "m/s",
    Excl(0.0),
    Incl(3.0),
    "k_a of eq 74, the cruise speed: above the top tool speed of collaborative arms (about 1-3 m/s); shipped 0.25 m/s",
    "k_a of eq 74, cruise speed",
);
const K_REP: Key = Key::number(
    "k_rep",
    "m/s",
    Incl(0.0),
    Incl(100.0),
    "k_r of eq 75/76 per unit gradient of f*: shipped 0.6, and 50 in avoid_extreme_gain.toml, the unsafe extreme studied",
    "k_r of eq 75/76, m/s per unit gradient",
);
const DT: Key = Key::number(
    "dt_s",
    "s",
    Incl(1e-4),
    Incl(0.1),
    "eq 79's control period: robot controllers run at 1-8 ms, the thesis's MATLAB loop took 81 ms (5.3)",
    "control period dt of eq 79",
);
const FRAME: Key = Key::number(
    "frame_period_s",
    "s",
    Incl(0.005),
    Incl(1.0),
    "depth cameras give 1-200 frames/s (the thesis's Kinect: 30 Hz)",
    "camera frame period (a new fit every frame)",
);
const MAX_TIME: Key = Key::number(
    "max_time_s",
    "s",
    Excl(0.0),
    Incl(600.0),
    "a crossing of the workspace takes seconds (shipped 4-12 s); 600 s bounds the run time",
    "give up after this long",
);
const GOAL_TOL: Key = Key::number(
    "goal_tolerance_m",
    "m",
    Excl(0.0),
    Incl(0.1),
    "a positioning tolerance, up to 10 cm (shipped 1 cm)",
    "goal reached within this distance",
);
const CAPTURE: Key = Key::number(
    "capture_radius_m",
    "m",
    Excl(0.0),
    Incl(1.0),
    "within the plane one camera sees (shipped 3 cm)",
    "attraction falls off linearly inside this radius",
);
const LATCH: Key = Key::number("latch_height_m", "m", Incl(0.0), Incl(2.0), HEIGHT, "vortex sign latched while f* is above this").default(0.02);
const SLOW: Key = Key::number("slow_height_m", "m", Incl(0.0), Incl(2.0), HEIGHT, "speed scaling starts at this height of f*");
const STOP: Key = height("stop_height_m", "speed is zero at this height of f* (above slow_height_m)");
const STALL_WINDOW: Key = Key::number(
    "stall_window_s",
    "s",
    Excl(0.0),
    Incl(60.0),
    "a stall is judged over a fraction of a second to seconds (default 0.5 s)",
    "stall window",
)
.default(0.5);
const STALL_MOVE: Key = Key::number("stall_move_m", "m", Excl(0.0), Incl(1.0), "a distance on the plane, up to 1 m (default 5 mm)", "stall: moved less than this in stall_window_s").default(0.005);
const PROGRESS_WINDOW: Key = Key::number(
    "progress_window_s",
    "s",
    Excl(0.0),
    Incl(600.0),
    "at most max_time_s's bound (default 2 s)",
    "progress monitor window",
)
.default(2.0);
const PROGRESS: Key = Key::number("progress_m", "m", Excl(0.0), Incl(1.0), "a distance on the plane, up to 1 m (default 2 cm)", "progress monitor: the least gain towards the goal per window").default(0.02);
const LATENCY: Key = Key::number(
    "latency_s",
    "s",
    Incl(0.0),
    Incl(1.0),
    "capture to command: the thesis measured 0.081 +- 0.008 s (5.3); 1 s is 12 times that",
    "capture-to-command latency",
)
.default(0.081);
const CLEARANCE: Key = Key::number(
    "clearance_m",
    "m",
    Incl(0.0),
    Incl(1.0),
    "the clearance asked for between the tool's surface and a person: centimetres; 1 m is beyond any cell's separation",
    "a reached goal must have kept at least this from the operator; added to the protective separation",
)
.default(0.02);
const BAUD: Key = Key::number("baud", "bit/s", Incl(300.0), Incl(2e7), "UART rates of MCUs: 300 baud to 20 Mbaud (8N1, 10 bits a byte)", "serial line rate, a whole number; a frame takes its bytes' time to arrive").optional("not modelled");
const SAFETY: Key = Key::of("safety", Ty::Table("speed and separation monitoring"), "[avoid.safety]").optional("the defaults");
const CAMERA: Key = Key::of("camera", Ty::Table("the synthetic depth camera"), "[avoid.camera]");
const FIT: Key = Key::of("fit", Ty::Table("the RBF fit"), "[avoid.fit]");
const ROBOT: Key = Key::of("robot", Ty::Table("the robot as the camera sees it"), "[avoid.robot]");
const OPERATOR: Key = Key::of("operator", Ty::Table("the operator and its motion"), "[avoid.operator]");
const DEPTH_CAMERA: Key = Key::of("depth_camera", Ty::Table("the pinhole camera of recorded depth frames (flinch avoid --depth)"), "[avoid.depth_camera]").optional("no recorded input (--depth is refused)");

/// `[avoid.depth_camera]`: the pinhole camera that took the recorded frames of `flinch avoid --depth`
/// (avoid/camera.rs), reprojected onto the `[avoid.camera]` raster of the work plane.
pub const DEPTH_CAMERA_KEYS: &[Key] = &[
    Key::number("fx_px", "px", Incl(10.0), Incl(20000.0), "focal lengths of depth cameras in pixels: about 200-1500 (RealSense D435 at 640 x 480: 380-620; Kinect v1: 525)", "focal length along the image columns"),
    Key::number("fy_px", "px", Incl(10.0), Incl(20000.0), "as fx_px", "focal length along the image rows"),
    Key::number("cx_px", "px", Incl(-10000.0), Incl(10000.0), "the principal point, near the image centre (TUM fr1: 318.6, 255.3); pixel centres at whole numbers", "principal point, column"),
    Key::number("cy_px", "px", Incl(-10000.0), Incl(10000.0), "as cx_px", "principal point, row"),
    Key::number("depth_scale_m", "m", Incl(1e-5), Incl(0.01), "metres per count of the 16-bit image: RealSense z16 0.001, TUM RGB-D 0.0002 (5000 per m), Azure Kinect 0.001", "metres per depth count (0 = null)"),
    point("position_m", "[x, y] of the camera's optical centre over the work plane"),
    Key::number("height_m", "m", Incl(0.3), Incl(5.0), "the working range of depth cameras, 0.3-5 m above the plane", "optical centre above the work plane"),
    Key::number("roll_deg", "deg", Incl(-60.0), Incl(60.0), "a camera looking down on the plane: at most 60 degrees from the vertical", "rotation about the plane's x axis, applied to the straight-down camera").default(0.0),
    Key::number("pitch_deg", "deg", Incl(-60.0), Incl(60.0), "as roll_deg", "rotation about the plane's y axis, after roll").default(0.0),
    Key::number("yaw_deg", "deg", Incl(-180.0), Incl(180.0), "any heading", "rotation about the vertical, after pitch").default(0.0),
];

/// `[avoid]`'s numbers.
pub const KEYS: &[Key] = &[
    START, GOAL, SPEED, K_REP, REPULSION, DT, FRAME, MAX_TIME, GOAL_TOL, CAPTURE, LATCH, SLOW, STOP, STALL_WINDOW, STALL_MOVE, PROGRESS_WINDOW, PROGRESS, LATENCY, CLEARANCE, BAUD, SAFETY, CAMERA, FIT, ROBOT, OPERATOR, DEPTH_CAMERA,
];

/// The repulsion laws, as `avoid::scene::Avoid::repulsion_law` reads them.
pub const REPULSIONS: &[&str] = &["vortex", "vortex_cw", "vortex_ccw", "gradient"];
const REPULSION: Key = Key::of(
    "repulsion",
    Ty::Choice(REPULSIONS),
    "eq 76's vortex (sign from the motion, or fixed clockwise / counter-clockwise), or eq 75's gradient",
)
.optional("\"vortex\"");

/// The top level of an avoidance scene: only `[avoid]`.
const AVOID: Key = Key::of("avoid", Ty::Table("the avoidance scene"), "[avoid]");

const MODE: Key = Key::of(
    "mode",
    Ty::Choice(&["ssm", "off"]),
    "\"ssm\": the monitor limits every command (ISO/TS 15066 5.5.4); \"off\": the thesis's law alone (eq 74-79), for comparison only",
)
.optional("\"ssm\"");

/// `[avoid.safety]` (ISO/TS 15066 5.5.4), every key optional: `avoid::scene::SafetyCfg::default()`.
pub const SAFETY_KEYS: &[Key] = &[
    MODE,
    Key::number("human_speed_mps", "m/s", Incl(1.6), Incl(10.0), "v_h: ISO 13855:2010 6.2 and ISO/TS 15066 5.5.4.2.3: 1.6 m/s (walking, arm beyond 0.5 m); slower is not a person; 10 m/s bounds a swing", "v_h, the human's far-field approach speed: where the protective separation with 2.0 m/s is at most 0.5 m, the monitor and the verdict use 2.0 m/s (ISO 13855 6.2, K = 2,000 mm/s), or this value if faster").default(1.6),
    Key::number("reaction_time_s", "s", Incl(0.0), Incl(10.0), "T_r: a control period plus the drive's delay, milliseconds; 10 s bounds it", "T_r").default(0.02),
    Key::number("stopping_time_s", "s", Incl(0.0), Incl(10.0), "T_s: a robot stops from cruise within a second; 10 s bounds it", "T_s").default(0.1),
    Key::number("intrusion_m", "m", Incl(0.0), Incl(1.0), "C of ISO 13855 5.3: up to 0.85 m (a reach over a barrier); the monitor never uses less than the sensor's detection capability requires", "C, intrusion distance").default(0.0),
    Key::number("sensor_uncertainty_m", "m", Incl(0.0), Incl(1.0), "Z_d: a few pixels; 1 m bounds it", "Z_d").default(0.01),
    Key::number("robot_uncertainty_m", "m", Incl(0.0), Incl(1.0), "Z_r: millimetres for an industrial arm; 1 m bounds it", "Z_r").default(0.005),
    Key::number("sense_height_m", "m", Incl(0.001), Incl(1.0), "above the depth noise (mm), below a person's hand over the plane; d of ISO 13855 sets the intrusion distance the monitor adds", "obstacle above this height").default(0.014),
];

const WIDTH: Key = Key::integer("width_px", 8, 2000, "depth cameras have 320-1280 columns; the thesis's image is 210 px", "image columns");
const HEIGHT_PX: Key = Key::integer("height_px", 8, 2000, "depth cameras have 240-1024 rows; the thesis's image is 210 px", "image rows");
const M_PER_PX: Key = Key::number(
    "m_per_px",
    "m",
    Incl(2e-4),
    Incl(0.05),
    "a depth camera 0.5-4.5 m above the plane gives about 1-10 mm per pixel (the thesis: 5 mm)",
    "pixel size on the plane",
);
const CAMERA_HEIGHT: Key = Key::number(
    "camera_height_m",
    "m",
    Incl(0.3),
    Incl(5.0),
    "the working range of Kinect-class depth cameras, 0.5-4.5 m (the thesis: 1.2 m)",
    "camera above the plane",
);

const SEED: Key = Key::integer("seed", 0, u32::MAX, "any whole number >= 0 (up to 2^63 - 1): it only picks the noise", "RNG seed of the synthetic noise and null pixels");

/// `[avoid.camera]`.
pub const CAMERA_KEYS: &[Key] = &[
    WIDTH,
    HEIGHT_PX,
    M_PER_PX,
    CAMERA_HEIGHT,
    Key::number("noise_mm", "mm", Incl(0.0), Incl(100.0), "depth noise of Kinect-class cameras: about 1 mm at 0.5 m to 40 mm at 4 m", "depth noise standard deviation"),
    Key::number("null_fraction", "", Incl(0.0), Incl(0.9), "a fraction of the pixels; a frame with more than 90 % null carries nothing", "fraction of null pixels"),
    SEED,
];

const OFFSET: Key = Key::number("offset_m", "m", Incl(0.0), Incl(0.5), "the thesis raises the image by about 0.065 m (5.2)", "raise before fitting");

const REMOVE_PLANE: Key = Key::of("remove_plane", Ty::Bool, "subtract the raised empty plane's own weights before eq 71 (without it the plane's border weights survive the threshold as walls up to 0.1 m high)").optional("true");

/// `[avoid.fit]`.
pub const FIT_KEYS: &[Key] = &[
    Key::integer("grid", 1, 30, "the thesis's 15 x 15 and 30 x 30 grids; the firmware holds at most 30 per axis (MAX_AXIS)", "centres across the width"),
    Key::number("sigma_factor", "", Incl(0.1), Incl(10.0), "1 is eq 70 (sigma = spacing / 2); a tenth to ten times that", "fit sigma in units of eq 70"),
    Key::number("eval_sigma_factor", "", Incl(0.1), Incl(10.0), "Fig. 90 widens by 1.5; a tenth to ten times the fit's", "evaluation sigma in units of the fit sigma"),
    OFFSET,
    REMOVE_PLANE,
];

const STEP: Key = Key::number(
    "calibration_step_m",
    "m",
    Incl(0.005),
    Incl(0.5),
    "d of Fig. 84: a zig-zag of 5 mm to 0.5 m steps (shipped 0.05 m)",
    "zig-zag step d of Fig. 84",
);
const THRESHOLD: Key = height("calibration_threshold_m", "cut height of the interpolated robot (Fig. 85), above fit.offset_m");
const DILATE: Key = Key::number(
    "calibration_dilate_m",
    "m",
    Incl(0.0),
    Incl(0.5),
    "0 is the thesis's plain cut; about d / sqrt 2 covers the robot between positions; at most calibration_step_m",
    "growth of each mask",
)
.default(0.0);

const REMOVAL: Key = Key::of(
    "removal",
    Ty::Choice(&["model", "calibration"]),
    "\"model\": clear only the pixels the robot's own height model explains; \"calibration\": the thesis's masks (5.2.1), which also clear whatever is near the robot",
)
.optional("\"model\"");

/// `[avoid.robot]`.
pub const ROBOT_KEYS: &[Key] = &[
    point("base_m", "[x, y] robot base"),
    part("wrist_radius_m", "wrist/tool radius"),
    height("wrist_height_m", "wrist/tool top above the plane"),
    part("link_width_m", "link width"),
    height("link_height_m", "link top above the plane"),
    STEP,
    THRESHOLD,
    DILATE,
    REMOVAL,
    Key::number("removal_margin_m", "m", Incl(0.0), Incl(1.0), "a height margin over the robot's model, up to 1 m (default 2 cm)", "model removal margin").default(0.02),
];

const HAND_KEYFRAMES: Key = Key::of("keyframes", Ty::Table("a list of at least one key frame { t_s, hand_m }, t_s increasing"), "hand position over time: linear between key frames, held after the last");
const OBSTACLES: Key = Key::of("obstacles", Ty::Table("a list of [[avoid.operator.obstacles]] tables"), "further obstacles, standing or moving").optional("none");

/// `[avoid.operator]`.
pub const OPERATOR_KEYS: &[Key] = &[
    point("entry_m", "[x, y] where the forearm enters the image"),
    part("hand_radius_m", "hand radius"),
    height("hand_height_m", "hand top"),
    part("forearm_width_m", "forearm width"),
    height("forearm_height_m", "forearm top"),
    HAND_KEYFRAMES,
    OBSTACLES,
];

/// The footprints of `[[avoid.operator.obstacles]]`.
pub const OBSTACLE_KINDS: &[&str] = &["disc", "box"];
const OB_KIND: Key = Key::of("kind", Ty::Choice(OBSTACLE_KINDS), "footprint: a disc (radius_m) or an axis-aligned box (size_m)");
const OB_CENTER: Key = point("center_m", "[x, y] centre of a standing obstacle, inside the image").optional("a moving obstacle: keyframes instead");
const OB_KEYFRAMES: Key = Key::of("keyframes", Ty::Table("a list of key frames { t_s, x_m, y_m }, t_s increasing"), "centre over time: linear between key frames, held before the first and after the last").optional("a standing obstacle at center_m");
const OB_HEIGHT: Key = Key::number("height_m", "m", Incl(0.001), Incl(2.0), "an obstacle's top above the plane, from a 1 mm plate to 2 m (a person standing)", "top above the plane");
/// Sizes of obstacles.
const OBSTACLE_SIZE: &str = "an obstacle on the plane one camera sees: at most 10 m across (shipped: 0.05-1.05 m)";
const OB_RADIUS: Key = Key::number("radius_m", "m", Excl(0.0), Incl(10.0), OBSTACLE_SIZE, "disc radius");
const OB_SIZE: Key = Key::number("size_m", "m", Excl(0.0), Incl(10.0), OBSTACLE_SIZE, "[x, y] box size along x and y");

/// `[[avoid.operator.obstacles]]` with `kind = "disc"`.
pub const DISC_KEYS: &[Key] = &[OB_KIND, OB_CENTER, OB_KEYFRAMES, OB_RADIUS, OB_HEIGHT];
/// `[[avoid.operator.obstacles]]` with `kind = "box"`.
pub const BOX_KEYS: &[Key] = &[OB_KIND, OB_CENTER, OB_KEYFRAMES, OB_SIZE, OB_HEIGHT];
/// One key frame of a moving obstacle (each coordinate also inside the image).
pub const OBSTACLE_KEYFRAME_KEYS: &[Key] = &[
    Key::number("t_s", "s", Incl(0.0), Incl(600.0), "within max_time_s's bound", "time of the key frame"),
    Key::number("x_m", "m", Incl(-10.0), Incl(10.0), PLANE, "centre along x, inside the image"),
    Key::number("y_m", "m", Incl(-10.0), Incl(10.0), PLANE, "centre along y, inside the image"),
];

/// One key frame of `avoid.operator.keyframes`.
pub const KEYFRAME_KEYS: &[Key] = &[
    Key::number("t_s", "s", Incl(0.0), Incl(600.0), "within max_time_s's bound", "time of the key frame"),
    point("hand_m", "[x, y] hand centre"),
];


/// Largest image extent on the plane, m: [`PLANE`].
pub const MAX_EXTENT_M: f64 = 10.0;
/// Largest work of the calibration pass, snapshot positions x pixels: each position renders, fits
/// and rasters the whole image. The shipped scene: 441 x 44,100 = 1.9e7 (3.8 s of CPU in release).
pub const MAX_CALIBRATION_PIXELS: f64 = 1e8;
/// Largest work of growing the masks, positions x pixels x offsets in the growth disc (an upper
/// bound: only the robot's pixels are grown). The shipped scene: 441 x 44,100 x 149 = 2.9e9.
pub const MAX_DILATION_WORK: f64 = 1e10;
/// Largest work of the run's frames, frames x pixels (render and fit every frame). The shipped
/// scene: 364 x 44,100 = 1.6e7.
pub const MAX_FRAME_PIXELS: f64 = 2e8;
/// Most control steps of a run, max_time_s / dt_s (the loader's previous bound).
pub const MAX_STEPS: f64 = 1e6;

/// Reads and checks an avoidance scene given as text; `file` names it in the messages.
pub fn parse(text: &str, file: &str) -> Result<Avoid, SceneError> {
    let doc = super::check::parse_toml(text, file)?;
    let mut cx = Ctx { text, file, issues: Vec::new() };
    let root = Tab { path: String::new(), t: doc.as_table(), line: Some(1) };
    // The top level holds only `[avoid]` (`check_keys` wants a listed table: this one is not
    // listed, so that the impact scene's schema does not grow an `avoid` key).
    for (key, _) in root.t.iter() {
        if key != AVOID.name {
            cx.bad(&root, key, "unknown key; an avoidance scene holds only the table [avoid] (allowed keys: avoid)".into());
        }
    }
    let avoid = cx.table(&root, &AVOID).and_then(|t| read_avoid(&mut cx, &t));
    match avoid {
        Some(a) if cx.issues.is_empty() => Ok(a),
        _ => {
            debug_assert!(!cx.issues.is_empty(), "an avoidance scene failed without saying why");
            cx.issues.sort_by_key(|i| i.line);
            Err(SceneError { file: file.to_string(), issues: cx.issues })
        }
    }
}

/// The problems of `e` one a line as `line N: key: message`, for a text without a file name
/// (`avoid::scene::Avoid::parse`).
pub fn without_file(e: &SceneError) -> String {
    let line = |i: &SceneIssue| i.line.map_or(String::new(), |l| format!("line {l}: "));
    let key = |i: &SceneIssue| if i.key.is_empty() { String::new() } else { format!("{}: ", i.key) };
    e.issues.iter().map(|i| format!("{}{}{}", line(i), key(i), i.message)).collect::<Vec<_>>().join("\n")
}

/// An optional choice key: the chosen name, `default` when absent, `None` (reported) when invalid.
fn choice_or(cx: &mut Ctx, tab: &Tab, key: &Key, default: &'static str) -> Option<String> {
    let Ty::Choice(options) = key.ty else { return None };
    cx.maybe_choice(tab, key, options).map(|c| c.unwrap_or(default).to_string())
}

/// A whole number written without a decimal point: `Some(None)` when absent (and optional),
/// `None` (reported) when missing, of another type, or out of the key's range.
fn whole(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<Option<i64>> {
    let what = key.what();
    let Some(item) = tab.t.get(key.name) else {
        if key.need == Need::Required {
            cx.missing(tab, key.name, &what);
            return None;
        }
        return Some(None);
    };
    let n = match item.as_value() {
        Some(Value::Integer(i)) => *i.value(),
        Some(Value::Float(f)) => {
            cx.bad(tab, key.name, format!("must be {what}, a whole number (write it without a decimal point), got {:?}", f.value()));
            return None;
        }
        _ => {
            cx.bad(tab, key.name, format!("must be {what}, got {}", item.type_name()));
            return None;
        }
    };
    let ok = match key.ty {
        Ty::Number(span) => span.contains(n as f64),
        Ty::Integer { lo, .. } => n >= i64::from(lo),
        _ => false,
    };
    if !ok {
        let msg = match key.span() {
            Some(span) => span.refuse(n as f64),
            None => format!("must be {what}, got {n}"),
        };
        cx.bad(tab, key.name, msg);
        return None;
    }
    Some(Some(n))
}

/// An integer key as a count.
fn count(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<usize> {
    cx.integer(tab, key).map(|n| n as usize)
}

/// The tables of a list key (`[[a.b]]` or `b = [{ ... }, ...]`), each with its path `a.b[i]` and
/// line; empty when an optional key is absent, `None` (reported) when missing or not a list of
/// tables.
fn tables<'d>(cx: &mut Ctx, tab: &Tab<'d>, key: &Key) -> Option<Vec<Tab<'d>>> {
    let Ty::Table(what) = key.ty else { return None };
    let Some(item) = tab.t.get(key.name) else {
        if key.need == Need::Required {
            cx.missing(tab, key.name, what);
            return None;
        }
        return Some(Vec::new());
    };
    let path = tab.key(key.name);
    let line_of = |cx: &Ctx, t: &dyn TableLike, span: Option<std::ops::Range<usize>>| {
        let first = t.iter().next().and_then(|(k, _)| t.get_key_value(k)).and_then(|(k, _)| k.span());
        first.or(span).map(|s| line_at(cx.text, s.start))
    };
    let mut out = Vec::new();
    if let Some(a) = item.as_array_of_tables() {
        for (i, t) in a.iter().enumerate() {
            let line = line_of(cx, t, t.span()).or(tab.line);
            out.push(Tab { path: format!("{path}[{i}]"), t, line });
        }
        return Some(out);
    }
    let Some(a) = item.as_value().and_then(Value::as_array) else {
        cx.bad(tab, key.name, format!("must be {what}, got {}", item.type_name()));
        return None;
    };
    let mut ok = true;
    for (i, v) in a.iter().enumerate() {
        match v.as_inline_table() {
            Some(t) => {
                let line = line_of(cx, t, t.span()).or(tab.line);
                out.push(Tab { path: format!("{path}[{i}]"), t, line });
            }
            None => {
                cx.bad(tab, key.name, format!("must be {what}, got {} at position {}", v.type_name(), i + 1));
                ok = false;
            }
        }
    }
    ok.then_some(out)
}

/// `[avoid]` and everything in it.
fn read_avoid(cx: &mut Ctx, t: &Tab) -> Option<Avoid> {
    cx.check_keys(t, KEYS, "");
    let start_m = xy(cx, t, &START);
    let goal_m = xy(cx, t, &GOAL);
    let speed_mps = cx.number(t, &SPEED);
    let k_rep = cx.number(t, &K_REP);
    let repulsion = choice_or(cx, t, &REPULSION, REPULSIONS[0]);
    let dt_s = cx.number(t, &DT);
    let frame_period_s = cx.number(t, &FRAME);
    let max_time_s = cx.number(t, &MAX_TIME);
    let goal_tolerance_m = cx.number(t, &GOAL_TOL);
    let capture_radius_m = cx.number(t, &CAPTURE);
    let latch_height_m = cx.number(t, &LATCH);
    let slow_height_m = cx.number(t, &SLOW);
    let stop_height_m = cx.number(t, &STOP);
    let stall_window_s = cx.number(t, &STALL_WINDOW);
    let stall_move_m = cx.number(t, &STALL_MOVE);
    let progress_window_s = cx.number(t, &PROGRESS_WINDOW);
    let progress_m = cx.number(t, &PROGRESS);
    let latency_s = cx.number(t, &LATENCY);
    let clearance_m = cx.number(t, &CLEARANCE);
    let baud = whole(cx, t, &BAUD).map(|b| b.map(|b| b as u32));
    let safety = match cx.maybe_table(t, &SAFETY) {
        Some(Some(s)) => safety(cx, &s),
        Some(None) => Some(default_safety()),
        None => None,
    };
    let camera_t = cx.table(t, &CAMERA);
    let camera = camera_t.as_ref().and_then(|c| camera(cx, c));
    let fit_t = cx.table(t, &FIT);
    let fit = fit_t.as_ref().and_then(|f| fit(cx, f));
    let robot_t = cx.table(t, &ROBOT);
    let robot = robot_t.as_ref().and_then(|r| robot(cx, r));
    let operator_t = cx.table(t, &OPERATOR);
    let operator = operator_t.as_ref().and_then(|o| operator(cx, o));
    let depth_camera = match cx.maybe_table(t, &DEPTH_CAMERA) {
        Some(Some(d)) => depth_camera(cx, &d).map(Some),
        Some(None) => Some(None),
        None => None,
    };
    let scene = Avoid {
        start_m: start_m?,
        goal_m: goal_m?,
        speed_mps: speed_mps?,
        k_rep: k_rep?,
        repulsion: repulsion?,
        dt_s: dt_s?,
        frame_period_s: frame_period_s?,
        max_time_s: max_time_s?,
        goal_tolerance_m: goal_tolerance_m?,
        capture_radius_m: capture_radius_m?,
        latch_height_m: latch_height_m?,
        slow_height_m: slow_height_m?,
        stop_height_m: stop_height_m?,
        stall_window_s: stall_window_s?,
        stall_move_m: stall_move_m?,
        progress_window_s: progress_window_s?,
        progress_m: progress_m?,
        latency_s: latency_s?,
        clearance_m: clearance_m?,
        baud: baud?,
        safety: safety?,
        camera: camera?,
        fit: fit?,
        robot: robot?,
        operator: operator?,
        depth_camera: depth_camera?,
    };
    let tabs = Tabs { avoid: t, camera: camera_t.as_ref()?, fit: fit_t.as_ref()?, robot: robot_t.as_ref()?, operator: operator_t.as_ref()? };
    if cx.issues.is_empty() {
        cross_checks(cx, &scene, &tabs);
    }
    Some(scene)
}

/// `[avoid.safety]` with every key at its default (`SafetyCfg::default()`): the defaults of
/// [`SAFETY_KEYS`], the one source.
pub fn default_safety() -> SafetyCfg {
    let empty = toml_edit::Table::new();
    let mut cx = Ctx { text: "", file: "", issues: Vec::new() };
    let t = Tab { path: "avoid.safety".into(), t: &empty, line: None };
    let s = safety(&mut cx, &t);
    debug_assert!(cx.issues.is_empty(), "{:?}", cx.issues);
    s.expect("the defaults of SAFETY_KEYS are in their ranges")
}

fn safety(cx: &mut Ctx, t: &Tab) -> Option<SafetyCfg> {
    cx.check_keys(t, SAFETY_KEYS, "");
    let mode = choice_or(cx, t, &MODE, "ssm");
    let v: Vec<Option<f64>> = SAFETY_KEYS[1..].iter().map(|k| cx.number(t, k)).collect();
    let g = |name: &str| SAFETY_KEYS[1..].iter().position(|k| k.name == name).and_then(|i| v[i]);
    Some(SafetyCfg {
        mode: mode?,
        human_speed_mps: g("human_speed_mps")?,
        reaction_time_s: g("reaction_time_s")?,
        stopping_time_s: g("stopping_time_s")?,
        intrusion_m: g("intrusion_m")?,
        sensor_uncertainty_m: g("sensor_uncertainty_m")?,
        robot_uncertainty_m: g("robot_uncertainty_m")?,
        sense_height_m: g("sense_height_m")?,
    })
}

/// The value of the number key `name` of `keys` in `t` (its default when absent).
fn number_of(cx: &mut Ctx, t: &Tab, keys: &[Key], name: &str) -> Option<f64> {
    let key = keys.iter().find(|k| k.name == name)?;
    cx.number(t, key)
}

fn camera(cx: &mut Ctx, t: &Tab) -> Option<CameraCfg> {
    cx.check_keys(t, CAMERA_KEYS, "");
    let width_px = count(cx, t, &WIDTH);
    let height_px = count(cx, t, &HEIGHT_PX);
    let m_per_px = cx.number(t, &M_PER_PX);
    let camera_height_m = cx.number(t, &CAMERA_HEIGHT);
    let noise_mm = number_of(cx, t, CAMERA_KEYS, "noise_mm");
    let null_fraction = number_of(cx, t, CAMERA_KEYS, "null_fraction");
    let seed = whole(cx, t, &SEED).flatten();
    Some(CameraCfg {
        width_px: width_px?,
        height_px: height_px?,
        m_per_px: m_per_px?,
        camera_height_m: camera_height_m?,
        noise_mm: noise_mm?,
        null_fraction: null_fraction?,
        seed: seed? as u64,
    })
}

fn fit(cx: &mut Ctx, t: &Tab) -> Option<FitCfg> {
    cx.check_keys(t, FIT_KEYS, "");
    let grid = count(cx, t, &FIT_KEYS[0]);
    let sigma_factor = number_of(cx, t, FIT_KEYS, "sigma_factor");
    let eval_sigma_factor = number_of(cx, t, FIT_KEYS, "eval_sigma_factor");
    let offset_m = cx.number(t, &OFFSET);
    let remove_plane = cx.boolean(t, &REMOVE_PLANE);
    Some(FitCfg {
        grid: grid?,
        sigma_factor: sigma_factor?,
        eval_sigma_factor: eval_sigma_factor?,
        offset_m: offset_m?,
        remove_plane: remove_plane?.unwrap_or(true),
    })
}

fn robot(cx: &mut Ctx, t: &Tab) -> Option<RobotCfg> {
    cx.check_keys(t, ROBOT_KEYS, "");
    let base_m = xy(cx, t, &ROBOT_KEYS[0]);
    let wrist_radius_m = number_of(cx, t, ROBOT_KEYS, "wrist_radius_m");
    let wrist_height_m = number_of(cx, t, ROBOT_KEYS, "wrist_height_m");
    let link_width_m = number_of(cx, t, ROBOT_KEYS, "link_width_m");
    let link_height_m = number_of(cx, t, ROBOT_KEYS, "link_height_m");
    let calibration_step_m = cx.number(t, &STEP);
    let calibration_threshold_m = cx.number(t, &THRESHOLD);
    let calibration_dilate_m = cx.number(t, &DILATE);
    let removal = choice_or(cx, t, &REMOVAL, "model");
    let removal_margin_m = number_of(cx, t, ROBOT_KEYS, "removal_margin_m");
    Some(RobotCfg {
        base_m: base_m?,
        wrist_radius_m: wrist_radius_m?,
        wrist_height_m: wrist_height_m?,
        link_width_m: link_width_m?,
        link_height_m: link_height_m?,
        calibration_step_m: calibration_step_m?,
        calibration_threshold_m: calibration_threshold_m?,
        calibration_dilate_m: calibration_dilate_m?,
        removal: removal?,
        removal_margin_m: removal_margin_m?,
    })
}

fn operator(cx: &mut Ctx, t: &Tab) -> Option<OperatorCfg> {
    cx.check_keys(t, OPERATOR_KEYS, "");
    let entry_m = xy(cx, t, &OPERATOR_KEYS[0]);
    let hand_radius_m = number_of(cx, t, OPERATOR_KEYS, "hand_radius_m");
    let hand_height_m = number_of(cx, t, OPERATOR_KEYS, "hand_height_m");
    let forearm_width_m = number_of(cx, t, OPERATOR_KEYS, "forearm_width_m");
    let forearm_height_m = number_of(cx, t, OPERATOR_KEYS, "forearm_height_m");
    let keyframes = tables(cx, t, &HAND_KEYFRAMES).and_then(|frames| {
        if frames.is_empty() {
            cx.bad(t, HAND_KEYFRAMES.name, "must hold at least one key frame { t_s, hand_m }, got none".into());
            return None;
        }
        let read: Vec<Option<Keyframe>> = frames
            .iter()
            .map(|f| {
                cx.check_keys(f, KEYFRAME_KEYS, "");
                let t_s = cx.number(f, &KEYFRAME_KEYS[0]);
                let hand_m = xy(cx, f, &KEYFRAME_KEYS[1]);
                Some(Keyframe { t_s: t_s?, hand_m: hand_m? })
            })
            .collect();
        let read: Vec<Keyframe> = read.into_iter().collect::<Option<_>>()?;
        let times: Vec<f64> = read.iter().map(|k| k.t_s).collect();
        increasing(cx, &frames, &times).then_some(read)
    });
    let obstacles = tables(cx, t, &OBSTACLES).and_then(|obs| obs.iter().map(|o| obstacle(cx, o)).collect::<Vec<_>>().into_iter().collect::<Option<Vec<_>>>());
    Some(OperatorCfg {
        entry_m: entry_m?,
        hand_radius_m: hand_radius_m?,
        hand_height_m: hand_height_m?,
        forearm_width_m: forearm_width_m?,
        forearm_height_m: forearm_height_m?,
        keyframes: keyframes?,
        obstacles: obstacles?,
    })
}

/// Key frames' `t_s` must increase: each later one refused naming the one before.
fn increasing(cx: &mut Ctx, frames: &[Tab], times: &[f64]) -> bool {
    let mut ok = true;
    for (i, w) in times.windows(2).enumerate() {
        if w[1] <= w[0] {
            cx.bad(&frames[i + 1], "t_s", format!("must be after the key frame before it ({}.t_s = {} s): key frames' t_s must increase, got {}", frames[i].path, num(w[0]), num(w[1])));
            ok = false;
        }
    }
    ok
}

/// One `[[avoid.operator.obstacles]]`: its kind's keys.
fn obstacle(cx: &mut Ctx, t: &Tab) -> Option<Obstacle> {
    let kind = cx.choice(t, &OB_KIND, OBSTACLE_KINDS)?;
    let disc = kind == "disc";
    let keys = if disc { DISC_KEYS } else { BOX_KEYS };
    cx.check_keys(t, keys, &format!(" for kind = \"{kind}\""));
    let center_m = if t.has(OB_CENTER.name) { xy(cx, t, &OB_CENTER).map(Some) } else { Some(None) };
    let frames = tables(cx, t, &OB_KEYFRAMES);
    let keyframes = frames.as_ref().and_then(|frames| {
        let read: Vec<Option<ObstacleKeyframe>> = frames
            .iter()
            .map(|f| {
                cx.check_keys(f, OBSTACLE_KEYFRAME_KEYS, "");
                let v: Vec<Option<f64>> = OBSTACLE_KEYFRAME_KEYS.iter().map(|k| cx.number(f, k)).collect();
                Some(ObstacleKeyframe { t_s: v[0]?, x_m: v[1]?, y_m: v[2]? })
            })
            .collect();
        let read: Vec<ObstacleKeyframe> = read.into_iter().collect::<Option<_>>()?;
        let times: Vec<f64> = read.iter().map(|k| k.t_s).collect();
        increasing(cx, frames, &times).then_some(read)
    });
    let radius_m = if disc { cx.number(t, &OB_RADIUS) } else { Some(0.0) };
    let size_m = if disc { Some([0.0; 2]) } else { xy(cx, t, &OB_SIZE) };
    let height_m = cx.number(t, &OB_HEIGHT);
    let (center_m, keyframes) = (center_m?, keyframes?);
    match (center_m, keyframes.is_empty()) {
        (None, true) => {
            cx.bad(t, OB_KIND.name, "needs center_m (a standing obstacle) or keyframes (a moving one), got neither".into());
            return None;
        }
        (Some(_), false) => {
            cx.bad(t, OB_CENTER.name, "give center_m (standing) or keyframes (moving), not both".into());
            return None;
        }
        _ => {}
    }
    Some(Obstacle {
        kind: kind.to_string(),
        center_m: center_m.unwrap_or([f64::NAN; 2]),
        keyframes,
        radius_m: radius_m?,
        size_m: size_m?,
        height_m: height_m?,
    })
}

fn depth_camera(cx: &mut Ctx, t: &Tab) -> Option<DepthCameraCfg> {
    cx.check_keys(t, DEPTH_CAMERA_KEYS, "");
    let k = DEPTH_CAMERA_KEYS;
    let v: Vec<Option<f64>> = k.iter().map(|key| if key.name == "position_m" { None } else { cx.number(t, key) }).collect();
    let g = |name: &str| k.iter().position(|key| key.name == name).and_then(|i| v[i]);
    let position_m = xy(cx, t, &k[5]);
    Some(DepthCameraCfg {
        fx_px: g("fx_px")?,
        fy_px: g("fy_px")?,
        cx_px: g("cx_px")?,
        cy_px: g("cy_px")?,
        depth_scale_m: g("depth_scale_m")?,
        position_m: position_m?,
        height_m: g("height_m")?,
        roll_deg: g("roll_deg")?,
        pitch_deg: g("pitch_deg")?,
        yaw_deg: g("yaw_deg")?,
    })
}

/// The tables cross-checks name.
struct Tabs<'a, 'd> {
    avoid: &'a Tab<'d>,
    camera: &'a Tab<'d>,
    fit: &'a Tab<'d>,
    robot: &'a Tab<'d>,
    operator: &'a Tab<'d>,
}

/// The checks that need several keys; every value is in its range here.
fn tables_one<'d>(cx: &mut Ctx, tab: &Tab<'d>, key: &Key) -> Option<Tab<'d>> {
    cx.maybe_table(tab, key).flatten()
}

fn cross_checks(cx: &mut Ctx, s: &Avoid, tabs: &Tabs) {
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
    // Start and goal inside the image.
    let (ew, eh) = s.extent_m();
    for (key, p) in [(&START, s.start_m), (&GOAL, s.goal_m)] {
        if !(0.0..=ew).contains(&p[0]) || !(0.0..=eh).contains(&p[1]) {
            cx.bad(tabs.avoid, key.name, format!("must be inside the image, [0, {}] x [0, {}] m (width_px x m_per_px, height_px x m_per_px), got [{}, {}]", approx(ew), approx(eh), num(p[0]), num(p[1])));
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

/// A point `[x, y]`: exactly two finite numbers in the key's range.
fn xy(cx: &mut Ctx, tab: &Tab, key: &Key) -> Option<[f64; 2]> {
    let span = key.span()?;
    let Some(item) = tab.t.get(key.name) else {
        cx.missing(tab, key.name, &format!("[x, y], two numbers {}", span.describe()));
        return None;
    };
    let Some(arr) = item.as_value().and_then(Value::as_array) else {
        cx.bad(tab, key.name, format!("must be [x, y], two numbers {}, got {}", span.describe(), item.type_name()));
        return None;
    };
    if arr.len() != 2 {
        cx.bad(tab, key.name, format!("must be [x, y], exactly two numbers, got {} values", arr.len()));
        return None;
    }
    let mut p = [0.0; 2];
    for (i, v) in arr.iter().enumerate() {
        let x = match v {
            Value::Integer(n) => *n.value() as f64,
            Value::Float(f) => *f.value(),
            other => {
                cx.bad(tab, key.name, format!("must be [x, y], two numbers, got {} at position {}", other.type_name(), i + 1));
                return None;
            }
        };
        if !x.is_finite() || !span.contains(x) {
            let coord = if i == 0 { "x" } else { "y" };
            cx.bad(tab, key.name, format!("{coord}: {}", span.refuse(x)));
            return None;
        }
        p[i] = x;
    }
    Some(p)
}

/// Largest evaluation sigma the MCU accepts, in units of the spacing: the firmware visits the centres
/// within 4 sigma' (`TRUNC_SIGMAS`) and holds at most `MAX_WINDOW` = 10 per axis, so
/// `2 * 4 * sigma' / s + 2 <= 10` (`Grid::set_geometry`), i.e. sigma' <= s.
pub const MAX_EVAL_SIGMA_OVER_SPACING: f64 = (flinch_firmware::avoidance::MAX_WINDOW as f64 - 2.0) / (2.0 * flinch_firmware::avoidance::TRUNC_SIGMAS);

/// sigma' = `sigma_factor * eval_sigma_factor * spacing / 2` (eq 70, Fig. 90) must fit the firmware's
/// window, or the MCU refuses every frame (`bad_header`) and the robot never moves: refused here,
/// on `fit.eval_sigma_factor`.
fn sigma_within_window(cx: &mut Ctx, fit: &Tab, sigma_factor: f64, eval_factor: f64) {
    let ratio = sigma_factor * eval_factor / 2.0;
    if ratio > MAX_EVAL_SIGMA_OVER_SPACING {
        cx.bad(fit, "eval_sigma_factor", format!(
            "sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = {} x spacing; the firmware evaluates centres within 4 sigma' and holds at most {} per axis, so sigma' must be at most {} x spacing (sigma_factor x eval_sigma_factor <= {}): the MCU would refuse every frame; got eval_sigma_factor = {} with sigma_factor = {}",
            approx(ratio), flinch_firmware::avoidance::MAX_WINDOW, num(MAX_EVAL_SIGMA_OVER_SPACING), num(2.0 * MAX_EVAL_SIGMA_OVER_SPACING), num(eval_factor), num(sigma_factor)
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHIPPED: &str = include_str!("../../../scenes/avoid_thesis_reach.toml");

    /// The scene's problems as `flinch avoid` prints them (`line N:` without a file name).
    fn check(text: &str, file: &str) -> Result<(), String> {
        parse(text, file).map(|_| ()).map_err(|e| if file.is_empty() { without_file(&e) } else { e.to_string() })
    }

    fn refused(from: &str, to: &str) -> String {
        let mut text = SHIPPED.to_string();
        for (f, t) in from.split(';').zip(to.split(';')) {
            assert!(text.contains(f), "{f} not in the scene");
            text = text.replacen(f, t, 1);
        }
        check(&text, "s.toml").expect_err(to)
    }

    #[test]
    fn shipped_avoid_scenes_pass() {
        for f in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes")).unwrap() {
            let p = f.unwrap().path();
            if p.file_name().unwrap().to_string_lossy().starts_with("avoid_") {
                let text = std::fs::read_to_string(&p).unwrap();
                check(&text, "x").unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            }
        }
    }

    #[test]
    fn refusals_name_file_line_key_range_and_source() {
        let e = refused("k_rep = 0.6 ", "k_rep = 1e9 ");
        assert!(e.starts_with("s.toml:12: avoid.k_rep: allowed range [0, 100] m/s (k_r of eq 75/76"), "{e}");
        assert!(e.ends_with("got 1e9"), "{e}");
        let e = refused("start_m = [0.12, 0.50]", "start_m = [0.12, 0.50, 0.3]");
        assert!(e.starts_with("s.toml:9: avoid.start_m: must be [x, y], exactly two numbers, got 3 values"), "{e}");
        let e = refused("hand_radius_m = 0.05", "hand_radius_m = nan");
        assert!(e.contains("avoid.operator.hand_radius_m: must be a finite number; allowed range (0, 0.5] m") && e.contains("got NaN"), "{e}");
        // Every problem at once, in line order.
        let text = SHIPPED.replacen("speed_mps = 0.25 ", "speed_mps = 1e9 ", 1).replacen("noise_mm = 3.0", "noise_mm = nan", 1).replacen("t_s = 1.2", "t_s = -1", 1);
        let all = check(&text, "s.toml").unwrap_err();
        assert_eq!(all.lines().count(), 3, "{all}");
        assert!(all.lines().next().unwrap().starts_with("s.toml:11: avoid.speed_mps: allowed range (0, 3] m/s"), "{all}");
        assert!(all.lines().nth(2).unwrap().contains("avoid.operator.keyframes[1].t_s: allowed range [0, 600] s"), "{all}");
        // Without a file name, `line N:` as `avoid::scene::Avoid::parse` reports.
        let e = check(&SHIPPED.replacen("dt_s = 0.01", "dt_s = 1e9", 1), "").unwrap_err();
        assert!(e.starts_with("line 14: avoid.dt_s: allowed range [1e-4, 0.1] s"), "{e}");
    }

    /// sigma' > spacing used to pass the loader and then be refused by the MCU on every frame (the
    /// robot never moved, silently). Refused here with the file, line and key; at the bound the
    /// firmware's receiver accepts the frame, just past it it refuses it: the two limits agree.
    #[test]
    fn sigma_wider_than_the_spacing_is_refused_where_the_mcu_would_refuse_it() {
        let e = refused("eval_sigma_factor = 1.5 ", "eval_sigma_factor = 2.5 ");
        assert!(e.starts_with("s.toml:37: avoid.fit.eval_sigma_factor: sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = 1.25 x spacing"), "{e}");
        assert!(e.contains("at most 1 x spacing") && e.contains("got eval_sigma_factor = 2.5 with sigma_factor = 1"), "{e}");
        let e = refused("sigma_factor = 1.0 ", "sigma_factor = 1.5 ");
        assert!(e.contains("avoid.fit.eval_sigma_factor: sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = 1.125 x spacing"), "{e}");
        // At the bound (the shipped demo's 1.0 x 2.0) the loader passes it.
        check(&SHIPPED.replacen("eval_sigma_factor = 1.5 ", "eval_sigma_factor = 2.0 ", 1), "s.toml").unwrap();
        // The firmware, through the wire's Q16.16 geometry, for every grid the loader allows.
        use flinch_firmware::avoidance::{self as fw, num::I16F16};
        for n in 1..=30usize {
            let spacing = 1.05 / n as f64;
            for (ratio, accepted) in [(MAX_EVAL_SIGMA_OVER_SPACING, true), (MAX_EVAL_SIGMA_OVER_SPACING * 1.01, false)] {
                let q = |v: f64| (v * 65536.0).round() as i32;
                let h = fw::FrameHeader { session: 0, nx: n as u8, ny: n as u8, seq: 1, age_ms: 0, x0_q16: q(spacing / 2.0), y0_q16: q(spacing / 2.0), spacing_q16: q(spacing), sigma_q16: q(ratio * spacing) };
                let mut out = vec![0u8; fw::frame::MAX_FRAME];
                let len = fw::encode_frame(&h, &vec![0; n * n], &mut out).unwrap();
                let mut rx = Box::new(fw::Receiver::<I16F16>::new(100, 10));
                rx.feed(&out[..len], 0);
                assert_eq!(rx.stats.good == 1, accepted, "grid {n}, sigma'/s = {ratio}: {:?}", rx.stats);
            }
        }
    }

    #[test]
    fn work_caps_refuse_what_would_crash_or_hang() {
        for (from, to, key) in [
            ("m_per_px = 0.005", "m_per_px = 1e9", "avoid.camera.m_per_px: allowed range"),
            ("m_per_px = 0.005", "m_per_px = 0.05", "avoid.camera.m_per_px: the image covers 10.5 m x 10.5 m"),
            ("calibration_step_m = 0.05", "calibration_step_m = 1e-9", "avoid.robot.calibration_step_m: allowed range"),
            ("calibration_step_m = 0.05;calibration_dilate_m = 0.035", "calibration_step_m = 0.005;calibration_dilate_m = 0.004", "avoid.robot.calibration_step_m: the calibration zig-zag has"),
            ("calibration_dilate_m = 0.035", "calibration_dilate_m = 1e9", "avoid.robot.calibration_dilate_m: allowed range"),
            ("calibration_dilate_m = 0.035", "calibration_dilate_m = -1", "avoid.robot.calibration_dilate_m: allowed range"),
            ("calibration_dilate_m = 0.035", "calibration_dilate_m = 0.35", "avoid.robot.calibration_dilate_m: must be at most calibration_step_m"),
            ("calibration_threshold_m = 0.10", "calibration_threshold_m = 0.05", "avoid.robot.calibration_threshold_m: must be above fit.offset_m"),
            ("max_time_s = 12.0", "max_time_s = 600", "avoid.frame_period_s: 18183 frames"),
            ("max_time_s = 12.0;dt_s = 0.01", "max_time_s = 200;dt_s = 0.0001", "avoid.dt_s: max_time_s / dt_s = 2e6 control steps"),
            ("camera_height_m = 1.2", "camera_height_m = 0.3", "avoid.robot.wrist_height_m: must be below the camera"),
        ] {
            let e = refused(from, to);
            assert!(e.contains(key), "{to}: {e}");
        }
    }
}
