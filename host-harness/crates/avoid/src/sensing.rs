//! One camera frame: the scene rendered (robot at the tool, operator where the key frames put it),
//! pre-processed, cleared of the robot and fitted; and the separations read off the sensed image
//! and off the true geometry.

use crate::calib::preprocess;
use crate::depth::{render, Rng};
use crate::rbf::{filter_weights, Field};
use crate::scene::Avoid;
use crate::setup::*;

/// The field fitted to one frame (robot at `tool`, hand at `hand`).
pub fn fit_frame(scene: &Avoid, setup: &Setup, tool: [f64; 2], hand: [f64; 2], rng: &mut Rng) -> Field {
    fit_and_sense(scene, setup, tool, hand, rng).0
}

/// No obstacle pixel in view: the separation reported, m.
pub const NOTHING_SENSED_M: f64 = 10.0;

/// The directional separation's sectors (the firmware monitor's, ISO/TS 15066 5.5.4.2.3).
pub use flinch_firmware::avoidance::SECTORS;

/// The nearest obstacle pixel seen from a point, overall and per sector of 45 degrees
/// ([`flinch_firmware::avoidance::sector_of`]), accumulated pixel by pixel. A pixel counts in the
/// sector of its centre and in those of its four corners (a pixel across a sector boundary is in
/// both), at the distance of its centre less half a pixel.
#[derive(Clone, Copy, Debug)]
pub struct Nearest {
    from: [f64; 2],
    half_px: f64,
    best_d2: f64,
    at: [f64; 2],
    sectors_d2: [f64; SECTORS],
}

impl Nearest {
    /// Nothing seen yet from `from`, pixels of `m_per_px`.
    pub fn new(from: [f64; 2], m_per_px: f64) -> Self {
        Nearest { from, half_px: 0.5 * m_per_px, best_d2: f64::INFINITY, at: [from[0] + NOTHING_SENSED_M, from[1]], sectors_d2: [f64::INFINITY; SECTORS] }
    }
    /// An obstacle pixel centred at `q`.
    pub fn add(&mut self, q: [f64; 2]) {
        let (dx, dy) = (q[0] - self.from[0], q[1] - self.from[1]);
        let d2 = dx * dx + dy * dy;
        if d2 < self.best_d2 {
            (self.best_d2, self.at) = (d2, q);
        }
        let h = self.half_px;
        for (ox, oy) in [(0.0, 0.0), (-h, -h), (h, -h), (-h, h), (h, h)] {
            let k = flinch_firmware::avoidance::sector_of(dx + ox, dy + oy);
            if d2 < self.sectors_d2[k] {
                self.sectors_d2[k] = d2;
            }
        }
    }
    /// The distance from the point to the nearest pixel less half a pixel (at least 0;
    /// [`NOTHING_SENSED_M`] when none), and its centre, m.
    pub fn nearest(&self) -> (f64, [f64; 2]) {
        (self.dist(self.best_d2), self.at)
    }
    /// The same per sector, m.
    pub fn sectors(&self) -> [f64; SECTORS] {
        self.sectors_d2.map(|d2| self.dist(d2))
    }
    fn dist(&self, d2: f64) -> f64 {
        if d2.is_finite() {
            (d2.sqrt() - self.half_px).max(0.0)
        } else {
            NOTHING_SENSED_M
        }
    }
}

/// The field fitted to one frame, and the separation the sensor sees: the distance from the tool's
/// surface (the wrist disc) to the nearest pixel of the height map (after robot removal, before the
/// raise) higher than `safety.sense_height_m`, less half a pixel; about [`NOTHING_SENSED_M`] when
/// there is none.
pub fn fit_and_sense(scene: &Avoid, setup: &Setup, tool: [f64; 2], hand: [f64; 2], rng: &mut Rng) -> (Field, f64) {
    let (f, sep, _) = fit_and_sense_at(scene, setup, tool, hand, rng);
    (f, sep)
}

/// [`fit_and_sense`], and the nearest sensed obstacle point (m; [`NOTHING_SENSED_M`] along x from
/// the tool when there is none).
pub fn fit_and_sense_at(scene: &Avoid, setup: &Setup, tool: [f64; 2], hand: [f64; 2], rng: &mut Rng) -> (Field, f64, [f64; 2]) {
    fit_and_sense_with(scene, setup, tool, &scene.operator_shape(), hand, rng)
}

