//! The robot reduced to one degree of freedom along the approach direction `u`: `m_r`, `k_r`,
//! `c_r` of eq 8 from `M_q(q)`, `K_q`, `D_q` of eq 11 (thesis eq 12-16).
//!
//! **Which one-dimensional value.** The thesis maps the whole robot to the 6-D operational space
//! (eq 12-14, `X_X = J^-T X_q J^-1`) and keeps the element along the approach (eq 16, `M_X,11`).
//! That element is the mass the flange shows when it is *held* in the five other directions. At
//! a collision the contact pushes along `u` only and the flange is free in the others, so Flinch
//! uses the value the contact feels:
//!
//! - mass: `m_r = 1 / (uᵀ J M_q^-1 Jᵀ u)` (operational-space mass along `u`; Khatib 1987). It is
//!   the mass that takes the impulse: a force impulse `p u` at the tip changes the tip's speed
//!   along `u` by `p uᵀ J M_q^-1 Jᵀ u`. It is also the least kinetic energy over all joint
//!   motions that move the tip at unit speed along `u`: `m_r <= 2 T(q') / (uᵀ J q')^2` for any `q'`.
//! - stiffness: `k_r = 1 / (uᵀ J K_q^-1 Jᵀ u)`, the inverse of the Cartesian compliance
//!   `J K_q^-1 Jᵀ` along `u` (eq 14 inverted: for a square, invertible `J`, `K_X^-1 = J K_q^-1 Jᵀ`).
//!   It is exact quasi-statically: a force `F u` at the tip moves it by `F/k_r` along `u`.
//! - damping: the joint dampers dissipate along the same joint deflection `δϑ = K_q^-1 Jᵀ u`
//!   that the force produces; reduced on it, `c_r = δϑᵀ D_q δϑ / (uᵀ J δϑ)^2`. For a single joint,
//!   or joint damping proportional to joint stiffness (`D_q = β K_q`, then `c_r = β k_r`), it is
//!   eq 13 exactly; a joint without damping (`D_i = 0`) is allowed.
//!
//! These need neither a square nor an invertible `J`: a redundant arm (n > 6) or one with fewer
//! joints (a planar arm) is reduced the same way. For a six-joint arm Flinch also gives the
//! thesis's element-along-`u` values (`J^-1` exists) to compare ([`Reduced::held`]); the held mass
//! is never below the free one.
//!
//! **Singular configuration.** When the tip can (almost) not move along `u`, `Jᵀ u` (almost)
//! vanishes and the reduced mass and stiffness grow without bound: the robot is a wall along `u`,
//! and no one-degree-of-freedom compliant robot describes it. Flinch refuses a configuration where
//! the tip's mobility along `u`, `|Jᵀ u| / |J_v|` (J_v: the translational rows; 1 = every joint
//! moves the tip along `u` as much as it moves it at all), is below [`MIN_MOBILITY`].
use crate::chain::Chain;
use crate::dynamics::{jacobian, mass_matrix};
use crate::error::KinError;
use nalgebra::{DMatrix, DVector, Vector3};

/// The least mobility `|Jᵀ u| / |J_v|_F` accepted. Below it the reduced mass and stiffness are
/// over about 1e6 times their values away from the singularity (they grow as 1/mobility^2).
pub const MIN_MOBILITY: f64 = 1e-3;

/// One joint's part in the reduction.
#[derive(Debug, Clone, PartialEq)]
pub struct JointShare {
    /// The joint's name in the URDF.
    pub name: String,
    /// Tip displacement along `u` per unit joint motion, `(Jᵀ u)_i`: m/rad or m/m.
    pub lever: f64,
    /// Share of the tip's compliance along `u` that this joint gives, `(w_i^2/K_i) k_r`, 0..1.
    pub compliance_share: f64,
}

/// The reduced robot at one configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Reduced {
    /// m_r, kg.
    pub mass_kg: f64,
    /// k_r, N/m.
    pub stiffness_npm: f64,
    /// c_r, N s/m.
    pub damping_nspm: f64,
    /// The approach direction, unit, base frame.
    pub direction: [f64; 3],
    /// The tip (flange) position, base frame, m.
    pub tip_m: [f64; 3],
    /// `|Jᵀ u| / |J_v|_F`, see the module doc.
    pub mobility: f64,
    /// Mass of every link that moves, kg.
    pub moving_mass_kg: f64,
    /// Per joint, base to tip.
    pub joints: Vec<JointShare>,
    /// The thesis's eq 12-14 element along `u` (flange held in the other five directions):
    /// `(m, k, c)`; `None` unless the chain has six joints and `J` is invertible.
    pub held: Option<(f64, f64, f64)>,
}

fn check_len(chain: &Chain, el: &str, len: usize) -> Result<(), KinError> {
    if len != chain.dof() {
        return Err(KinError::new(
            &chain.file,
            el,
            format!(
                "has {len} values; the chain \"{}\" -> \"{}\" has {} moving joints ({})",
                chain.base_link,
                chain.tip_link,
                chain.dof(),
                chain.joint_names.join(", ")
            ),
        ));
    }
    Ok(())
}

