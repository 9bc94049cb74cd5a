//! Joint-space mass matrix (composite-rigid-body algorithm) and tip Jacobian of a [`Chain`].
//!
//! Everything is written in the base frame with spatial vectors `(ω, v_O)`: `ω` the angular
//! velocity, `v_O` the velocity of the body point at the base origin. Joint i's motion axis is
//! `s_i = (a_i, p_i × a_i)` (revolute, axis `a_i` through `p_i`) or `(0, a_i)` (prismatic). A link
//! of mass `m`, centre of mass `c` and inertia `I_c` about it has the spatial inertia
//! `[[I_c - m [c]x^2, m [c]x], [m [c]x^T, m 1]]` (kinetic energy `½ Vᵀ I V`). The composite
//! inertia `I^c_i` of joint i is the sum over the links that move with it (body >= i), and
//! `M_ij = s_iᵀ I^c_max(i,j) s_j` (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, §6.2).
use crate::chain::{Chain, JointKind, Placement};
use nalgebra::{DMatrix, Matrix3, Matrix6, Vector3, Vector6};

fn skew(c: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -c.z, c.y, c.z, 0.0, -c.x, -c.y, c.x, 0.0)
}

/// Spatial inertia about the base origin of a body of mass `m`, centre of mass `c`, inertia
/// `ic` about `c` (all in the base frame).
fn spatial_inertia(m: f64, c: &Vector3<f64>, ic: &Matrix3<f64>) -> Matrix6<f64> {
    let s = skew(c);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&(ic - m * s * s));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(m * s));
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(m * s.transpose()));
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&(m * Matrix3::identity()));
    out
}

/// The motion axis of each chain joint, `(ω, v_O)` per unit joint rate.
fn motion_axes(chain: &Chain, at: &Placement) -> Vec<Vector6<f64>> {
    (0..chain.dof())
        .map(|i| {
            let a = at.axes[i];
            let mut s = Vector6::zeros();
            match chain.joint_kinds[i] {
                JointKind::Revolute => {
                    s.fixed_rows_mut::<3>(0).copy_from(&a);
                    s.fixed_rows_mut::<3>(3).copy_from(&at.points[i].cross(&a));
                }
                JointKind::Prismatic => s.fixed_rows_mut::<3>(3).copy_from(&a),
            }
            s
        })
        .collect()
}

/// The joint-space mass matrix `M_q(q)` (eq 10-11), n x n, kg m^2 / kg m / kg by joint kinds.
pub fn mass_matrix(chain: &Chain, at: &Placement) -> DMatrix<f64> {
    let n = chain.dof();
    // Composite inertias: each link adds to its own body, then accumulate tip -> base.
    let mut comp = vec![Matrix6::<f64>::zeros(); n];
    for (node, frame) in chain.nodes.iter().zip(&at.links) {
        if let Some(b) = node.body {
            if node.mass == 0.0 && node.inertia.iter().all(|x| *x == 0.0) {
                continue;
            }
            let r = frame.rotation.to_rotation_matrix();
            let c = frame * nalgebra::Point3::from(node.com);
            let ic = r.matrix() * node.inertia * r.matrix().transpose();
            comp[b] += spatial_inertia(node.mass, &c.coords, &ic);
        }
    }
    for i in (1..n).rev() {
        let add = comp[i];
        comp[i - 1] += add;
    }
    let s = motion_axes(chain, at);
    let mut m = DMatrix::zeros(n, n);
    for i in 0..n {
        for j in 0..=i {
            // max(i, j) = i
            let v = s[j].dot(&(comp[i] * s[i]));
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
    m
}

/// The geometric Jacobian of the tip link frame's origin: rows 0-2 its linear velocity, rows
/// 3-5 the angular velocity, per unit joint rate (6 x n).
pub fn jacobian(chain: &Chain, at: &Placement) -> DMatrix<f64> {
    let n = chain.dof();
    let mut j = DMatrix::zeros(6, n);
    for i in 0..n {
        let a = at.axes[i];
        let (lin, ang) = match chain.joint_kinds[i] {
            JointKind::Revolute => (a.cross(&(at.tip - at.points[i])), a),
            JointKind::Prismatic => (a, Vector3::zeros()),
        };
        // A joint past the tip does not move it (the tip link is the last of the chain, so none is).
        for r in 0..3 {
            j[(r, i)] = lin[r];
            j[(r + 3, i)] = ang[r];
        }
    }
    j
}
