//! The interpolated field `f*` and its gradient at one point (eq 65-66, 72-73), over a truncated window.
//!
//! Centre `(i, j)` sits at `(x0 + i s, y0 + j s)` (spacing `s`, metres). The weights are stored row
//! by row (`j` outer). Because the grid is regular, `phi = g(tx) g(ty)`: the step computes `g` once
//! per window column and once per window row, then
//!
//! ```text
//! a_j = sum_i w_ji g(tx_i)          b_j = sum_i w_ji g(tx_i) tx_i
//! f*  = sum_j g(ty_j) a_j
//! df*/dx = -(1/sigma) sum_j g(ty_j) b_j      df*/dy = -(1/sigma) sum_j g(ty_j) ty_j a_j
//! ```
//!
//! with `t = (p - centre) / sigma`, using `d/dx exp(-t^2/2) = -(t / sigma) exp(-t^2/2)`.
//! Only centres within [`TRUNC_SIGMAS`] standard deviations are visited (at most
//! [`MAX_WINDOW`] per axis).

use super::gauss::Gauss;
use super::num::Real;

/// Truncation radius of the Gaussian, in standard deviations (defined with the Gaussian).
pub use super::gauss::TRUNC_SIGMAS;
/// Largest grid side the firmware accepts (the thesis's 30 x 30).
pub const MAX_AXIS: usize = 30;
/// Largest number of centres (`MAX_AXIS^2`).
pub const MAX_CENTRES: usize = MAX_AXIS * MAX_AXIS;
/// Most centres visited per axis: `2 * TRUNC_SIGMAS * sigma / s + 1` must fit; with the thesis's
/// `sigma = s/2` that is 5, and 7 with the widened `sigma' = 1.5 sigma` of Fig. 90.
pub const MAX_WINDOW: usize = 10;

/// A received grid of weights and its geometry, in the number type of the step.
#[derive(Clone, Debug)]
pub struct Grid<R> {
    /// Centres along x (1..=MAX_AXIS).
    pub nx: usize,
    /// Centres along y (1..=MAX_AXIS).
    pub ny: usize,
    /// Position of centre (0, 0), metres.
    pub x0: R,
    /// Position of centre (0, 0), metres.
    pub y0: R,
    /// Standard deviation of the basis used for evaluation, metres (eq 70, widened per Fig. 90).
    pub sigma: R,
    /// `1 / sigma`, 1/m.
    pub inv_sigma: R,
    /// Centre spacing in units of sigma, `s / sigma` (2 for eq 70).
    pub step_t: R,
    /// `sigma / s`, used for the window bounds.
    pub sigma_over_s: R,
    /// Weights lambda (eq 68 after the filter of eq 71), metres, row-major (`j * nx + i`).
    pub weights: [R; MAX_CENTRES],
    /// Sequence number of the frame the weights came from.
    pub seq: u32,
}

impl<R: Real> Grid<R> {
    /// An empty grid (no centres: the field is zero everywhere).
    pub fn empty() -> Self {
        Grid {
            nx: 0,
            ny: 0,
            x0: R::ZERO,
            y0: R::ZERO,
            sigma: R::ONE,
            inv_sigma: R::ONE,
            step_t: R::ONE,
            sigma_over_s: R::ONE,
            weights: [R::ZERO; MAX_CENTRES],
            seq: 0,
        }
    }

