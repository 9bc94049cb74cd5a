//! The pinhole depth camera of recorded frames (`flinch avoid --depth`, `[avoid.depth_camera]`):
//! intrinsics `fx, fy, cx, cy`, its pose over the work plane, the depth scale; the reprojection of a
//! 16-bit depth image onto the work plane's raster (`[avoid.camera]`'s `width_px x height_px` cells
//! of `m_per_px`), and the renderer that makes the project's own recorded frames from its scenes.
//!
//! Frames. The work plane is `z = 0`, heights up. The camera frame is the usual one (x along the
//! image columns, y along the rows, z along the optical axis). With roll = pitch = yaw = 0 the camera
//! looks straight down, its x along the plane's +x and its y along the plane's -y (a right-handed
//! camera seen from above); then it is rotated by roll about the plane's x, pitch about y, yaw about
//! z, in that order (`R = Rz(yaw) Ry(pitch) Rx(roll) R0`).
//!
//! Depth. A pixel's count times `depth_scale_m` is its depth along the optical axis (the z-depth of
//! RealSense z16 and TUM RGB-D, not the length of the ray); 0 is null. Pixel `(u, v)` (column, row)
//! has its centre at `(u, v)` in the intrinsics (OpenCV's convention), so the point of a count is
//! `R z ((u - cx) / fx, (v - cy) / fy, 1) + C`.

use crate::depth::{DepthImage, OperatorShape, RobotShape};

pub use flinch_model::avoid::depth_camera::DepthCameraCfg;

/// A pinhole camera placed over the work plane.
#[derive(Clone, Debug)]
pub struct Pinhole {
    /// Focal lengths, px.
    pub fx: f64,
    /// See `fx`.
    pub fy: f64,
    /// Principal point, px.
    pub cx: f64,
    /// See `cx`.
    pub cy: f64,
    /// Optical centre in the plane's frame, m.
    pub origin: [f64; 3],
    /// Camera-to-plane rotation, row-major.
    pub r: [[f64; 3]; 3],
    /// Metres per count.
    pub scale_m: f64,
}

fn mat_mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

impl Pinhole {
    /// From the scene's table.
    pub fn new(c: &DepthCameraCfg) -> Self {
        let (r, p, y) = (c.roll_deg.to_radians(), c.pitch_deg.to_radians(), c.yaw_deg.to_radians());
        let rx = [[1.0, 0.0, 0.0], [0.0, r.cos(), -r.sin()], [0.0, r.sin(), r.cos()]];
        let ry = [[p.cos(), 0.0, p.sin()], [0.0, 1.0, 0.0], [-p.sin(), 0.0, p.cos()]];
        let rz = [[y.cos(), -y.sin(), 0.0], [y.sin(), y.cos(), 0.0], [0.0, 0.0, 1.0]];
        // Straight down: camera x = +x, camera y = -y, optical axis = -z.
        let r0 = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        Pinhole {
            fx: c.fx_px,
            fy: c.fy_px,
            cx: c.cx_px,
            cy: c.cy_px,
            origin: [c.position_m[0], c.position_m[1], c.height_m],
            r: mat_mul(rz, mat_mul(ry, mat_mul(rx, r0))),
            scale_m: c.depth_scale_m,
        }
    }

    /// The direction (in the plane's frame) of pixel `(u, v)`, scaled so that one unit of it is one
    /// metre of z-depth.
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        let c = [(u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0];
        let r = &self.r;
        [0, 1, 2].map(|i| r[i][0] * c[0] + r[i][1] * c[1] + r[i][2] * c[2])
    }

    /// The point seen by pixel `(u, v)` at z-depth `z_m`, in the plane's frame.
    pub fn unproject(&self, u: f64, v: f64, z_m: f64) -> [f64; 3] {
        let d = self.ray(u, v);
        [0, 1, 2].map(|i| self.origin[i] + z_m * d[i])
    }

    /// Depth in metres of a count: the count times the scale, rounded to the micrometre so that one
    /// physical depth written in two conventions (1 mm counts, 0.2 mm counts) decodes to the same
    /// number exactly (a micrometre is far below any depth camera's resolution).
    pub fn depth_m(&self, count: u16) -> f64 {
        (count as f64 * self.scale_m * 1e6).round() * 1e-6
    }
}

/// The work plane's raster (`[avoid.camera]`): `width x height` cells of `m_per_px`, cell `(c, r)`
/// centred at `((c + 1/2) m_per_px, (r + 1/2) m_per_px)`.
#[derive(Clone, Copy, Debug)]
pub struct PlaneRaster {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell size, m.
    pub m_per_px: f64,
}

