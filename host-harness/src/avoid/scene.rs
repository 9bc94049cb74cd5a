//! The avoidance scene file (TOML, table `[avoid]`): documented key by key in `docs/avoidance.md`.

use serde::Deserialize;
use std::path::Path;

use super::depth::{Camera, OperatorShape, RobotShape};

/// `[avoid]`: the task, the potential field and the simulation.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Avoid {
    /// Start of the tool, m.
    pub start_m: [f64; 2],
    /// Goal of the tool, m.
    pub goal_m: [f64; 2],
    /// `k_a` of eq 74: cruise speed, m/s.
    pub speed_mps: f64,
    /// `k_r` of eq 75/76, m/s per unit gradient.
    pub k_rep: f64,
    /// `"vortex"` (eq 76, sign from the motion), `"vortex_cw"`, `"vortex_ccw"` or `"gradient"` (eq 75).
    #[serde(default = "default_repulsion")]
    pub repulsion: String,
    /// Control period `dt` of eq 79, s.
    pub dt_s: f64,
    /// Camera frame period (a new fit every frame), s.
    pub frame_period_s: f64,
    /// Give up after this long, s.
    pub max_time_s: f64,
    /// Goal reached within this distance, m.
    pub goal_tolerance_m: f64,
    /// Attraction falls off linearly inside this radius, m.
    pub capture_radius_m: f64,
    /// Vortex sign latched while `f*` is above this, m.
    #[serde(default = "default_latch")]
    pub latch_height_m: f64,
    /// Speed scaling starts at this height of `f*`, m.
    pub slow_height_m: f64,
    /// Speed is zero at this height of `f*`, m.
    pub stop_height_m: f64,
    /// A stall: the tool moved less than `stall_move_m` in `stall_window_s` away from the goal.
    #[serde(default = "default_stall_window")]
    pub stall_window_s: f64,
    /// See `stall_window_s`, m.
    #[serde(default = "default_stall_move")]
    pub stall_move_m: f64,
    /// Progress monitor: the tool must get `progress_m` closer to the goal than it has ever been
    /// within every `progress_window_s` (time in a protective stop not counted), or the run stops with
    /// `stalled` (it barely moved) or `no_path` (it moved without approaching: orbiting, climbing), s.
    #[serde(default = "default_progress_window")]
    pub progress_window_s: f64,
    /// See `progress_window_s`, m.
    #[serde(default = "default_progress")]
    pub progress_m: f64,
    /// Capture-to-command latency: a frame taken at `t` reaches the controller at `t + latency_s`
    /// (capture, fit and transmission; the thesis measured 81 ms), s.
    #[serde(default = "default_latency")]
    pub latency_s: f64,
    /// The clearance asked for: the tool's surface (the wrist disc, `robot.wrist_radius_m` round the
    /// tool point) must stay at least this far from the operator; a run that comes closer is not
    /// `reached`. The monitor adds it to its protective separation, m.
    #[serde(default = "default_clearance")]
    pub clearance_m: f64,
    /// The serial line's baud rate (8N1: 10 bits a byte), if modelled: each frame then reaches the
    /// controller `latency_s` plus its transmission time after capture, and a line too slow for one
    /// frame per `frame_period_s` is refused. Absent: the transmission is taken to be inside
    /// `latency_s` (the thesis's 81 ms is capture to command).
    #[serde(default)]
    pub baud: Option<u32>,
    /// Speed and separation monitoring.
    #[serde(default)]
    pub safety: SafetyCfg,
    /// The camera.
    pub camera: CameraCfg,
    /// The fit.
    pub fit: FitCfg,
    /// The robot as the camera sees it, and its calibration pass.
    pub robot: RobotCfg,
    /// The operator and its motion.
    pub operator: OperatorCfg,
    /// The pinhole camera of recorded frames (`flinch avoid --depth`), if any.
    #[serde(default)]
    pub depth_camera: Option<super::camera::DepthCameraCfg>,
}

fn default_repulsion() -> String {
    "vortex".into()
}
fn default_latch() -> f64 {
    0.02
}
fn default_stall_window() -> f64 {
    0.5
}
fn default_stall_move() -> f64 {
    0.005
}
fn default_latency() -> f64 {
    0.081
}
fn default_clearance() -> f64 {
    0.02
}

