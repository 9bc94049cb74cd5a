//! `decoupler.friction = { mu, v0, law }`: the bi-stable slide's friction (eq 41-42,
//! `plant/friction.rs`): with v0 = 0 the Coulomb law as stick/slip states (`law = "stick-slip"`,
//! the default then), or `F = mu F_n tanh(v / v0)` (`law = "regularised"`, the default for v0 > 0);
//! absent, the slide is frictionless.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::{FrictionLaw, TanhFriction};

/// The `friction` table in `[decoupler]`.
pub const TABLE: Key = Key::of(
    "friction",
    Ty::Table("{ mu, v0, law }; omit it for a frictionless slide"),
    "slide friction (eq 41-42)",
)
.optional("a frictionless slide");

/// mu.
pub const MU: Key = Key::number("mu", "", Incl(0.0), Incl(1.0), "dry sliding friction: 0.04 (PTFE) to about 1 (rubber on steel); 0.12-0.23 in Tables 5-15", "mu, the friction coefficient of the slide");
/// v0.
pub const V0: Key = Key::number("v0", "m/s", Incl(0.0), Incl(0.1), "0 is the Coulomb limit (Tables 4, 8, 11, 13); 1e-3 m/s in Table 15; beyond 0.1 m/s friction is no longer dry", "v0, the velocity regularising sgn() with law = \"regularised\" (values below 1e-3 m/s are raised to it and the run says so); must be 0 with law = \"stick-slip\"");
/// The law's names, in the order of [`LAW_VALUES`].
const LAW_NAMES: &[&str] = &["stick-slip", "regularised"];
const LAW_VALUES: &[FrictionLaw] = &[FrictionLaw::StickSlip, FrictionLaw::Regularised];
/// law.
pub const LAW: Key = Key::of("law", Ty::Choice(LAW_NAMES), "stick-slip: Coulomb friction (v0 = 0) with sticking and slipping as states switched at located events (Karnopp); regularised: mu F_n tanh(v / v0) (docs/accuracy.md compares them)")
    .optional("stick-slip when v0 = 0, regularised when v0 > 0");

/// The keys of `decoupler.friction`.
pub const KEYS: &[Key] = &[MU, V0, LAW];

/// Reads `decoupler.friction`: `Some(None)` when absent.
pub(super) fn friction(cx: &mut Ctx, t: &Tab) -> Option<Option<TanhFriction>> {
    let Some(f) = cx.maybe_table(t, &TABLE)? else {
        return Some(None);
    };
    cx.check_keys(&f, KEYS, "");
    let mu = cx.number(&f, &MU);
    let v0 = cx.number(&f, &V0);
    let law = cx.maybe_choice(&f, &LAW, LAW_VALUES)?;
    let (mu, v0) = mu.zip(v0)?;
    let law = law.unwrap_or(if v0 == 0.0 { FrictionLaw::StickSlip } else { FrictionLaw::Regularised });
    if law == FrictionLaw::StickSlip && v0 != 0.0 {
        cx.bad(&f, LAW.name, format!("law = \"stick-slip\" is Coulomb friction without a regularising velocity: it needs v0 = 0, got v0 = {v0} m/s (or use law = \"regularised\")"));
        return None;
    }
    Some(Some(TanhFriction { mu, v0, law }))
}
