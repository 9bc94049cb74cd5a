//! The robot from its URDF (`flinch-kinematics`), and `flinch robot` (cli.rs).
pub use flinch_kinematics::*;
pub mod cli;
