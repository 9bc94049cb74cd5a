//! The geometry an avoidance scene describes, as it is, not as a camera sees it: the synthetic
//! camera's set-up, the robot's and the operator's shapes on the work plane, obstacles (standing or
//! moving on key frames), with their heights and signed distances. The true geometry the verdicts of
//! `flinch avoid` are judged on (`flinch-avoid` renders and senses it).

/// The camera looking down on the plane.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Image columns.
    pub width_px: usize,
    /// Image rows.
    pub height_px: usize,
    /// Size of one pixel on the plane, m.
    pub m_per_px: f64,
    /// Distance from the camera to the plane, m.
    pub camera_height_m: f64,
    /// Standard deviation of the depth noise, mm.
    pub noise_mm: f64,
    /// Fraction of pixels that read 0 (null).
    pub null_fraction: f64,
}

/// The robot as the camera sees it: a tool/wrist disc at the tool point and a link to the base.
#[derive(Clone, Debug)]
pub struct RobotShape {
    /// Base position on the plane, m (the link runs from here to the tool).
    pub base_m: [f64; 2],
    /// Radius of the wrist/tool disc, m.
    pub wrist_radius_m: f64,
    /// Top of the wrist/tool above the plane, m.
    pub wrist_height_m: f64,
    /// Width of the link, m.
    pub link_width_m: f64,
    /// Top of the link above the plane, m.
    pub link_height_m: f64,
}

/// The operator's hand and forearm, reaching in from `entry_m` (on the edge of the workspace).
#[derive(Clone, Debug)]
pub struct OperatorShape {
    /// Where the forearm enters the image, m.
    pub entry_m: [f64; 2],
    /// Hand radius, m.
    pub hand_radius_m: f64,
    /// Top of the hand above the plane, m.
    pub hand_height_m: f64,
    /// Forearm width, m.
    pub forearm_width_m: f64,
    /// Top of the forearm above the plane, m.
    pub forearm_height_m: f64,
    /// Further static obstacles (discs and boxes) in the workspace: sensed, fitted and judged like
    /// the operator (the monitor cannot tell them from a person).
    pub obstacles: Vec<Obstacle>,
}

/// An obstacle on the plane: a disc (`radius_m`) or an axis-aligned box (`size_m`), `height_m`
/// high, centred at `center_m` (standing) or moving on `keyframes` (then `center_m` is left out).
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// `"disc"` or `"box"`.
    pub kind: String,
    /// Centre on the plane, m (NaN when not written: a moving obstacle; see [`Obstacle::at`]).
    #[serde(default = "unset_centre")]
    pub center_m: [f64; 2],
    /// Centre over time, `{ t_s, x_m, y_m }`: linear between key frames, held before the first and
    /// after the last (as the hand's). Empty: the obstacle stands at `center_m`.
    #[serde(default)]
    pub keyframes: Vec<ObstacleKeyframe>,
    /// Disc radius, m.
    #[serde(default)]
    pub radius_m: f64,
    /// Box size along x and y, m.
    #[serde(default)]
    pub size_m: [f64; 2],
    /// Top above the plane, m.
    pub height_m: f64,
    /// A fixed fixture (`class = "fixture"`: a tray, a jig, a wall), not a person: the monitor
    /// keeps the tool's clearance from what the sensor classes as it (a pixel inside its footprint
    /// no higher than `height_m` plus `safety.fixture_tolerance_m`) without a human approach; the
    /// verdict judges contact with it a collision and its clearance without `K`. Standing only.
    #[serde(default)]
    pub fixture: bool,
}

fn unset_centre() -> [f64; 2] {
    [f64::NAN; 2]
}

/// One key frame of a moving obstacle.
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleKeyframe {
    /// Time, s.
    pub t_s: f64,
    /// Centre along x, m.
    pub x_m: f64,
    /// Centre along y, m.
    pub y_m: f64,
}

/// Linear interpolation over key frames `(t_s, [x, y])`, held before the first and after the last.
pub fn interpolate(k: &[(f64, [f64; 2])], t: f64) -> [f64; 2] {
    let Some(first) = k.first() else { return [f64::NAN; 2] };
    if t <= first.0 {
        return first.1;
    }
    for w in k.windows(2) {
        if t <= w[1].0 {
            let a = (t - w[0].0) / (w[1].0 - w[0].0);
            return [w[0].1[0] + a * (w[1].1[0] - w[0].1[0]), w[0].1[1] + a * (w[1].1[1] - w[0].1[1])];
        }
    }
    k[k.len() - 1].1
}

