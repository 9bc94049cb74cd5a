//! Robot removal by calibration (section 5.2.1, Fig. 84-86).
//!
//! The robot alone moves over the plane along a zig-zag (rows `step_m` apart, `step_m` between
//! snapshots). Each snapshot is pre-processed and fitted; the pixels where the interpolated robot
//! stands above `threshold_m` form that position's mask (the interpolation widens the robot, which
//! makes the mask conservative). At run time the mask of the stored position nearest to the robot's
//! reported position is cleared (set to 0 m) in the height map before the fit.
//!
//! # File format (`.flcal`, little-endian)
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `FLAVCAL1` |
//! | 4 | width, px (u32) |
//! | 4 | height, px (u32) |
//! | 4 | number of positions `n` (u32) |
//! | 8 | threshold, m (f64) |
//! | n x (16 + ceil(w h / 8)) | per position: x, y in m (f64, f64), then the mask, one bit per pixel in row-major order, bit `k % 8` of byte `k / 8` |

use std::path::Path;

use crate::depth::{raise, render, to_height, Camera, HeightMap, RobotShape, Rng};
use crate::rbf::{filter_weights, Field, Fitter};

const MAGIC: &[u8; 8] = b"FLAVCAL1";

/// Stored masks, one per calibration position.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// Image columns.
    pub width: usize,
    /// Image rows.
    pub height: usize,
    /// Height at which the interpolated robot was cut, m.
    pub threshold_m: f64,
    /// Robot positions of the snapshots, m.
    pub positions: Vec<[f64; 2]>,
    /// One packed bit mask per position.
    pub masks: Vec<Vec<u8>>,
}

/// The zig-zag of Fig. 84 over `[min, max]` (m), `step_m` apart in both directions.
pub fn zigzag(min: [f64; 2], max: [f64; 2], step_m: f64) -> Vec<[f64; 2]> {
    let count = |a: f64, b: f64| ((b - a) / step_m).floor().max(0.0) as usize + 1;
    let (nx, ny) = (count(min[0], max[0]), count(min[1], max[1]));
    let mut out = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for k in 0..nx {
            let i = if j % 2 == 0 { k } else { nx - 1 - k };
            out.push([min[0] + i as f64 * step_m, min[1] + j as f64 * step_m]);
        }
    }
    out
}

/// Pre-processing shared by calibration and run time: flip, fill, optional robot removal, raise.
pub fn preprocess(
    depth: &crate::depth::DepthImage,
    cam: &Camera,
    offset_m: f64,
    removal: Option<(&Calibration, [f64; 2])>,
) -> HeightMap {
    let mut map = to_height(depth, cam.camera_height_m);
    if let Some((cal, p)) = removal {
        cal.clear(p, &mut map);
    }
    raise(&mut map, offset_m);
    map
}