/// [`fit_and_sense_at`] at time `t_s`: the hand and every moving obstacle where they are then.
pub fn fit_and_sense_at_time(scene: &Avoid, setup: &Setup, tool: [f64; 2], t_s: f64, rng: &mut Rng) -> (Field, f64, [f64; 2]) {
    fit_and_sense_with(scene, setup, tool, &scene.operator_shape_at(t_s), scene.hand_at(t_s), rng)
}

pub(crate) fn fit_and_sense_with(scene: &Avoid, setup: &Setup, tool: [f64; 2], op: &crate::depth::OperatorShape, hand: [f64; 2], rng: &mut Rng) -> (Field, f64, [f64; 2]) {
    let (f, sep, near, _) = fit_and_sense_full(scene, setup, tool, op, hand, rng);
    (f, sep, near)
}

/// [`fit_and_sense_with`], and the separation sensed from the goal (the tool's surface there), m.
pub(crate) fn fit_and_sense_full(scene: &Avoid, setup: &Setup, tool: [f64; 2], op: &crate::depth::OperatorShape, hand: [f64; 2], rng: &mut Rng) -> (Field, f64, [f64; 2], f64) {
    let (f, sep, near, goal, _) = fit_and_sense_sectors(scene, setup, tool, op, hand, rng);
    (f, sep, near, goal)
}

/// [`fit_and_sense_full`], and the separation per sector from the tool's surface, m.
pub(crate) fn fit_and_sense_sectors(scene: &Avoid, setup: &Setup, tool: [f64; 2], op: &crate::depth::OperatorShape, hand: [f64; 2], rng: &mut Rng) -> (Field, f64, [f64; 2], f64, [f64; SECTORS]) {
    let cam = scene.camera();
    let robot = scene.robot_shape();
    let img = render(&cam, Some((&robot, tool)), Some((op, hand)), rng);
    let mut map = if scene.robot.removal == "model" {
        let mut m = preprocess(&img, &cam, 0.0, None);
        remove_robot_by_model(&mut m, cam.m_per_px, &robot, tool, scene.robot.removal_margin_m);
        m
    } else {
        preprocess(&img, &cam, 0.0, Some((&setup.calibration, tool)))
    };
    let acc = if scene.robot.removal == "model" {
        sensed_acc(&img, &cam, &robot, tool, tool, scene.robot.removal_margin_m, scene.safety.sense_height_m)
    } else {
        nearest_acc(&map, cam.m_per_px, tool, scene.safety.sense_height_m)
    };
    let (from_centre, nearest) = acc.nearest();
    // From the tool's surface, as the signed distance is measured.
    let sep = (from_centre - robot.wrist_radius_m).max(0.0);
    let sectors = acc.sectors().map(|d| (d - robot.wrist_radius_m).max(0.0));
    let goal_from_centre = if scene.robot.removal == "model" {
        sensed_nearest_from(&img, &cam, &robot, tool, scene.goal_m, scene.robot.removal_margin_m, scene.safety.sense_height_m).0
    } else {
        nearest_obstacle_at(&map, cam.m_per_px, scene.goal_m, scene.safety.sense_height_m).0
    };
    let goal_sep = (goal_from_centre - robot.wrist_radius_m).max(0.0);
    crate::depth::raise(&mut map, scene.fit.offset_m);
    let mut w = setup.fitter.weights(&map);
    if scene.fit.remove_plane {
        for (v, p) in w.iter_mut().zip(&setup.plane_weights) {
            *v -= p;
        }
    }
    filter_weights(&mut w);
    (Field::new(&setup.fitter.grid, w, scene.fit.eval_sigma_factor), sep, nearest, goal_sep, sectors)
}

