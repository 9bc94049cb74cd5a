//! Gaussian RBF fit of a height map (section 5.2, eq 65-73).
//!
//! A regular `nx x ny` grid of Gaussians, centre `(i, j)` at `((i + 1/2) s, (j + 1/2) s)` pixels with
//! spacing `s = width / nx`, standard deviation `sigma = s / 2` (eq 70) times a factor. The basis is
//! separable, `phi = g(x - cx_i) g(y - cy_j)`, so the image-by-centre matrix of eq 67 is the Kronecker
//! product `G = Gy (x) Gx` and its pseudo-inverse is `G+ = Gy+ (x) Gx+`. The weights of eq 68 are then
//! `W = Gy+ F Gx+^T` (`F` the image as a `height x width` matrix): [`Fitter`]. [`DenseFitter`] does the
//! thesis's literal `lambda = G+ f` with the full matrix, for comparison (`benches/avoid.rs`).
//! [`filter_weights`] is eq 71; [`Field`] evaluates `f*` and its analytic gradient (eq 72-73) with
//! any sigma on the same weights (Fig. 90).

use flinch_firmware::avoidance::{self as fw, Real};
use nalgebra::DMatrix;

use crate::depth::HeightMap;

/// Geometry of the RBF grid over an image.
#[derive(Clone, Debug, PartialEq)]
pub struct RbfGrid {
    /// Centres along x.
    pub nx: usize,
    /// Centres along y.
    pub ny: usize,
    /// Image columns.
    pub width_px: usize,
    /// Image rows.
    pub height_px: usize,
    /// Pixel size on the plane, m.
    pub m_per_px: f64,
    /// Centre spacing, px.
    pub spacing_px: f64,
    /// Standard deviation used for the fit, px (eq 70 times `sigma_factor`).
    pub sigma_px: f64,
}

impl RbfGrid {
    /// `n` centres across the width, as many rows as fit the height at the same spacing.
    pub fn new(width_px: usize, height_px: usize, n: usize, m_per_px: f64, sigma_factor: f64) -> Result<Self, String> {
        if n == 0 || n > fw::MAX_AXIS {
            return Err(format!("grid size {n} out of range 1..={}", fw::MAX_AXIS));
        }
        if width_px < n || height_px == 0 {
            return Err(format!("image {width_px} x {height_px} px too small for a {n}-centre grid"));
        }
        let spacing_px = width_px as f64 / n as f64;
        let ny = ((height_px as f64 / spacing_px).round() as usize).clamp(1, fw::MAX_AXIS);
        Ok(RbfGrid { nx: n, ny, width_px, height_px, m_per_px, spacing_px, sigma_px: sigma_factor * spacing_px / 2.0 })
    }

    /// 1-D basis: `n_px` pixels by `n_c` centres, `exp(-(p + 1/2 - c)^2 / (2 sigma^2))`.
    pub fn basis(&self, n_px: usize, n_c: usize) -> DMatrix<f64> {
        let s2 = 2.0 * self.sigma_px * self.sigma_px;
        DMatrix::from_fn(n_px, n_c, |p, i| {
            let d = p as f64 + 0.5 - (i as f64 + 0.5) * self.spacing_px;
            (-d * d / s2).exp()
        })
    }
}

/// Separable least-squares fit: `W = Gy+ F Gx+^T`, pseudo-inverses computed once.
#[derive(Clone, Debug)]
pub struct Fitter {
    /// The grid.
    pub grid: RbfGrid,
    gy_pinv: DMatrix<f64>,
    gx_pinv_t: DMatrix<f64>,
}

fn pinv(m: DMatrix<f64>) -> Result<DMatrix<f64>, String> {
    m.pseudo_inverse(1e-12).map_err(|e| format!("pseudo-inverse failed: {e}"))
}

impl Fitter {
    /// Compute `Gx+` and `Gy+` (the offline part of eq 68).
    pub fn new(grid: RbfGrid) -> Result<Self, String> {
        let gx = grid.basis(grid.width_px, grid.nx);
        let gy = grid.basis(grid.height_px, grid.ny);
        Ok(Fitter { gy_pinv: pinv(gy)?, gx_pinv_t: pinv(gx)?.transpose(), grid })
    }

