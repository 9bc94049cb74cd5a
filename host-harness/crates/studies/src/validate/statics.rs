//! The Z prototype's statics at the back stop (Tables 9-11, issue 15): where the springs hold the
//! tool against its weight.

use flinch_model::scene::{Decoupler, Scene};

/// The Z prototype's statics at the back stop (issue 15).
#[derive(Debug, Clone, Copy)]
pub struct ZStatics {
    /// N k_b, N/m.
    pub k_b: f64,
    /// L0, H, C1, C2, m.
    pub l0_m: f64,
    /// H, m.
    pub h_m: f64,
    /// C1, m.
    pub c1_m: f64,
    /// C2, m.
    pub c2_m: f64,
    /// Spring force toward the back stop at s = -C2, N.
    pub hold_n: f64,
    /// m_t g along the approach, N.
    pub weight_n: f64,
    /// The back stroke where the spring holds hardest, m, and that force, N.
    pub best_c2_m: f64,
    /// The largest hold, N.
    pub best_hold_n: f64,
    /// The back strokes for which the hold exceeds the weight, m.
    pub holds_m: Option<(f64, f64)>,
}

/// Hold of a bi-stable spring toward the back stop at back stroke `c2` (eq 24-25), N.
pub(crate) fn hold(nk: f64, l0: f64, h: f64, c2: f64) -> f64 {
    let l = (h * h + c2 * c2).sqrt();
    nk * (l0 - l) * c2 / l
}

/// The statics of a bi-stable scene at its back stop.
pub fn z_statics(sc: &Scene) -> Option<ZStatics> {
    let Decoupler::Bistable(b) = &sc.decoupler else { return None };
    let nk = b.springs as f64 * b.spring_rate;
    let weight = sc.tool.mass * sc.motion.gravity.abs();
    // Where L reaches L0 the spring no longer pushes: scan up to there, 0.01 mm apart.
    let top = (b.free_length * b.free_length - b.height * b.height).max(0.0).sqrt();
    let n = ((top / 1e-5) as usize).clamp(1, 100_000);
    let (mut best, mut best_f, mut lo, mut hi) = (0.0, 0.0, f64::NAN, f64::NAN);
    for i in 0..=n {
        let c2 = top * i as f64 / n as f64;
        let f = hold(nk, b.free_length, b.height, c2);
        if f > best_f {
            (best, best_f) = (c2, f);
        }
        if f > weight {
            if lo.is_nan() {
                lo = c2;
            }
            hi = c2;
        }
    }
    Some(ZStatics {
        k_b: nk,
        l0_m: b.free_length,
        h_m: b.height,
        c1_m: b.front_stroke,
        c2_m: b.back_stroke,
        hold_n: hold(nk, b.free_length, b.height, b.back_stroke),
        weight_n: weight,
        best_c2_m: best,
        best_hold_n: best_f,
        holds_m: (!lo.is_nan()).then_some((lo, hi)),
    })
}
