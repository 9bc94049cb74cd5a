//! `[sensor]`: the collision detector (MODEL.md element 5, `plant/sensor.rs`): a travel switch on
//! the decoupler's stroke or a force threshold on the contact; absent, the robot never brakes.
use super::check::{approx, num, Bound::*, Ctx, Key, Span, Tab, Ty};
use super::model::{Decoupler, Sensor};

/// The `[sensor]` table in the top level.
pub const TABLE: Key = Key::of(
    "sensor",
    Ty::Table("the collision detector; omit it and the robot never brakes"),
    "the collision detector",
)
.optional("nothing detects the collision and the robot never brakes");

/// Travel or force.
pub const KIND: Key = Key::of("kind", Ty::Choice(&["travel", "force"]), "\"travel\" (inductive or magnetic switch on the stroke) or \"force\" (on the contact force)");
/// d_sw of a travel switch.
pub const TRAVEL_THRESHOLD: Key = Key::number("threshold", "m", Incl(1e-5), Incl(0.2), "10 um (the repeatability of an inductive switch) to the longest stroke in range; 0.5-5 mm in the thesis", "d_sw, travel back from the front stop at which the switch fires (kind = \"travel\")");
/// Force threshold.
pub const FORCE_THRESHOLD: Key = Key::number("threshold", "N", Incl(0.1), Incl(1e4), "0.1 N to 10 kN; 1-25 N in the thesis, ISO/TS 15066 Table A.2 limits are 65-280 N", "contact force at which the detector fires (kind = \"force\")");

/// The keys of a travel switch.
pub const TRAVEL_KEYS: &[Key] = &[KIND, TRAVEL_THRESHOLD];
/// The keys of a force threshold.
pub const FORCE_KEYS: &[Key] = &[KIND, FORCE_THRESHOLD];

#[derive(Clone, Copy)]
enum K {
    Travel,
    Force,
}

/// Reads `[sensor]`; a travel threshold is checked against the decoupler's stroke.
pub(super) fn sensor(cx: &mut Ctx, t: &Tab, decoupler: Option<&Decoupler>) -> Option<Sensor> {
    cx.check_keys(t, TRAVEL_KEYS, "");
    let kind = cx.choice(t, &KIND, &[K::Travel, K::Force]);
    let threshold = match kind {
        Some(K::Travel) => cx.number(t, &TRAVEL_THRESHOLD),
        Some(K::Force) => cx.number(t, &FORCE_THRESHOLD),
        None => {
            // Without a valid kind the unit is unknown: check what both kinds require.
            let mut key = TRAVEL_THRESHOLD;
            if let Ty::Number(s) = key.ty {
                let lo = s.lo;
                key.ty = Ty::Number(Span { unit: "(m for travel, N for force)", lo, hi: Open, source: "" });
            }
            cx.number(t, &key)
        }
    };
    if let (Some(K::Travel), Some(Decoupler::Rigid)) = (kind, decoupler) {
        cx.bad(t, KIND.name, "must be \"force\" for decoupler.kind = \"rigid\" (a rigid tool has no travel), got \"travel\"".into());
        return None;
    }
    let (kind, threshold) = (kind?, threshold?);
    match kind {
        K::Force => Some(Sensor::Force { threshold }),
        K::Travel => {
            let stroke = match decoupler {
                Some(Decoupler::Rigid) => None,
                Some(Decoupler::Bistable(b)) => Some((
                    b.front_stroke + b.back_stroke,
                    "total stroke front_stroke + back_stroke",
                )),
                Some(Decoupler::Hydraulic(h)) => Some((h.stroke, "stroke")),
                Some(Decoupler::Linear(_)) | None => None,
            };
            if let Some((c, what)) = stroke {
                if threshold >= c {
                    cx.bad(
                        t,
                        TRAVEL_THRESHOLD.name,
                        format!(
                            "must be < the decoupler's {what} = {} m, got {}",
                            approx(c),
                            num(threshold)
                        ),
                    );
                    return None;
                }
            }
            Some(Sensor::Travel { threshold })
        }
    }
}
