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
/// both), at the distance of its centre less half the pixel's diagonal (`m_per_px / sqrt 2`: a
/// square pixel's nearest point can be its corner, 0.7071 px from its centre; half a pixel, as
/// before issue 29 item 7, overstated the separation by up to 0.21 px seen along a diagonal).
#[derive(Clone, Copy, Debug)]
pub struct Nearest {
    from: [f64; 2],
    half_px: f64,
    half_diag: f64,
    best_d2: f64,
    at: [f64; 2],
    sectors_d2: [f64; SECTORS],
}

impl Nearest {
    /// Nothing seen yet from `from`, pixels of `m_per_px`.
    pub fn new(from: [f64; 2], m_per_px: f64) -> Self {
        Nearest { from, half_px: 0.5 * m_per_px, half_diag: m_per_px * std::f64::consts::FRAC_1_SQRT_2, best_d2: f64::INFINITY, at: [from[0] + NOTHING_SENSED_M, from[1]], sectors_d2: [f64::INFINITY; SECTORS] }
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
    /// The distance from the point to the nearest pixel's centre less half its diagonal (at least 0;
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
            (d2.sqrt() - self.half_diag).max(0.0)
        } else {
            NOTHING_SENSED_M
        }
    }
}

/// The sensor's classification of obstacle pixels (issue 29 item 2): a pixel is a fixture's only
/// when its centre lies inside a declared fixture's footprint (`class = "fixture"`) AND it is no
/// higher than that fixture's `height_m` plus `safety.fixture_tolerance_m`; anything else sensed is
/// a person's (a hand reaching over or into a tray is a person). From what the sensor measures,
/// never from the scene's ground truth of where the people are.
#[derive(Clone, Debug, Default)]
pub struct Fixtures {
    /// The declared fixtures (standing).
    pub list: Vec<crate::depth::Obstacle>,
    /// The height tolerance, m.
    pub tolerance_m: f64,
}

impl Fixtures {
    /// The fixtures a scene declares.
    pub fn of(scene: &Avoid) -> Self {
        Fixtures { list: scene.operator.obstacles.iter().filter(|o| o.fixture).cloned().collect(), tolerance_m: scene.safety.fixture_tolerance_m }
    }
    /// Whether a pixel centred at `p`, `h` above the plane, is a fixture's.
    pub fn is_fixture(&self, p: [f64; 2], h: f64) -> bool {
        self.list.iter().any(|o| o.signed_distance(p) <= 0.0 && h <= o.height_m + self.tolerance_m)
    }
}

/// Sensed pixels, split by class: people and fixtures, each accumulated from one point.
#[derive(Clone, Copy, Debug)]
pub struct Classed {
    /// The people's pixels.
    pub person: Nearest,
    /// The fixtures' pixels.
    pub fixture: Nearest,
}

impl Classed {
    fn new(from: [f64; 2], m_per_px: f64) -> Self {
        Classed { person: Nearest::new(from, m_per_px), fixture: Nearest::new(from, m_per_px) }
    }
    fn add(&mut self, fx: &Fixtures, p: [f64; 2], h: f64) {
        if fx.is_fixture(p, h) {
            self.fixture.add(p);
        } else {
            self.person.add(p);
        }
    }
    /// The nearest pixel of either class: its distance and centre (for the steering).
    pub fn nearest_either(&self) -> (f64, [f64; 2]) {
        let (a, b) = (self.person.nearest(), self.fixture.nearest());
        if b.0 < a.0 {
            b
        } else {
            a
        }
    }
}

/// The field fitted to one frame, and the separation the sensor sees: the distance from the tool's
/// surface (the wrist disc) to the nearest pixel of the height map (after robot removal, before the
/// raise) higher than `safety.sense_height_m`, less half a pixel's diagonal; about [`NOTHING_SENSED_M`] when
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
    let s = fit_and_sense_classed(scene, setup, tool, op, hand, rng);
    (s.field, s.separation_m, s.nearest_m, s.goal_separation_m, s.sectors_m)
}

/// One synthetic frame through the pipeline, its pixels classed ([`Fixtures`]).
pub struct Sensing {
    /// The field fitted to it.
    pub field: Field,
    /// The people's separation from the tool's surface, m.
    pub separation_m: f64,
    /// The nearest sensed pixel of either class, m (for the steering).
    pub nearest_m: [f64; 2],
    /// The people's separation from the goal (the tool's surface there), m.
    pub goal_separation_m: f64,
    /// The people's separation per sector, m.
    pub sectors_m: [f64; SECTORS],
    /// The fixtures' separation per sector from the tool's surface, m ([`NOTHING_SENSED_M`] where
    /// none).
    pub fixture_sectors_m: [f64; SECTORS],
}

