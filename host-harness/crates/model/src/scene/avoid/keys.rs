//! The keys of an avoidance scene, each declared once (type, unit, physical range with its source,
//! default, doc line), the tables that list them (`KEYS`, `SAFETY_KEYS`, ...; the loader, the docs and
//! the property tests read them) and the caps on the work a scene may ask for.

use crate::scene::check::{Bound::*, Key, Ty};

/// Where points may lie: the plane one camera sees.
pub(crate) const PLANE: &str = "a point on the work plane one ceiling camera sees, at most 10 m across (the thesis's plane: 1.05 m)";

/// Heights above the work plane.
pub(crate) const HEIGHT: &str = "a height above the work plane, below a ceiling camera (the thesis's camera: 1.2 m up)";

/// Sizes of the robot's and the operator's parts.
pub(crate) const PART: &str = "a part of an arm or a hand seen from above: up to 0.5 m across (shipped: 0.045-0.07 m)";

pub(crate) const fn point(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Incl(-10.0), Incl(10.0), PLANE, doc)
}

pub(crate) const fn height(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Excl(0.0), Incl(2.0), HEIGHT, doc)
}

pub(crate) const fn part(name: &'static str, doc: &'static str) -> Key {
    Key::number(name, "m", Excl(0.0), Incl(0.5), PART, doc)
}

/// Keys holding `[x, y]` (two numbers, each in the key's range), not one number.
pub const POINTS: &[&str] = &["start_m", "goal_m", "base_m", "entry_m", "hand_m", "position_m", "center_m", "size_m", "axis"];

pub(crate) const START: Key = point("start_m", "[x, y] start of the tool");

pub(crate) const GOAL: Key = point("goal_m", "[x, y] goal of the tool");

pub(crate) const SPEED: Key = Key::number(
    "speed_mps",
    "m/s",
    Excl(0.0),
    Incl(3.0),
    "k_a of eq 74, the cruise speed: above the top tool speed of collaborative arms (about 1-3 m/s); shipped 0.25 m/s",
    "k_a of eq 74, cruise speed",
);

pub(crate) const K_REP: Key = Key::number(
    "k_rep",
    "m/s",
    Incl(0.0),
    Incl(100.0),
    "k_r of eq 75/76 per unit gradient of f*: shipped 0.6, and 50 in avoid_extreme_gain.toml, the unsafe extreme studied",
    "k_r of eq 75/76, m/s per unit gradient",
);

pub(crate) const DT: Key = Key::number(
    "dt_s",
    "s",
    Incl(1e-4),
    Incl(0.1),
    "eq 79's control period: robot controllers run at 1-8 ms, the thesis's MATLAB loop took 81 ms (5.3)",
    "control period dt of eq 79",
);

pub(crate) const FRAME: Key = Key::number(
    "frame_period_s",
    "s",
    Incl(0.005),
    Incl(1.0),
    "depth cameras give 1-200 frames/s (the thesis's Kinect: 30 Hz)",
    "camera frame period (a new fit every frame)",
);

pub(crate) const MAX_TIME: Key = Key::number(
    "max_time_s",
    "s",
    Excl(0.0),
    Incl(600.0),
    "a crossing of the workspace takes seconds (shipped 4-12 s); 600 s bounds the run time",
    "give up after this long",
);

pub(crate) const GOAL_TOL: Key = Key::number(
    "goal_tolerance_m",
    "m",
    Excl(0.0),
    Incl(0.1),
    "a positioning tolerance, up to 10 cm (shipped 1 cm)",
    "goal reached within this distance",
);

pub(crate) const CAPTURE: Key = Key::number(
    "capture_radius_m",
    "m",
    Excl(0.0),
    Incl(1.0),
    "within the plane one camera sees (shipped 3 cm)",
    "attraction falls off linearly inside this radius",
);

pub(crate) const LATCH: Key = Key::number("latch_height_m", "m", Incl(0.0), Incl(2.0), HEIGHT, "vortex sign latched while f* is above this").default(0.02);

pub(crate) const SLOW: Key = Key::number("slow_height_m", "m", Incl(0.0), Incl(2.0), HEIGHT, "speed scaling starts at this height of f*");