/// Reduces `chain` at configuration `q` (rad or m per joint) along `direction` (base frame, any
/// length > 0) with diagonal joint stiffness `k_q` (N m/rad or N/m, > 0) and damping `d_q`
/// (N m s/rad or N s/m, >= 0).
pub fn reduce(chain: &Chain, q: &[f64], direction: [f64; 3], k_q: &[f64], d_q: &[f64]) -> Result<Reduced, KinError> {
    check_len(chain, "joints", q.len())?;
    check_len(chain, "joint_stiffness", k_q.len())?;
    check_len(chain, "joint_damping", d_q.len())?;
    let file = chain.file.as_str();
    for (i, name) in chain.joint_names.iter().enumerate() {
        if !q[i].is_finite() {
            return Err(KinError::new(file, "joints", format!("joint \"{name}\" is at {}; allowed: a finite number", q[i])));
        }
        if !(k_q[i] > 0.0 && k_q[i].is_finite()) {
            return Err(KinError::new(file, "joint_stiffness", format!("joint \"{name}\" has {}; allowed: > 0 and finite", k_q[i])));
        }
        if !(d_q[i] >= 0.0 && d_q[i].is_finite()) {
            return Err(KinError::new(file, "joint_damping", format!("joint \"{name}\" has {}; allowed: >= 0 and finite", d_q[i])));
        }
    }
    let u = Vector3::from(direction);
    if !(u.iter().all(|x| x.is_finite()) && u.norm() > 1e-12) {
        return Err(KinError::new(file, "direction", format!("is {direction:?}; allowed: a finite, non-zero vector")));
    }
    let u = u.normalize();

    let at = chain.place(q);
    let m = mass_matrix(chain, &at);
    let j = jacobian(chain, &at);
    let jv = j.rows(0, 3).into_owned();
    let w: DVector<f64> = jv.transpose() * u;

    let jv_norm = jv.norm();
    let mobility = if jv_norm > 0.0 { w.norm() / jv_norm } else { 0.0 };
    if !(mobility >= MIN_MOBILITY) {
        return Err(KinError::new(
            file,
            "joints",
            format!(
                "singular configuration: the tip \"{}\" can (almost) not move along direction [{:.4}, {:.4}, {:.4}] \
                 (mobility |J^T u|/|J| = {mobility:.2e}, allowed >= {MIN_MOBILITY:.0e}); the reduced mass and \
                 stiffness would be unbounded and no one-degree-of-freedom robot describes it: change the \
                 configuration or the direction",
                chain.tip_link, u.x, u.y, u.z
            ),
        ));
    }

    let Some(chol) = m.clone().cholesky() else {
        let weak = (0..chain.dof()).min_by(|&a, &b| m[(a, a)].total_cmp(&m[(b, b)])).unwrap_or(0);
        return Err(KinError::new(
            file,
            format!("joint \"{}\"", chain.joint_names[weak]),
            "the joint-space mass matrix is not positive definite at this configuration: a joint moves \
             no mass (the links past it have no <inertial> mass or inertia about its axis)"
                .to_string(),
        ));
    };
    let minv_w = chol.solve(&w);
    let mobility_mass = w.dot(&minv_w);
    let compliance: f64 = (0..chain.dof()).map(|i| w[i] * w[i] / k_q[i]).sum();
    let mass_kg = 1.0 / mobility_mass;
    let stiffness_npm = 1.0 / compliance;
    let dissip: f64 = (0..chain.dof()).map(|i| d_q[i] * (w[i] / k_q[i]).powi(2)).sum();
    let damping_nspm = dissip / (compliance * compliance);
    if !(mass_kg.is_finite() && mass_kg > 0.0 && stiffness_npm.is_finite() && damping_nspm.is_finite()) {
        return Err(KinError::new(file, "joints", "the reduction is not finite at this configuration (singular)".to_string()));
    }

    let held = (chain.dof() == 6)
        .then(|| {
            let lu = j.clone().lu();
            let u6 = DVector::from_vec(vec![u.x, u.y, u.z, 0.0, 0.0, 0.0]);
            let x = lu.solve(&u6)?;
            // J invertible in a useful sense: the solve reproduces u6.
            if ((&j * &x) - &u6).norm() > 1e-9 || !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            let kd = DMatrix::from_diagonal(&DVector::from_column_slice(k_q));
            let dd = DMatrix::from_diagonal(&DVector::from_column_slice(d_q));
            Some(((&x.transpose() * &m * &x)[0], (&x.transpose() * kd * &x)[0], (&x.transpose() * dd * &x)[0]))
        })
        .flatten();

    let joints = chain
        .joint_names
        .iter()
        .enumerate()
        .map(|(i, name)| JointShare { name: name.clone(), lever: w[i], compliance_share: w[i] * w[i] / k_q[i] * stiffness_npm })
        .collect();
    Ok(Reduced {
        mass_kg,
        stiffness_npm,
        damping_nspm,
        direction: [u.x, u.y, u.z],
        tip_m: [at.tip.x, at.tip.y, at.tip.z],
        mobility,
        moving_mass_kg: chain.moving_mass(),
        joints,
        held,
    })
}
