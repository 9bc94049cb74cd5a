//! The serial chain from `base_link` to `tip_link` of a URDF, with every link that moves with it.
//!
//! The URDF is read by `urdf-rs`. From the tree it describes, Flinch keeps the links at and below
//! `base_link`. The joints on the path from `base_link` to `tip_link` are the chain: `revolute`
//! and `continuous` turn, `prismatic` slides, `fixed` ones only carry a frame; `floating`,
//! `planar` and `spherical` on that path are refused. A joint off the path (a second finger, a
//! camera mount) is held at its zero position: its links add their mass to the chain joint they
//! hang from, as a payload does. Links above `base_link` do not move and are ignored.
//!
//! Frames follow the URDF specification: a joint's `<origin xyz rpy>` places its frame in the
//! parent link's frame, `rpy` being fixed-axis roll, pitch, yaw (`R = Rz(y) Ry(p) Rx(r)`); the
//! child link's frame is the joint frame turned by `q` about `<axis>` (revolute) or moved by `q`
//! along it (prismatic); `<inertial><origin>` places the centre of mass and the axes in which
//! `<inertia>` is written.
use crate::error::KinError;
use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::path::Path;

/// How a chain joint moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Turns about its axis, q in rad (`revolute`, `continuous`).
    Revolute,
    /// Slides along its axis, q in m (`prismatic`).
    Prismatic,
}

/// One link below `base_link`, in an order where a parent comes before its children.
#[derive(Debug, Clone)]
pub(crate) struct Node {
    pub(crate) name: String,
    /// Index of the parent link's node; `None` for `base_link`.
    pub(crate) parent: Option<usize>,
    /// The joint's `<origin>`: joint frame in the parent link's frame.
    pub(crate) origin: Isometry3<f64>,
    /// `Some((i, kind, axis))` if the joint into this link is the chain's moving joint i.
    pub(crate) motion: Option<(usize, JointKind, Unit<Vector3<f64>>)>,
    /// The last chain joint between `base_link` and this link: the link moves with joints 0..=body.
    pub(crate) body: Option<usize>,
    /// kg.
    pub(crate) mass: f64,
    /// Centre of mass in the link frame, m.
    pub(crate) com: Vector3<f64>,
    /// Rotational inertia about the centre of mass, in the link frame, kg m^2.
    pub(crate) inertia: Matrix3<f64>,
}

/// A serial chain read from a URDF.
#[derive(Debug, Clone)]
pub struct Chain {
    /// The URDF file (for messages).
    pub file: String,
    /// `base_link`.
    pub base_link: String,
    /// `tip_link`: the flange; the reduced values are for its frame's origin.
    pub tip_link: String,
    /// The moving joints from base to tip, in order.
    pub joint_names: Vec<String>,
    /// Their kinds.
    pub joint_kinds: Vec<JointKind>,
    /// Their `<limit lower upper>` (rad or m); `None` for `continuous` or an absent or empty limit.
    pub joint_limits: Vec<Option<(f64, f64)>>,
    pub(crate) nodes: Vec<Node>,
    pub(crate) tip: usize,
}

/// Where every link and chain joint is at one configuration, in the base frame.
#[derive(Debug, Clone)]
pub struct Placement {
    /// Each node's link frame.
    pub(crate) links: Vec<Isometry3<f64>>,
    /// Each chain joint's axis (unit).
    pub axes: Vec<Vector3<f64>>,
    /// A point on each chain joint's axis (the joint frame's origin), m.
    pub points: Vec<Vector3<f64>>,
    /// The tip link frame's origin, m.
    pub tip: Vector3<f64>,
}

