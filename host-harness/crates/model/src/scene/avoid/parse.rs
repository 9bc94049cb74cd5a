//! Reads `[avoid]` into `crate::avoid::scene::Avoid`, table by table, every problem at once; the
//! entry points (`parse`, `Avoid::load`, `Avoid::parse`) and the safety table's defaults.

use crate::scene::check::{num, Ctx, SceneError, SceneIssue, Tab};
use crate::avoid::depth_camera::DepthCameraCfg;
use crate::avoid::shapes::{Obstacle, ObstacleKeyframe};
use crate::avoid::scene::{Avoid, CameraCfg, FitCfg, Keyframe, OperatorCfg, PflCfg, RobotCfg, SafetyCfg};
use std::path::Path;
use super::{keys::*, values::*, checks::*};

/// Reads and checks an avoidance scene given as text; `file` names it in the messages.
pub fn parse(text: &str, file: &str) -> Result<Avoid, SceneError> {
    let doc = crate::scene::check::parse_toml(text, file)?;
    let mut cx = Ctx { text, file, issues: Vec::new(), tables: crate::scene::key_tables() };
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

/// `[avoid]` and everything in it.
pub(crate) fn read_avoid(cx: &mut Ctx, t: &Tab) -> Option<Avoid> {
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
    let pfl = match cx.maybe_table(t, &PFL) {
        Some(Some(p)) => pfl(cx, &p).map(Some),
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
        pfl: pfl?,
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
    let mut cx = Ctx { text: "", file: "", issues: Vec::new(), tables: crate::scene::key_tables() };
    let t = Tab { path: "avoid.safety".into(), t: &empty, line: None };
    let s = safety(&mut cx, &t);
    debug_assert!(cx.issues.is_empty(), "{:?}", cx.issues);
    s.expect("the defaults of SAFETY_KEYS are in their ranges")
}

pub(crate) fn safety(cx: &mut Ctx, t: &Tab) -> Option<SafetyCfg> {
    cx.check_keys(t, SAFETY_KEYS, "");
    let mode = choice_or(cx, t, &MODE, "ssm");
    // The number keys (between `mode` and `whole_body_only`).
    let numbers = &SAFETY_KEYS[1..SAFETY_KEYS.len() - 1];
    let v: Vec<Option<f64>> = numbers.iter().map(|k| cx.number(t, k)).collect();
    let g = |name: &str| numbers.iter().position(|k| k.name == name).and_then(|i| v[i]);
    Some(SafetyCfg {
        mode: mode?,
        human_speed_mps: g("human_speed_mps")?,
        reaction_time_s: g("reaction_time_s")?,
        stopping_time_s: g("stopping_time_s")?,
        intrusion_m: g("intrusion_m")?,
        sensor_uncertainty_m: g("sensor_uncertainty_m")?,
        robot_uncertainty_m: g("robot_uncertainty_m")?,
        sense_height_m: g("sense_height_m")?,
        fixture_tolerance_m: g("fixture_tolerance_m")?,
        whole_body_only: cx.boolean(t, &WHOLE_BODY)?.unwrap_or(false),
    })
}

/// `[avoid.pfl]`: the module scene resolved against the scene file's directory, the regions (face
/// and skull refused: ISO/TS 15066 Table A.2 permits no contact there), the axis normalised.
pub(crate) fn pfl(cx: &mut Ctx, t: &Tab) -> Option<PflCfg> {
    cx.check_keys(t, PFL_KEYS, "");
    let module = cx.string(t, &PFL_MODULE);
    let regions = cx.list(t, &PFL_REGIONS);
    let axis = xy(cx, t, &PFL_AXIS);
    let regions: Vec<String> = regions?.into_iter().map(|i| crate::body::REGION_NAMES[i].to_string()).collect();
    if regions.is_empty() {
        cx.bad(t, PFL_REGIONS.name, "must name at least one region that may be touched (for example [\"hand\"]); without any, leave [avoid.pfl] out".into());
        return None;
    }
    if let Some(r) = regions.iter().find(|r| matches!(r.as_str(), "face" | "skull")) {
        cx.bad(t, PFL_REGIONS.name, format!("{r:?}: ISO/TS 15066 Table A.2 permits no contact with the face or the skull; a cell where they can be reached needs SSM alone there"));
        return None;
    }
    let axis = axis?;
    let n = axis[0].hypot(axis[1]);
    if !(n >= 1e-3) {
        cx.bad(t, PFL_AXIS.name, format!("must be a direction (length at least 0.001), got [{}, {}]", num(axis[0]), num(axis[1])));
        return None;
    }
    let module = module?;
    let module_path = std::path::Path::new(cx.file).parent().map_or_else(|| std::path::PathBuf::from(&module), |d| d.join(&module));
    Some(PflCfg { module, module_path, body_regions: regions, axis: [axis[0] / n, axis[1] / n], resolved: None })
}

pub(crate) fn camera(cx: &mut Ctx, t: &Tab) -> Option<CameraCfg> {
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

pub(crate) fn fit(cx: &mut Ctx, t: &Tab) -> Option<FitCfg> {
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

pub(crate) fn robot(cx: &mut Ctx, t: &Tab) -> Option<RobotCfg> {
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

pub(crate) fn operator(cx: &mut Ctx, t: &Tab) -> Option<OperatorCfg> {
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

/// One `[[avoid.operator.obstacles]]`: its kind's keys.
pub(crate) fn obstacle(cx: &mut Ctx, t: &Tab) -> Option<Obstacle> {
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
    let class = cx.maybe_choice(t, &OB_CLASS, OBSTACLE_CLASSES);
    let (center_m, keyframes) = (center_m?, keyframes?);
    let fixture = class? == Some("fixture");
    if fixture && !keyframes.is_empty() {
        cx.bad(t, OB_CLASS.name, "a fixture stands still: give center_m, not keyframes (a moving obstacle is a person's)".into());
        return None;
    }
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
        fixture,
    })
}

pub(crate) fn depth_camera(cx: &mut Ctx, t: &Tab) -> Option<DepthCameraCfg> {
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

impl Avoid {
    /// Read and validate a scene: a file, `-`, or a shipped scene's name (`avoid_wall`); every
    /// problem on its own line, `file:line: avoid.key: what is allowed, got value`.
    pub fn load(path: &Path) -> Result<Self, String> {
        let (file, text) = crate::shipped::read(path).map_err(|e| e.0)?;
        parse(&text, &file).map_err(|e| e.to_string())
    }

    /// Parse and validate scene text: every problem on its own line, `line N: avoid.key: what is
    /// allowed, got value`.
    pub fn parse(text: &str) -> Result<Self, String> {
        parse(text, "").map_err(|e| without_file(&e))
    }
}

impl Default for SafetyCfg {
    /// Every key at its default: the defaults of `scene::avoid::SAFETY_KEYS` (ISO 13855's finger,
    /// d = 14 mm, for `sense_height_m`: every part of a body is thicker, so with pixels no larger
    /// than 10 mm no intrusion distance is needed).
    fn default() -> Self {
        default_safety()
    }
}
