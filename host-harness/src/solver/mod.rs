//! Integrators for the plant: adaptive Dormand-Prince 5(4) with dense output, and fixed-step RK4
//! and semi-implicit Euler for the speed/accuracy study. One [`driver`] runs them all, steps onto
//! breakpoints (where the motion law's acceleration jumps) and locates events on each step's
//! interpolant to a time tolerance, so contact onsets and threshold crossings are found, not
//! sampled. State is a stack array; nothing is allocated per step.

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
    fn step(&mut self, sys: &dyn System<N>, t: f64, y: &[f64; N], f0: &[f64; N], h: f64) -> ([f64; N], f64);
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
