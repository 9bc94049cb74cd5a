//! The planar plant (issue 30, docs/planar.md): the 1-D plant's elements in the plane of motion,
//! for collisions that are not along the decoupler's axis. Composed, not copied: the decoupler's
//! force along its guide, the contact's normal law, the target, the sensor and the motion law are
//! the 1-D files' (`crate::decoupler`, `crate::contact`, ...); the files here add what the plane
//! needs: the frame (`frame.rs`), the robot across its path (`robot.rs`), the contact's Coulomb
//! friction (`surface_contact.rs`) and the thesis's 2-D rotational module (`rotational_stage.rs`).
//!
//! State slots (the 1-D plant's seven, `crate::N`, so that `flinch-sim` drives both unchanged):
//! - XR, VR: the flange along its path e_p (m, m/s), as in 1-D;
//! - XT, VT: a 1-D module's tool along its guide u, absolute (x_t = F . u + s: the 1-D x_t);
//!   the rotational module's stroke coordinate s;
//! - XP, VP: a free object along m (into the target), as in 1-D; with a fixed obstacle and a
//!   compliant robot, the flange across its path y_r (m, m/s); the rotational module's stage
//!   angle phi (rad, rad/s);
//! - IMPULSE: eq 21 as in 1-D.
//! A scene with every direction along one axis (beta = 0, theta = -90, no contact friction) does
//! the 1-D plant's arithmetic to the last bit (tests/planar_equivalence.rs runs every shipped 1-D
//! scene both ways).
//!
//! The 1-D modules (rigid, linear, bi-stable, hydraulic): the tool rides the guide, rigid across it
//! with the flange: across u it moves as the flange does and the guide passes the contact's
//! across-u force to the flange (the reaction R_w of `robot.rs`). The flange's compliance across
//! its path is the robot's along it (isotropic: no data across, stated in docs/planar.md); with a
//! free object (which takes the XP slots) the flange is rigid across its path.

pub mod frame;
pub mod robot;
pub mod rotational_stage;
pub mod setup;
pub mod surface_contact;

pub use setup::Planar;
use setup::{loads, Loads};

use crate::friction::Slide;
use crate::state::{Forces, Kinematics, Parts as Plant, State, IMPULSE, VP, VR, VT, XP, XR, XT};
use frame::{comb, dot, V2};

/// Where the flange is: along and across its path (path frame) and in the plane.
#[derive(Debug, Clone, Copy)]
struct Flange {
    /// Along the path, m and m/s.
    x: f64,
    v: f64,
    /// Across the path, m and m/s.
    y: f64,
    vy: f64,
    /// F and F' in the plane.
    pos: V2,
    vel: V2,
}

fn flange(plant: &Plant, p: &Planar, c: &crate::motion_law::Commanded, y: &State) -> Flange {
    let (x, v) = if plant.robot.is_some() { (y[XR], y[VR]) } else { (c.x, c.v) };
    let (yy, vy) = if p.across_states { (y[XP], y[VP]) } else { (0.0, 0.0) };
    Flange { x, v, y: yy, vy, pos: comb(x, p.dir.ep, yy, p.dir.eq), vel: comb(v, p.dir.ep, vy, p.dir.eq) }
}

/// The 1-D view of the instant (`crate::Kinematics`): s and s' along the guide, the penetration
/// along m, the flange along the guide (xr, vr), the tool along the guide (xt, vt), the target along
/// m (xp, vp); the planar extras in `Kinematics::plane`.
pub(crate) fn kinematics(plant: &Plant, p: &Planar, t: f64, y: &State) -> Kinematics {
    if let Some(st) = &p.scene.rotational {
        return rotational_stage::kinematics(plant, p, st, t, y);
    }
    let c = plant.motion.at(t);
    let f = flange(plant, p, &c, y);
    let d = &p.dir;
    let (xr, vr) = (dot(f.pos, d.u), dot(f.vel, d.u));
    let (xt, vt) = match plant.slide {
        _ if plant.decoupler.is_rigid() => (xr, vr),
        Some(Slide::Stick { s }) => (xr + s, vr),
        _ => (y[XT], y[VT]),
    };
    // The tool: along the guide at xt, across it with the flange.
    let (fw, vw) = (dot(f.pos, d.w), dot(f.vel, d.w));
    let tool = comb(xt, d.u, fw, d.w);
    let tool_v = comb(vt, d.u, vw, d.w);
    let (xp, vp) = match plant.target {
        crate::target::Target::Obstacle { surface } => (surface, 0.0),
        crate::target::Target::Object { .. } => (y[XP], y[VP]),
    };
    let (tm, tvm) = (dot(tool, d.m), dot(tool_v, d.m));
    Kinematics {
        xc: c.x, vc: c.v, ac: c.a, xr, vr, xt, vt, xp, vp,
        s: xt - xr, s_dot: vt - vr, delta: tm - xp, delta_dot: tvm - vp,
        plane: crate::state::PlaneKinematics { path: [f.x, f.v, f.y, f.vy], slip_v: dot(tool_v, d.t), across_u: [fw, vw], ..Default::default() },
    }
}

