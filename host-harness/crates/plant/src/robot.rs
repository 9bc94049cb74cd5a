//! Robot along the approach direction (MODEL.md element 2): rigid (x_r = x_c), or compliant, a
//! base-excited mass `m_r x_r'' = c_r (x_c' - x_r') + k_r (x_c - x_r) - F_dec` (eq 33, 35, 39, 44,
//! 53). Table 7: m_r = 8.4 kg, k_r = 2.3e5 N/m, c_r = 71 N s/m (Viper s650). Units: kg, N/m, N s/m.
//!
//! The robot's own weight is taken as compensated by its controller; the tool's weight reaches the
//! robot through the decoupler, so eq 44's separate -F_w on the robot is not added twice.

use super::motion_law::Commanded;
use flinch_model::scene::Robot;

/// The compliant robot's parameters.
#[derive(Debug, Clone, Copy)]
pub struct CompliantRobot {
    /// Moving mass, kg (m_r, plus m_t for a rigid tool).
    pub mass: f64,
    /// k_r, N/m.
    pub stiffness: f64,
    /// c_r, N s/m.
    pub damping: f64,
}

impl CompliantRobot {
    /// From the scene, with `extra_mass` (the tool, when fastened rigidly) added.
    pub fn new(r: &Robot, extra_mass: f64) -> Self {
        Self { mass: r.mass + extra_mass, stiffness: r.stiffness, damping: r.damping }
    }

    /// Force of the joints (spring-damper to the commanded motion) on the robot mass, N.
    pub fn drive_force(&self, c: &Commanded, x_r: f64, v_r: f64) -> f64 {
        self.damping * (c.v - v_r) + self.stiffness * (c.x - x_r)
    }

    /// Acceleration under the drive and an external force `f_ext` (positive forwards), m/s^2.
    pub fn accel(&self, c: &Commanded, x_r: f64, v_r: f64, f_ext: f64) -> f64 {
        (self.drive_force(c, x_r, v_r) + f_ext) / self.mass
    }

    /// Static lag behind x_c under a steady external force: x_r = x_c + f_ext / k_r, m.
    pub fn static_offset(&self, f_ext: f64) -> f64 {
        f_ext / self.stiffness
    }
}
