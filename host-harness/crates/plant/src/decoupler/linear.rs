//! Linear decoupler (Ch. 2.3, eq 17, 23): spring k_t and damper c_t between flange and tool,
//! `F = -k_t s - c_t s'` on the tool, c_t = 2 zeta sqrt(k_t m_t). No end-stops. Units: N/m, N s/m.
//! k_t = 0 with zeta = 0 is the completely decoupled tool of Fig. 1b / 4b.

use flinch_model::scene::LinearDecoupler;

/// The spring-damper.
#[derive(Debug, Clone, Copy)]
pub struct LinearSpringDamper {
    /// k_t, N/m.
    pub stiffness: f64,
    /// c_t, N s/m.
    pub damping: f64,
}

impl LinearSpringDamper {
    /// From k_t, zeta and the tool mass (eq 23).
    pub fn new(p: &LinearDecoupler, tool_mass: f64) -> Self {
        Self { stiffness: p.stiffness, damping: 2.0 * p.damping_ratio * (p.stiffness * tool_mass).sqrt() }
    }

    /// Force on the tool, N.
    pub fn force(&self, s: f64, s_dot: f64) -> f64 {
        -self.stiffness * s - self.damping * s_dot
    }
}