pub(crate) const STOP: Key = height("stop_height_m", "speed is zero at this height of f* (above slow_height_m)");

pub(crate) const STALL_WINDOW: Key = Key::number(
    "stall_window_s",
    "s",
    Excl(0.0),
    Incl(60.0),
    "a stall is judged over a fraction of a second to seconds (default 0.5 s)",
    "stall window",
)
.default(0.5);

pub(crate) const STALL_MOVE: Key = Key::number("stall_move_m", "m", Excl(0.0), Incl(1.0), "a distance on the plane, up to 1 m (default 5 mm)", "stall: moved less than this in stall_window_s").default(0.005);

pub(crate) const PROGRESS_WINDOW: Key = Key::number(
    "progress_window_s",
    "s",
    Excl(0.0),
    Incl(600.0),
    "at most max_time_s's bound (default 2 s)",
    "progress monitor window",
)
.default(2.0);

pub(crate) const PROGRESS: Key = Key::number("progress_m", "m", Excl(0.0), Incl(1.0), "a distance on the plane, up to 1 m (default 2 cm)", "progress monitor: the least gain towards the goal per window").default(0.02);

pub(crate) const LATENCY: Key = Key::number(
    "latency_s",
    "s",
    Incl(0.0),
    Incl(1.0),
    "capture to command: the thesis measured 0.081 +- 0.008 s (5.3); 1 s is 12 times that",
    "capture-to-command latency",
)
.default(0.081);

pub(crate) const CLEARANCE: Key = Key::number(
    "clearance_m",
    "m",
    Incl(0.0),
    Incl(1.0),
    "the clearance asked for between the tool's surface and a person: centimetres; 1 m is beyond any cell's separation",
    "a reached goal must have kept at least this from the operator; added to the protective separation",
)
.default(0.02);

pub(crate) const BAUD: Key = Key::number("baud", "bit/s", Incl(300.0), Incl(2e7), "UART rates of MCUs: 300 baud to 20 Mbaud (8N1, 10 bits a byte)", "serial line rate, a whole number; a frame takes its bytes' time to arrive").optional("not modelled");

pub(crate) const SAFETY: Key = Key::of("safety", Ty::Table("speed and separation monitoring"), "[avoid.safety]").optional("the defaults");

pub(crate) const CAMERA: Key = Key::of("camera", Ty::Table("the synthetic depth camera"), "[avoid.camera]");

pub(crate) const FIT: Key = Key::of("fit", Ty::Table("the RBF fit"), "[avoid.fit]");

pub(crate) const ROBOT: Key = Key::of("robot", Ty::Table("the robot as the camera sees it"), "[avoid.robot]");

pub(crate) const OPERATOR: Key = Key::of("operator", Ty::Table("the operator and its motion"), "[avoid.operator]");

pub(crate) const PFL: Key = Key::of("pfl", Ty::Table("power and force limiting beside the monitor (ISO/TS 15066 5.5.5)"), "[avoid.pfl]").optional("no contact permitted: SSM alone");

pub(crate) const DEPTH_CAMERA: Key = Key::of("depth_camera", Ty::Table("the pinhole camera of recorded depth frames (flinch avoid --depth)"), "[avoid.depth_camera]").optional("no recorded input (--depth is refused)");

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
    START, GOAL, SPEED, K_REP, REPULSION, DT, FRAME, MAX_TIME, GOAL_TOL, CAPTURE, LATCH, SLOW, STOP, STALL_WINDOW, STALL_MOVE, PROGRESS_WINDOW, PROGRESS, LATENCY, CLEARANCE, BAUD, SAFETY, CAMERA, FIT, ROBOT, OPERATOR, DEPTH_CAMERA, PFL,
];

/// The repulsion laws, as `avoid::scene::Avoid::repulsion_law` reads them.
pub const REPULSIONS: &[&str] = &["vortex", "vortex_cw", "vortex_ccw", "gradient"];

pub(crate) const REPULSION: Key = Key::of(
    "repulsion",
    Ty::Choice(REPULSIONS),
    "eq 76's vortex (sign from the motion, or fixed clockwise / counter-clockwise), or eq 75's gradient",
)
.optional("\"vortex\"");

