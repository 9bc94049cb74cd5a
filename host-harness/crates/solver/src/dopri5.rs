//! Dormand-Prince 5(4) (Hairer, Norsett, Wanner, "Solving ODEs I", DOPRI5) with its 4th-order
//! continuous extension, FSAL: six new RHS evaluations per step.

use crate::system::{error_norm, Stepper, System};

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// The adaptive method with its tolerances and the last step's interpolant.
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    r: [[f64; N]; 5],
    k7: [f64; N],
}

impl<const N: usize> Dopri5<N> {
    /// With tolerances.
    pub fn new(rtol: f64, atol: f64) -> Self {
        Self { rtol, atol, r: [[0.0; N]; 5], k7: [0.0; N] }
    }
}

#[inline]
fn comb<const N: usize>(y: &[f64; N], h: f64, terms: &[(f64, &[f64; N])]) -> [f64; N] {
    let mut out = *y;
    for &(c, k) in terms {
        let hc = h * c;
        for i in 0..N {
            out[i] += hc * k[i];
        }
    }
    out
}

impl<const N: usize> Stepper<N> for Dopri5<N> {
    #[inline]
    fn step<S: System<N> + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], k1: &[f64; N], h: f64) -> ([f64; N], f64) {
        let mut k2 = [0.0; N];
        let mut k3 = [0.0; N];
        let mut k4 = [0.0; N];
        let mut k5 = [0.0; N];
        let mut k6 = [0.0; N];
        let mut k7 = [0.0; N];
        sys.rhs(t + C2 * h, &comb(y, h, &[(A21, k1)]), &mut k2);
        sys.rhs(t + C3 * h, &comb(y, h, &[(A31, k1), (A32, &k2)]), &mut k3);
        sys.rhs(t + C4 * h, &comb(y, h, &[(A41, k1), (A42, &k2), (A43, &k3)]), &mut k4);
        sys.rhs(t + C5 * h, &comb(y, h, &[(A51, k1), (A52, &k2), (A53, &k3), (A54, &k4)]), &mut k5);
        sys.rhs(t + h, &comb(y, h, &[(A61, k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)]), &mut k6);
        let y1 = comb(y, h, &[(A71, k1), (A73, &k3), (A74, &k4), (A75, &k5), (A76, &k6)]);
        sys.rhs(t + h, &y1, &mut k7);
        let mut err = [0.0; N];
        for i in 0..N {
            err[i] = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        }
        // Continuous extension (DOPRI5's contd5).
        for i in 0..N {
            let ydiff = y1[i] - y[i];
            let bspl = h * k1[i] - ydiff;
            self.r[0][i] = y[i];
            self.r[1][i] = ydiff;
            self.r[2][i] = bspl;
            self.r[3][i] = ydiff - h * k7[i] - bspl;
            self.r[4][i] = h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        }
        self.k7 = k7;
        (y1, error_norm(&err, y, &y1, self.rtol, self.atol))
    }

    fn f_end(&self) -> Option<[f64; N]> {
        Some(self.k7)
    }

    fn dense(&self, theta: f64) -> [f64; N] {
        let t1 = 1.0 - theta;
        let mut out = [0.0; N];
        for i in 0..N {
            let r = &self.r;
            out[i] = r[0][i] + theta * (r[1][i] + t1 * (r[2][i] + theta * (r[3][i] + t1 * r[4][i])));
        }
        out
    }

    fn adaptive(&self) -> bool {
        true
    }

    fn tolerances(&self) -> (f64, f64) {
        (self.rtol, self.atol)
    }
}
