//! The damping keys of a nonlinear contact (`plant/contact.rs`, `model/src/damping_law.rs`):
//! `restitution` with a `damping_law`, or a fixed `chi` (Table 12). The target and the back
//! end-stop share them.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::model::{ContactDamping, DampingLaw};

/// The damping laws by name, in the order of [`LAW_VALUES`].
const LAW_NAMES: &[&str] = &["hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "exact"];
/// The laws named by [`LAW_NAMES`].
const LAW_VALUES: &[DampingLaw] = &[
    DampingLaw::HuntCrossley,
    DampingLaw::LankaraniNikravesh,
    DampingLaw::Flores,
    DampingLaw::Gonthier,
    DampingLaw::Exact,
];

/// e, the requested coefficient of restitution.
pub const RESTITUTION: Key = Key::number("restitution", "", Incl(0.0), Incl(1.0), "a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)", "e, the requested coefficient of restitution (with damping_law)")
    .optional("give chi instead");
/// The law mapping e to chi.
pub const DAMPING_LAW: Key = Key::of("damping_law", Ty::Choice(LAW_NAMES), "the law mapping e to chi = alpha(e) k / v_in (eq 7 and others)")
    .optional("required with restitution");
/// A fixed chi.
pub const CHI: Key = Key::number("chi", "N s/m^2.5", Incl(0.0), Incl(1e8), "4.5e4-1.35e6 N s/m^2.5 in Table 12; 1e8 is overdamped for every stiffness in range", "a fixed damping chi (Table 12) instead of restitution and damping_law")
    .optional("restitution and damping_law set chi");

/// `restitution` + `damping_law` or `chi`; `default_law` is used when `damping_law` is absent
/// (`None`: the law is required).
pub(super) fn contact_damping(
    cx: &mut Ctx,
    t: &Tab,
    default_law: Option<DampingLaw>,
) -> Option<ContactDamping> {
    let has_chi = t.has(CHI.name);
    let has_e = t.has(RESTITUTION.name);
    let has_law = t.has(DAMPING_LAW.name);
    if has_chi {
        if has_e || has_law {
            let other = if has_e { RESTITUTION.name } else { DAMPING_LAW.name };
            cx.bad(
                t,
                other,
                "give either chi (a fixed damping) or restitution with damping_law, not both"
                    .into(),
            );
            return None;
        }
        return cx.number(t, &CHI).map(ContactDamping::FixedChi);
    }
    let (e_range, chi_range) = (RESTITUTION.span()?.describe(), CHI.span()?.describe());
    if !has_e {
        cx.missing(
            t,
            RESTITUTION.name,
            &format!("restitution {e_range} (with damping_law), or chi ({chi_range})"),
        );
        if has_law {
            cx.maybe_choice(t, &DAMPING_LAW, LAW_VALUES);
        }
        return None;
    }
    let e = cx.number(t, &RESTITUTION);
    let law = match default_law {
        Some(d) if !has_law => Some(d),
        _ if !has_law => {
            cx.missing(t, DAMPING_LAW.name, &DAMPING_LAW.what());
            None
        }
        _ => cx.maybe_choice(t, &DAMPING_LAW, LAW_VALUES).flatten(),
    };
    let (e, law) = (e?, law?);
    // These two laws divide by e.
    if e == 0.0 && matches!(law, DampingLaw::Flores | DampingLaw::Gonthier) {
        cx.bad(t, RESTITUTION.name, "must be in (0, 1] with damping_law \"flores\" or \"gonthier\" (the law divides by e), got 0".into());
        return None;
    }
    Some(ContactDamping::Restitution {
        restitution: e,
        law,
    })
}
