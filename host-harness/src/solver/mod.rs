//! Integrators for the plant: adaptive Dormand-Prince 5(4) with dense output, and fixed-step RK4
//! and semi-implicit Euler for the speed/accuracy study. One [`driver`] runs them all, steps onto
//! breakpoints (where the motion law's acceleration jumps) and locates events on each step's
//! interpolant to a time tolerance, so contact onsets and threshold crossings are found, not
//! sampled. State is a stack array; nothing is allocated per step, and the right-hand side is
//! called through generics (no dynamic dispatch in the inner loop: `docs/accuracy.md`).

pub mod dopri5;
pub mod driver;
pub mod fixed;

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

/// Every method the simulator offers, as one type so a run picks it at run time without boxing.
#[derive(Debug, Clone)]
pub enum AnyStepper<const N: usize> {
    /// Adaptive Dormand-Prince 5(4).
    Dopri5(dopri5::Dopri5<N>),
    /// A fixed-step method.
    Fixed(fixed::Fixed<N>),
}

impl<const N: usize> Stepper<N> for AnyStepper<N> {
    #[inline]
    fn step<S: System<N> + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], f0: &[f64; N], h: f64) -> ([f64; N], f64) {
        match self {
            Self::Dopri5(s) => s.step(sys, t, y, f0, h),
            Self::Fixed(s) => s.step(sys, t, y, f0, h),
        }
    }
    fn f_end(&self) -> Option<[f64; N]> {
        match self {
            Self::Dopri5(s) => s.f_end(),
            Self::Fixed(s) => s.f_end(),
        }
    }
    #[inline]
    fn dense(&self, theta: f64) -> [f64; N] {
        match self {
            Self::Dopri5(s) => s.dense(theta),
            Self::Fixed(s) => s.dense(theta),
        }
    }
    fn adaptive(&self) -> bool {
        matches!(self, Self::Dopri5(_))
    }
    fn order(&self) -> f64 {
        match self {
            Self::Dopri5(s) => s.order(),
            Self::Fixed(s) => s.order(),
        }
    }
    fn tolerances(&self) -> (f64, f64) {
        match self {
            Self::Dopri5(s) => s.tolerances(),
            Self::Fixed(s) => s.tolerances(),
        }
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