/// `[avoid.safety]`: speed and separation monitoring (ISO/TS 15066, 5.5.4) after the field.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyCfg {
    /// `"ssm"` (default): the monitor limits every command; `"off"`: the thesis's law alone (eq 74-79,
    /// for comparison only).
    pub mode: String,
    /// `v_h`, the human's approach speed (ISO 13855, 6.2: 1.6 m/s), m/s.
    pub human_speed_mps: f64,
    /// `T_r`, from the command to the drive braking (one control period plus the drive's delay), s.
    pub reaction_time_s: f64,
    /// `T_s`, the robot's stopping time from the cruise speed, s.
    pub stopping_time_s: f64,
    /// `C`, intrusion distance (ISO 13855, 5.3), m. The monitor uses the larger of this and what the
    /// sensor's detection capability requires ([`SafetyCfg::required_intrusion_m`]).
    pub intrusion_m: f64,
    /// `Z_d`, the sensor's position uncertainty on the plane, m.
    pub sensor_uncertainty_m: f64,
    /// `Z_r`, the robot's position uncertainty, m.
    pub robot_uncertainty_m: f64,
    /// A pixel higher than this above the plane, after robot removal, is an obstacle, m. Anything
    /// thinner is not seen: the intrusion distance the monitor uses grows with it (ISO 13855, 6.2).
    pub sense_height_m: f64,
}

impl Default for SafetyCfg {
    fn default() -> Self {
        SafetyCfg {
            mode: "ssm".into(),
            human_speed_mps: 1.6,
            reaction_time_s: 0.02,
            stopping_time_s: 0.1,
            intrusion_m: 0.0,
            sensor_uncertainty_m: 0.01,
            robot_uncertainty_m: 0.005,
            // ISO 13855's finger (d = 14 mm): every part of a body, a finger lying flat included, is
            // thicker, so with pixels no larger than 10 mm no intrusion distance is needed. With the
            // synthetic camera's 3 mm noise it is 4.7 standard deviations above the plane.
            sense_height_m: 0.014,
        }
    }
}

impl SafetyCfg {
    /// True when the monitor is on.
    pub fn on(&self) -> bool {
        self.mode == "ssm"
    }

    /// The sensor's detection capability `d` (ISO 13855: the smallest object it detects), m:
    /// the larger of what it sees in height (`sense_height_m`: a body part lying thinner on the
    /// plane is invisible) and on the plane (a disc of diameter `sqrt 2` pixels always covers a pixel
    /// centre; anything narrower can fall between them).
    pub fn detection_capability_m(&self, m_per_px: f64) -> f64 {
        self.sense_height_m.max(std::f64::consts::SQRT_2 * m_per_px)
    }

    /// The intrusion distance `C` that detection capability `d` requires (ISO 13855:2010's formula for
    /// electro-sensitive protective equipment of capability `d`, normal approach): 0 for `d <= 14 mm` (a finger is
    /// detected), `8 (d - 14 mm)` up to 40 mm (fingers or a hand can reach that far unseen),
    /// 850 mm above (an arm can reach in unseen), m.
    pub fn required_intrusion_m(&self, m_per_px: f64) -> f64 {
        let d_mm = self.detection_capability_m(m_per_px) * 1e3;
        if d_mm <= 14.0 {
            0.0
        } else if d_mm <= 40.0 {
            8.0 * (d_mm - 14.0) * 1e-3
        } else {
            0.85
        }
    }

    /// The intrusion distance the monitor uses: the configured `intrusion_m`, never less than
    /// [`Self::required_intrusion_m`], m.
    pub fn intrusion_used_m(&self, m_per_px: f64) -> f64 {
        self.intrusion_m.max(self.required_intrusion_m(m_per_px))
    }
}

fn default_progress_window() -> f64 {
    2.0
}
fn default_progress() -> f64 {
    0.02
}

/// `[avoid.camera]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraCfg {
    /// Image columns.
    pub width_px: usize,
    /// Image rows.
    pub height_px: usize,
    /// Pixel size on the plane, m.
    pub m_per_px: f64,
    /// Camera above the plane, m.
    pub camera_height_m: f64,
    /// Depth noise standard deviation, mm.
    pub noise_mm: f64,
    /// Fraction of null pixels.
    pub null_fraction: f64,
    /// RNG seed.
    pub seed: u64,
}

/// `[avoid.fit]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitCfg {
    /// Centres across the width (15 or 30 in the thesis).
    pub grid: usize,
    /// Fit sigma in units of eq 70 (`spacing / 2`).
    pub sigma_factor: f64,
    /// Evaluation sigma in units of the fit sigma (1.5 in Fig. 90).
    pub eval_sigma_factor: f64,
    /// Raise before fitting, m (about 0.065 in the thesis).
    pub offset_m: f64,
    /// Subtract the raised empty plane's own weights before eq 71 (default true): without it the
    /// plane's larger border weights survive the threshold as walls up to ~0.1 m high.
    #[serde(default = "yes")]
    pub remove_plane: bool,
}

fn yes() -> bool {
    true
}

