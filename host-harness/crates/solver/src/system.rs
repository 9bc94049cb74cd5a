//! What a plant and an integration method implement ([`System`], [`Stepper`]), and the two step-size
//! helpers every method shares: the scaled error norm and HINIT's initial step.

/// A first-order system y' = f(t, y) of N states.
pub trait System<const N: usize> {
    /// Writes f(t, y) into `dy`.
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);
}

/// One integration method: takes a step and interpolates inside it.
pub trait Stepper<const N: usize> {
    /// Attempts a step of size `h` from (t, y) with f0 = f(t, y); returns y1 and the scaled error
    /// norm (<= 1 is acceptable; fixed-step methods return 0).
    fn step<S: System<N> + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], f0: &[f64; N], h: f64) -> ([f64; N], f64);
    /// f at the end of the last step, when the method computed it (FSAL), else `None`.
    fn f_end(&self) -> Option<[f64; N]>;
    /// State at t + theta h inside the last step, theta in [0, 1].
    fn dense(&self, theta: f64) -> [f64; N];
    /// True for error-controlled methods.
    fn adaptive(&self) -> bool;
    /// Order of the error estimate's lower method (for the step-size law).
    fn order(&self) -> f64 {
        4.0
    }
    /// Tolerances (rtol, atol) of an adaptive method, for the initial-step estimate.
    fn tolerances(&self) -> (f64, f64) {
        (1e-6, 1e-9)
    }
}

/// Scaled RMS error norm used for step acceptance.
pub fn error_norm<const N: usize>(err: &[f64; N], y0: &[f64; N], y1: &[f64; N], rtol: f64, atol: f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..N {
        let sc = atol + rtol * y0[i].abs().max(y1[i].abs());
        let r = err[i] / sc;
        sum += r * r;
    }
    (sum / N as f64).sqrt()
}

/// Initial step size (Hairer, Norsett, Wanner, "Solving ODEs I", II.4, routine HINIT): makes the
/// first Euler step's local error about 1 % of the tolerance, from f0 and one more evaluation of f.
/// Used at the start and after every event, where the right-hand side has just changed (a contact
/// begins, a damping is fixed) and the step carried over from before says nothing. `order` is the
/// method's order; the result is at most `h_max`.
// HINIT's own arguments (the system, the state, the method's order and the tolerances): a struct
// for them would be built at its one call site only to be taken apart here.
#[allow(clippy::too_many_arguments)]
pub fn initial_step<const N: usize, S: System<N> + ?Sized>(sys: &S, t: f64, y0: &[f64; N], f0: &[f64; N], order: f64, rtol: f64, atol: f64, h_max: f64) -> f64 {
    let mut dnf = 0.0;
    let mut dny = 0.0;
    let mut sk = [0.0; N];
    for i in 0..N {
        sk[i] = atol + rtol * y0[i].abs();
        dnf += (f0[i] / sk[i]).powi(2);
        dny += (y0[i] / sk[i]).powi(2);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
    h = h.min(h_max);
    let mut y1 = [0.0; N];
    for i in 0..N {
        y1[i] = y0[i] + h * f0[i];
    }
    let mut f1 = [0.0; N];
    sys.rhs(t + h, &y1, &mut f1);
    let mut der2 = 0.0;
    for i in 0..N {
        der2 += ((f1[i] - f0[i]) / sk[i]).powi(2);
    }
    let der2 = der2.sqrt() / h;
    let der12 = der2.abs().max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 { (h * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / (order + 1.0)) };
    let h = (100.0 * h).min(h1).min(h_max);
    if h.is_finite() && h > 0.0 { h } else { h_max.min(1e-6) }
}
