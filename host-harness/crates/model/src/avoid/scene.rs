//! The avoidance scene (TOML, table `[avoid]`): documented key by key in `docs/avoidance.md`; read
//! and checked by the scene loader's tables (`scene/avoid/`: keys, units, ranges with their
//! sources, defaults), which build these structs.

use super::shapes::{Camera, Obstacle, OperatorShape, RobotShape};

/// `[avoid]`: the task, the potential field and the simulation.
#[derive(Clone, Debug)]
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
    pub latch_height_m: f64,
    /// Speed scaling starts at this height of `f*`, m.
    pub slow_height_m: f64,
    /// Speed is zero at this height of `f*`, m.
    pub stop_height_m: f64,
    /// A stall: the tool moved less than `stall_move_m` in `stall_window_s` away from the goal.
    pub stall_window_s: f64,
    /// See `stall_window_s`, m.
    pub stall_move_m: f64,
    /// Progress monitor: the tool must get `progress_m` closer to the goal than it has ever been
    /// within every `progress_window_s` (time in a protective stop not counted), or the run stops with
    /// `stalled` (it barely moved) or `no_path` (it moved without approaching: orbiting, climbing), s.
    pub progress_window_s: f64,
    /// See `progress_window_s`, m.
    pub progress_m: f64,
    /// Capture-to-command latency: a frame taken at `t` reaches the controller at `t + latency_s`
    /// (capture, fit and transmission; the thesis measured 81 ms), s.
    pub latency_s: f64,
    /// The clearance asked for: the tool's surface (the wrist disc, `robot.wrist_radius_m` round the
    /// tool point) must stay at least this far from the operator; a run that comes closer is not
    /// `reached`. The monitor adds it to its protective separation, m.
    pub clearance_m: f64,
    /// The serial line's baud rate (8N1: 10 bits a byte), if modelled: each frame then reaches the
    /// controller `latency_s` plus its transmission time after capture, and a line too slow for one
    /// frame per `frame_period_s` is refused. Absent: the transmission is taken to be inside
    /// `latency_s` (the thesis's 81 ms is capture to command).
    pub baud: Option<u32>,
    /// Speed and separation monitoring.
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
    pub depth_camera: Option<super::depth_camera::DepthCameraCfg>,
    /// Power and force limiting beside the monitor (`[avoid.pfl]`), if the scene allows contact.
    pub pfl: Option<PflCfg>,
}

/// `[avoid.pfl]`: power and force limiting (ISO/TS 15066 5.5.5) beside speed and separation
/// monitoring. The speeds come from the module scene by the computation of `flinch design
/// --body-region` ([`PflCfg::resolved`], filled in by `flinch_studies::body_design::resolve_pfl`
/// before a run; a run refuses a scene whose PFL is not resolved).
#[derive(Clone, Debug)]
pub struct PflCfg {
    /// The module scene (a `[target] kind = "body_region"` scene: its module, robot, dead time,
    /// contact kind and area), as written, and resolved against the avoidance scene's directory.
    pub module: String,
    /// See `module`: the path the run reads.
    pub module_path: std::path::PathBuf,
    /// The body regions that may be touched (ISO/TS 15066 Table A.2 names); the speeds are the
    /// smallest over them.
    pub body_regions: Vec<String>,
    /// The module's axis in the cell's plane (normalised by the loader): it yields along it only.
    pub axis: [f64; 2],
    /// The speeds, once computed.
    pub resolved: Option<PflResolved>,
}

/// The PFL speeds of a module on its robot and their provenance: what the board receives.
#[derive(Clone, Debug, PartialEq)]
pub struct PflResolved {
    /// Along the module's axis, with the module: the smallest over the regions of the largest speed
    /// at which the run is safe (body limits and stroke), m/s.
    pub along_mps: f64,
    /// The region that set `along_mps`.
    pub along_region: String,
    /// Across the axis: a rigid tool's speed (the module does not yield there), m/s.
    pub across_mps: f64,
    /// The region that set `across_mps`.
    pub across_region: String,
    /// The force limit of `along_region` (ISO/TS 15066 Table A.2, the contact kind's), N.
    pub along_force_limit_n: f64,
    /// "transient" or "quasi_static": the module scene's contact.
    pub contact: String,
    /// SHA-256 of the module scene's text, hex.
    pub module_sha256: String,
}


/// `[avoid.safety]`: speed and separation monitoring (ISO/TS 15066, 5.5.4) after the field.
#[derive(Clone, Debug)]
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
    /// Only a whole (walking) body can approach, never a reaching hand or arm: ISO 13855 6.2's
    /// 1.6 m/s beyond 0.5 m applies. False (the default): `K = max(2.0 m/s, v_h)` everywhere.
    pub whole_body_only: bool,
    /// A sensed pixel inside a fixture's footprint is the fixture's only when it is no higher than
    /// the fixture's `height_m` plus this (the depth noise), m; anything higher there (a hand over
    /// the tray) is a person.
    pub fixture_tolerance_m: f64,
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


