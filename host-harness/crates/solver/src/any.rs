//! Every method as one type ([`AnyStepper`]), so a run picks its method at run time without boxing.

use crate::dopri5;
use crate::fixed;
use crate::system::{Stepper, System};

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
