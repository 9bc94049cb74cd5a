//! Flinch host harness: the `flinch` command line (src/main.rs) over the layered crates of
//! `host-harness/crates/` (docs/architecture.md draws them), re-exported here under the paths the
//! integration tests (tests/, host-harness/tests/), the benches and the Python package use
//! (`flinch_harness::scene`, `::sim`, `::sweep`, ...). Nothing is defined here: a change belongs in
//! the crate that owns it.
//!
//! Bottom to top: `solver`, `kinematics` (the robot from its URDF) and the output conventions;
//! the scene model (`scene`, `body`, `stopping`, `damping_law`, `shipped`); the `plant`; a run
//! (`sim`, `verdict`); firmware in the loop (`hil`); what a run produced (`report`); the studies
//! (`check`, `design`, `body_design`, `sweep`, `sample`, `bench`, `validate`, `kinematics::cli`);
//! collision avoidance (`avoid`); the schemas and the HTML report (`report::schema`, `report::html`).

pub use flinch_avoid as avoid;
pub use flinch_hil as hil;
pub use flinch_model::{body, damping_law, headline, overrides, scene, shipped, stopping};
pub use flinch_plant as plant;
pub use flinch_sim as sim;
pub use flinch_sim::verdict;
pub use flinch_solver as solver;
pub use flinch_studies::{bench, body_design, check, design, pfl, sample, sweep, validate};

/// The robot from its URDF (`flinch-kinematics`), and `flinch robot` (`cli`, in `flinch-studies`).
pub mod kinematics {
    pub use flinch_kinematics::*;
    pub use flinch_studies::robot as cli;
}

/// What a run produced (`flinch-report`), how Flinch writes (`flinch-output`: `figure`, `font`,
/// `output`, the JSON frame), the JSON Schemas of every document and the HTML report
/// (`flinch-publish`).
pub mod report {
    pub use flinch_publish::{html, schema};
    pub use flinch_report::*;
}