/// `[avoid.camera]`.
#[derive(Clone, Debug)]
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
#[derive(Clone, Debug)]
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
    pub remove_plane: bool,
}


/// `[avoid.robot]`.
#[derive(Clone, Debug)]
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
    pub calibration_dilate_m: f64,
    /// `"model"` (default): clear only the pixels the robot's own height model explains;
    /// `"calibration"`: the thesis's masks (5.2.1), which also clear whatever is near the robot.
    pub removal: String,
    /// With `removal = "model"`: a pixel on the robot is cleared when it is no higher than the
    /// robot there plus this, m.
    pub removal_margin_m: f64,
}


/// `[avoid.operator]`.
#[derive(Clone, Debug)]
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
    pub obstacles: Vec<Obstacle>,
}

/// One key frame of the hand.
#[derive(Clone, Debug)]
pub struct Keyframe {
    /// Time, s.
    pub t_s: f64,
    /// Hand centre, m.
    pub hand_m: [f64; 2],
}

impl Avoid {
    /// Everything as the thesis wrote it, for comparison: no monitor, calibration masks, no plane
    /// removal (`flinch avoid --thesis`).
    pub fn thesis_mode(&mut self) {
        self.safety.mode = "off".into();
        self.robot.removal = "calibration".into();
        self.fit.remove_plane = false;
        // The thesis has no power and force limiting: its law is judged on contact alone.
        self.pfl = None;
    }

    /// Image extent on the plane, m.
    pub fn extent_m(&self) -> (f64, f64) {
        (self.camera.width_px as f64 * self.camera.m_per_px, self.camera.height_px as f64 * self.camera.m_per_px)
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

    /// [`Self::signed_distance_m`] to the people only (hand, forearm, obstacles that are not
    /// fixtures), m.
    pub fn person_signed_distance_m(&self, t: f64, p: [f64; 2]) -> f64 {
        let mut op = self.operator_shape_at(t);
        op.obstacles.retain(|o| !o.fixture);
        op.signed_distance(self.hand_at(t), p) - self.robot.wrist_radius_m
    }

    /// Signed distance from the tool's surface to the nearest fixture (`class = "fixture"`, standing),
    /// m; infinite when the scene has none.
    pub fn fixture_signed_distance_m(&self, p: [f64; 2]) -> f64 {
        self.operator.obstacles.iter().filter(|o| o.fixture).map(|o| o.signed_distance(p) - self.robot.wrist_radius_m).fold(f64::INFINITY, f64::min)
    }

    /// Whether the scene declares any fixture.
    pub fn has_fixtures(&self) -> bool {
        self.operator.obstacles.iter().any(|o| o.fixture)
    }

    /// Signed plan distance from the robot's link (base to the tool at `p`, 3-D: only parts that
    /// reach its underside count) to the operator and the obstacles at time `t`, m (negative
    /// inside; infinite when nothing reaches its height): `super::link`.
    pub fn link_signed_distance_m(&self, t: f64, p: [f64; 2]) -> f64 {
        super::link::link_signed_distance(&self.robot_shape(), p, &self.operator_shape_at(t), self.hand_at(t))
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

    const SHIPPED: &str = include_str!("../../../../../scenes/avoid_thesis_reach.toml");

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
        assert!(e.contains("avoid.operator.obstacles[0].keyframes[1].t_s: must be after the key frame before it (avoid.operator.obstacles[0].keyframes[0].t_s = 0 s): key frames' t_s must increase, got 0"), "{e}");
        assert!(e.starts_with("line 63: "), "the key frame's line: {e}");
        let e = bad("x_m = 1.40", "x_m = 3.0");
        assert!(e.starts_with("line 64: "), "{e}");
        assert!(e.contains("avoid.operator.obstacles[0].keyframes[2].x_m: must be inside the image, [0, 2.1] m, got 3"), "{e}");
        let e = bad("y_m = 1.90", "y_m = nan");
        assert!(e.starts_with("line 62: avoid.operator.obstacles[0].keyframes[0].y_m: must be a finite number; allowed range [-10, 10] m") && e.ends_with("got NaN"), "{e}");
        let e = bad("radius_m = 0.10", "radius_m = 0.10\ncenter_m = [1.0, 1.0]");
        assert!(e.contains("avoid.operator.obstacles[0].center_m: give center_m (standing) or keyframes (moving), not both"), "{e}");
    }

    const MOVING: &str = include_str!("../../../../../scenes/avoid_moving_disc_wide.toml");
}