/// The forces of the instant: the contact's normal force (as 1-D) and friction, the decoupler's
/// force along the guide, and the force on the robot (its magnitude, signed by its component along
/// the path; the 1-D plant's signed force for an axial scene).
pub(crate) fn forces(plant: &Plant, p: &Planar, k: &Kinematics) -> (Forces, Loads) {
    if let Some(st) = &p.scene.rotational {
        let (f, acc) = rotational_stage::forces(plant, p, st, k);
        return (f, Loads { accel: [acc[0], 0.0], ..Loads::default() });
    }
    let contact = plant.contact.force(k.delta, k.delta_dot, plant.target_chi);
    let friction = p.friction.force(contact, k.plane.slip_v);
    let mut decoupler = plant.decoupler.force(k.s, k.s_dot, plant.front_chi, plant.back_chi);
    let loads0 = loads(plant, p, contact, friction);
    if plant.slide.is_some() {
        if let Some(slide) = plant.slide {
            let (limit, req, _) = slide_terms(plant, p, k, &loads0, decoupler.total);
            decoupler.friction = slide.force(limit, req);
            decoupler.total += decoupler.friction;
        }
    }
    let acc = robot::flange_accel(plant, p, k, &loads0, decoupler.total);
    let on_robot = robot::force_on_robot(plant, p, &loads0, decoupler.total, acc);
    let r = on_robot[0].hypot(on_robot[1]);
    let robot = r.copysign(dot(on_robot, p.dir.ep));
    (Forces { contact, decoupler, robot }, Loads { accel: acc, ..loads0 })
}

/// For a Coulomb slide along the guide: the friction limit (N), the friction that would keep
/// s'' = 0 (N) and s'' without it (m/s^2), as `Plant::slide_terms` in 1-D.
pub(crate) fn slide_terms(plant: &Plant, p: &Planar, k: &Kinematics, l: &Loads, others: f64) -> (f64, f64, f64) {
    let limit = plant.decoupler.friction_limit(k.s);
    let a_t = (others + dot(l.contact, p.dir.u) + dot(l.weight, p.dir.u)) / plant.tool_mass;
    let acc = robot::flange_accel(plant, p, k, l, others);
    let a_r = dot(comb(acc[0], p.dir.ep, acc[1], p.dir.eq), p.dir.u);
    let a0 = a_t - a_r;
    (limit, crate::friction::required(a0, 1.0 / plant.tool_mass + robot::inverse_mass_along_u(plant, p)), a0)
}

/// The right-hand side (`Plant::eval` for a planar scene).
pub(crate) fn eval(plant: &Plant, p: &Planar, t: f64, y: &State, dy: &mut State) -> (Kinematics, Forces) {
    if let Some(st) = &p.scene.rotational {
        return rotational_stage::eval(plant, p, st, t, y, dy);
    }
    let k = kinematics(plant, p, t, y);
    let (f, l) = forces(plant, p, &k);
    *dy = [0.0; crate::state::N];
    if plant.robot.is_some() {
        dy[XR] = k.plane.path[1];
        dy[VR] = l.accel[0];
        if p.across_states {
            dy[XP] = k.plane.path[3];
            dy[VP] = l.accel[1];
        }
    }
    if !plant.decoupler.is_rigid() {
        dy[XT] = k.vt;
        dy[VT] = match plant.slide {
            Some(Slide::Stick { .. }) => dot(comb(l.accel[0], p.dir.ep, l.accel[1], p.dir.eq), p.dir.u),
            _ => (f.decoupler.total + dot(l.contact, p.dir.u) + dot(l.weight, p.dir.u)) / plant.tool_mass,
        };
    }
    if plant.target.is_object() {
        dy[XP] = k.vp;
        dy[VP] = plant.target.accel(f.contact, k.vp);
    }
    dy[IMPULSE] = if plant.in_contact { f.decoupler.total } else { 0.0 };
    (k, f)
}

/// `slide_terms` from the contact's normal force alone (the 1-D plant's call): the friction at the
/// contact is recomputed from the instant's slip.
pub(crate) fn slide_terms_at(plant: &Plant, p: &Planar, k: &Kinematics, contact: f64, others: f64) -> (f64, f64, f64) {
    let l = loads(plant, p, contact, p.friction.force(contact, k.plane.slip_v));
    slide_terms(plant, p, k, &l, others)
}

