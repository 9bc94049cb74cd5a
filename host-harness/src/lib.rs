//! Flinch host harness: the plant, the controller model, the solvers, scenes and the CLI.
//!
//! Layout: `scene` reads and validates scene files; `plant` holds one physical element per file;
//! `solver` integrates; `sim` runs a scene and summarises it; `report` prints, plots and writes
//! what a run produced; `avoid` is collision avoidance (Ch. 5); `bench` is the speed/accuracy study (`flinch bench`).
pub mod report;

pub use flinch_solver as solver;
pub use flinch_model::{body, scene, shipped};
pub use flinch_plant as plant;
pub use flinch_sim as sim;
pub use flinch_sim::verdict;
pub use flinch_hil as hil;
pub use flinch_studies::{bench, body_design, check, design, sample, sweep, validate};
/// The robot from its URDF (`flinch-kinematics`), and `flinch robot` (`cli`).
pub mod kinematics {
    pub use flinch_kinematics::*;
    pub use flinch_studies::robot as cli;
}
pub use flinch_avoid as avoid;