    /// Eq 68 on one height map: the `ny * nx` weights, row-major (`j * nx + i`), metres.
    pub fn weights(&self, map: &HeightMap) -> Vec<f64> {
        let f = DMatrix::from_row_slice(map.height, map.width, &map.m);
        let w = &self.gy_pinv * f * &self.gx_pinv_t; // ny x nx
        let mut out = Vec::with_capacity(self.grid.nx * self.grid.ny);
        for j in 0..self.grid.ny {
            for i in 0..self.grid.nx {
                out.push(w[(j, i)]);
            }
        }
        out
    }
}

/// The literal eq 67-68: the full `(w h) x (nx ny)` matrix `G` and its pseudo-inverse.
#[derive(Clone, Debug)]
pub struct DenseFitter {
    g_pinv: DMatrix<f64>,
}

impl DenseFitter {
    /// Build `G` and compute `G+` by SVD (slow: this is what separability avoids).
    pub fn new(grid: &RbfGrid) -> Result<Self, String> {
        Ok(DenseFitter { g_pinv: pinv(dense_basis(grid))? })
    }

    /// The same `G+` assembled as `Gy+ (x) Gx+` from a separable fitter (no SVD of the big matrix).
    pub fn from_separable(f: &Fitter) -> Self {
        DenseFitter { g_pinv: f.gy_pinv.kronecker(&f.gx_pinv_t.transpose()) }
    }

    /// `lambda = G+ f`, row-major weights.
    pub fn weights(&self, map: &HeightMap) -> Vec<f64> {
        let f = nalgebra::DVector::from_column_slice(&map.m);
        (&self.g_pinv * f).as_slice().to_vec()
    }
}

/// The full matrix of eq 67: row `r * w + c` (pixel), column `j * nx + i` (centre).
pub fn dense_basis(grid: &RbfGrid) -> DMatrix<f64> {
    let gx = grid.basis(grid.width_px, grid.nx);
    let gy = grid.basis(grid.height_px, grid.ny);
    gy.kronecker(&gx)
}

/// Eq 71: zero every weight below `mean + std` of the weights; returns how many were zeroed.
pub fn filter_weights(w: &mut [f64]) -> usize {
    if w.is_empty() {
        return 0;
    }
    let n = w.len() as f64;
    let mean = w.iter().sum::<f64>() / n;
    let std = (w.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    let cut = mean + std;
    let mut zeroed = 0;
    for v in w.iter_mut() {
        if *v < cut {
            *v = 0.0;
            zeroed += 1;
        }
    }
    zeroed
}

/// The session byte of this host start (frame byte 5): the Unix time in whole seconds, modulo 256,
/// taken once per process. The receiver applies a new session only once the weights in use are
/// stale (the watchdog has stopped the tool) and never one it applied before since the MCU booted.
/// Restarts at least 1 s and less than 256 s apart therefore always get a byte the MCU has not seen
/// from the previous start; a byte that happens to match an earlier start of the same MCU run is
/// refused (the tool stays stopped, `old_session` counts it) until the host starts again: a loss of
/// availability, never an accepted stale writer. A random byte would collide with the previous start
/// once in 256; a counter would need storage the host does not have. Nothing is persisted.
pub fn host_session() -> u8 {
    static SESSION: std::sync::OnceLock<u8> = std::sync::OnceLock::new();
    *SESSION.get_or_init(|| std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| (d.as_secs() % 256) as u8))
}

/// The interpolated field `f*` in metres on the plane, evaluated with its own sigma.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Centres along x.
    pub nx: usize,
    /// Centres along y.
    pub ny: usize,
    /// Centre (0, 0), m.
    pub x0_m: f64,
    /// Centre (0, 0), m.
    pub y0_m: f64,
    /// Spacing, m.
    pub spacing_m: f64,
    /// Sigma used for evaluation, m.
    pub sigma_m: f64,
    /// Weights, m, row-major.
    pub weights: Vec<f64>,
}

impl Field {
    /// The field of `weights` on `grid`, evaluated at `sigma_factor` times the fit's sigma (Fig. 90).
    pub fn new(grid: &RbfGrid, weights: Vec<f64>, eval_sigma_factor: f64) -> Self {
        let s = grid.m_per_px;
        Field {
            nx: grid.nx,
            ny: grid.ny,
            x0_m: 0.5 * grid.spacing_px * s,
            y0_m: 0.5 * grid.spacing_px * s,
            spacing_m: grid.spacing_px * s,
            sigma_m: grid.sigma_px * s * eval_sigma_factor,
            weights,
        }
    }

