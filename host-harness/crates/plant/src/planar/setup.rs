//! The planar parts of a plant (issue 30): the scene's resolved angles, the directions, which
//! slots hold what, the contact's friction, and the loads of an instant (the contact's force and
//! the tool's weight as vectors, N). Read by every planar file; names no other planar file but the
//! leaves `frame.rs` and `surface_contact.rs`.

use super::frame::{self, comb, dot, Directions, V2};
use super::surface_contact;
use crate::state::{Kinematics, Parts as Plant};
use flinch_model::scene::Planar as PlanarScene;

/// The planar parts of a plant.
#[derive(Debug, Clone, Copy)]
pub struct Planar {
    /// The scene's resolved angles.
    pub scene: PlanarScene,
    /// The directions of the approach.
    pub dir: Directions,
    /// The flange's position across its path is integrated (XP, VP hold y_r, y_r').
    pub across_states: bool,
    /// The contact's Coulomb friction.
    pub friction: surface_contact::SurfaceFriction,
}

impl Planar {
    /// From the scene's planar keys; `across_states` when the robot is compliant and the target a
    /// fixed obstacle.
    pub fn new(p: &PlanarScene, across_states: bool) -> Self {
        Self {
            scene: *p,
            dir: Directions::new(p.off_axis_deg, p.surface_angle_deg),
            across_states: across_states && p.rotational.is_none(),
            friction: surface_contact::SurfaceFriction::new(p.contact_mu),
        }
    }
}

/// The contact's force on the tool and the tool's weight, split along and across the guide, and
/// the flange's acceleration (path frame) once known.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Loads {
    /// The contact's force on the tool, N (vector).
    pub contact: V2,
    /// The tool's weight m_t g e_p (`motion.gravity` along the path), N.
    pub weight: V2,
    /// The flange's acceleration along and across its path, m/s^2.
    pub accel: [f64; 2],
}

pub(crate) fn loads(plant: &Plant, p: &Planar, normal: f64, friction: f64) -> Loads {
    let d = &p.dir;
    // The target pushes the tool along -m; friction acts along t.
    let contact = comb(-normal, d.m, friction, d.t);
    let w = plant.tool_mass * plant.gravity;
    Loads { contact, weight: [w * d.ep[0], w * d.ep[1]], accel: [0.0, 0.0] }
}


impl Planar {
    /// How far the tool moves away from the target (along -m) per metre of travel back along its
    /// guide (-u): u . m, 1 in 1-D, 0 for a guide parallel to the surface (beta or theta 90 deg off
    /// the axis), negative when the guide leads into the target. The rotational module's guide
    /// turns with its stage.
    pub fn retreat_share(&self, k: &Kinematics) -> f64 {
        let u = frame::rot(k.plane.phi[0], self.dir.u);
        dot(u, self.dir.m)
    }
}
