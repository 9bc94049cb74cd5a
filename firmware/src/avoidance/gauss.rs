//! The Gaussian basis `exp(-t^2 / 2)` of eq 66, with `t = |x - xi| / sigma` along one axis.
//!
//! A grid of Gaussians is separable, `phi(x, y) = g(tx) g(ty)`, so the step only needs the 1-D
//! function. All implementations truncate at [`TRUNC_SIGMAS`] standard
//! deviations (`exp(-8) = 3.4e-4` of the peak at 4 sigma): that compact support is what lets the step
//! visit only the few centres near the tool.

/// Truncation radius of the Gaussian, in standard deviations (the field visits only the centres
/// within it: `field.rs`).
pub const TRUNC_SIGMAS: f64 = 4.0;
use super::num::Real;

/// A 1-D Gaussian `g(t) = exp(-t^2/2)` for `t >= 0`, zero at and beyond the truncation.
pub trait Gauss<R: Real> {
    /// `exp(-t^2/2)` for `t = |t|` already made non-negative by the caller.
    fn g(&self, t_abs: R) -> R;
}

/// Number of segments of the lookup table over `[0, TRUNC_SIGMAS]`.
pub const LUT_SEGMENTS: usize = 128;

/// Lookup table with linear interpolation: `LUT_SEGMENTS` segments over `[0, TRUNC_SIGMAS]`.
///
/// Interpolation error bound `h^2/8 max|g''| = (4/128)^2 / 8 = 1.2e-4` of the peak.
#[derive(Clone, Debug)]
pub struct GaussLut<R> {
    table: [R; LUT_SEGMENTS + 2],
    inv_step: R,
}

impl<R: Real> GaussLut<R> {
    /// Build the table (once, at start-up) from `libm::exp`.
    pub fn new() -> Self {
        let mut table = [R::ZERO; LUT_SEGMENTS + 2];
        let step = TRUNC_SIGMAS / LUT_SEGMENTS as f64;
        for (k, slot) in table.iter_mut().enumerate().take(LUT_SEGMENTS + 1) {
            let t = k as f64 * step;
            *slot = R::from_f64(libm::exp(-0.5 * t * t));
        }
        // The last segment interpolates towards zero so the truncation is continuous.
        if let Some(last) = table.get_mut(LUT_SEGMENTS) {
            *last = R::ZERO;
        }
        GaussLut { table, inv_step: R::from_f64(1.0 / step) }
    }
}

impl<R: Real> Default for GaussLut<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: Real> Gauss<R> for GaussLut<R> {
    #[inline]
    fn g(&self, t_abs: R) -> R {
        let u = t_abs.mul(self.inv_step);
        let k = u.floor_int();
        if k < 0 || k as usize >= LUT_SEGMENTS {
            return R::ZERO;
        }
        let frac = u.sub(R::from_int(k));
        let (a, b) = match (self.table.get(k as usize), self.table.get((k as usize).saturating_add(1))) {
            (Some(a), Some(b)) => (*a, *b),
            _ => return R::ZERO,
        };
        a.add(b.sub(a).mul(frac))
    }
}

/// `libm::expf` / `libm::exp`, truncated like the table.
#[derive(Clone, Copy, Debug, Default)]
pub struct GaussLibm;

impl Gauss<f32> for GaussLibm {
    #[inline]
    fn g(&self, t: f32) -> f32 {
        if t >= TRUNC_SIGMAS as f32 {
            0.0
        } else {
            libm::expf(-0.5 * t * t)
        }
    }
}

impl Gauss<f64> for GaussLibm {
    #[inline]
    fn g(&self, t: f64) -> f64 {
        if t >= TRUNC_SIGMAS {
            0.0
        } else {
            libm::exp(-0.5 * t * t)
        }
    }
}

/// `micromath`'s fast `exp` approximation (f32 only), truncated like the table.
#[derive(Clone, Copy, Debug, Default)]
pub struct GaussMicromath;

impl Gauss<f32> for GaussMicromath {
    #[inline]
    fn g(&self, t: f32) -> f32 {
        if t >= TRUNC_SIGMAS as f32 {
            0.0
        } else {
            // Fully qualified: the inherent `f32::exp` must not shadow micromath's.
            micromath::F32Ext::exp(-0.5 * t * t)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fixed::types::{I16F16, I8F24};

    fn max_err<R: Real, G: Gauss<R>>(g: &G) -> f64 {
        let mut worst = 0.0f64;
        for k in 0..4000 {
            let t = k as f64 * 0.001;
            let exact = libm::exp(-0.5 * t * t);
            let e = (g.g(R::from_f64(t)).to_f64() - exact).abs();
            worst = worst.max(e);
        }
        worst
    }

    #[test]
    fn gaussians_match_exp() {
        // Table: interpolation bound 1.2e-4 plus the last segment bent to zero (exp(-8) = 3.4e-4).
        assert!(max_err::<f64, _>(&GaussLut::<f64>::new()) < 4e-4);
        assert!(max_err::<I16F16, _>(&GaussLut::<I16F16>::new()) < 4.5e-4);
        assert!(max_err::<I8F24, _>(&GaussLut::<I8F24>::new()) < 4e-4);
        assert!(max_err::<f32, _>(&GaussLibm) < 1e-6);
        assert!(max_err::<f32, _>(&GaussMicromath) < 1e-2);
        assert_eq!(GaussLut::<f32>::new().g(5.0), 0.0);
    }
}
