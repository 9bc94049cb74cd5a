//! The robot in the plane (issue 30): the flange driven along its path by eq 33 and held across it
//! by the same spring-damper (isotropic: the thesis gives k_r, c_r only along the approach, Table 7;
//! docs/planar.md lists the across values as open), with the tool's across-guide load on it.
//! Units: kg, N/m, N s/m, m/s^2, N.
//!
//! Flange F (mass m_r), tool on a guide along u, rigid across it (w = R(90) u):
//!   tool across u:  m_t (F'' . w) = h + R_w,          h = (F_c + m_t g e_p) . w
//!   flange:         m_r F'' = D_drive - D u - R_w w,  D the decoupler's force on the tool
//! so  m_r F'' + m_t (F'' . w) w = D_drive - D u + h w  (solved in the path frame e_p, e_q), and
//! the force on the robot is -D u - R_w w with R_w = m_t (F'' . w) - h. A rigid tool (mass in m_r):
//! m_r F'' = D_drive + F_c + m_t g e_p, force on the robot F_c (the 1-D plant's -contact). Along an
//! axial path w . e_p = 0 and this is eq 33 exactly, in the 1-D plant's operation order.

use super::frame::{comb, dot, V2};
use super::setup::{Loads, Planar};
use crate::motion_law::Commanded;
use crate::state::{Kinematics, Parts as Plant};

/// The flange's acceleration along and across its path, m/s^2, under the decoupler's force
/// `dec` (N, on the tool along u).
pub(crate) fn flange_accel(plant: &Plant, p: &Planar, k: &Kinematics, l: &Loads, dec: f64) -> [f64; 2] {
    let Some(r) = &plant.robot else { return [k.ac, 0.0] };
    let d = &p.dir;
    let c = Commanded { x: k.xc, v: k.vc, a: k.ac };
    let [x, v, y, vy] = k.plane.path;
    let drive_p = r.drive_force(&c, x, v);
    // Across the path the commanded position is 0.
    let drive_q = r.drive_force(&Commanded { x: 0.0, v: 0.0, a: 0.0 }, y, vy);
    if plant.decoupler.is_rigid() {
        let fp = dot(l.weight, d.ep) + dot(l.contact, d.ep);
        let ap = (drive_p + fp) / r.mass;
        let aq = if p.across_states { (drive_q + (dot(l.weight, d.eq) + dot(l.contact, d.eq))) / r.mass } else { 0.0 };
        return [ap, aq];
    }
    let mt = plant.tool_mass;
    let fu = -dec;
    let h = dot(l.contact, d.w) + dot(l.weight, d.w);
    let (up, uq, wp, wq) = (dot(d.u, d.ep), dot(d.u, d.eq), dot(d.w, d.ep), dot(d.w, d.eq));
    let rhs_p = drive_p + (fu * up + h * wp);
    let m_pp = r.mass + mt * wp * wp;
    if !p.across_states {
        return [rhs_p / m_pp, 0.0];
    }
    let rhs_q = drive_q + (fu * uq + h * wq);
    let m_qq = r.mass + mt * wq * wq;
    let m_pq = mt * wp * wq;
    if m_pq == 0.0 {
        [rhs_p / m_pp, rhs_q / m_qq]
    } else {
        let det = m_pp * m_qq - m_pq * m_pq;
        [(rhs_p * m_qq - m_pq * rhs_q) / det, (m_pp * rhs_q - m_pq * rhs_p) / det]
    }
}

/// The force the module puts on the flange (vector, N), given the flange's acceleration `acc`.
pub(crate) fn force_on_robot(plant: &Plant, p: &Planar, l: &Loads, dec: f64, acc: [f64; 2]) -> V2 {
    if plant.decoupler.is_rigid() {
        return l.contact;
    }
    let d = &p.dir;
    let a = comb(acc[0], d.ep, acc[1], d.eq);
    let h = dot(l.contact, d.w) + dot(l.weight, d.w);
    let r_w = plant.tool_mass * dot(a, d.w) - h;
    comb(-dec, d.u, -r_w, d.w)
}

/// The flange's acceleration along u per newton pushed on it along u, 1/kg (0 for a rigid robot):
/// 1/m_r when it moves freely in the plane (u is normal to w, so the tool's across mass does not
/// couple), u.e_p^2 / (m_r + m_t (w.e_p)^2) when it is held on its path.
pub(crate) fn inverse_mass_along_u(plant: &Plant, p: &Planar) -> f64 {
    let Some(r) = &plant.robot else { return 0.0 };
    if p.across_states {
        return 1.0 / r.mass;
    }
    let (up, wp) = (dot(p.dir.u, p.dir.ep), dot(p.dir.w, p.dir.ep));
    up * up / (r.mass + plant.tool_mass * wp * wp)
}