fn finite3(v: [f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

impl Chain {
    /// Reads `path` and builds the chain from `base_link` to `tip_link`.
    pub fn load(path: &Path, base_link: &str, tip_link: &str) -> Result<Chain, KinError> {
        let file = path.display().to_string();
        // A library convenience (the `flinch` commands read URDFs through flinch-output's reader):
        // a regular file of at most 16 MiB only, so a FIFO or a device cannot block or flood it.
        match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => return Err(KinError::new(&file, "urdf", "is not a regular file; a URDF must be one")),
            Ok(m) if m.len() > 16 << 20 => return Err(KinError::new(&file, "urdf", format!("{} bytes; a URDF is at most 16 MiB", m.len()))),
            _ => {}
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| KinError::new(&file, "urdf", format!("cannot be read: {e}")))?;
        Chain::from_urdf_str(&text, &file, base_link, tip_link)
    }

    /// Builds the chain from URDF text; `file` names it in messages.
    pub fn from_urdf_str(text: &str, file: &str, base_link: &str, tip_link: &str) -> Result<Chain, KinError> {
        // Bounded first: depth, element count, one <robot> root, every number in its range.
        crate::urdf_scan::scan(text, file)?;
        let robot = urdf_rs::read_from_string(text)
            .map_err(|e| match crate::urdf_diag::diagnose(text) {
                Some((element, what)) => KinError::new(file, element, format!("is not a URDF that parses: {what}")),
                None => KinError::new(file, "<robot>", format!("is not a URDF that parses: {e}")),
            })?;
        let err = |el: String, what: String| KinError::new(file, el, what);

        // Links by name, once each.
        let mut link_ix: HashMap<&str, usize> = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if link_ix.insert(l.name.as_str(), i).is_some() {
                return Err(err(format!("link \"{}\"", l.name), "appears twice; link names must be unique".into()));
            }
        }
        let names = || {
            let mut v: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
            v.truncate(20);
            v.join(", ")
        };
        // The joint into each link, once each, with parent and child present.
        let mut joint_names: HashMap<&str, ()> = HashMap::new();
        let mut parent_joint: HashMap<&str, usize> = HashMap::new();
        for (j, jt) in robot.joints.iter().enumerate() {
            let el = format!("joint \"{}\"", jt.name);
            if joint_names.insert(jt.name.as_str(), ()).is_some() {
                return Err(err(el, "appears twice; joint names must be unique".into()));
            }
            for (role, l) in [("parent", &jt.parent.link), ("child", &jt.child.link)] {
                if !link_ix.contains_key(l.as_str()) {
                    return Err(err(el, format!("its {role} link \"{l}\" is not a <link> of the URDF (links: {})", names())));
                }
            }
            if parent_joint.insert(jt.child.link.as_str(), j).is_some() {
                return Err(err(el, format!("link \"{}\" is the child of two joints; a URDF is a tree", jt.child.link)));
            }
        }
        for (role, l) in [("base_link", base_link), ("tip_link", tip_link)] {
            if !link_ix.contains_key(l) {
                return Err(err(role.into(), format!("link \"{l}\" is not in the URDF (links: {})", names())));
            }
        }

        // The path tip -> base.
        let mut path_joints: Vec<usize> = Vec::new();
        let mut at = tip_link;
        let mut steps = 0;
        while at != base_link {
            let Some(&j) = parent_joint.get(at) else {
                return Err(err(
                    "tip_link".into(),
                    format!("link \"{tip_link}\" is not below base_link \"{base_link}\" (its root is \"{at}\")"),
                ));
            };
            path_joints.push(j);
            at = robot.joints[j].parent.link.as_str();
            steps += 1;
            if steps > robot.joints.len() {
                return Err(err("<robot>".into(), "its joints form a loop; a URDF is a tree".into()));
            }
        }
        path_joints.reverse();
        let mut chain_of_joint: HashMap<usize, (usize, JointKind)> = HashMap::new();
        let mut chain_names = Vec::new();
        let mut chain_kinds = Vec::new();
        let mut chain_limits = Vec::new();
        for &j in &path_joints {
            let jt = &robot.joints[j];
            let kind = match jt.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointKind::Revolute,
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                urdf_rs::JointType::Fixed => continue,
                ref t => {
                    return Err(err(
                        format!("joint \"{}\"", jt.name),
                        format!("type {} between base_link and tip_link; allowed: revolute, continuous, prismatic, fixed", format!("{t:?}").to_lowercase()),
                    ))
                }
            };
            chain_of_joint.insert(j, (chain_names.len(), kind));
            chain_names.push(jt.name.clone());
            chain_kinds.push(kind);
            let (lo, hi) = (jt.limit.lower, jt.limit.upper);
            let limited = jt.joint_type != urdf_rs::JointType::Continuous && lo.is_finite() && hi.is_finite() && lo < hi;
            chain_limits.push(limited.then_some((lo, hi)));
        }
        if chain_names.is_empty() {
            return Err(err(
                "tip_link".into(),
                format!("no revolute, continuous or prismatic joint between \"{base_link}\" and \"{tip_link}\": nothing moves"),
            ));
        }

        // Children of each link, then the links below base in parent-first order.
        let mut children: HashMap<&str, Vec<usize>> = HashMap::new();
        for (j, jt) in robot.joints.iter().enumerate() {
            children.entry(jt.parent.link.as_str()).or_default().push(j);
        }
        let mut nodes: Vec<Node> = Vec::new();
        let mut queue: Vec<(usize, Option<usize>, Option<usize>)> = vec![(link_ix[base_link], None, None)];
        // (URDF link index, joint index into it, parent node)
        let mut k = 0;
        while k < queue.len() {
            let (li, ji, parent) = queue[k];
            k += 1;
            let link = &robot.links[li];
            let (origin, motion) = match ji {
                None => (Isometry3::identity(), None),
                Some(j) => {
                    let jt = &robot.joints[j];
                    let el = format!("joint \"{}\"", jt.name);
                    if !finite3(jt.origin.xyz.0) || !finite3(jt.origin.rpy.0) {
                        return Err(err(el, "<origin> has a value that is not a finite number".into()));
                    }
                    let motion = match chain_of_joint.get(&j) {
                        None => None,
                        Some(&(i, kind)) => {
                            let a = Vector3::from(jt.axis.xyz.0);
                            if !finite3(jt.axis.xyz.0) || a.norm() < 1e-9 {
                                return Err(err(el, format!("<axis xyz> is {:?}; allowed: a finite, non-zero vector", jt.axis.xyz.0)));
                            }
                            Some((i, kind, Unit::new_normalize(a)))
                        }
                    };
                    (pose(jt.origin.xyz.0, jt.origin.rpy.0), motion)
                }
            };
            let body = match motion {
                Some((i, _, _)) => Some(i),
                None => parent.and_then(|p: usize| nodes[p].body),
            };
            let (mass, com, inertia) = inertial(file, link, body.is_some())?;
            let me = nodes.len();
            nodes.push(Node { name: link.name.clone(), parent, origin, motion, body, mass, com, inertia });
            if let Some(js) = children.get(link.name.as_str()) {
                for &j in js {
                    queue.push((link_ix[robot.joints[j].child.link.as_str()], Some(j), Some(me)));
                }
            }
            if nodes.len() > robot.links.len() {
                return Err(err("<robot>".into(), "its joints form a loop; a URDF is a tree".into()));
            }
        }
        let tip = nodes.iter().position(|n| n.name == tip_link).expect("tip is below base: found on the path");
        Ok(Chain {
            file: file.to_string(),
            base_link: base_link.to_string(),
            tip_link: tip_link.to_string(),
            joint_names: chain_names,
            joint_kinds: chain_kinds,
            joint_limits: chain_limits,
            nodes,
            tip,
        })
    }

    /// Number of moving joints.
    pub fn dof(&self) -> usize {
        self.joint_names.len()
    }

    /// Total mass of the links that move with at least one chain joint, kg.
    pub fn moving_mass(&self) -> f64 {
        self.nodes.iter().filter(|n| n.body.is_some()).map(|n| n.mass).sum()
    }

    /// Places every link at configuration `q` (length [`Chain::dof`], checked by the caller).
    pub fn place(&self, q: &[f64]) -> Placement {
        let n = self.dof();
        let mut links: Vec<Isometry3<f64>> = Vec::with_capacity(self.nodes.len());
        let mut axes = vec![Vector3::zeros(); n];
        let mut points = vec![Vector3::zeros(); n];
        for node in &self.nodes {
            let parent = node.parent.map(|p| links[p]).unwrap_or_else(Isometry3::identity);
            let joint = parent * node.origin;
            let frame = match node.motion {
                None => joint,
                Some((i, kind, axis)) => {
                    axes[i] = joint.rotation * axis.into_inner();
                    points[i] = joint.translation.vector;
                    match kind {
                        JointKind::Revolute => joint * Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&axis, q[i])),
                        JointKind::Prismatic => joint * Isometry3::from_parts(Translation3::from(axis.into_inner() * q[i]), UnitQuaternion::identity()),
                    }
                }
            };
            links.push(frame);
        }
        let tip = links[self.tip].translation.vector;
        Placement { links, axes, points, tip }
    }
}