impl PlaneRaster {
    /// The cell holding `(x, y)`, if on the raster.
    pub fn cell(&self, x: f64, y: f64) -> Option<usize> {
        let (c, r) = ((x / self.m_per_px).floor(), (y / self.m_per_px).floor());
        (c >= 0.0 && r >= 0.0 && (c as usize) < self.width && (r as usize) < self.height).then(|| r as usize * self.width + c as usize)
    }
    /// Centre of cell `k`, m.
    pub fn centre(&self, k: usize) -> [f64; 2] {
        [((k % self.width) as f64 + 0.5) * self.m_per_px, ((k / self.width) as f64 + 0.5) * self.m_per_px]
    }
}

/// What one cell of the plane raster holds after reprojection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell {
    /// No point of the frame fell in it.
    Unknown,
    /// The highest point in it that the robot's model does not explain, m above the plane (0 when
    /// every point in it was the robot's).
    Seen(f64),
}

/// One frame reprojected onto the plane raster.
#[derive(Clone, Debug)]
pub struct Reprojected {
    /// Row-major cells.
    pub cells: Vec<Cell>,
    /// Points that the robot's model explained (dropped as robot), count.
    pub robot_points: usize,
    /// Points more than the tolerance below the plane, count: measurement errors (multipath, a
    /// reflection, a wrong depth scale), dropped as if null, so their cells stay unknown unless
    /// another point sees them.
    pub below_plane_points: usize,
    /// Valid points that fell on the plane raster (the robot's, those below the plane and the
    /// rest), count.
    pub valid_points: usize,
}

/// Reproject a depth image onto the plane raster: every valid pixel's point goes into the cell that
/// holds it, a cell keeps its highest point (the conservative reading: an obstacle never shrinks).
/// A point at most `below_m` under the plane is the plane seen through the depth noise and reads 0;
/// one lower is no floor but a wrong measurement of whatever the ray met, and is dropped like a null
/// pixel (counted in `below_plane_points`; earlier it read as floor seen, painting over what stood
/// there). With `robot = Some((shape, pose, margin))`, a point that the
/// robot's height model explains (on the robot at its recorded pose and no higher than the robot
/// there plus `margin`) is the robot's and is dropped: its cell reads 0 unless another point in it
/// stands higher. Each point is judged at its own position, not its cell's centre, so the robot's
/// edge is not left behind as an obstacle one cell wide.
pub fn reproject(cam: &Pinhole, img: &DepthImage, plane: &PlaneRaster, robot: Option<(&RobotShape, [f64; 2], f64)>, below_m: f64) -> Reprojected {
    let mut cells = vec![Cell::Unknown; plane.width * plane.height];
    let mut robot_points = 0;
    let mut below_plane_points = 0;
    let mut valid_points = 0;
    for v in 0..img.height {
        for u in 0..img.width {
            let count = img.mm[v * img.width + u];
            if count == 0 {
                continue;
            }
            let p = cam.unproject(u as f64, v as f64, cam.depth_m(count));
            let Some(k) = plane.cell(p[0], p[1]) else { continue };
            valid_points += 1;
            if p[2] < -below_m {
                below_plane_points += 1;
                continue;
            }
            let mut h = p[2].max(0.0);
            if let Some((shape, pose, margin)) = robot {
                let hr = grown_height(shape, pose, [p[0], p[1]], margin);
                if hr > 0.0 && h <= hr + margin {
                    robot_points += 1;
                    h = 0.0;
                }
            }
            cells[k] = match cells[k] {
                Cell::Seen(old) => Cell::Seen(old.max(h)),
                Cell::Unknown => Cell::Seen(h),
            };
        }
    }
    Reprojected { cells, robot_points, below_plane_points, valid_points }
}

/// The robot's height over `p` grown sideways by `margin` (the highest of `p` and 8 points
/// `margin` round it): a recorded point on the robot's edge that the depth noise moved off it
/// (a "flying pixel": 3 mm of noise along a slanted ray is 2 mm sideways at 35 degrees) or a pose a
/// little off is still the robot's.
pub fn grown_height(shape: &RobotShape, pose: [f64; 2], p: [f64; 2], margin: f64) -> f64 {
    let mut h = shape.height_at(pose, p);
    for k in 0..8 {
        let a = k as f64 * std::f64::consts::FRAC_PI_4;
        h = h.max(shape.height_at(pose, [p[0] + margin * a.cos(), p[1] + margin * a.sin()]));
    }
    h
}