/// The top level of an avoidance scene: only `[avoid]`.
pub(crate) const AVOID: Key = Key::of("avoid", Ty::Table("the avoidance scene"), "[avoid]");

pub(crate) const MODE: Key = Key::of(
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
    Key::number("fixture_tolerance_m", "m", Incl(0.0), Incl(0.1), "the depth noise: a few mm (10 mm is 3.3 sigma of the synthetic camera's 3 mm); 0.1 m bounds it", "a pixel in a fixture's footprint at most this above its height_m is the fixture's, else a person's").default(0.01),
    WHOLE_BODY,
];

pub(crate) const WHOLE_BODY: Key = Key::of(
    "whole_body_only",
    Ty::Bool,
    "only a whole walking body can approach (no hand or arm can reach in): K may fall to v_h beyond 0.5 m (ISO 13855:2010 6.2); otherwise K = max(2.0 m/s, v_h) at every distance",
)
.optional("false");

pub(crate) const PFL_MODULE: Key = Key::of(
    "module",
    Ty::Text,
    "the module scene (relative to this file): a [target] kind = \"body_region\" scene whose module, robot, dead time, contact and area give the PFL speeds, computed as flinch design --body-region does",
);

pub(crate) const PFL_REGIONS: Key = Key::of("body_regions", Ty::List(crate::body::REGION_NAMES), "the body regions that may be touched (ISO/TS 15066 Table A.2); the PFL speeds are the smallest over them; face and skull are refused (no contact permitted)");

pub(crate) const PFL_AXIS: Key = Key::number("axis", "", Incl(-1.0), Incl(1.0), "a direction in the plane, normalised by the loader: the module yields along it (a 1-D decoupler), as rigid as without it across it", "[x, y] of the module's axis in the cell's frame");

/// `[avoid.pfl]`.
pub const PFL_KEYS: &[Key] = &[PFL_MODULE, PFL_REGIONS, PFL_AXIS];

pub(crate) const WIDTH: Key = Key::integer("width_px", 8, 2000, "depth cameras have 320-1280 columns; the thesis's image is 210 px", "image columns");

pub(crate) const HEIGHT_PX: Key = Key::integer("height_px", 8, 2000, "depth cameras have 240-1024 rows; the thesis's image is 210 px", "image rows");

pub(crate) const M_PER_PX: Key = Key::number(
    "m_per_px",
    "m",
    Incl(2e-4),
    Incl(0.05),
    "a depth camera 0.5-4.5 m above the plane gives about 1-10 mm per pixel (the thesis: 5 mm)",
    "pixel size on the plane",
);

pub(crate) const CAMERA_HEIGHT: Key = Key::number(
    "camera_height_m",
    "m",
    Incl(0.3),
    Incl(5.0),
    "the working range of Kinect-class depth cameras, 0.5-4.5 m (the thesis: 1.2 m)",
    "camera above the plane",
);

pub(crate) const SEED: Key = Key::integer("seed", 0, u32::MAX, "any whole number >= 0 (up to 2^63 - 1): it only picks the noise", "RNG seed of the synthetic noise and null pixels");

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

pub(crate) const OFFSET: Key = Key::number("offset_m", "m", Incl(0.0), Incl(0.5), "the thesis raises the image by about 0.065 m (5.2)", "raise before fitting");

pub(crate) const REMOVE_PLANE: Key = Key::of("remove_plane", Ty::Bool, "subtract the raised empty plane's own weights before eq 71 (without it the plane's border weights survive the threshold as walls up to 0.1 m high)").optional("true");

/// `[avoid.fit]`.
pub const FIT_KEYS: &[Key] = &[
    Key::integer("grid", 1, 30, "the thesis's 15 x 15 and 30 x 30 grids; the firmware holds at most 30 per axis (MAX_AXIS)", "centres across the width"),
    Key::number("sigma_factor", "", Incl(0.1), Incl(10.0), "1 is eq 70 (sigma = spacing / 2); a tenth to ten times that", "fit sigma in units of eq 70"),
    Key::number("eval_sigma_factor", "", Incl(0.1), Incl(10.0), "Fig. 90 widens by 1.5; a tenth to ten times the fit's", "evaluation sigma in units of the fit sigma"),
    OFFSET,
    REMOVE_PLANE,
];