/// `[avoid.robot]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotCfg {
    /// Base position, m.
    pub base_m: [f64; 2],
    /// Wrist/tool radius, m.
    pub wrist_radius_m: f64,
    /// Wrist/tool top above the plane, m.
    pub wrist_height_m: f64,
    /// Link width, m.
    pub link_width_m: f64,
    /// Link top above the plane, m.
    pub link_height_m: f64,
    /// Zig-zag step `d` of Fig. 84, m.
    pub calibration_step_m: f64,
    /// Cut height of the interpolated robot (Fig. 85), m.
    pub calibration_threshold_m: f64,
    /// Growth of each mask, m (0 = the thesis's plain cut).
    #[serde(default)]
    pub calibration_dilate_m: f64,
    /// `"model"` (default): clear only the pixels the robot's own height model explains;
    /// `"calibration"`: the thesis's masks (5.2.1), which also clear whatever is near the robot.
    #[serde(default = "default_removal")]
    pub removal: String,
    /// With `removal = "model"`: a pixel on the robot is cleared when it is no higher than the
    /// robot there plus this, m.
    #[serde(default = "default_removal_margin")]
    pub removal_margin_m: f64,
}

fn default_removal() -> String {
    "model".into()
}
fn default_removal_margin() -> f64 {
    0.02
}

/// `[avoid.operator]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperatorCfg {
    /// Where the forearm enters the image, m.
    pub entry_m: [f64; 2],
    /// Hand radius, m.
    pub hand_radius_m: f64,
    /// Hand top, m.
    pub hand_height_m: f64,
    /// Forearm width, m.
    pub forearm_width_m: f64,
    /// Forearm top, m.
    pub forearm_height_m: f64,
    /// Hand position over time: linear between key frames, held after the last.
    pub keyframes: Vec<Keyframe>,
    /// Further obstacles, `[[avoid.operator.obstacles]]`: `kind = "disc"` (`radius_m`) or
    /// `"box"` (`size_m`), `height_m`, and `center_m` (standing) or `keyframes = [{ t_s, x_m, y_m
    /// }, ...]` (moving).
    #[serde(default)]
    pub obstacles: Vec<super::depth::Obstacle>,
}

/// One key frame of the hand.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time, s.
    pub t_s: f64,
    /// Hand centre, m.
    pub hand_m: [f64; 2],
}

/// Prefix `err` (which starts with `avoid.[table.]key`) with `line N: ` where that key is written.
fn locate(text: &str, err: String) -> String {
    let Some(path) = err.strip_prefix("avoid.").and_then(|r| r.split([' ', ':', '/']).next()) else { return err };
    if let Some(n) = obstacle_line(text, path) {
        return format!("line {}: {err}", n + 1);
    }
    let key = path.rsplit('.').next().unwrap_or(path);
    let found = text.lines().position(|l| {
        let t = l.trim_start();
        t.strip_prefix(key).is_some_and(|r| r.trim_start().starts_with('='))
    });
    match found {
        Some(n) => format!("line {}: {err}", n + 1),
        None => err,
    }
}

/// The line (from 0) of `operator.obstacles[k].key` or `operator.obstacles[k].keyframes[j].key`:
/// in the k-th `[[avoid.operator.obstacles]]` table, the key's line or the j-th key frame's.
fn obstacle_line(text: &str, path: &str) -> Option<usize> {
    let rest = path.strip_prefix("operator.obstacles[")?;
    let (k, rest) = rest.split_once(']')?;
    let k: usize = k.parse().ok()?;
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().enumerate().filter(|(_, l)| l.trim_start().starts_with("[[avoid.operator.obstacles]]")).nth(k)?.0;
    let end = (start + 1..lines.len()).find(|&n| lines[n].trim_start().starts_with('[')).unwrap_or(lines.len());
    if let Some(kf) = rest.strip_prefix(".keyframes[") {
        let j: usize = kf.split_once(']')?.0.parse().ok()?;
        return (start + 1..end).filter(|&n| lines[n].contains("t_s")).nth(j);
    }
    let key = rest.trim_start_matches('.').split(['.', '[']).next()?;
    (start + 1..end).find(|&n| lines[n].trim_start().strip_prefix(key).is_some_and(|r| r.trim_start().starts_with('=')))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    avoid: Avoid,
}

impl Avoid {
    /// Read and validate a scene: a file, `-`, or a shipped scene's name (`avoid_wall`); errors
    /// name the file, the line (when the key is written in the file) and the key:
    /// `file:line: avoid.key = value: what is allowed`.
    pub fn load(path: &Path) -> Result<Self, String> {
        let (file, text) = crate::shipped::read(path).map_err(|e| e.0)?;
        crate::scene::avoid::check(&text, &file)?; // ranges: scene/avoid.rs
        Self::parse(&text).map_err(|e| match e.strip_prefix("line ") {
            Some(rest) => format!("{file}:{rest}"),
            None => format!("{file}: {e}"),
        })
    }