/// A link's mass, centre of mass and inertia about it (link frame), checked: mass >= 0 and the
/// inertia tensor physical (symmetric by construction, principal moments >= 0, each at most the
/// sum of the other two). A link with neither mass nor inertia (a frame) is allowed.
fn inertial(file: &str, link: &urdf_rs::Link, moves: bool) -> Result<(f64, Vector3<f64>, Matrix3<f64>), KinError> {
    let el = format!("link \"{}\"", link.name);
    let i = &link.inertial;
    let m = i.mass.value;
    let t = &i.inertia;
    let vals = [m, t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    if vals.iter().any(|v| !v.is_finite()) || !finite3(i.origin.xyz.0) || !finite3(i.origin.rpy.0) {
        return Err(KinError::new(file, el, "<inertial> has a value that is not a finite number"));
    }
    if m < 0.0 {
        return Err(KinError::new(file, el, format!("<inertial><mass value> is {m} kg; allowed: >= 0")));
    }
    let local = Matrix3::new(t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz);
    let scale = t.ixx.abs() + t.iyy.abs() + t.izz.abs() + 1e-300;
    let ev = local.symmetric_eigenvalues();
    let (mut p0, mut p1, mut p2) = (ev[0], ev[1], ev[2]);
    if p0 > p1 { std::mem::swap(&mut p0, &mut p1); }
    if p1 > p2 { std::mem::swap(&mut p1, &mut p2); }
    if p0 > p1 { std::mem::swap(&mut p0, &mut p1); }
    let tol = 1e-9 * scale;
    if p0 < -tol {
        return Err(KinError::new(
            file,
            el,
            format!("<inertia> has a negative principal moment ({p0:.6e} kg m^2); allowed: a positive semi-definite tensor"),
        ));
    }
    if p2 > p0 + p1 + tol {
        return Err(KinError::new(
            file,
            el,
            format!("<inertia> principal moments {p0:.6e}, {p1:.6e}, {p2:.6e} kg m^2 break the triangle inequality (the largest must not exceed the sum of the other two): no body has them"),
        ));
    }
    if moves && m == 0.0 && p2 > tol.max(0.0) {
        return Err(KinError::new(file, el, "<inertia> is non-zero with zero mass: no body has it"));
    }
    let o = pose(i.origin.xyz.0, i.origin.rpy.0);
    let r = o.rotation.to_rotation_matrix();
    Ok((m, o.translation.vector, r.matrix() * local * r.matrix().transpose()))
}
