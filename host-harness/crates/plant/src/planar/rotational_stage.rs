//! The thesis's 2-D rotational module (Ch. 3.5, Fig. 63-66; issue 30): the bi-stable mechanism's
//! guide on a stage that turns about the flange's axis O, held by two retaining springs (Fig. 65,
//! as one torsional spring with a preload), on bearings with a friction moment; the tool offset
//! from the guide by l along it and b across it (Fig. 66) so that an impact turns the stage.
//! The thesis gives no model; this one is the caster the text describes (docs/planar.md).
//!
//! Coordinates q = (x, s, phi): the flange along its path (a compliant robot's; a rigid robot
//! follows its law), the 1-D stroke coordinate s along the guide (front stop at s = C1... as the
//! bi-stable's), the stage's turn phi from rest (rad, counter-clockwise). u = R(phi) u0, and
//!   T = F + r,   r = R(phi) [ (s - s_f - l) u0 - b w0 ]       (the tool's axis; s_f the front stop)
//!   P = T + r_t m                                            (the contact point on the tool's disc)
//! Lagrange, M(q) q'' = Q:
//!   M = m_r J_F^T J_F + m_t J_T^T J_T + J e_phi e_phi^T,   J_F = [e_p, 0, 0],
//!   J_T = [e_p, u, perp(r)],   J_T' q' = 2 s' phi' perp(u) - phi'^2 r,
//!   Q = (D_drive, D, M_ret + M_bear) + J_P^T F_c + J_T^T m_t g e_p - m_t J_T^T (J_T' q'),
//!   J_P = J_T + [0, 0, r_t t]  (the disc turns with the stage: its contact point slips at
//!   T' . t + r_t phi'),
//! D the bi-stable's force along u on the tool (eq 24-42, `crate::decoupler`), F_c = -N m + f t
//! the contact's force (`surface_contact.rs`), M_ret = -k_phi phi - M0 tanh(phi / 1 deg) the
//! retaining springs, M_bear = -M_b tanh(phi' / 0.01 rad/s) the bearings. The force on the robot is
//! F_c + m_t g e_p - m_t T'' (the stage's own mass sits on the axis, moving with the flange: in
//! m_r). The flange is rigid across its path (the stage angle takes the slots the across motion
//! would). Units: m, rad, kg, kg m^2, N, N m.

use super::frame::{comb, cross, dot, perp, rot, V2};
use super::setup::{Loads, Planar};
use crate::motion_law::Commanded;
use crate::state::{Forces, Kinematics, Parts as Plant, State, IMPULSE, VP, VR, VT, XP, XR, XT};
use flinch_model::scene::Stage;

/// The preload's smoothing angle: M0 is reached within about this turn, rad (1 deg).
pub const PRELOAD_ANGLE: f64 = 0.017453292519943295;
/// The bearings' regularising rate, rad/s.
pub const OMEGA0: f64 = 0.01;

/// The retaining springs' and bearings' moment on the stage, N m.
pub fn stage_moment(st: &Stage, phi: f64, phi_dot: f64) -> f64 {
    -st.stiffness * phi - st.preload * (phi / PRELOAD_ANGLE).tanh() - st.bearing_torque * (phi_dot / OMEGA0).tanh()
}

/// Where the stage puts the tool: r (from O to the tool's axis) for the stroke s and turn phi.
pub fn tool_offset(st: &Stage, s_front: f64, s: f64, phi: f64) -> V2 {
    rot(phi, [s - s_front - st.lever, -st.offset_b])
}

/// The front stop's s (the tool's reference on the guide).
fn s_front(plant: &Plant) -> f64 {
    plant.decoupler.front_stop().map_or(plant.s_rest, |f| f.at)
}

struct Geo {
    tool: V2,
    tool_v: V2,
}