    /// Parse and validate scene text. A validation error starts with `line N: ` when the key it
    /// names is written in the text.
    pub fn parse(text: &str) -> Result<Self, String> {
        crate::scene::avoid::check(text, "")?; // every number's range and the work caps: scene/avoid.rs
        let f: File = toml::from_str(text).map_err(|e| e.to_string().trim_end().to_string())?;
        f.avoid.validate().map_err(|e| locate(text, e))?;
        Ok(f.avoid)
    }

    fn validate(&self) -> Result<(), String> {
        let pos = |k: &str, v: f64| if v > 0.0 && v.is_finite() { Ok(()) } else { Err(format!("avoid.{k} = {v}: must be > 0")) };
        pos("speed_mps", self.speed_mps)?;
        pos("dt_s", self.dt_s)?;
        pos("frame_period_s", self.frame_period_s)?;
        pos("max_time_s", self.max_time_s)?;
        pos("goal_tolerance_m", self.goal_tolerance_m)?;
        pos("capture_radius_m", self.capture_radius_m)?;
        pos("stall_window_s", self.stall_window_s)?;
        pos("progress_window_s", self.progress_window_s)?;
        pos("progress_m", self.progress_m)?;
        let range = |k: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(format!("avoid.{k} = {v}: must be a number in [{lo}, {hi}]"))
            }
        };
        range("latency_s", self.latency_s, 0.0, 10.0)?;
        range("clearance_m", self.clearance_m, 0.0, 1.0)?;
        if let Some(b) = self.baud {
            if !(300..=20_000_000).contains(&b) {
                return Err(format!("avoid.baud = {b}: must be 300..=20000000"));
            }
        }
        if !matches!(self.robot.removal.as_str(), "model" | "calibration") {
            return Err(format!("avoid.robot.removal = {:?}: expected \"model\" or \"calibration\"", self.robot.removal));
        }
        range("robot.removal_margin_m", self.robot.removal_margin_m, 0.0, 1.0)?;
        let sf = &self.safety;
        if !matches!(sf.mode.as_str(), "ssm" | "off") {
            return Err(format!("avoid.safety.mode = {:?}: expected \"ssm\" or \"off\"", sf.mode));
        }
        range("safety.human_speed_mps", sf.human_speed_mps, 0.0, 10.0)?;
        range("safety.reaction_time_s", sf.reaction_time_s, 0.0, 10.0)?;
        range("safety.stopping_time_s", sf.stopping_time_s, 0.0, 10.0)?;
        range("safety.intrusion_m", sf.intrusion_m, 0.0, 1.0)?;
        range("safety.sensor_uncertainty_m", sf.sensor_uncertainty_m, 0.0, 1.0)?;
        range("safety.robot_uncertainty_m", sf.robot_uncertainty_m, 0.0, 1.0)?;
        range("safety.sense_height_m", sf.sense_height_m, 0.001, 1.0)?;
        if self.progress_window_s > self.max_time_s.max(1.0) * 100.0 {
            return Err(format!("avoid.progress_window_s = {}: must be at most 100 x max_time_s", self.progress_window_s));
        }
        pos("camera.m_per_px", self.camera.m_per_px)?;
        pos("camera.camera_height_m", self.camera.camera_height_m)?;
        pos("fit.sigma_factor", self.fit.sigma_factor)?;
        pos("fit.eval_sigma_factor", self.fit.eval_sigma_factor)?;
        pos("robot.calibration_step_m", self.robot.calibration_step_m)?;
        if self.k_rep < 0.0 {
            return Err(format!("avoid.k_rep = {}: must be >= 0", self.k_rep));
        }
        if self.stop_height_m <= self.slow_height_m {
            return Err(format!(
                "avoid.stop_height_m = {} must be above avoid.slow_height_m = {}",
                self.stop_height_m, self.slow_height_m
            ));
        }
        if self.max_time_s / self.dt_s > 1e6 {
            return Err("avoid.max_time_s / avoid.dt_s: more than 1e6 steps".into());
        }
        if !(1..=30).contains(&self.fit.grid) {
            return Err(format!("avoid.fit.grid = {}: must be 1..=30", self.fit.grid));
        }
        if !(8..=2000).contains(&self.camera.width_px) || !(8..=2000).contains(&self.camera.height_px) {
            return Err("avoid.camera.width_px / height_px: must be 8..=2000".into());
        }
        if !(0.0..1.0).contains(&self.camera.null_fraction) {
            return Err(format!("avoid.camera.null_fraction = {}: must be in [0, 1)", self.camera.null_fraction));
        }
        let (w, h) = self.extent_m();
        for (k, p) in [("start_m", self.start_m), ("goal_m", self.goal_m)] {
            if !(0.0..=w).contains(&p[0]) || !(0.0..=h).contains(&p[1]) {
                return Err(format!("avoid.{k} = {p:?}: outside the image (0..{w} x 0..{h} m)"));
            }
        }
        self.repulsion_law()?;
        if self.operator.keyframes.is_empty() {
            return Err("avoid.operator.keyframes: at least one key frame".into());
        }
        for (k, o) in self.operator.obstacles.iter().enumerate() {
            let key = format!("operator.obstacles[{k}]");
            match o.kind.as_str() {
                "disc" => pos(&format!("{key}.radius_m"), o.radius_m)?,
                "box" => {
                    pos(&format!("{key}.size_m[0]"), o.size_m[0])?;
                    pos(&format!("{key}.size_m[1]"), o.size_m[1])?;
                }
                other => return Err(format!("avoid.{key}.kind = {other:?}: expected \"disc\" or \"box\"")),
            }
            range(&format!("{key}.height_m"), o.height_m, 0.001, 2.0)?;
            let written = !o.center_m.iter().all(|v| v.is_nan());
            if o.keyframes.is_empty() {
                if !o.center_m.iter().all(|v| v.is_finite()) {
                    return Err(format!("avoid.{key}.center_m = {:?}: must be finite (a standing obstacle needs center_m, a moving one keyframes)", o.center_m));
                }
                if !(0.0..=w).contains(&o.center_m[0]) || !(0.0..=h).contains(&o.center_m[1]) {
                    return Err(format!("avoid.{key}.center_m = {:?}: outside the image (0..{w} x 0..{h} m)", o.center_m));
                }
            } else if written {
                return Err(format!("avoid.{key}.center_m = {:?}: give center_m (standing) or keyframes (moving), not both", o.center_m));
            }
            for (j, f) in o.keyframes.iter().enumerate() {
                let fk = format!("{key}.keyframes[{j}]");
                range(&format!("{fk}.t_s"), f.t_s, 0.0, 600.0)?;
                range(&format!("{fk}.x_m"), f.x_m, 0.0, w)?;
                range(&format!("{fk}.y_m"), f.y_m, 0.0, h)?;
            }
            if let Some(j) = o.keyframes.windows(2).position(|k| k[1].t_s <= k[0].t_s) {
                return Err(format!("avoid.{key}.keyframes[{}].t_s = {}: t_s must increase (the key frame before is at {} s)", j + 1, o.keyframes[j + 1].t_s, o.keyframes[j].t_s));
            }
        }
        if self.operator.keyframes.windows(2).any(|k| k[1].t_s <= k[0].t_s) {
            return Err("avoid.operator.keyframes: t_s must increase".into());
        }
        Ok(())
    }

    /// Everything as the thesis wrote it, for comparison: no monitor, calibration masks, no plane
    /// removal (`flinch avoid --thesis`).
    pub fn thesis_mode(&mut self) {
        self.safety.mode = "off".into();
        self.robot.removal = "calibration".into();
        self.fit.remove_plane = false;
    }

    /// Image extent on the plane, m.
    pub fn extent_m(&self) -> (f64, f64) {
        (self.camera.width_px as f64 * self.camera.m_per_px, self.camera.height_px as f64 * self.camera.m_per_px)
    }

    /// The repulsion law named by `repulsion`.
    pub fn repulsion_law(&self) -> Result<flinch_firmware::avoidance::Repulsion, String> {
        use flinch_firmware::avoidance::Repulsion;
        Ok(match self.repulsion.as_str() {
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

    /// The synthetic camera.
    pub fn camera(&self) -> Camera {
        let c = &self.camera;
        Camera {
            width_px: c.width_px,
            height_px: c.height_px,
            m_per_px: c.m_per_px,
            camera_height_m: c.camera_height_m,
            noise_mm: c.noise_mm,
            null_fraction: c.null_fraction,
        }
    }

    /// The robot's shape.
    pub fn robot_shape(&self) -> RobotShape {
        let r = &self.robot;
        RobotShape {
            base_m: r.base_m,
            wrist_radius_m: r.wrist_radius_m,
            wrist_height_m: r.wrist_height_m,
            link_width_m: r.link_width_m,
            link_height_m: r.link_height_m,
        }
    }

    /// The operator's shape with every obstacle where it stands at t = 0 (see
    /// [`Avoid::operator_shape_at`] for a moving one).
    pub fn operator_shape(&self) -> OperatorShape {
        self.operator_shape_at(0.0)
    }

    /// The operator's shape with every obstacle where it stands at time `t`, s.
    pub fn operator_shape_at(&self, t: f64) -> OperatorShape {
        let o = &self.operator;
        OperatorShape {
            entry_m: o.entry_m,
            hand_radius_m: o.hand_radius_m,
            hand_height_m: o.hand_height_m,
            forearm_width_m: o.forearm_width_m,
            forearm_height_m: o.forearm_height_m,
            obstacles: o.obstacles.iter().map(|ob| ob.at(t)).collect(),
        }
    }

    /// Signed distance from the tool's surface (the wrist disc of `robot.wrist_radius_m` round the
    /// tool point `p`) to the operator's true footprint at time `t`, m: negative is the depth of the
    /// overlap.
    pub fn signed_distance_m(&self, t: f64, p: [f64; 2]) -> f64 {
        self.operator_shape_at(t).signed_distance(self.hand_at(t), p) - self.robot.wrist_radius_m
    }

    /// Hand position at time `t`.
    pub fn hand_at(&self, t: f64) -> [f64; 2] {
        let k = &self.operator.keyframes;
        let first = &k[0];
        if t <= first.t_s {
            return first.hand_m;
        }
        for w in k.windows(2) {
            if t <= w[1].t_s {
                let a = (t - w[0].t_s) / (w[1].t_s - w[0].t_s);
                return [
                    w[0].hand_m[0] + a * (w[1].hand_m[0] - w[0].hand_m[0]),
                    w[0].hand_m[1] + a * (w[1].hand_m[1] - w[0].hand_m[1]),
                ];
            }
        }
        k[k.len() - 1].hand_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHIPPED: &str = include_str!("../../../scenes/avoid_thesis_reach.toml");

    #[test]
    fn shipped_scene_loads_and_errors_name_the_key() {
        let s = Avoid::parse(SHIPPED).unwrap();
        assert_eq!(s.fit.grid, 15);
        assert_eq!(s.hand_at(0.6), [0.49, 0.26]);
        assert_eq!(s.hand_at(99.0), [0.53, 0.44]);
        let bad = |from: &str, to: &str| Avoid::parse(&SHIPPED.replacen(from, to, 1)).unwrap_err();
        assert!(bad("grid = 15", "grid = 40").contains("avoid.fit.grid: must be an integer in [1, 30], got 40"));
        assert!(bad("repulsion = \"vortex\"", "repulsion = \"swirl\"").contains("avoid.repulsion"));
        assert!(bad("stop_height_m = 0.30", "stop_height_m = 0.01").contains("avoid.stop_height_m"));
        assert!(bad("goal_m = [0.93, 0.50]", "goal_m = [3.0, 0.50]").contains("avoid.goal_m"));
        let e = bad("stall_move_m = 0.005", "stall_move_m = 0.005\nlatency_s = -0.1");
        assert!(e.starts_with("line 24: avoid.latency_s: allowed range [0, 1] s"), "{e}");
        let with_safety = |kv: &str| Avoid::parse(&format!("{SHIPPED}\n[avoid.safety]\n{kv}\n"));
        assert_eq!(with_safety("human_speed_mps = 2.0").unwrap().safety.human_speed_mps, 2.0);
        for (kv, key) in [("human_speed_mps = inf", "avoid.safety.human_speed_mps"), ("stopping_time_s = -1", "avoid.safety.stopping_time_s"), ("mode = \"fast\"", "avoid.safety.mode"), ("sense_height_m = 0", "avoid.safety.sense_height_m")] {
            let e = with_safety(kv).unwrap_err();
            assert!(e.contains(key) && e.starts_with("line "), "{kv}: {e}");
        }
        assert!(with_safety("speed = 1").unwrap_err().contains("speed"));
        let e = bad("stall_move_m = 0.005", "stall_move_m = 0.005\nprogress_m = -1");
        assert!(e.starts_with("line 24: avoid.progress_m: allowed range (0, 1] m"), "{e}");
        assert!(bad("grid = 15", "grid = 40").starts_with("line "), "the line of a nested key");
        assert!(bad("stall_move_m = 0.005", "stall_move_m = 0.005\nprogress_window_s = nan").contains("progress_window_s"));
        let unknown = bad("dt_s = 0.01", "dt_s = 0.01\nspeeed = 1");
        assert!(unknown.contains("speeed") && unknown.contains("line"), "{unknown}");
    }

    /// A moving obstacle's true signed distance follows its key frames (linear between them, held
    /// before the first and after the last), and bad key frames are refused naming the key.
    #[test]
    fn moving_obstacle_signed_distance_follows_its_keyframes() {
        let s = Avoid::parse(MOVING).unwrap();
        let o = &s.operator.obstacles[0];
        assert!(o.moves());
        assert_eq!(o.center_at(-1.0), [1.05, 1.90]);
        assert_eq!(o.center_at(99.0), [1.40, 0.20]);
        let r = s.robot.wrist_radius_m;
        // A point on the disc's path: at t the disc's centre is at (1.05, 1.90 - 1.7 t / 6).
        let p = [1.05, 1.05];
        for t in [0.0, 1.0, 3.0, 4.5, 6.0, 7.5, 9.0, 20.0] {
            let c = o.center_at(t);
            let want = if t <= 6.0 { [1.05, 1.90 - 1.7 * t / 6.0] } else { [1.05 + 0.35 * ((t - 6.0) / 3.0).min(1.0), 0.20] };
            assert!((c[0] - want[0]).abs() < 1e-12 && (c[1] - want[1]).abs() < 1e-12, "t {t}: {c:?} vs {want:?}");
            let sd = s.signed_distance_m(t, p);
            let disc = ((p[0] - want[0]).powi(2) + (p[1] - want[1]).powi(2)).sqrt() - 0.10 - r;
            assert!((sd - disc).abs() < 1e-12, "t {t}: {sd} vs {disc}");
        }
        // At t = 3 s the disc sits on the point: inside (negative), 0.10 m deep less the wrist.
        assert!((s.signed_distance_m(3.0, p) + 0.10 + r).abs() < 1e-12);
        // The depth render sees it where it is: its top over the point at 3 s, not at 0 s.
        assert_eq!(s.operator_shape_at(3.0).height_at(s.hand_at(3.0), p), 0.25);
        assert_eq!(s.operator_shape_at(0.0).height_at(s.hand_at(0.0), p), 0.0);
        let bad = |from: &str, to: &str| Avoid::parse(&MOVING.replacen(from, to, 1)).unwrap_err();
        let e = bad("{ t_s = 6.0, x_m = 1.05", "{ t_s = 0.0, x_m = 1.05");
        assert!(e.contains("avoid.operator.obstacles[0].keyframes[1].t_s = 0: t_s must increase"), "{e}");
        assert!(e.starts_with("line 63: "), "the key frame's line: {e}");
        let e = bad("x_m = 1.40", "x_m = 3.0");
        assert!(e.starts_with("line 64: "), "{e}");
        assert!(e.contains("avoid.operator.obstacles[0].keyframes[2].x_m = 3: must be a number in [0, 2.1"), "{e}");
        let e = bad("y_m = 1.90", "y_m = nan");
        assert!(e.contains("avoid.operator.obstacles[0].keyframes[0].y_m = NaN"), "{e}");
        let e = bad("radius_m = 0.10", "radius_m = 0.10\ncenter_m = [1.0, 1.0]");
        assert!(e.contains("avoid.operator.obstacles[0].center_m = [1.0, 1.0]: give center_m (standing) or keyframes (moving), not both"), "{e}");
    }

    const MOVING: &str = include_str!("../../../scenes/avoid_moving_disc_wide.toml");

    /// The table-driven loader (`scene::avoid::parse`) against the serde path it replaces: every
    /// shipped avoidance scene loads to the identical struct, and of thousands of mutated scenes
    /// none is accepted that the serde path refused; where the serde path accepted and the new
    /// loader refuses, the refusal is one of the tightenings listed here.
    #[test]
    fn table_loader_matches_the_serde_loader() {
        let mut bases: Vec<(String, String)> = crate::shipped::names().filter(|n| n.starts_with("avoid_")).map(|n| (n.to_string(), crate::shipped::get(n).unwrap().to_string())).collect();
        assert!(bases.len() >= 19, "{}", bases.len());
        for (name, text) in &bases {
            let old = Avoid::parse(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            let new = crate::scene::avoid::parse(text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(format!("{old:?}"), format!("{new:?}"), "{name}");
        }
        let cam = "\n[avoid.depth_camera]\nfx_px = 160.0\nfy_px = 160.0\ncx_px = 119.5\ncy_px = 119.5\ndepth_scale_m = 0.001\nposition_m = [1.05, 1.05]\nheight_m = 1.5\n";
        let safety = "\n[avoid.safety]\nmode = \"ssm\"\nhuman_speed_mps = 2.0\nsense_height_m = 0.02\n";
        let hand = bases.iter().find(|b| b.0 == "avoid_operator_hand").unwrap().1.clone();
        bases.push(("with_camera".into(), format!("{hand}{cam}{safety}")));
        const EDGES: &[&str] = &["0", "1", "-1", "0.5", "2", "10", "1e-9", "1e9", "nan", "inf", "5e-324", "9223372036854775807", "9600", "9600.0", "\"x\"", "\"gradient\"", "\"off\"", "\"calibration\"", "\"box\"", "\"disc\"", "true", "[1, 2]", "[0.5, 0.5, 0.5]", "[]", "{ t_s = 1.0, hand_m = [0.5, 0.5] }", "[{ t_s = 0.5, x_m = 0.5, y_m = 0.5 }]"];
        const LINES: &[&str] = &["repulsion = \"gradient\"", "repulsion = \"vortex_cw\"", "baud = 115200", "baud = 9600.0", "seed = -1", "seed = 9223372036854775807", "radius_m = 0.1", "size_m = [0.1, 0.2]", "center_m = [0.5, 0.5]", "center_m = [nan, nan]", "keyframes = []", "remove_plane = false", "remove_plane = 1", "removal = \"calibration\"", "mode = \"off\"", "speeed = 1", "latency_s = 0.5", "progress_window_s = 600", "max_time_s = 1", "[avoid.safety]", "[[avoid.operator.obstacles]]\nkind = \"disc\"\nradius_m = 0.05\nheight_m = 0.1\ncenter_m = [0.5, 0.5]", "[[avoid.operator.obstacles]]\nkind = \"box\"\nsize_m = [0.05, 0.3]\nheight_m = 0.1\nkeyframes = [{ t_s = 0.0, x_m = 0.5, y_m = 0.5 }, { t_s = 2.0, x_m = 0.7, y_m = 0.5 }]", "name = \"x\""];
        let mut rng = 0x5eed_0018_u64;
        let mut next = |n: usize| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng % n as u64) as usize
        };
        let (mut same_ok, mut same_err, mut tightened) = (0, 0, Vec::new());
        for case in 0..4000 {
            let (name, base) = &bases[next(bases.len())];
            let mut t = base.clone();
            for _ in 0..1 + next(2) {
                match next(5) {
                    0 | 1 => {
                        // A value replaced.
                        let lines: Vec<&str> = t.lines().collect();
                        let k = next(lines.len());
                        let l = lines[k];
                        let new = match l.find('=') {
                            Some(i) if !l.trim_start().starts_with('#') => format!("{}= {}", &l[..i], EDGES[next(EDGES.len())]),
                            _ => l.to_string(),
                        };
                        t = lines.iter().enumerate().map(|(i, x)| if i == k { new.clone() } else { x.to_string() }).collect::<Vec<_>>().join("\n");
                    }
                    2 => {
                        let lines: Vec<&str> = t.lines().collect();
                        let k = next(lines.len());
                        t = lines.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, l)| *l).collect::<Vec<_>>().join("\n");
                    }
                    _ => {
                        let lines: Vec<&str> = t.lines().collect();
                        let k = next(lines.len() + 1);
                        let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
                        v.insert(k, LINES[next(LINES.len())].to_string());
                        t = v.join("\n");
                    }
                }
            }
            let old = Avoid::parse(&t);
            let new = crate::scene::avoid::parse(&t, "s.toml");
            match (old, new) {
                (Ok(o), Ok(n)) => {
                    assert_eq!(format!("{o:?}"), format!("{n:?}"), "case {case} from {name}:\n{t}");
                    same_ok += 1;
                }
                (Err(_), Err(_)) => same_err += 1,
                (Err(e), Ok(_)) => panic!("case {case} from {name}: the new loader accepts what the serde path refused ({e}):\n{t}"),
                (Ok(_), Err(e)) => {
                    let e = e.to_string();
                    // Tightenings: a key that does not apply to the obstacle's kind (it was
                    // ignored), an obstacle larger than the plane one camera sees (no bound
                    // before), a NaN centre written beside key frames (ignored before).
                    let known = e.lines().all(|l| {
                        (l.contains("unknown key for kind = ") && (l.contains(".radius_m") || l.contains(".size_m")))
                            || (l.contains("obstacles[") && (l.contains(".radius_m: allowed range (0, 10] m") || l.contains(".size_m: ")))
                            || (l.contains("obstacles[") && l.contains(".center_m: ") && l.contains("NaN"))
                    });
                    assert!(known, "case {case} from {name}: refused now, accepted before: {e}\n{t}");
                    tightened.push(e);
                }
            }
        }
        eprintln!("{same_ok} accepted by both, {same_err} refused by both, {} tightened: {:?}", tightened.len(), tightened.iter().take(5).collect::<Vec<_>>());
        assert!(same_ok > 500 && same_err > 500, "{same_ok} {same_err}");
    }
}