    /// Eq 65 and 72-73, full sum (no truncation): `(f*, df*/dx, df*/dy)` at `(x, y)` m.
    pub fn sample(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let s2 = self.sigma_m * self.sigma_m;
        let gx: Vec<(f64, f64)> = (0..self.nx)
            .map(|i| {
                let d = x - (self.x0_m + i as f64 * self.spacing_m);
                let g = (-d * d / (2.0 * s2)).exp();
                (g, -g * d / s2)
            })
            .collect();
        let (mut f, mut fx, mut fy) = (0.0, 0.0, 0.0);
        for j in 0..self.ny {
            let d = y - (self.y0_m + j as f64 * self.spacing_m);
            let gy = (-d * d / (2.0 * s2)).exp();
            let dgy = -gy * d / s2;
            let row = &self.weights[j * self.nx..(j + 1) * self.nx];
            let (mut a, mut b) = (0.0, 0.0);
            for (w, (g, dg)) in row.iter().zip(&gx) {
                a += w * g;
                b += w * dg;
            }
            f += gy * a;
            fx += gy * b;
            fy += dgy * a;
        }
        (f, fx, fy)
    }

    /// `f*` at every pixel centre of a `width x height` image (eq 69).
    pub fn raster(&self, width: usize, height: usize, m_per_px: f64) -> Vec<f64> {
        let s2 = 2.0 * self.sigma_m * self.sigma_m;
        let b = |n: usize, nc: usize, c0: f64| {
            DMatrix::from_fn(n, nc, |p, i| {
                let d = (p as f64 + 0.5) * m_per_px - (c0 + i as f64 * self.spacing_m);
                (-d * d / s2).exp()
            })
        };
        let gx = b(width, self.nx, self.x0_m);
        let gy = b(height, self.ny, self.y0_m);
        let w = DMatrix::from_row_slice(self.ny, self.nx, &self.weights);
        let img = gy * w * gx.transpose();
        let mut out = Vec::with_capacity(width * height);
        for r in 0..height {
            for c in 0..width {
                out.push(img[(r, c)]);
            }
        }
        out
    }

    fn q16(v: f64) -> i32 {
        (v * 65536.0).round().clamp(i32::MIN as f64, i32::MAX as f64) as i32
    }

    /// The frame that carries this field to the MCU (`flinch_firmware::avoidance::frame`), in this
    /// host start's session ([`host_session`]), with the default monitor part (a person touching
    /// the tool in every sector: a monitored board stops; a zero clock echo; see
    /// [`Field::to_frame_with`]). For the receiver's and the number types' tests.
    pub fn to_frame(&self, seq: u32, age_ms: u16) -> Result<Vec<u8>, String> {
        self.to_frame_with(seq, age_ms, &fw::FrameHeader::default())
    }

    /// [`Field::to_frame`] with the monitor's part of the header (clock echo, tool at capture,
    /// nearest point, separations per sector) taken from `sensed`.
    pub fn to_frame_with(&self, seq: u32, age_ms: u16, sensed: &fw::FrameHeader) -> Result<Vec<u8>, String> {
        let h = fw::FrameHeader {
            session: host_session(),
            nx: self.nx as u8,
            ny: self.ny as u8,
            seq,
            age_ms,
            x0_q16: Self::q16(self.x0_m),
            y0_q16: Self::q16(self.y0_m),
            spacing_q16: Self::q16(self.spacing_m),
            sigma_q16: Self::q16(self.sigma_m),
            ..*sensed
        };
        let w: Vec<i32> = self.weights.iter().map(|&v| Self::q16(v)).collect();
        let mut out = vec![0u8; fw::frame::MAX_FRAME];
        let n = fw::encode_frame(&h, &w, &mut out).ok_or_else(|| format!("grid {} x {} cannot be framed", self.nx, self.ny))?;
        out.truncate(n);
        Ok(out)
    }