/// Robot removal by the robot-only height model: a pixel is cleared only when the robot, at the
/// position it reports, stands there and the measured height is no more than the robot's own height
/// there plus `margin_m` (it is explained by the robot). Everything else is kept: a hand beside the
/// wrist or the link stays in the image. The model is grown by nothing: the robot's position
/// uncertainty belongs in the monitor's `Z_r`. What stays hidden is only what the robot itself
/// occludes from the camera (under the wrist and the link). Returns the pixels cleared.
pub fn remove_robot_by_model(map: &mut crate::depth::HeightMap, m_per_px: f64, robot: &crate::depth::RobotShape, tool: [f64; 2], margin_m: f64) -> usize {
    let mut n = 0;
    let w = map.width;
    for (k, v) in map.m.iter_mut().enumerate() {
        let p = [((k % w) as f64 + 0.5) * m_per_px, ((k / w) as f64 + 0.5) * m_per_px];
        let hr = robot.height_at(tool, p);
        if hr > 0.0 && *v <= hr + margin_m {
            *v = 0.0;
            n += 1;
        }
    }
    n
}

/// The separation the monitor uses, from the raw depth image: the distance from the tool to the
/// nearest valid pixel higher than `sense_m` that the robot's height model does not explain (see
/// [`remove_robot_by_model`]), less half a pixel, m. Null pixels are not filled here: a filled pixel
/// beside the robot would borrow the robot's height and read as an obstacle.
pub fn sensed_separation(img: &crate::depth::DepthImage, cam: &crate::depth::Camera, robot: &crate::depth::RobotShape, tool: [f64; 2], margin_m: f64, sense_m: f64) -> f64 {
    sensed_nearest(img, cam, robot, tool, margin_m, sense_m).0
}

/// [`sensed_separation`] and the nearest pixel's centre, m.
pub fn sensed_nearest(img: &crate::depth::DepthImage, cam: &crate::depth::Camera, robot: &crate::depth::RobotShape, tool: [f64; 2], margin_m: f64, sense_m: f64) -> (f64, [f64; 2]) {
    sensed_nearest_from(img, cam, robot, tool, tool, margin_m, sense_m)
}

/// [`sensed_nearest`] measured from the point `from` (the robot removed at `tool`).
pub fn sensed_nearest_from(img: &crate::depth::DepthImage, cam: &crate::depth::Camera, robot: &crate::depth::RobotShape, tool: [f64; 2], from: [f64; 2], margin_m: f64, sense_m: f64) -> (f64, [f64; 2]) {
    sensed_acc(img, cam, robot, tool, from, margin_m, sense_m).nearest()
}

/// The pixels [`sensed_nearest_from`] counts, accumulated from `from`.
pub fn sensed_acc(img: &crate::depth::DepthImage, cam: &crate::depth::Camera, robot: &crate::depth::RobotShape, tool: [f64; 2], from: [f64; 2], margin_m: f64, sense_m: f64) -> Nearest {
    let mut acc = Nearest::new(from, cam.m_per_px);
    let w = img.width;
    for (k, &d) in img.mm.iter().enumerate() {
        if d == 0 {
            continue;
        }
        let p = [((k % w) as f64 + 0.5) * cam.m_per_px, ((k / w) as f64 + 0.5) * cam.m_per_px];
        let h = cam.camera_height_m - d as f64 * 1e-3;
        let hr = robot.height_at(tool, p);
        if h <= sense_m || (hr > 0.0 && h <= hr + margin_m) {
            continue;
        }
        acc.add(p);
    }
    acc
}

/// Distance from `p` to the nearest pixel above `height_m`, less half a pixel, m.
pub fn nearest_obstacle(map: &crate::depth::HeightMap, m_per_px: f64, p: [f64; 2], height_m: f64) -> f64 {
    nearest_obstacle_at(map, m_per_px, p, height_m).0
}

/// [`nearest_obstacle`] and the nearest pixel's centre, m.
pub fn nearest_obstacle_at(map: &crate::depth::HeightMap, m_per_px: f64, p: [f64; 2], height_m: f64) -> (f64, [f64; 2]) {
    nearest_acc(map, m_per_px, p, height_m).nearest()
}

/// The pixels above `height_m`, accumulated from `p`.
pub fn nearest_acc(map: &crate::depth::HeightMap, m_per_px: f64, p: [f64; 2], height_m: f64) -> Nearest {
    let mut acc = Nearest::new(p, m_per_px);
    for (k, v) in map.m.iter().enumerate() {
        if *v > height_m {
            acc.add([((k % map.width) as f64 + 0.5) * m_per_px, ((k / map.width) as f64 + 0.5) * m_per_px]);
        }
    }
    acc
}