/// Distance between the segments `a`-`b` and `c`-`d` on the plane.
fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    let (d1, d2, d3, d4) = (cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d));
    if ((d1 > 0.0) != (d2 > 0.0)) && ((d3 > 0.0) != (d4 > 0.0)) {
        return 0.0;
    }
    use crate::depth::dist_to_segment as ds;
    ds(a, c, d).min(ds(b, c, d)).min(ds(c, a, b)).min(ds(d, a, b))
}

/// A part's outline for the renderer's quick test: a capsule (segment and radius) or a box.
enum Part {
    Capsule([f64; 2], [f64; 2], f64),
    Box([f64; 4]),
}

impl Part {
    /// Whether the segment `a`-`b` on the plane comes within the part (plus 1 mm).
    fn near(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        match *self {
            Part::Capsule(p, q, r) => segment_distance(a, b, p, q) <= r + 1e-3,
            Part::Box(q) => a[0].min(b[0]) <= q[2] && a[0].max(b[0]) >= q[0] && a[1].min(b[1]) <= q[3] && a[1].max(b[1]) >= q[1],
        }
    }
}

/// Every part of the robot and the operator that stands above the plane.
fn parts(robot: Option<(&RobotShape, [f64; 2])>, operator: Option<(&OperatorShape, [f64; 2])>) -> Vec<Part> {
    let mut out = Vec::new();
    if let Some((r, tool)) = robot {
        out.push(Part::Capsule(tool, tool, r.wrist_radius_m));
        out.push(Part::Capsule(tool, r.base_m, 0.5 * r.link_width_m));
    }
    if let Some((o, hand)) = operator {
        out.push(Part::Capsule(hand, hand, o.hand_radius_m));
        out.push(Part::Capsule(o.entry_m, hand, 0.5 * o.forearm_width_m));
        for ob in &o.obstacles {
            if ob.kind == "box" {
                let half = [0.5 * ob.size_m[0], 0.5 * ob.size_m[1]];
                out.push(Part::Box([ob.center_m[0] - half[0], ob.center_m[1] - half[1], ob.center_m[0] + half[0], ob.center_m[1] + half[1]]));
            } else {
                out.push(Part::Capsule(ob.center_m, ob.center_m, ob.radius_m));
            }
        }
    }
    out
}

