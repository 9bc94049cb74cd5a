//! The target of the collision (MODEL.md element 4): a fixed obstacle at x_o, or a free object of
//! mass m_p (eq 6, 9, 18, 27, 50) with optional floor friction (eq 30, F_f_floor), regularised
//! Coulomb `-mu m_p g tanh(v_p / v0)`. Units: kg, m, m/s, N. A human body region (ISO/TS 15066
//! Annex A) is a free object of its effective mass m_H (transient contact) or an obstacle (clamped).

use super::friction::TanhFriction;
use flinch_model::body::BodyContact;
use flinch_model::scene::TargetKind;

/// Standard gravity for the floor's normal force, m/s^2 (the floor is horizontal; the scene's
/// `motion.gravity` is along the approach axis, a different direction).
pub const G_FLOOR: f64 = 9.81;

/// The target, ready to evaluate.
#[derive(Debug, Clone, Copy)]
pub enum Target {
    /// Fixed surface at x_o, m.
    Obstacle {
        /// x_o, m.
        surface: f64,
    },
    /// Free object whose contact face starts at `start`.
    Object {
        /// m_p, kg.
        mass: f64,
        /// Initial position of the object's face, m.
        start: f64,
        /// Floor friction, if any.
        floor: Option<TanhFriction>,
    },
}

impl Target {
    /// Target `gap` in front of the tool's initial face position `tool_face`.
    pub fn new(kind: &TargetKind, tool_face: f64, gap: f64) -> Self {
        match *kind {
            TargetKind::Obstacle => Self::Obstacle { surface: tool_face + gap },
            TargetKind::Object { mass, floor_friction } => Self::Object {
                mass,
                start: tool_face + gap,
                floor: floor_friction.map(|mu| TanhFriction::new(mu, 0.0)),
            },
            // ISO/TS 15066 Annex A: a transient contact meets the free effective mass m_H (it
            // recoils, nothing holds it); a quasi-static one a body backed by a rigid surface.
            TargetKind::BodyRegion(b) => match b.contact {
                BodyContact::Transient => Self::Object { mass: b.mass_kg, start: tool_face + gap, floor: None },
                BodyContact::QuasiStatic => Self::Obstacle { surface: tool_face + gap },
            },
        }
    }

    /// Acceleration of a free object under the contact force `f_c` (N), m/s^2 (0 for an obstacle).
    pub fn accel(&self, f_c: f64, v_p: f64) -> f64 {
        match self {
            Self::Obstacle { .. } => 0.0,
            Self::Object { mass, floor, .. } => {
                let friction = floor.map_or(0.0, |f| f.force(mass * G_FLOOR, -v_p));
                (f_c + friction) / mass
            }
        }
    }

    /// True for a free object.
    pub fn is_object(&self) -> bool {
        matches!(self, Self::Object { .. })
    }
}