    /// Set the geometry from metres; `false` (and nothing changed) if it is invalid.
    // The negated comparisons are deliberate: they also refuse NaN.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn set_geometry(&mut self, nx: usize, ny: usize, x0: R, y0: R, spacing: R, sigma: R) -> bool {
        let zero = R::ZERO;
        if nx == 0 || ny == 0 || nx > MAX_AXIS || ny > MAX_AXIS || !(spacing > zero) || !(sigma > zero) {
            return false;
        }
        let step_t = spacing.div(sigma);
        let sigma_over_s = sigma.div(spacing);
        // The window must fit MAX_WINDOW centres per axis: 2 * TRUNC * sigma/s + 1 < MAX_WINDOW.
        let reach = sigma_over_s.mul(R::from_f64(2.0 * TRUNC_SIGMAS)).add(R::from_int(2));
        if !(reach <= R::from_int(MAX_WINDOW as i32)) {
            return false;
        }
        self.nx = nx;
        self.ny = ny;
        self.x0 = x0;
        self.y0 = y0;
        self.sigma = sigma;
        self.inv_sigma = R::ONE.div(sigma);
        self.step_t = step_t;
        self.sigma_over_s = sigma_over_s;
        true
    }

    /// Weight of centre `(i, j)`, zero outside the grid.
    #[inline]
    pub fn weight(&self, i: usize, j: usize) -> R {
        if i >= self.nx {
            return R::ZERO;
        }
        match self.weights.get(j.saturating_mul(self.nx).saturating_add(i)) {
            Some(w) => *w,
            None => R::ZERO,
        }
    }
}

/// The field and its gradient at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSample<R> {
    /// `f*(x, y)`, metres.
    pub height: R,
    /// `df*/dx`, dimensionless.
    pub grad_x: R,
    /// `df*/dy`, dimensionless.
    pub grad_y: R,
}

/// Window of centre indices `lo..=hi` along one axis around grid coordinate `u = (p - p0) / s`.
#[inline]
fn window<R: Real>(u: R, reach: R, n: usize) -> (usize, usize) {
    let lo = u.sub(reach).floor_int().saturating_add(1).max(0);
    let hi = u.add(reach).floor_int().min((n as i32).saturating_sub(1));
    if hi < lo {
        return (1, 0);
    }
    let hi = hi.min(lo.saturating_add(MAX_WINDOW as i32).saturating_sub(1));
    (lo as usize, hi as usize)
}

