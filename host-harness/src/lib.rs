//! Flinch host harness: the plant, the controller model, the solvers, scenes and the CLI.
//!
//! Layout: `scene` reads and validates scene files; `plant` holds one physical element per file;
//! `solver` integrates; `sim` runs a scene and summarises it; `report` prints, plots and writes
//! what a run produced; `avoid` is collision avoidance (Ch. 5); `bench` is the speed/accuracy study (`flinch bench`).
pub mod avoid;
pub mod bench;
pub mod body_design;
pub mod check;
pub mod design;
pub mod kinematics;
pub mod report;
pub mod sample;
pub mod sweep;
pub mod validate;

pub use flinch_solver as solver;
pub use flinch_model::{body, scene, shipped};
pub use flinch_plant as plant;
pub use flinch_sim as sim;
pub use flinch_sim::verdict;
pub use flinch_hil as hil;
