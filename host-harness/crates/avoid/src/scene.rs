//! The avoidance scene's values (`flinch-model`'s `avoid::scene`), under the path the avoidance code
//! and its tests name.

pub use flinch_model::avoid::scene::*;