/// [`fit_and_sense_sectors`] with the pixels classed into people and fixtures.
pub fn fit_and_sense_classed(scene: &Avoid, setup: &Setup, tool: [f64; 2], op: &crate::depth::OperatorShape, hand: [f64; 2], rng: &mut Rng) -> Sensing {
    let fx = Fixtures::of(scene);
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
    let classed = |from: [f64; 2]| {
        if scene.robot.removal == "model" {
            sensed_classed(&img, &cam, &robot, tool, from, scene.robot.removal_margin_m, scene.safety.sense_height_m, &fx)
        } else {
            map_classed(&map, cam.m_per_px, from, scene.safety.sense_height_m, &fx)
        }
    };
    let acc = classed(tool);
    let (from_centre, _) = acc.person.nearest();
    let (_, nearest) = acc.nearest_either();
    // From the tool's surface, as the signed distance is measured.
    let surface = |d: f64| if d >= NOTHING_SENSED_M { NOTHING_SENSED_M } else { (d - robot.wrist_radius_m).max(0.0) };
    let sep = (from_centre - robot.wrist_radius_m).max(0.0);
    let sectors = acc.person.sectors().map(|d| (d - robot.wrist_radius_m).max(0.0));
    let fixture_sectors = acc.fixture.sectors().map(surface);
    // The people's separation from the goal (a fixture beside the goal leaves room).
    let goal_from_centre = classed(scene.goal_m).person.nearest().0;
    let goal_sep = (goal_from_centre - robot.wrist_radius_m).max(0.0);
    crate::depth::raise(&mut map, scene.fit.offset_m);
    let mut w = setup.fitter.weights(&map);
    if scene.fit.remove_plane {
        for (v, p) in w.iter_mut().zip(&setup.plane_weights) {
            *v -= p;
        }
    }
    filter_weights(&mut w);
    Sensing { field: Field::new(&setup.fitter.grid, w, scene.fit.eval_sigma_factor), separation_m: sep, nearest_m: nearest, goal_separation_m: goal_sep, sectors_m: sectors, fixture_sectors_m: fixture_sectors }
}

/// [`sensed_acc`] with the pixels classed ([`Fixtures`]) by their measured height.
#[allow(clippy::too_many_arguments)]
pub fn sensed_classed(img: &crate::depth::DepthImage, cam: &crate::depth::Camera, robot: &crate::depth::RobotShape, tool: [f64; 2], from: [f64; 2], margin_m: f64, sense_m: f64, fx: &Fixtures) -> Classed {
    let mut acc = Classed::new(from, cam.m_per_px);
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
        acc.add(fx, p, h);
    }
    acc
}

/// [`nearest_acc`] with the pixels classed ([`Fixtures`]) by their height in the map.
pub fn map_classed(map: &crate::depth::HeightMap, m_per_px: f64, p: [f64; 2], height_m: f64, fx: &Fixtures) -> Classed {
    let mut acc = Classed::new(p, m_per_px);
    for (k, v) in map.m.iter().enumerate() {
        if *v > height_m {
            acc.add(fx, [((k % map.width) as f64 + 0.5) * m_per_px, ((k / map.width) as f64 + 0.5) * m_per_px], *v);
        }
    }
    acc
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
/// [`remove_robot_by_model`]), less half a pixel's diagonal, m. Null pixels are not filled here: a filled pixel
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

/// Distance from `p` to the nearest pixel above `height_m`, less half a pixel's diagonal, m.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The separation from a pixel is never more than the distance to the nearest point of its
    /// square, in any direction (along a diagonal the corner is nearest: half the diagonal from the
    /// centre). With half a pixel subtracted (before) a pixel seen at 45 degrees read 2.1 mm too far
    /// at 10 mm pixels.
    #[test]
    fn a_pixel_is_as_near_as_its_nearest_corner() {
        let m = 0.01;
        for deg in [0.0f64, 10.0, 30.0, 45.0, 60.0, 135.0, 225.0, 315.0] {
            let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
            let q = [0.3 + 0.1 * c, 0.3 + 0.1 * s];
            let mut n = Nearest::new([0.3, 0.3], m);
            n.add(q);
            // The nearest point of the square: the tool's point clamped into it.
            let near = [(0.3f64).clamp(q[0] - m / 2.0, q[0] + m / 2.0), (0.3f64).clamp(q[1] - m / 2.0, q[1] + m / 2.0)];
            let truth = (near[0] - 0.3).hypot(near[1] - 0.3);
            let (d, _) = n.nearest();
            assert!(d <= truth + 1e-12, "{deg} deg: sensed {d} m, the square is {truth} m away");
            assert!(n.sectors().iter().all(|&k| k >= d - 1e-12));
            // Conservative by at most (sqrt 2 - 1) / 2 of a pixel.
            assert!(truth - d <= (std::f64::consts::SQRT_2 - 1.0) / 2.0 * m + 1e-12, "{deg} deg");
        }
    }

    /// A pixel is a fixture's only inside its footprint and no higher than its top plus the
    /// tolerance: the tray's floor and rim are the tray's, a hand over it (or in it, standing
    /// higher than the rim) is a person's, and so is anything beside it however low.
    #[test]
    fn a_pixel_is_a_fixtures_only_inside_it_and_no_higher() {
        let tray = crate::depth::Obstacle { kind: "box".into(), center_m: [0.8, 0.25], keyframes: vec![], radius_m: 0.0, size_m: [0.2, 0.2], height_m: 0.04, fixture: true };
        let fx = Fixtures { list: vec![tray], tolerance_m: 0.01 };
        assert!(fx.is_fixture([0.8, 0.25], 0.04));
        assert!(fx.is_fixture([0.71, 0.34], 0.049));
        assert!(!fx.is_fixture([0.8, 0.25], 0.051), "a hand over the tray");
        assert!(!fx.is_fixture([0.8, 0.25], 0.12), "a hand over the tray");
        assert!(!fx.is_fixture([0.8, 0.36], 0.02), "beside the tray");
        assert!(!Fixtures::default().is_fixture([0.8, 0.25], 0.02));
    }
}
