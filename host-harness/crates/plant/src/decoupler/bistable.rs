//! Bi-stable spring mechanism (Ch. 2.4, 3.1; Fig. 21, 38): N springs of rate k_b and free length
//! L0, hinged at height H above the slide. Along the slide (eq 24-25, N springs as Ch. 3):
//! `F_b = N k_b (L0 - L) s / L`, `L = sqrt(H^2 + s^2)`; normal to it (eq 42, not eq 32's stray
//! tanh): `F_n = N k_b (L0 - L) H / L`; slide friction `F_f = mu |F_n| tanh((x_r' - x_t') / v0)`
//! (eq 41). End-stops at s = C1 (front, linear) and s = -C2 (back, nonlinear).
//! Units: m, N/m, N. s = 0 is the unstable equilibrium (the springs aligned).

use super::end_stop::{BackStop, FrontStop};
use crate::friction::TanhFriction;
use flinch_model::scene::{Bistable, FrictionLaw};

/// The slide's friction law.
#[derive(Debug, Clone, Copy)]
pub enum SlideFriction {
    /// `mu |F_n| tanh(v / v0)`.
    Regularised(TanhFriction),
    /// Coulomb, v0 = 0: the plant carries the stick/slip state (`plant::friction::Slide`) and
    /// computes the force ([`BistableMechanism::friction_force`] returns 0).
    StickSlip {
        /// mu.
        mu: f64,
    },
}

/// The mechanism, ready to evaluate.
#[derive(Debug, Clone, Copy)]
pub struct BistableMechanism {
    /// N k_b, N/m.
    nk: f64,
    l0: f64,
    h: f64,
    /// Front end-stop at s = C1.
    pub front: FrontStop,
    /// Back end-stop at s = -C2.
    pub back: BackStop,
    /// Slide friction, if any.
    pub friction: Option<SlideFriction>,
}

impl BistableMechanism {
    /// From the scene's parameters.
    pub fn new(p: &Bistable) -> Self {
        Self {
            nk: p.springs as f64 * p.spring_rate,
            l0: p.free_length,
            h: p.height,
            front: FrontStop::new(p.front_stroke, &p.front_stop),
            back: BackStop::new(-p.back_stroke, &p.back_stop),
            friction: p.friction.map(|f| match f.law {
                FrictionLaw::Regularised => SlideFriction::Regularised(TanhFriction::new(f.mu, f.v0)),
                FrictionLaw::StickSlip => SlideFriction::StickSlip { mu: f.mu },
            }),
        }
    }

    /// Spring force along the slide, on the tool, N (eq 24-25).
    pub fn spring_force(&self, s: f64) -> f64 {
        let l = (self.h * self.h + s * s).sqrt();
        self.nk * (self.l0 - l) * s / l
    }

    /// Spring force normal to the slide, N (eq 42).
    pub fn normal_force(&self, s: f64) -> f64 {
        let l = (self.h * self.h + s * s).sqrt();
        self.nk * (self.l0 - l) * self.h / l
    }

    /// Small-displacement stiffness -dF_b/ds at the front stop... as the thesis defines it
    /// (eq 64): k_bm = N k_b (L0 - L) / L at s = C1, N/m.
    pub fn k_bm(&self) -> f64 {
        let s = self.front.at;
        let l = (self.h * self.h + s * s).sqrt();
        self.nk * (self.l0 - l) / l
    }

    /// Spring force along the slide and the regularised friction on the tool for relative
    /// velocity s' = x_t' - x_r' (0 without friction or with the stick-slip law), N: one square
    /// root for both.
    pub fn spring_and_friction(&self, s: f64, s_dot: f64) -> (f64, f64) {
        let l = (self.h * self.h + s * s).sqrt();
        let stretch = self.nk * (self.l0 - l) / l;
        let friction = match &self.friction {
            Some(SlideFriction::Regularised(f)) => f.force(stretch * self.h, -s_dot),
            _ => 0.0,
        };
        (stretch * s, friction)
    }

    /// Friction on the tool for relative velocity s' = x_t' - x_r', N (regularised law only; the
    /// stick-slip law's force is the plant's).
    pub fn friction_force(&self, s: f64, s_dot: f64) -> f64 {
        self.spring_and_friction(s, s_dot).1
    }

    /// mu of a stick-slip (Coulomb) slide.
    pub fn stick_slip_mu(&self) -> Option<f64> {
        match self.friction {
            Some(SlideFriction::StickSlip { mu }) => Some(mu),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flinch_model::scene::{ContactDamping, DampingLaw, LinearStop, NonlinearStop};

    fn table15() -> Bistable {
        Bistable {
            springs: 1, spring_rate: 490.0, free_length: 0.062, height: 0.053,
            front_stroke: 0.0235, back_stroke: 0.0235,
            front_stop: LinearStop { stiffness: 2.25e6, damping: 235.0, law: flinch_model::scene::FrontStopLaw::Linear },
            back_stop: NonlinearStop { stiffness: 2.25e6, damping: ContactDamping::Restitution { restitution: 0.3, law: DampingLaw::HuntCrossley } },
            friction: None,
        }
    }

    #[test]
    fn table15_gives_k_bm_of_34() {
        // Ch. 4.4: k_bm = 34 N/m (eq 64 with Table 15).
        let k = BistableMechanism::new(&table15()).k_bm();
        assert!((k - 34.0).abs() < 0.5, "{k}");
    }

    #[test]
    fn spring_pushes_forward_in_front_and_back_behind_the_alignment() {
        let m = BistableMechanism::new(&table15());
        assert!(m.spring_force(0.01) > 0.0);
        assert!(m.spring_force(-0.01) < 0.0);
        assert_eq!(m.spring_force(0.0), 0.0);
    }
}
