//! Depth images: 16-bit files (PNG or PGM), the synthetic scene generator, and pre-processing
//! (section 5.1: flip to height, fill null pixels from their neighbours, raise by an offset).
//!
//! Coordinates: pixel `(c, r)` covers `[c, c+1) x [r, r+1)` times `m_per_px`; its centre is at
//! `((c + 0.5) m_per_px, (r + 0.5) m_per_px)` metres. Depth is millimetres from the camera, 0 = null.

use std::path::Path;

/// A depth image, millimetres from the camera, row-major; 0 marks a null pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width * height` depths, mm.
    pub mm: Vec<u16>,
}

impl DepthImage {
    /// Load a 16-bit grey PNG or PGM (by extension or content).
    pub fn load(path: &Path) -> Result<Self, String> {
        // Through the one reader: a FIFO, a device or a directory is refused by name, at most 64 MiB.
        let bytes = flinch_output::input::read_bytes(path, flinch_output::input::Kind::DepthFrame).map_err(|e| format!("cannot read depth image: {e}"))?;
        let img = image::io::Reader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("{}: cannot read depth image: {e}", path.display()))?
            .decode()
            .map_err(|e| format!("{}: cannot read depth image: {e}", path.display()))?;
        let grey = match img {
            image::DynamicImage::ImageLuma16(g) => g,
            other => {
                return Err(format!(
                    "{}: depth image must be 16-bit greyscale (millimetres), found {:?}",
                    path.display(),
                    other.color()
                ))
            }
        };
        let (w, h) = grey.dimensions();
        Ok(DepthImage { width: w as usize, height: h as usize, mm: grey.into_raw() })
    }

    /// Save as 16-bit grey PNG or PGM (chosen by the extension, `.png` or `.pgm`).
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let buf = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(
            self.width as u32,
            self.height as u32,
            self.mm.clone(),
        )
        .ok_or_else(|| format!("{}: image buffer size mismatch", path.display()))?;
        let fmt = match path.extension().and_then(|e| e.to_str()) {
            Some("pgm") | Some("PGM") => image::ImageFormat::Pnm,
            _ => image::ImageFormat::Png,
        };
        if fmt == image::ImageFormat::Pnm {
            // Binary PGM, maxval 65535, big-endian samples (netpbm); `image` reads it back.
            let mut bytes = format!("P5\n{} {}\n65535\n", self.width, self.height).into_bytes();
            bytes.extend(self.mm.iter().flat_map(|v| v.to_be_bytes()));
            return std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()));
        }
        buf.save_with_format(path, fmt).map_err(|e| format!("{}: {e}", path.display()))
    }
}

