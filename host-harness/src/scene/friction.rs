//! `decoupler.friction = { mu, v0 }`: the bi-stable slide's friction `F = mu F_n tanh(v / v0)`
//! (eq 41-42, `plant/friction.rs`); absent, the slide is frictionless.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::TanhFriction;

/// The `friction` table in `[decoupler]`.
pub const TABLE: Key = Key::of(
    "friction",
    Ty::Table("{ mu, v0 }; omit it for a frictionless slide"),
    "slide friction (eq 41-42)",
)
.optional("a frictionless slide");

/// mu.
pub const MU: Key = Key::number("mu", "", Incl(0.0), Incl(1.0), "dry sliding friction: 0.04 (PTFE) to about 1 (rubber on steel); 0.12-0.23 in Tables 5-15", "mu, the friction coefficient of the slide");
/// v0.
pub const V0: Key = Key::number("v0", "m/s", Incl(0.0), Incl(0.1), "0 is the Coulomb limit (regularised); 1e-3 m/s in the thesis (eq 41); beyond 0.1 m/s friction is no longer dry", "v0, the velocity regularising sgn(); values below 1e-3 m/s are raised to it and the run says so");

/// The keys of `decoupler.friction`.
pub const KEYS: &[Key] = &[MU, V0];

/// Reads `decoupler.friction`: `Some(None)` when absent.
pub(super) fn friction(cx: &mut Ctx, t: &Tab) -> Option<Option<TanhFriction>> {
    let Some(f) = cx.maybe_table(t, &TABLE)? else {
        return Some(None);
    };
    cx.check_keys(&f, KEYS, "");
    let mu = cx.number(&f, &MU);
    let v0 = cx.number(&f, &V0);
    mu.zip(v0).map(|(mu, v0)| Some(TanhFriction { mu, v0 }))
}
