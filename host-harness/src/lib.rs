//! Flinch host harness: the plant, the controller model, the solvers, scenes and the CLI.
//!
//! Layout: `scene` reads and validates scene files; `plant` holds one physical element per file;
//! `solver` integrates; `sim` assembles a scene into a plant and runs it; `report` prints, plots and
//! writes what a run produced; `hil` runs the firmware in the loop; `avoid` is collision avoidance.
pub mod avoid;
pub mod scene;