pub(crate) const STEP: Key = Key::number(
    "calibration_step_m",
    "m",
    Incl(0.005),
    Incl(0.5),
    "d of Fig. 84: a zig-zag of 5 mm to 0.5 m steps (shipped 0.05 m)",
    "zig-zag step d of Fig. 84",
);

pub(crate) const THRESHOLD: Key = height("calibration_threshold_m", "cut height of the interpolated robot (Fig. 85), above fit.offset_m");

pub(crate) const DILATE: Key = Key::number(
    "calibration_dilate_m",
    "m",
    Incl(0.0),
    Incl(0.5),
    "0 is the thesis's plain cut; about d / sqrt 2 covers the robot between positions; at most calibration_step_m",
    "growth of each mask",
)
.default(0.0);

pub(crate) const REMOVAL: Key = Key::of(
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

pub(crate) const HAND_KEYFRAMES: Key = Key::of("keyframes", Ty::Table("a list of at least one key frame { t_s, hand_m }, t_s increasing"), "hand position over time: linear between key frames, held after the last");

pub(crate) const OBSTACLES: Key = Key::of("obstacles", Ty::Table("a list of [[avoid.operator.obstacles]] tables"), "further obstacles, standing or moving").optional("none");

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

pub(crate) const OB_KIND: Key = Key::of("kind", Ty::Choice(OBSTACLE_KINDS), "footprint: a disc (radius_m) or an axis-aligned box (size_m)");

pub(crate) const OB_CENTER: Key = point("center_m", "[x, y] centre of a standing obstacle, inside the image").optional("a moving obstacle: keyframes instead");

pub(crate) const OB_KEYFRAMES: Key = Key::of("keyframes", Ty::Table("a list of key frames { t_s, x_m, y_m }, t_s increasing"), "centre over time: linear between key frames, held before the first and after the last").optional("a standing obstacle at center_m");

pub(crate) const OB_HEIGHT: Key = Key::number("height_m", "m", Incl(0.001), Incl(2.0), "an obstacle's top above the plane, from a 1 mm plate to 2 m (a person standing)", "top above the plane");

/// Sizes of obstacles.
pub(crate) const OBSTACLE_SIZE: &str = "an obstacle on the plane one camera sees: at most 10 m across (shipped: 0.05-1.05 m)";

pub(crate) const OB_RADIUS: Key = Key::number("radius_m", "m", Excl(0.0), Incl(10.0), OBSTACLE_SIZE, "disc radius");

pub(crate) const OB_SIZE: Key = Key::number("size_m", "m", Excl(0.0), Incl(10.0), OBSTACLE_SIZE, "[x, y] box size along x and y");

/// The classes of `[[avoid.operator.obstacles]]`.
pub const OBSTACLE_CLASSES: &[&str] = &["person", "fixture"];

pub(crate) const OB_CLASS: Key = Key::of(
    "class",
    Ty::Choice(OBSTACLE_CLASSES),
    "\"person\": a person's body (the monitor budgets a human approach at K); \"fixture\": a standing tray, jig or wall (the tool keeps its clearance without a human approach; contact is a collision; needs center_m, not keyframes). The sensor classes a pixel as the fixture's only inside its footprint and no higher than height_m + safety.fixture_tolerance_m",
)
.optional("\"person\"");

/// `[[avoid.operator.obstacles]]` with `kind = "disc"`.
pub const DISC_KEYS: &[Key] = &[OB_KIND, OB_CENTER, OB_KEYFRAMES, OB_RADIUS, OB_HEIGHT, OB_CLASS];

/// `[[avoid.operator.obstacles]]` with `kind = "box"`.
pub const BOX_KEYS: &[Key] = &[OB_KIND, OB_CENTER, OB_KEYFRAMES, OB_SIZE, OB_HEIGHT, OB_CLASS];

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