/// Render the scene (plane, robot with the tool at `tool`, operator with the hand at `hand`) through
/// the pinhole camera: one z-depth per pixel of a `width x height` image, m (`None`: the ray never
/// meets the plane). Ray marching in steps of 1 mm of height from the tallest part down, then 20
/// bisections; a ray whose path between that height and the plane comes nowhere near a part
/// (capsules round the discs and strips, boxes) meets the plane directly.
pub fn render_depth(
    cam: &Pinhole,
    width: usize,
    height: usize,
    robot: Option<(&RobotShape, [f64; 2])>,
    operator: Option<(&OperatorShape, [f64; 2])>,
) -> Vec<Option<f64>> {
    let parts = parts(robot, operator);
    let surface = |x: f64, y: f64| -> f64 {
        let p = [x, y];
        let a = robot.map_or(0.0, |(r, t)| r.height_at(t, p));
        let b = operator.map_or(0.0, |(o, h)| o.height_at(h, p));
        a.max(b)
    };
    let top = robot.map_or(0.0, |(r, _)| r.wrist_height_m.max(r.link_height_m)).max(operator.map_or(0.0, |(o, _)| {
        o.obstacles.iter().fold(o.hand_height_m.max(o.forearm_height_m), |m, ob| m.max(ob.height_m))
    })) + 1e-3;
    let mut out = Vec::with_capacity(width * height);
    for v in 0..height {
        for u in 0..width {
            let d = cam.ray(u as f64, v as f64);
            if d[2] >= -1e-9 {
                out.push(None);
                continue;
            }
            // z-depth at which the ray is at height h: origin.z + z d.z = h.
            let z_at = |h: f64| (h - cam.origin[2]) / d[2];
            let (z_top, z_floor) = (z_at(top).max(0.0), z_at(0.0));
            let at = |z: f64| [cam.origin[0] + z * d[0], cam.origin[1] + z * d[1], cam.origin[2] + z * d[2]];
            let (a, b) = (at(z_top), at(z_floor));
            let near = parts.iter().any(|q| q.near([a[0], a[1]], [b[0], b[1]]));
            if !near {
                out.push(Some(z_floor));
                continue;
            }
            let step = 1e-3 / -d[2];
            let n = ((z_floor - z_top) / step).ceil().max(1.0) as usize;
            let mut hit = z_floor;
            let mut prev = z_top;
            for i in 0..=n {
                let z = (z_top + i as f64 * step).min(z_floor);
                let p = at(z);
                if p[2] <= surface(p[0], p[1]) {
                    // Refine between the last point above the surface and this one.
                    let (mut lo, mut hi) = (prev, z);
                    for _ in 0..20 {
                        let mid = 0.5 * (lo + hi);
                        let q = at(mid);
                        if q[2] <= surface(q[0], q[1]) {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    hit = hi;
                    break;
                }
                prev = z;
            }
            out.push(Some(hit));
        }
    }
    out
}

/// Depths in metres to a 16-bit image of counts at `scale_m` metres per count (0 for `None` and
/// for depths the format cannot hold).
pub fn to_counts(depth_m: &[Option<f64>], width: usize, height: usize, scale_m: f64) -> DepthImage {
    let mm = depth_m
        .iter()
        .map(|d| match d {
            Some(z) => {
                let c = (z / scale_m).round();
                if (1.0..=65535.0).contains(&c) {
                    c as u16
                } else {
                    0
                }
            }
            None => 0,
        })
        .collect();
    DepthImage { width, height, mm }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> DepthCameraCfg {
        DepthCameraCfg { fx_px: 120.0, fy_px: 110.0, cx_px: 79.5, cy_px: 59.5, depth_scale_m: 0.001, position_m: [0.5, 0.4], height_m: 1.2, roll_deg: 0.0, pitch_deg: 0.0, yaw_deg: 0.0 }
    }

    #[test]
    fn straight_down_axes_and_a_tilted_camera_sees_a_box_where_it_stands() {
        let cam = Pinhole::new(&cfg());
        // The principal point looks straight down at the camera's foot.
        let p = cam.unproject(79.5, 59.5, 1.2);
        assert!((p[0] - 0.5).abs() < 1e-12 && (p[1] - 0.4).abs() < 1e-12 && p[2].abs() < 1e-12, "{p:?}");
        // Columns to the right go to +x, rows down go to -y.
        let q = cam.unproject(79.5 + 120.0, 59.5 + 110.0, 1.0);
        assert!((q[0] - 1.5).abs() < 1e-12 && (q[1] - (0.4 - 1.0)).abs() < 1e-12 && (q[2] - 0.2).abs() < 1e-12, "{q:?}");
        // A box 0.1 m high, seen by cameras tilted every way, reprojects onto its own footprint.
        let op = OperatorShape {
            entry_m: [0.55, 0.45],
            hand_radius_m: 0.06,
            hand_height_m: 0.1,
            forearm_width_m: 0.0,
            forearm_height_m: 0.0,
            obstacles: Vec::new(),
        };
        let plane = PlaneRaster { width: 100, height: 80, m_per_px: 0.01 };
        for (roll, pitch, yaw) in [(0.0, 0.0, 0.0), (20.0, 0.0, 30.0), (0.0, -25.0, -90.0), (15.0, 15.0, 180.0)] {
            let mut c = cfg();
            (c.roll_deg, c.pitch_deg, c.yaw_deg) = (roll, pitch, yaw);
            c.fx_px = 200.0;
            c.fy_px = 200.0;
            c.cx_px = 159.5;
            c.cy_px = 119.5;
            let cam = Pinhole::new(&c);
            let z = render_depth(&cam, 320, 240, None, Some((&op, [0.55, 0.45])));
            let img = to_counts(&z, 320, 240, 0.001);
            let rep = reproject(&cam, &img, &plane, None, 0.014);
            let h = |x: f64, y: f64| rep.cells[plane.cell(x, y).unwrap()];
            // Top of the hand dome (0.1 m at the centre, at least 0.03 m on its rim).
            match h(0.555, 0.455) {
                Cell::Seen(v) => assert!((v - 0.1).abs() < 3e-3, "{roll} {pitch} {yaw}: {v}"),
                Cell::Unknown => panic!("{roll} {pitch} {yaw}: centre not seen"),
            }
            // Two cells (20 mm) outside the footprint, the plane where it is seen.
            for (x, y) in [(0.635, 0.455), (0.465, 0.455), (0.555, 0.535), (0.555, 0.365)] {
                if let Cell::Seen(v) = h(x, y) {
                    assert!(v < 2e-3, "{roll} {pitch} {yaw}: ({x}, {y}) reads {v}");
                }
            }
        }
    }

    #[test]
    fn one_depth_in_two_conventions_decodes_to_the_same_metres() {
        let mut a = cfg();
        let mut b = cfg();
        a.depth_scale_m = 0.001;
        b.depth_scale_m = 0.0002;
        let (ca, cb) = (Pinhole::new(&a), Pinhole::new(&b));
        for mm in [1u16, 7, 333, 1199, 1500, 4095, 13107] {
            assert_eq!(ca.depth_m(mm), cb.depth_m(mm * 5), "{mm}");
        }
    }
}