fn geo(plant: &Plant, p: &Planar, st: &Stage, x: f64, v: f64, y: &State) -> Geo {
    let (s, sd, phi, pd) = (y[XT], y[VT], y[XP], y[VP]);
    let r = tool_offset(st, s_front(plant), s, phi);
    let u = rot(phi, p.dir.u);
    let f = comb(x, p.dir.ep, 0.0, p.dir.eq);
    let fv = comb(v, p.dir.ep, 0.0, p.dir.eq);
    let tool = [f[0] + r[0], f[1] + r[1]];
    let pr = perp(r);
    let tool_v = [fv[0] + sd * u[0] + pd * pr[0], fv[1] + sd * u[1] + pd * pr[1]];
    Geo { tool, tool_v }
}

/// The 1-D view of the instant (see `planar::kinematics`).
pub(crate) fn kinematics(plant: &Plant, p: &Planar, st: &Stage, t: f64, y: &State) -> Kinematics {
    let c = plant.motion.at(t);
    let (x, v) = if plant.robot.is_some() { (y[XR], y[VR]) } else { (c.x, c.v) };
    let g = geo(plant, p, st, x, v, y);
    let d = &p.dir;
    let surface = match plant.target {
        crate::target::Target::Obstacle { surface } => surface,
        crate::target::Target::Object { start, .. } => start,
    };
    let delta = dot(g.tool, d.m) + st.tool_radius - surface;
    Kinematics {
        xc: c.x, vc: c.v, ac: c.a, xr: x, vr: v, xt: x + y[XT], vt: v + y[VT], xp: surface, vp: 0.0,
        s: y[XT], s_dot: y[VT], delta, delta_dot: dot(g.tool_v, d.m),
        plane: crate::state::PlaneKinematics {
            path: [x, v, 0.0, 0.0],
            slip_v: dot(g.tool_v, d.t) + st.tool_radius * y[VP],
            across_u: [0.0, 0.0],
            phi: [y[XP], y[VP]],
        },
    }
}

/// The generalised accelerations (x'', s'', phi'') and the tool's acceleration T''.
fn solve(plant: &Plant, p: &Planar, st: &Stage, k: &Kinematics, l: &Loads, dec: f64) -> ([f64; 3], V2) {
    let d = &p.dir;
    let (s, sd, phi, pd) = (k.s, k.s_dot, k.plane.phi[0], k.plane.phi[1]);
    let r = tool_offset(st, s_front(plant), s, phi);
    let u = rot(phi, d.u);
    let pr = perp(r);
    let mt = plant.tool_mass;
    // Columns of J_T and J_P.
    let jt = [d.ep, u, pr];
    let jp = [d.ep, u, [pr[0] + st.tool_radius * d.t[0], pr[1] + st.tool_radius * d.t[1]]];
    let bias = comb(2.0 * sd * pd, perp(u), -pd * pd, r);
    let mut m = [[0.0; 3]; 3];
    let mut q = [0.0; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = mt * dot(jt[i], jt[j]);
        }
        q[i] = dot(jp[i], l.contact) + dot(jt[i], l.weight) - mt * dot(jt[i], bias);
    }
    m[2][2] += st.inertia;
    q[1] += dec;
    q[2] += stage_moment(st, phi, pd);
    let c = Commanded { x: k.xc, v: k.vc, a: k.ac };
    let acc = match &plant.robot {
        Some(rb) => {
            m[0][0] += rb.mass;
            q[0] += rb.drive_force(&c, k.plane.path[0], k.plane.path[1]);
            solve3(m, q)
        }
        None => {
            // The flange follows its law: move x'' = a_c to the right-hand side.
            let a = c.a;
            let m2 = [[m[1][1], m[1][2]], [m[2][1], m[2][2]]];
            let q2 = [q[1] - m[1][0] * a, q[2] - m[2][0] * a];
            let det = m2[0][0] * m2[1][1] - m2[0][1] * m2[1][0];
            [a, (q2[0] * m2[1][1] - m2[0][1] * q2[1]) / det, (m2[0][0] * q2[1] - m2[1][0] * q2[0]) / det]
        }
    };
    let tdd = [
        jt[0][0] * acc[0] + jt[1][0] * acc[1] + jt[2][0] * acc[2] + bias[0],
        jt[0][1] * acc[0] + jt[1][1] * acc[1] + jt[2][1] * acc[2] + bias[1],
    ];
    (acc, tdd)
}