/// Heights above the plane, metres, row-major (the flipped image).
#[derive(Clone, Debug, PartialEq)]
pub struct HeightMap {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width * height` heights, m.
    pub m: Vec<f64>,
}

/// Section 5.1: flip depth to height above the plane (`camera_height - depth`, not below zero) and
/// fill null pixels with the mean of their valid 8-neighbours, repeating until none is left.
pub fn to_height(depth: &DepthImage, camera_height_m: f64) -> HeightMap {
    let (w, h) = (depth.width, depth.height);
    let mut m: Vec<f64> = depth.mm.iter().map(|&d| (camera_height_m - d as f64 * 1e-3).max(0.0)).collect();
    let mut valid: Vec<bool> = depth.mm.iter().map(|&d| d != 0).collect();
    // Each pass fills every null pixel touching a valid one; w + h passes reach any pixel.
    for _ in 0..(w + h) {
        let mut filled = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if valid[r * w + c] {
                    continue;
                }
                let (mut sum, mut n) = (0.0, 0);
                for dr in -1i64..=1 {
                    for dc in -1i64..=1 {
                        let (rr, cc) = (r as i64 + dr, c as i64 + dc);
                        if (dr, dc) != (0, 0) && rr >= 0 && cc >= 0 && (rr as usize) < h && (cc as usize) < w {
                            let k = rr as usize * w + cc as usize;
                            if valid[k] {
                                sum += m[k];
                                n += 1;
                            }
                        }
                    }
                }
                if n > 0 {
                    filled.push((r * w + c, sum / n as f64));
                }
            }
        }
        if filled.is_empty() {
            break;
        }
        for (k, v) in filled {
            m[k] = v;
            valid[k] = true;
        }
    }
    HeightMap { width: w, height: h, m }
}

/// Raise every pixel by `offset_m` (the thesis's ~65 mm, section 5.2).
pub fn raise(map: &mut HeightMap, offset_m: f64) {
    for v in &mut map.m {
        *v += offset_m;
    }
}

/// Seeded generator (SplitMix64) with Gaussian samples: reproducible scenes without a dependency.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

pub use flinch_model::avoid::shapes::*;

/// Render one synthetic depth frame: plane, optional robot (tool position), optional operator (hand
/// position), Gaussian depth noise and null pixels.
pub fn render(
    cam: &Camera,
    robot: Option<(&RobotShape, [f64; 2])>,
    operator: Option<(&OperatorShape, [f64; 2])>,
    rng: &mut Rng,
) -> DepthImage {
    let (w, h) = (cam.width_px, cam.height_px);
    let mut mm = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            let p = [(c as f64 + 0.5) * cam.m_per_px, (r as f64 + 0.5) * cam.m_per_px];
            let mut top: f64 = 0.0;
            if let Some((shape, tool)) = robot {
                top = top.max(shape.height_at(tool, p));
            }
            if let Some((shape, hand)) = operator {
                top = top.max(shape.height_at(hand, p));
            }
            let depth_mm = (cam.camera_height_m - top) * 1e3 + cam.noise_mm * rng.normal();
            let null = rng.uniform() < cam.null_fraction;
            mm.push(if null { 0 } else { depth_mm.round().clamp(1.0, 65535.0) as u16 });
        }
    }
    DepthImage { width: w, height: h, mm }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera { width_px: 60, height_px: 40, m_per_px: 0.01, camera_height_m: 1.2, noise_mm: 2.0, null_fraction: 0.05 }
    }

    #[test]
    fn png_and_pgm_roundtrip() {
        let mut rng = Rng::new(1);
        let img = render(&cam(), None, None, &mut rng);
        let dir = std::env::temp_dir().join(format!("flinch-avoid-depth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["d.png", "d.pgm"] {
            let p = dir.join(name);
            img.save(&p).unwrap();
            assert_eq!(DepthImage::load(&p).unwrap(), img, "{name}");
        }
        let bad = dir.join("bad.png");
        image::GrayImage::new(4, 4).save(&bad).unwrap();
        let e = DepthImage::load(&bad).unwrap_err();
        assert!(e.contains("bad.png") && e.contains("16-bit"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn flip_fills_nulls_and_raises() {
        let mut rng = Rng::new(2);
        let op = OperatorShape {
            entry_m: [0.3, 0.0],
            hand_radius_m: 0.05,
            hand_height_m: 0.2,
            forearm_width_m: 0.06,
            forearm_height_m: 0.15,
            obstacles: Vec::new(),
        };
        let img = render(&cam(), None, Some((&op, [0.3, 0.2])), &mut rng);
        assert!(img.mm.iter().any(|&d| d == 0), "some null pixels");
        let mut map = to_height(&img, 1.2);
        // No pixel left at the null value (height 1.2 m) and the hand stands out.
        assert!(map.m.iter().all(|&v| v < 0.3));
        let hand = map.m[20 * 60 + 30];
        assert!((hand - 0.2).abs() < 0.02, "hand top {hand}");
        let plane = map.m[35 * 60 + 5];
        assert!(plane < 0.01, "plane {plane}");
        raise(&mut map, 0.065);
        assert!((map.m[35 * 60 + 5] - plane - 0.065).abs() < 1e-12);
    }
}
