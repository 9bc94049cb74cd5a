//! The scene model: what a scene file says, checked, with no time integration in it.
//!
//! * `scene`: the loader (one file per element, every key declared once with its unit, range and
//!   source), the validated values (`scene/model.rs`), the messages (`file:line: key: what is
//!   allowed`), and the avoidance scene's loader (`scene/avoid/`);
//! * `avoid`: the avoidance scene's values and its true geometry;
//! * `body`: ISO/TS 15066 Annex A's body regions (Tables A.2, A.3) and the limits check;
//! * `stopping`: a robot's published stopping table (ISO 10218-1 Annex B) and its interpolation;
//! * `damping_law`: the contact damping laws' closed forms (restitution to alpha, chi), which the
//!   loader converts and estimates with and the plant's contacts use;
//! * `headline`: what a scene simulates in one line, and what its name claims that it contradicts;
//! * `overrides`: `--set KEY=VALUE`, applied to a scene's text and validated with it;
//! * `shipped`: the scenes built into the binary, and the one way a command reads a scene argument.
//!
//! Depends on `flinch-kinematics` (a `[robot]` given by its URDF is reduced while it is read) and
//! on the firmware library's constants (what the board accepts); nothing of the plant or a run.

pub mod avoid;
pub mod body;
pub mod damping_law;
pub mod headline;
pub mod overrides;
pub mod scene;
pub mod shipped;
pub mod stopping;