/// Solves the symmetric positive definite 3 x 3 system (Gaussian elimination; M is SPD: every
/// body has mass and the stage inertia is >= 1e-7 kg m^2).
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> [f64; 3] {
    for c in 0..3 {
        for r in c + 1..3 {
            let f = a[r][c] / a[c][c];
            for k in c..3 {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 3];
    for r in (0..3).rev() {
        let s: f64 = (r + 1..3).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Forces of the instant (see `planar::forces`).
pub(crate) fn forces(plant: &Plant, p: &Planar, st: &Stage, k: &Kinematics) -> (Forces, [f64; 3]) {
    let contact = plant.contact.force(k.delta, k.delta_dot, plant.target_chi);
    let friction = p.friction.force(contact, k.plane.slip_v);
    let decoupler = plant.decoupler.force(k.s, k.s_dot, plant.front_chi, plant.back_chi);
    let l = super::setup::loads(plant, p, contact, friction);
    let (acc, tdd) = solve(plant, p, st, k, &l, decoupler.total);
    let mt = plant.tool_mass;
    let on_robot = [l.contact[0] + l.weight[0] - mt * tdd[0], l.contact[1] + l.weight[1] - mt * tdd[1]];
    let r = on_robot[0].hypot(on_robot[1]);
    (Forces { contact, decoupler, robot: r.copysign(dot(on_robot, p.dir.ep)) }, acc)
}

/// The right-hand side.
pub(crate) fn eval(plant: &Plant, p: &Planar, st: &Stage, t: f64, y: &State, dy: &mut State) -> (Kinematics, Forces) {
    let k = kinematics(plant, p, st, t, y);
    let (f, acc) = forces(plant, p, st, &k);
    *dy = [0.0; crate::state::N];
    if plant.robot.is_some() {
        dy[XR] = k.vr;
        dy[VR] = acc[0];
    }
    dy[XT] = k.s_dot;
    dy[VT] = acc[1];
    dy[XP] = k.plane.phi[1];
    dy[VP] = acc[2];
    dy[IMPULSE] = if plant.in_contact { f.decoupler.total } else { 0.0 };
    (k, f)
}

/// The moment of the contact's force about the stage's axis per newton of normal force (N m / N),
/// for the docs' statics: positive turns the stage counter-clockwise.
pub fn lever_arm(st: &Stage, s_front: f64, s: f64, phi: f64, m: V2) -> f64 {
    cross(tool_offset(st, s_front, s, phi), [-m[0], -m[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_caster_turns_towards_the_push() {
        let st = Stage { inertia: 1e-4, lever: 0.04, offset_b: 0.02, tool_radius: 0.0, stiffness: 0.0, preload: 0.0, bearing_torque: 0.0 };
        // theta = 0: m = (0, 1), a push along -m on a trailing tool turns the stage ccw.
        assert!(lever_arm(&st, 0.0, 0.0, 0.0, [0.0, 1.0]) > 0.0);
        // theta = 90: m = (-1, 0), the push runs along the guide: only b turns it, ccw for b > 0.
        assert!((lever_arm(&st, 0.0, 0.0, 0.0, [-1.0, 0.0]) - 0.02).abs() < 1e-15);
        let lead = Stage { lever: -0.04, ..st };
        assert!(lever_arm(&lead, 0.0, 0.0, 0.0, [0.0, 1.0]) < 0.0);
    }

    #[test]
    fn solve3_solves() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = solve3(a, [1.0, 2.0, 3.0]);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a[i][j] * x[j]).sum();
            assert!((r - [1.0, 2.0, 3.0][i]).abs() < 1e-14);
        }
    }
}
