//! The plant's state vector, its slot indices, and what one instant looks like to the simulation
//! (`Kinematics`, `Forces`), plus `Parts`, the elements the planar plant reads (a borrowed view of
//! `crate::Plant`, so `planar/` never names the assembly and the files form no import circle).

use crate::contact::Contact;
use crate::decoupler::{Decoupler, DecouplerForce};
use crate::friction::Slide;
use crate::motion_law::MotionLaw;
use crate::robot::CompliantRobot;
use crate::target::Target;

/// Number of states.
pub const N: usize = 7;
/// The state vector.
pub type State = [f64; N];
/// x_r, m.
pub const XR: usize = 0;
/// x_r', m/s.
pub const VR: usize = 1;
/// x_t, m.
pub const XT: usize = 2;
/// x_t', m/s.
pub const VT: usize = 3;
/// x_p, m.
pub const XP: usize = 4;
/// x_p', m/s.
pub const VP: usize = 5;
/// Decoupler impulse during contact (eq 21), N s.
pub const IMPULSE: usize = 6;

/// Positions and velocities of every body at one instant (rigid ones filled in from the law).
#[derive(Debug, Clone, Copy, Default)]
pub struct Kinematics {
    /// x_c, x_c', m, m/s.
    pub xc: f64,
    /// x_c'.
    pub vc: f64,
    /// x_c'' (kept so the right-hand side evaluates the motion law once).
    pub ac: f64,
    /// x_r.
    pub xr: f64,
    /// x_r'.
    pub vr: f64,
    /// x_t (tool face).
    pub xt: f64,
    /// x_t'.
    pub vt: f64,
    /// Target face position.
    pub xp: f64,
    /// Target velocity.
    pub vp: f64,
    /// s = x_t - x_r.
    pub s: f64,
    /// s'.
    pub s_dot: f64,
    /// Penetration into the target, m (positive in contact).
    pub delta: f64,
    /// Its rate, m/s.
    pub delta_dot: f64,
    /// What only the planar plant fills in (`planar/`; zero in 1-D).
    pub plane: PlaneKinematics,
}

/// The planar plant's extras of an instant (`planar/`).
#[derive(Debug, Clone, Copy, Default)]
pub struct PlaneKinematics {
    /// The flange along its path (m, m/s) and across it (m, m/s).
    pub path: [f64; 4],
    /// The tool's slip velocity along the contact's tangent, m/s.
    pub slip_v: f64,
    /// The flange across the guide (F . w, m, and its rate, m/s).
    pub across_u: [f64; 2],
    /// The rotational module's stage angle from rest, rad, and its rate, rad/s.
    pub phi: [f64; 2],
}

/// Forces at one instant, N.
#[derive(Debug, Clone, Copy, Default)]
pub struct Forces {
    /// Contact force on the target (>= 0).
    pub contact: f64,
    /// The decoupler's force on the tool, by part.
    pub decoupler: DecouplerForce,
    /// Force the tool puts on the robot (decoupler, or the contact for a rigid tool), signed.
    pub robot: f64,
}

/// The elements of the assembled plant the planar plant reads, borrowed (see `crate::Plant`'s
/// fields of the same names).
#[derive(Debug, Clone, Copy)]
pub struct Parts<'a> {
    /// The commanded flange motion.
    pub motion: &'a MotionLaw,
    /// Compliant robot, or `None` for x_r = x_c.
    pub robot: Option<&'a CompliantRobot>,
    /// m_t, kg.
    pub tool_mass: f64,
    /// Gravity along the approach (the path in the plane), m/s^2.
    pub gravity: f64,
    /// The decoupler.
    pub decoupler: &'a Decoupler,
    /// Tool-target contact.
    pub contact: &'a Contact,
    /// The target.
    pub target: Target,
    /// chi of the tool-target contact.
    pub target_chi: f64,
    /// chi of the back stop.
    pub back_chi: f64,
    /// chi of a Hunt-Crossley front stop.
    pub front_chi: f64,
    /// Stroke at rest, m.
    pub s_rest: f64,
    /// Contact on (eq 21's impulse accumulates).
    pub in_contact: bool,
    /// The Coulomb slide's state, if any.
    pub slide: Option<Slide>,
}