/// Evaluate `f*` and its gradient at `(x, y)` (metres).
pub fn sample<R: Real, G: Gauss<R>>(grid: &Grid<R>, gauss: &G, x: R, y: R) -> FieldSample<R> {
    let zero = R::ZERO;
    let mut out = FieldSample { height: zero, grad_x: zero, grad_y: zero };
    if grid.nx == 0 || grid.ny == 0 {
        return out;
    }
    let reach = grid.sigma_over_s.mul(R::from_f64(TRUNC_SIGMAS));
    // Position in units of sigma relative to centre 0, and in grid units for the window.
    let tx0 = x.sub(grid.x0).mul(grid.inv_sigma);
    let ty0 = y.sub(grid.y0).mul(grid.inv_sigma);
    let ux = tx0.mul(grid.sigma_over_s);
    let uy = ty0.mul(grid.sigma_over_s);
    let (ilo, ihi) = window(ux, reach, grid.nx);
    let (jlo, jhi) = window(uy, reach, grid.ny);
    if ihi < ilo || jhi < jlo {
        return out;
    }

    // Per column: g(tx_i) and g(tx_i) * tx_i.
    let mut gx = [zero; MAX_WINDOW];
    let mut hx = [zero; MAX_WINDOW];
    // `t_i = tx0 - i step_t`, one product for the first and a subtraction per column after it
    // (exact in fixed point, where `i step_t` is exact too).
    let mut t = tx0.sub(grid.step_t.mul(R::from_int(ilo as i32)));
    for (gk, hk) in gx.iter_mut().zip(hx.iter_mut()).take(ihi.saturating_sub(ilo).saturating_add(1)) {
        let g = gauss.g(t.abs());
        *gk = g;
        *hk = g.mul(t);
        t = t.sub(grid.step_t);
    }

    let mut f = zero;
    let mut sx = zero;
    let mut sy = zero;
    let mut t_next = ty0.sub(grid.step_t.mul(R::from_int(jlo as i32)));
    for j in jlo..=jhi {
        let t = t_next;
        t_next = t_next.sub(grid.step_t);
        let gy = gauss.g(t.abs());
        if gy == zero {
            continue;
        }
        let row = j.saturating_mul(grid.nx);
        let ws = match grid.weights.get(row.saturating_add(ilo)..=row.saturating_add(ihi)) {
            Some(ws) => ws,
            None => continue,
        };
        let (a, b) = R::dot2(ws, &gx, &hx);
        f = f.add(gy.mul(a));
        sx = sx.add(gy.mul(b));
        sy = sy.add(gy.mul(t).mul(a));
    }
    out.height = f;
    out.grad_x = sx.mul(grid.inv_sigma).neg();
    out.grad_y = sy.mul(grid.inv_sigma).neg();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::avoidance::gauss::{GaussLibm, GaussLut};

    fn grid_f64() -> Grid<f64> {
        let mut g = Grid::<f64>::empty();
        assert!(g.set_geometry(15, 15, 0.035, 0.035, 0.07, 0.035));
        for j in 0..15 {
            for i in 0..15 {
                g.weights[j * 15 + i] = 0.01 * ((i * 7 + j * 3) % 11) as f64;
            }
        }
        g
    }

    /// The full, untruncated sum of eq 65 and its derivative.
    fn exact(g: &Grid<f64>, x: f64, y: f64) -> (f64, f64, f64) {
        let s = 1.0 / g.inv_sigma;
        let (mut f, mut fx, mut fy) = (0.0, 0.0, 0.0);
        for j in 0..g.ny {
            for i in 0..g.nx {
                let dx = x - (g.x0 + i as f64 * g.step_t * s);
                let dy = y - (g.y0 + j as f64 * g.step_t * s);
                let p = libm::exp(-(dx * dx + dy * dy) / (2.0 * s * s));
                let w = g.weights[j * g.nx + i];
                f += w * p;
                fx -= w * p * dx / (s * s);
                fy -= w * p * dy / (s * s);
            }
        }
        (f, fx, fy)
    }

    #[test]
    fn truncated_window_matches_full_sum() {
        let g = grid_f64();
        for k in 0..50 {
            let x = 0.02 * k as f64 + 0.003;
            let y = 1.0 - 0.019 * k as f64;
            let (f, fx, fy) = exact(&g, x, y);
            let s = sample(&g, &GaussLibm, x, y);
            let max_w = 0.1;
            // Truncation at 4 sigma: at most exp(-8) per centre beyond the window.
            assert!((s.height - f).abs() < 30.0 * max_w * 3.4e-4, "{x} {y}: {} vs {f}", s.height);
            assert!((s.grad_x - fx).abs() < 0.05 * (1.0 + fx.abs()), "{} vs {fx}", s.grad_x);
            assert!((s.grad_y - fy).abs() < 0.05 * (1.0 + fy.abs()), "{} vs {fy}", s.grad_y);
            let l = sample(&g, &GaussLut::<f64>::new(), x, y);
            assert!((l.height - s.height).abs() < 3e-3);
        }
    }

    #[test]
    fn far_outside_is_zero_and_invalid_geometry_is_refused() {
        let g = grid_f64();
        let s = sample(&g, &GaussLibm, 5.0, 5.0);
        assert_eq!(s.height, 0.0);
        let mut e = Grid::<f64>::empty();
        assert!(!e.set_geometry(0, 3, 0.0, 0.0, 0.1, 0.05));
        assert!(!e.set_geometry(31, 3, 0.0, 0.0, 0.1, 0.05));
        assert!(!e.set_geometry(3, 3, 0.0, 0.0, 0.1, 0.0));
        assert!(!e.set_geometry(3, 3, 0.0, 0.0, 0.1, 1.0), "window too wide");
        assert_eq!(sample(&e, &GaussLibm, 0.0, 0.0).height, 0.0);
    }
}
