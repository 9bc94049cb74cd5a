//! Collision detector (MODEL.md element 5): a travel switch that fires once the tool has moved
//! `threshold` back from its front end-stop (5 mm in Ch. 3 simulations, 1.5 mm prototypes and
//! hydraulic, 0.5 mm Z prototype), or, for a rigid tool, a force threshold on the contact force
//! (25 N Ch. 3, 1 N Ch. 2). Units: m, N.
//!
//! "Travel" is measured from the front stop's surface (s = C1, or s = 0 hydraulic); a linear
//! decoupler has no stop, so from the tool's rest position.

use flinch_model::scene::Sensor;

/// The detector as the plant sees it: a signed distance to firing (fires when it crosses 0 up).
#[derive(Debug, Clone, Copy)]
pub enum Detector {
    /// Fires when travel back from `reference` reaches `threshold`.
    Travel {
        /// s of the front stop (or rest), m.
        reference: f64,
        /// d_sw, m.
        threshold: f64,
    },
    /// Fires when the contact force reaches `threshold`, N.
    Force {
        /// N.
        threshold: f64,
    },
}

impl Detector {
    /// From the scene's sensor; `reference` is the s the travel is measured from.
    pub fn new(s: &Sensor, reference: f64) -> Self {
        match *s {
            Sensor::Travel { threshold } => Self::Travel { reference, threshold },
            Sensor::Force { threshold } => Self::Force { threshold },
        }
    }

    /// Event function: negative before firing, crosses zero upwards at detection.
    pub fn signal(&self, s: f64, contact_force: f64) -> f64 {
        match *self {
            Self::Travel { reference, threshold } => (reference - s) - threshold,
            Self::Force { threshold } => contact_force - threshold,
        }
    }

    /// The switch's physical state: true once the threshold is passed (inductive switch OFF).
    pub fn tripped(&self, s: f64, contact_force: f64) -> bool {
        self.signal(s, contact_force) >= 0.0
    }
}
