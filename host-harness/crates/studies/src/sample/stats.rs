//! The statistics of `flinch sample`: confidence intervals for a failure probability estimated from
//! k failures in n runs, the normal distribution's quantile for drawing, and the regularised
//! incomplete beta function the exact (Clopper-Pearson) interval needs. No dependency beyond `libm`
//! (erfc, lgamma); every function is checked against published values in the tests below and in
//! tests/sample.rs.

/// z for a two-sided 95 % interval: the normal quantile at 0.975.
pub const Z95: f64 = 1.959_963_984_540_054;

/// The Wilson score interval for k successes in n trials at two-sided level given by `z`
/// (Wilson 1927). Defined for n >= 1; both ends in [0, 1].
pub fn wilson(k: u64, n: u64, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n = n as f64;
    let p = k as f64 / n;
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z / denom * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// The Clopper-Pearson ("exact") interval for k successes in n trials at confidence 1 - alpha: the
/// beta quantiles `B(alpha/2; k, n-k+1)` and `B(1-alpha/2; k+1, n-k)`. At k = 0 the upper end is
/// `1 - (alpha/2)^(1/n)` and at k = n the lower end `(alpha/2)^(1/n)`, in closed form.
pub fn clopper_pearson(k: u64, n: u64, alpha: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let k = k.min(n);
    let nf = n as f64;
    let kf = k as f64;
    let half = alpha / 2.0;
    let lo = if k == 0 {
        0.0
    } else if k == n {
        half.powf(1.0 / nf)
    } else {
        beta_quantile(half, kf, nf - kf + 1.0)
    };
    let hi = if k == n {
        1.0
    } else if k == 0 {
        // 1 - (alpha/2)^(1/n), without cancellation for large n.
        -(half.ln() / nf).exp_m1()
    } else {
        beta_quantile(1.0 - half, kf + 1.0, nf - kf)
    };
    (lo, hi)
}

/// The x in [0, 1] where the regularised incomplete beta `I_x(a, b)` equals `q`, by bisection
/// (I is increasing in x); about 1e-15 relative.
pub fn beta_quantile(q: f64, a: f64, b: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if inc_beta(a, b, mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// The regularised incomplete beta function `I_x(a, b)`, a, b > 0 (continued fraction, modified
/// Lentz; Numerical Recipes 3rd ed. 6.4).
pub fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = libm::lgamma(a + b) - libm::lgamma(a) - libm::lgamma(b) + a * x.ln() + b * (-x).ln_1p();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-16;
    // The fraction converges in O(sqrt(max(a, b))) terms.
    let max_iter = 1000 + (20.0 * (a.max(b)).sqrt()) as usize;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=max_iter {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// The standard normal distribution function.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// The standard normal quantile for p in (0, 1): Acklam's rational approximation, refined by one
/// Halley step on `erfc` (about 1e-15 relative). 0 and 1 give -inf and +inf.
#[allow(clippy::excessive_precision)] // Acklam's coefficients as published
pub fn normal_quantile(p: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [-3.969683028665376e1, 2.209460984245205e2, -2.759285104469687e2, 1.383577518672690e2, -3.066479806614716e1, 2.506628277459239];
    const B: [f64; 5] = [-5.447609879822406e1, 1.615858368580409e2, -1.556989798598866e2, 6.680131188771972e1, -1.328068155288572e1];
    const C: [f64; 6] = [-7.784894002430293e-3, -3.223964580411365e-1, -2.400758277161838, -2.549732539343734, 4.374664141464968, 2.938163982698783];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    const P_LOW: f64 = 0.02425;
    let x = if p < P_LOW {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5]) / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - P_LOW {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (-p).ln_1p()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5]) / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // One Halley step on e = Phi(x) - p; in the upper tail Phi(x) = 1 - erfc(x/sqrt 2)/2.
    let e = if x > 0.0 { (1.0 - p) - 0.5 * libm::erfc(x / std::f64::consts::SQRT_2) } else { 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2) - p };
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (x * x / 2.0).exp();
    x - u / (1.0 + x * u / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol, "{a} vs {b} (tol {tol})");
    }

    #[test]
    fn normal_quantile_against_tables() {
        close(normal_quantile(0.975), 1.959_963_984_540_054, 1e-12);
        close(normal_quantile(0.5), 0.0, 1e-15);
        close(normal_quantile(0.025), -1.959_963_984_540_054, 1e-12);
        close(normal_quantile(1e-6), -4.753_424_308_822_899, 1e-9);
        close(normal_quantile(1.0 - 1e-6), 4.753_424_308_822_899, 1e-7);
        close(normal_quantile(0.8413447460685429), 1.0, 1e-12);
        for p in [1e-10, 0.01, 0.3, 0.7, 0.99] {
            close(normal_cdf(normal_quantile(p)), p, 1e-14_f64.max(p * 1e-12));
        }
    }

    #[test]
    fn incomplete_beta_closed_forms() {
        // I_x(1, b) = 1 - (1-x)^b; I_x(a, 1) = x^a.
        close(inc_beta(1.0, 5.0, 0.2), 1.0 - 0.8f64.powi(5), 1e-14);
        close(inc_beta(3.0, 1.0, 0.4), 0.064, 1e-14);
        close(inc_beta(2.5, 2.5, 0.5), 0.5, 1e-14);
    }
}
