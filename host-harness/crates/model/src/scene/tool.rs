//! `[tool]`: the end-effector the decoupler carries (m_t in `plant/mod.rs`).
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::Tool;

/// The `[tool]` table in the top level.
pub const TABLE: Key = Key::of("tool", Ty::Table("the tool"), "the tool");

/// m_t.
pub const MASS: Key = Key::number("mass", "kg", Incl(1e-3), Incl(50.0), "1 g to 50 kg: the largest payload of arms in the Table 7 class and beyond (the thesis: 0.048-0.75 kg)", "m_t, the tool's mass (everything the decoupler carries)");

/// The keys of `[tool]`.
pub const KEYS: &[Key] = &[MASS];

/// Reads `[tool]`.
pub(super) fn tool(cx: &mut Ctx, t: &Tab) -> Option<Tool> {
    cx.check_keys(t, KEYS, "");
    Some(Tool {
        mass: cx.number(t, &MASS)?,
    })
}
