//! The `[decoupler]` table's own keys: the table, `kind` (a new decoupler adds its name here), and
//! the (no) keys of a rigid decoupler.

use crate::scene::check::{Key, Ty};

/// The `[decoupler]` table in the top level.
pub const TABLE: Key = Key::of("decoupler", Ty::Table("what holds the tool on the flange"), "what holds the tool on the flange");

/// The mechanism; a new decoupler adds its name here and its arm in [`decoupler`].
pub const KIND: Key = Key::of(
    "kind",
    Ty::Choice(&["rigid", "linear", "bistable", "hydraulic"]),
    "the mechanism: \"rigid\" (no decoupler), \"linear\" (eq 17, 23), \"bistable\" (eq 24-42), \"hydraulic\" (eq 46-56)",
);

/// The keys of a rigid decoupler.
pub const RIGID_KEYS: &[Key] = &[KIND];
