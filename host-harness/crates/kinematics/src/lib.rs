//! The compliant robot reduced from joint space to one degree of freedom along the approach
//! (thesis eq 10-16), from the robot's URDF.
//!
//! The thesis writes the robot in joint space (eq 11: `M_q(q) ϑ'' + D_q (ϑ' - q') + K_q (ϑ - q) = 0`,
//! `K_q`, `D_q` diagonal and configuration-independent), maps it to the operational space
//! (eq 12-14: `M_X = J^-T M_q J^-1`, the same for `D_X`, `K_X`) and keeps one direction (eq 16) to
//! get the lumped `m_r`, `c_r`, `k_r` of eq 8 (Table 7).
//!
//! Layout: [`chain`] reads the URDF (`urdf-rs`) and builds the serial chain from `base_link` to
//! `tip_link` with every link that moves with it; [`dynamics`] computes the joint-space mass
//! matrix by the composite-rigid-body algorithm and the tip Jacobian; [`reduce`] projects the
//! mass, stiffness and damping on the approach direction.
//!
//! Which one-dimensional value: see [`reduce`]'s module doc (the contact pushes along `u` only,
//! the flange is free in the other directions, so the mass is the operational-space one,
//! `1 / (u^T J M_q^-1 J^T u)`, and the stiffness the one of the Cartesian compliance
//! `J K_q^-1 J^T`, eq 14 inverted).
//! The error type of all of them is in [`error`]. `flinch robot` (the command) is in `flinch-studies`.
pub mod chain;
pub mod dynamics;
pub mod error;
pub mod reduce;
pub mod urdf_diag;
pub mod urdf_scan;

pub use chain::{Chain, JointKind};
pub use error::KinError;
pub use reduce::{reduce, Reduced, MIN_MOBILITY};