    /// The same field as a firmware grid in number type `R` (no wire rounding).
    pub fn to_grid<R: Real>(&self) -> Option<Box<fw::Grid<R>>> {
        let mut g = Box::new(fw::Grid::<R>::empty());
        let ok = g.set_geometry(
            self.nx,
            self.ny,
            R::from_f64(self.x0_m),
            R::from_f64(self.y0_m),
            R::from_f64(self.spacing_m),
            R::from_f64(self.sigma_m),
        );
        if !ok {
            return None;
        }
        for (d, s) in g.weights.iter_mut().zip(&self.weights) {
            *d = R::from_f64(*s);
        }
        Some(g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> RbfGrid {
        RbfGrid::new(60, 60, n, 0.01, 1.0).unwrap()
    }

    /// An image that is exactly a sum of the grid's Gaussians is fitted back to its weights.
    #[test]
    fn fit_reproduces_a_known_sum_of_gaussians() {
        let g = grid(6);
        let mut truth = vec![0.0; 36];
        truth[2 * 6 + 3] = 0.3;
        truth[4 * 6 + 1] = 0.12;
        truth[0] = 0.05;
        let field = Field::new(&g, truth.clone(), 1.0);
        let map = HeightMap { width: 60, height: 60, m: field.raster(60, 60, 0.01) };
        let fit = Fitter::new(g.clone()).unwrap();
        let w = fit.weights(&map);
        for (a, b) in w.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-8, "{a} vs {b}");
        }
        let dense = DenseFitter::new(&g).unwrap().weights(&map);
        for (a, b) in dense.iter().zip(&w) {
            assert!((a - b).abs() < 1e-8, "dense {a} vs separable {b}");
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let g = grid(6);
        let w: Vec<f64> = (0..36).map(|k| ((k * 7) % 5) as f64 * 0.03).collect();
        for factor in [1.0, 1.5] {
            let f = Field::new(&g, w.clone(), factor);
            for k in 0..20 {
                let (x, y) = (0.03 * k as f64 + 0.01, 0.55 - 0.025 * k as f64);
                let (_, fx, fy) = f.sample(x, y);
                let h = 1e-6;
                let nx = (f.sample(x + h, y).0 - f.sample(x - h, y).0) / (2.0 * h);
                let ny = (f.sample(x, y + h).0 - f.sample(x, y - h).0) / (2.0 * h);
                assert!((fx - nx).abs() < 1e-6 * (1.0 + nx.abs()), "{fx} vs {nx}");
                assert!((fy - ny).abs() < 1e-6 * (1.0 + ny.abs()), "{fy} vs {ny}");
            }
        }
    }

    #[test]
    fn filter_keeps_only_weights_above_mean_plus_std() {
        // mean 2, population std 2: cut at 4, and a weight exactly at the cut is kept.
        let mut w = vec![0.0, 0.0, 4.0, 4.0];
        assert_eq!(filter_weights(&mut w), 2);
        assert_eq!(w, vec![0.0, 0.0, 4.0, 4.0]);
        // mean 2, std 3: cut at 5.
        let mut w = vec![-1.0, 5.0, 4.9, -0.9];
        assert_eq!(filter_weights(&mut w), 3);
        assert_eq!(w, vec![0.0, 5.0, 0.0, 0.0]);
        assert_eq!(filter_weights(&mut []), 0);
    }

    #[test]
    fn wider_sigma_keeps_weights_and_spreads_the_hill() {
        let g = grid(6);
        let mut w = vec![0.0; 36];
        w[2 * 6 + 2] = 0.2;
        let narrow = Field::new(&g, w.clone(), 1.0);
        let wide = Field::new(&g, w, 1.5);
        let (cx, cy) = (narrow.x0_m + 2.0 * narrow.spacing_m, narrow.y0_m + 2.0 * narrow.spacing_m);
        let off = cx + 1.5 * narrow.spacing_m;
        assert!((narrow.sample(cx, cy).0 - wide.sample(cx, cy).0).abs() < 1e-12, "same peak");
        assert!(wide.sample(off, cy).0 > 5.0 * narrow.sample(off, cy).0, "wider flank");
    }

    #[test]
    fn frame_and_grid_carry_the_field() {
        let g = grid(6);
        let w: Vec<f64> = (0..36).map(|k| (k % 4) as f64 * 0.05).collect();
        let f = Field::new(&g, w, 1.5);
        let frame = f.to_frame(7, 3).unwrap();
        let mut rx = fw::Receiver::<f64>::new(100, 10);
        rx.feed(&frame, 0);
        assert_eq!(rx.stats.good, 1);
        let grid = f.to_grid::<f64>().unwrap();
        let lut = fw::GaussLibm;
        for k in 0..10 {
            let (x, y) = (0.05 * k as f64 + 0.02, 0.3);
            let (h, gx, gy) = f.sample(x, y);
            let a = fw::sample(rx.grid(), &lut, x, y);
            let b = fw::sample(&grid, &lut, x, y);
            assert!((a.height - h).abs() < 2e-3 && (b.height - h).abs() < 2e-3);
            assert!((b.grad_x - gx).abs() < 0.05 && (b.grad_y - gy).abs() < 0.05);
        }
    }
}