impl Calibration {
    /// Run the calibration pass with the synthetic camera. Each mask is the interpolated robot above
    /// `threshold_m`, grown by `dilate_m` (0 for the thesis's plain cut; about `d / sqrt 2` makes the
    /// nearest position's mask cover the robot anywhere between the zig-zag's positions).
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        cam: &Camera,
        robot: &RobotShape,
        fitter: &Fitter,
        positions: &[[f64; 2]],
        offset_m: f64,
        threshold_m: f64,
        dilate_m: f64,
        rng: &mut Rng,
    ) -> Self {
        let r = (dilate_m / cam.m_per_px).round().max(0.0) as i64;
        let disc: Vec<(i64, i64)> =
            (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (dx, dy))).filter(|(dx, dy)| dx * dx + dy * dy <= r * r).collect();
        let (w, h) = (cam.width_px, cam.height_px);
        let mut masks = Vec::with_capacity(positions.len());
        for &p in positions {
            let img = render(cam, Some((robot, p)), None, rng);
            let map = preprocess(&img, cam, offset_m, None);
            let mut weights = fitter.weights(&map);
            filter_weights(&mut weights);
            let f = Field::new(&fitter.grid, weights, 1.0).raster(w, h, cam.m_per_px);
            let mut mask = vec![0u8; (w * h).div_ceil(8)];
            for (k, v) in f.iter().enumerate() {
                if *v > threshold_m {
                    let (c, rr) = ((k % w) as i64, (k / w) as i64);
                    for (dx, dy) in &disc {
                        let (x, y) = (c + dx, rr + dy);
                        if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                            let q = y as usize * w + x as usize;
                            mask[q / 8] |= 1 << (q % 8);
                        }
                    }
                }
            }
            masks.push(mask);
        }
        Calibration { width: w, height: h, threshold_m, positions: positions.to_vec(), masks }
    }

    /// Index of the stored position nearest to `p`.
    pub fn nearest(&self, p: [f64; 2]) -> Option<usize> {
        let d2 = |q: &[f64; 2]| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
        (0..self.positions.len()).min_by(|&a, &b| d2(&self.positions[a]).total_cmp(&d2(&self.positions[b])))
    }

    /// Set to 0 m every pixel of the nearest position's mask; returns how many pixels were cleared.
    pub fn clear(&self, p: [f64; 2], map: &mut HeightMap) -> usize {
        let Some(k) = self.nearest(p) else { return 0 };
        if map.width != self.width || map.height != self.height {
            return 0;
        }
        let mask = &self.masks[k];
        let mut n = 0;
        for (i, v) in map.m.iter_mut().enumerate() {
            if mask[i / 8] & (1 << (i % 8)) != 0 {
                *v = 0.0;
                n += 1;
            }
        }
        n
    }

    /// Write the calibration file (format in the module docs).
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        for v in [self.width, self.height, self.positions.len()] {
            b.extend_from_slice(&(v as u32).to_le_bytes());
        }
        b.extend_from_slice(&self.threshold_m.to_le_bytes());
        for (p, m) in self.positions.iter().zip(&self.masks) {
            b.extend_from_slice(&p[0].to_le_bytes());
            b.extend_from_slice(&p[1].to_le_bytes());
            b.extend_from_slice(m);
        }
        std::fs::write(path, b).map_err(|e| format!("{}: cannot write calibration: {e}", path.display()))
    }

    /// Read a calibration file, checking its size and magic.
    pub fn load(path: &Path) -> Result<Self, String> {
        let b = flinch_output::input::read_bytes(path, flinch_output::input::Kind::Calibration).map_err(|e| format!("cannot read calibration: {e}"))?;
        let bad = |what: &str| format!("{}: not a Flinch calibration file: {what}", path.display());
        if b.len() < 28 || &b[..8] != MAGIC {
            return Err(bad("missing FLAVCAL1 header"));
        }
        let u = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize;
        let f = |at: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[at..at + 8]);
            f64::from_le_bytes(a)
        };
        let (width, height, n) = (u(8), u(12), u(16));
        let threshold_m = f(20);
        // Checked: a header's numbers cannot wrap the size they imply.
        let mlen = width.checked_mul(height).map(|x| x.div_ceil(8));
        let want = mlen.and_then(|m| m.checked_add(16)).and_then(|r| r.checked_mul(n)).and_then(|x| x.checked_add(28));
        let mlen = mlen.unwrap_or(0);
        if width == 0 || height == 0 || want != Some(b.len()) || !threshold_m.is_finite() {
            return Err(bad("size does not match its header"));
        }
        let mut positions = Vec::with_capacity(n);
        let mut masks = Vec::with_capacity(n);
        for k in 0..n {
            let at = 28 + k * (16 + mlen);
            positions.push([f(at), f(at + 8)]);
            masks.push(b[at + 16..at + 16 + mlen].to_vec());
        }
        Ok(Calibration { width, height, threshold_m, positions, masks })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rbf::RbfGrid;

    fn setup() -> (Camera, RobotShape, Fitter) {
        let cam = Camera { width_px: 100, height_px: 100, m_per_px: 0.01, camera_height_m: 1.2, noise_mm: 2.0, null_fraction: 0.01 };
        let robot = RobotShape {
            base_m: [1.05, 0.5],
            wrist_radius_m: 0.05,
            wrist_height_m: 0.3,
            link_width_m: 0.08,
            link_height_m: 0.4,
        };
        let fitter = Fitter::new(RbfGrid::new(100, 100, 15, 0.01, 1.0).unwrap()).unwrap();
        (cam, robot, fitter)
    }

    #[test]
    fn zigzag_alternates_direction() {
        let z = zigzag([0.0, 0.0], [0.2, 0.1], 0.1);
        assert_eq!(z.len(), 6);
        assert_eq!(z[2], [0.2, 0.0]);
        assert_eq!(z[3], [0.2, 0.1]);
        assert_eq!(z[5], [0.0, 0.1]);
    }

    /// Remove the robot at a position between the stored ones: the fitted field there is flat.
    #[test]
    fn robot_removal_clears_the_robot() {
        let (cam, robot, fitter) = setup();
        let mut rng = Rng::new(11);
        let pos = zigzag([0.1, 0.1], [0.9, 0.9], 0.05);
        let cal = Calibration::run(&cam, &robot, &fitter, &pos, 0.065, 0.1, 0.05 / 2f64.sqrt(), &mut rng);
        let field_max = |map: &HeightMap| {
            let mut w = fitter.weights(map);
            filter_weights(&mut w);
            Field::new(&fitter.grid, w, 1.0).raster(100, 100, 0.01).into_iter().fold(0.0f64, f64::max)
        };
        for p in [[0.33, 0.47], [0.71, 0.22], [0.5, 0.85]] {
            let img = render(&cam, Some((&robot, p)), None, &mut rng);
            let kept = preprocess(&img, &cam, 0.065, None);
            let removed = preprocess(&img, &cam, 0.065, Some((&cal, p)));
            let (before, after) = (field_max(&kept), field_max(&removed));
            // Without removal the robot stands in the field (so the test can tell); what is left
            // after it is the 65 mm raise and the filter's residue, not the robot.
            assert!(before >= 0.1, "robot at {p:?} not in the field before removal: {before} m");
            assert!(after < 0.1, "robot at {p:?} left {after} m after removal");
        }
        // Save and load give the same calibration; a damaged file is refused with its name.
        let path = std::env::temp_dir().join(format!("flinch-cal-{}.flcal", std::process::id()));
        cal.save(&path).unwrap();
        assert_eq!(Calibration::load(&path).unwrap(), cal);
        std::fs::write(&path, b"FLAVCAL1xx").unwrap();
        assert!(Calibration::load(&path).unwrap_err().contains("flinch-cal-"));
        std::fs::remove_file(&path).ok();
    }
}
