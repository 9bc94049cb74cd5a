//! `[target]`: what the tool runs into, a fixed obstacle, a free object or a human body region
//! (`plant/target.rs`, `crate::body`), and the tool-target contact (`plant/contact.rs`; the damping
//! keys are in `contact.rs`).
//!
//! A body region (`kind = "body_region"`) takes its effective mass m_H and linear spring constant k
//! from ISO/TS 15066:2016 Table A.3 and its limits from Table A.2 (`crate::body::PRESETS`, values as
//! commonly reproduced: check them against the licensed text). Its contact is the Annex A model, an
//! undamped linear spring, so it has no `restitution`, `damping_law` or `chi`.
use super::check::{Bound::*, Ctx, Key, Tab, Ty};
use super::contact::{self, contact_damping};
use super::model::{ContactDamping, Target, TargetKind};
use crate::body::{BodyContact, BodyTarget};

/// The `[target]` table in the top level.
pub const TABLE: Key = Key::of("target", Ty::Table("what the tool runs into"), "what the tool runs into");

/// Obstacle, object or body region.
pub const KIND: Key = Key::of("kind", Ty::Choice(&["obstacle", "object", "body_region"]), "\"obstacle\" (fixed), \"object\" (free, needs mass) or \"body_region\" (ISO/TS 15066 Annex A)");
/// Gap at t = 0.
pub const GAP: Key = Key::number("gap", "m", Incl(1e-6), Incl(2.0), "1 um to 2 m, within the reach of an arm; 0.005-0.15 m in the thesis", "gap between the tool and the target at t = 0; the motion must close it within duration");
/// k_c.
pub const STIFFNESS: Key = Key::number("stiffness", "N/m^1.5", Incl(1e3), Incl(1e10), "Hertz contact from foam (1e3 N/m^1.5) to metal on metal; 1e3-1e8 in the thesis", "k_c, the Hertz contact stiffness of tool and target (eq 5)");
/// m_p.
pub const MASS: Key = Key::number("mass", "kg", Incl(1e-3), Incl(1000.0), "1 g to 1 t; 0.136-0.25 kg in Tables 4-15", "m_p, the free object's mass (kind = \"object\" only)");
/// Floor friction under a free object.
pub const FLOOR_FRICTION: Key = Key::number("floor_friction", "", Incl(0.0), Incl(1.0), "dry friction coefficients: 0 (ice) to about 1 (rubber on concrete)", "Coulomb friction coefficient between a free object and the floor (kind = \"object\" only)")
    .optional("no floor friction");

/// The body region (ISO/TS 15066 Table A.2/A.3).
pub const REGION: Key = Key::of("region", Ty::Choice(crate::body::REGION_NAMES), "the body region of ISO/TS 15066 Table A.2/A.3 (kind = \"body_region\"): its m_H, k and limits (crate::body::PRESETS)");
/// Transient (free) or quasi-static (clamped).
pub const CONTACT: Key = Key::of("contact", Ty::Choice(&["transient", "quasi_static"]), "\"transient\" (the body part is a free mass m_H and recoils; limits 2x Table A.2) or \"quasi_static\" (clamped: backed by a rigid surface; Table A.2 limits) (kind = \"body_region\")");
/// Contact area for the pressure.
pub const AREA: Key = Key::number("area", "m^2", Incl(1e-6), Incl(1e-2), "1 mm^2 (an edge) to 100 cm^2 (a flat pad); ISO/TS 15066 measures pressure over about 1 cm^2", "contact area of the tool on the body, for the pressure = force / area (kind = \"body_region\")");
/// Override of m_H.
pub const BODY_MASS: Key = Key::number("mass", "kg", Incl(0.1), Incl(200.0), "0.6-75 kg in Table A.3", "m_H, the body region's effective mass (kind = \"body_region\": overrides Table A.3)")
    .optional("the region's Table A.3 effective mass");
/// Override of k.
pub const BODY_STIFFNESS: Key = Key::number("stiffness", "N/m", Incl(1e3), Incl(1e6), "10-150 N/mm (1e4-1.5e5 N/m) in Table A.3", "k, the body region's linear effective spring constant (kind = \"body_region\": overrides Table A.3)")
    .optional("the region's Table A.3 spring constant");

/// The keys of an obstacle.
pub const OBSTACLE_KEYS: &[Key] = &[KIND, GAP, STIFFNESS, contact::RESTITUTION, contact::DAMPING_LAW, contact::CHI, super::planar::SURFACE_ANGLE, super::planar::CONTACT_MU];
/// The keys of a free object.
pub const OBJECT_KEYS: &[Key] = &[KIND, GAP, STIFFNESS, contact::RESTITUTION, contact::DAMPING_LAW, contact::CHI, MASS, FLOOR_FRICTION, super::planar::SURFACE_ANGLE, super::planar::CONTACT_MU];
/// The keys of a body region.
pub const BODY_KEYS: &[Key] = &[KIND, GAP, REGION, CONTACT, AREA, BODY_MASS, BODY_STIFFNESS];

#[derive(Clone, Copy)]
enum K {
    Obstacle,
    Object,
    Body,
}

/// Reads `[target]`.
pub(super) fn target(cx: &mut Ctx, t: &Tab) -> Option<Target> {
    let kind = cx.choice(t, &KIND, &[K::Obstacle, K::Object, K::Body]);
    match kind {
        Some(K::Obstacle) => cx.check_keys(t, OBSTACLE_KEYS, " for kind = \"obstacle\""),
        Some(K::Object) => cx.check_keys(t, OBJECT_KEYS, " for kind = \"object\""),
        Some(K::Body) => return body(cx, t),
        None => {}
    }
    let gap = cx.number(t, &GAP);
    let stiffness = cx.number(t, &STIFFNESS);
    let damping = contact_damping(cx, t, None);
    let kind = match kind? {
        K::Obstacle => TargetKind::Obstacle,
        K::Object => {
            let mass = cx.number(t, &MASS);
            let floor_friction = cx.maybe_number(t, &FLOOR_FRICTION)?;
            TargetKind::Object {
                mass: mass?,
                floor_friction,
            }
        }
        K::Body => return None,
    };
    Some(Target {
        kind,
        gap: gap?,
        stiffness: stiffness?,
        damping: damping?,
    })
}

/// `kind = "body_region"`: the preset of `region`, with `mass` and `stiffness` overriding it.
fn body(cx: &mut Ctx, t: &Tab) -> Option<Target> {
    cx.check_keys(t, BODY_KEYS, " for kind = \"body_region\" (the Annex A contact is an undamped linear spring: no restitution, damping_law or chi)");
    let gap = cx.number(t, &GAP);
    let region = cx.choice(t, &REGION, crate::body::PRESETS);
    let contact = cx.choice(t, &CONTACT, &[BodyContact::Transient, BodyContact::QuasiStatic]);
    let area = cx.number(t, &AREA);
    let mass = cx.maybe_number(t, &BODY_MASS);
    let stiffness = cx.maybe_number(t, &BODY_STIFFNESS);
    let region: &'static crate::body::Preset = crate::body::preset(region?.name)?;
    let body = BodyTarget {
        region,
        contact: contact?,
        area_m2: area?,
        mass_kg: mass?.unwrap_or(region.mass_kg),
        stiffness_n_per_m: stiffness?.unwrap_or(region.stiffness_n_per_m),
    };
    Some(Target {
        kind: TargetKind::BodyRegion(body),
        gap: gap?,
        stiffness: body.stiffness_n_per_m,
        damping: ContactDamping::FixedChi(0.0),
    })
}
