//! Fixed-step methods for the speed/accuracy study: classical RK4 and semi-implicit (symplectic)
//! Euler. Both interpolate inside a step with a cubic Hermite on the end values and slopes, so
//! events are located the same way as with the adaptive method.

use crate::system::{Stepper, System};

/// Which fixed-step method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FixedKind {
    /// Classical Runge-Kutta 4.
    Rk4,
    /// Velocities first, then positions with the new velocities. Needs the state laid out as
    /// (position, velocity) pairs for the first `pairs` pairs; the rest is explicit Euler.
    SemiImplicitEuler {
        /// Number of leading (x, v) pairs.
        pairs: usize,
    },
}

/// A fixed-step method and its last step.
#[derive(Debug, Clone)]
pub struct Fixed<const N: usize> {
    kind: FixedKind,
    y0: [f64; N],
    f0: [f64; N],
    y1: [f64; N],
    f1: [f64; N],
    h: f64,
}

impl<const N: usize> Fixed<N> {
    /// A method of this kind.
    pub fn new(kind: FixedKind) -> Self {
        Self { kind, y0: [0.0; N], f0: [0.0; N], y1: [0.0; N], f1: [0.0; N], h: 0.0 }
    }
}

impl<const N: usize> Stepper<N> for Fixed<N> {
    #[inline]
    fn step<S: System<N> + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], f0: &[f64; N], h: f64) -> ([f64; N], f64) {
        let mut y1 = *y;
        match self.kind {
            FixedKind::Rk4 => {
                let mut k2 = [0.0; N];
                let mut k3 = [0.0; N];
                let mut k4 = [0.0; N];
                let mut tmp = [0.0; N];
                for i in 0..N { tmp[i] = y[i] + 0.5 * h * f0[i]; }
                sys.rhs(t + 0.5 * h, &tmp, &mut k2);
                for i in 0..N { tmp[i] = y[i] + 0.5 * h * k2[i]; }
                sys.rhs(t + 0.5 * h, &tmp, &mut k3);
                for i in 0..N { tmp[i] = y[i] + h * k3[i]; }
                sys.rhs(t + h, &tmp, &mut k4);
                for i in 0..N { y1[i] = y[i] + h / 6.0 * (f0[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]); }
            }
            FixedKind::SemiImplicitEuler { pairs } => {
                // v_{n+1} = v_n + h a(t_n, x_n, v_n); x_{n+1} = x_n + h v_{n+1}.
                for p in 0..pairs.min(N / 2) {
                    let (ix, iv) = (2 * p, 2 * p + 1);
                    y1[iv] = y[iv] + h * f0[iv];
                    y1[ix] = y[ix] + h * y1[iv];
                }
                for i in 2 * pairs.min(N / 2)..N { y1[i] = y[i] + h * f0[i]; }
            }
        }
        let mut f1 = [0.0; N];
        sys.rhs(t + h, &y1, &mut f1);
        self.y0 = *y;
        self.f0 = *f0;
        self.y1 = y1;
        self.f1 = f1;
        self.h = h;
        (y1, 0.0)
    }

    fn f_end(&self) -> Option<[f64; N]> {
        Some(self.f1)
    }

    fn dense(&self, theta: f64) -> [f64; N] {
        let (t2, t3) = (theta * theta, theta * theta * theta);
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + theta;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        let mut out = [0.0; N];
        for (i, o) in out.iter_mut().enumerate() {
            *o = h00 * self.y0[i] + h10 * self.h * self.f0[i] + h01 * self.y1[i] + h11 * self.h * self.f1[i];
        }
        out
    }

    fn adaptive(&self) -> bool {
        false
    }
}