impl Obstacle {
    /// Does it move (more than one distinct key frame position)?
    pub fn moves(&self) -> bool {
        self.keyframes.windows(2).any(|k| (k[0].x_m, k[0].y_m) != (k[1].x_m, k[1].y_m))
    }

    /// Centre at time `t`, m: `center_m` when standing, else its key frames interpolated.
    pub fn center_at(&self, t: f64) -> [f64; 2] {
        if self.keyframes.is_empty() {
            return self.center_m;
        }
        let k: Vec<(f64, [f64; 2])> = self.keyframes.iter().map(|k| (k.t_s, [k.x_m, k.y_m])).collect();
        interpolate(&k, t)
    }

    /// The obstacle as it stands at time `t` (centre moved there).
    pub fn at(&self, t: f64) -> Obstacle {
        Obstacle { center_m: self.center_at(t), ..self.clone() }
    }

    /// Signed distance from `p` to the footprint, m (negative inside).
    pub fn signed_distance(&self, p: [f64; 2]) -> f64 {
        let (dx, dy) = (p[0] - self.center_m[0], p[1] - self.center_m[1]);
        if self.kind == "box" {
            let (qx, qy) = (dx.abs() - 0.5 * self.size_m[0], dy.abs() - 0.5 * self.size_m[1]);
            qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0)
        } else {
            dx.hypot(dy) - self.radius_m
        }
    }
    /// Height above `p`, m (0 off it).
    pub fn height_at(&self, p: [f64; 2]) -> f64 {
        if self.signed_distance(p) < 0.0 {
            self.height_m
        } else {
            0.0
        }
    }
}

/// Distance from `p` to the segment `a`-`b`.
pub fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let l2 = abx * abx + aby * aby;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / l2).clamp(0.0, 1.0) } else { 0.0 };
    let (dx, dy) = (p[0] - a[0] - t * abx, p[1] - a[1] - t * aby);
    (dx * dx + dy * dy).sqrt()
}

impl RobotShape {
    /// Height of the robot above point `p` with the tool at `tool`, m (0 off the robot).
    pub fn height_at(&self, tool: [f64; 2], p: [f64; 2]) -> f64 {
        let d = ((p[0] - tool[0]).powi(2) + (p[1] - tool[1]).powi(2)).sqrt();
        let wrist = if d < self.wrist_radius_m {
            self.wrist_height_m * (1.0 - 0.3 * (d / self.wrist_radius_m).powi(2))
        } else {
            0.0
        };
        let link = if dist_to_segment(p, tool, self.base_m) < 0.5 * self.link_width_m { self.link_height_m } else { 0.0 };
        wrist.max(link)
    }
}

impl OperatorShape {
    /// Height of the operator above `p` with the hand at `hand`, m (0 off the operator).
    pub fn height_at(&self, hand: [f64; 2], p: [f64; 2]) -> f64 {
        let d = ((p[0] - hand[0]).powi(2) + (p[1] - hand[1]).powi(2)).sqrt();
        let palm = if d < self.hand_radius_m {
            self.hand_height_m * (1.0 - (d / self.hand_radius_m).powi(2)).sqrt().max(0.3)
        } else {
            0.0
        };
        let arm =
            if dist_to_segment(p, self.entry_m, hand) < 0.5 * self.forearm_width_m { self.forearm_height_m } else { 0.0 };
        self.obstacles.iter().fold(palm.max(arm), |h, o| h.max(o.height_at(p)))
    }

    /// Planar distance from `p` to the operator's footprint (0 inside), m.
    pub fn clearance(&self, hand: [f64; 2], p: [f64; 2]) -> f64 {
        self.signed_distance(hand, p).max(0.0)
    }

    /// Signed planar distance from `p` to the operator's footprint (hand disc and forearm strip), m:
    /// positive outside, negative inside (the depth of penetration), from the true geometry, never
    /// from the sensed image. Minimum over the two parts, so inside it is at least as deep as the
    /// deeper part says.
    pub fn signed_distance(&self, hand: [f64; 2], p: [f64; 2]) -> f64 {
        let d_hand = ((p[0] - hand[0]).powi(2) + (p[1] - hand[1]).powi(2)).sqrt() - self.hand_radius_m;
        let d_arm = dist_to_segment(p, self.entry_m, hand) - 0.5 * self.forearm_width_m;
        self.obstacles.iter().fold(d_hand.min(d_arm), |d, o| d.min(o.signed_distance(p)))
    }
}
