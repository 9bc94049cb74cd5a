//! `motion.stopping`: the robot's own stopping data (ISO 10218-1 Annex B), the alternative to
//! `motion.decel` (plant: `model/src/stopping.rs`, which says how it is interpolated and what the plant
//! brakes with). `{ category = 0 | 1, speed = [...], distance = [...], time = [...] }`, optionally
//! `payload`: distance and time measured from the stop signal to standstill, reaction included.
use super::check::{num, Bound::*, Ctx, Key, Span, Tab, Ty};
use crate::stopping::{StoppingTable, TableError, MAX_POINTS};

/// `motion.stopping`.
pub const TABLE: Key = Key::of(
    "stopping",
    Ty::Table("{ category, speed, distance, time }: the robot's stopping distance and time against speed, as the manufacturer publishes them (ISO 10218-1 Annex B)"),
    "the robot's own stopping data, measured from the stop signal to standstill (reaction included); replaces decel",
)
.optional("give decel and dead_time instead");

/// The stop category.
pub const CATEGORY: Key = Key::integer("category", 0, 1, "IEC 60204-1 9.2.2: the stops ISO 10218-1 Annex B data is published for are category 0 and 1", "the stop category the data is for (0: power removed at once; 1: a controlled stop, then power removed)");
/// The speeds.
pub const SPEED: Key = Key::of("speed", Ty::Table(LIST), "v, the speeds the stops start from, m/s, strictly increasing (Annex B: 33 %, 66 %, 100 % of the maximum)");
/// The distances.
pub const DISTANCE: Key = Key::of("distance", Ty::Table(LIST), "D, the stopping distance from each speed, m, from the stop signal to standstill, increasing");
/// The times.
pub const TIME: Key = Key::of("time", Ty::Table(LIST), "T, the stopping time from each speed, s, from the stop signal to standstill, not decreasing");
/// The payload the data is for.
pub const PAYLOAD: Key = Key::number("payload", "kg", Excl(0.0), Incl(1000.0), "beyond the payload of the heaviest arms in the Table 7 class and of most industrial arms", "the payload the data was measured with: it must be at least the tool's mass (a heavier payload stops later)")
    .optional("not checked against the tool's mass");

const LIST: &str = "a list of numbers, one per point, 1 to 16 points";

/// Each speed.
pub const SPEED_SPAN: Span = Span { lo: Excl(0.0), hi: Incl(5.0), unit: "m/s", source: "the range of motion.speed" };
/// Each distance.
pub const DISTANCE_SPAN: Span = Span { lo: Excl(0.0), hi: Incl(5.0), unit: "m", source: "Annex B stopping distances of industrial arms are under 2 m" };
/// Each time.
pub const TIME_SPAN: Span = Span { lo: Excl(0.0), hi: Incl(5.0), unit: "s", source: "Annex B stopping times of industrial arms are under 2 s" };

/// The keys of `motion.stopping`.
pub const KEYS: &[Key] = &[CATEGORY, SPEED, DISTANCE, TIME, PAYLOAD];

/// Reads `motion.stopping`; `tool_mass` checks `payload` when both are known.
pub(super) fn stopping(cx: &mut Ctx, t: &Tab, tool_mass: Option<f64>) -> Option<(StoppingTable, Option<f64>)> {
    cx.check_keys(t, KEYS, "");
    let category = cx.integer(t, &CATEGORY);
    let speed = cx.numbers(t, &SPEED, LIST, MAX_POINTS, |_| SPEED_SPAN);
    let distance = cx.numbers(t, &DISTANCE, LIST, MAX_POINTS, |_| DISTANCE_SPAN);
    let time = cx.numbers(t, &TIME, LIST, MAX_POINTS, |_| TIME_SPAN);
    let payload = cx.maybe_number(t, &PAYLOAD);
    let (category, speed, distance, time, payload) = (category?, speed?, distance?, time?, payload?);
    if let (Some(p), Some(m)) = (payload, tool_mass) {
        if p < m {
            cx.bad(t, PAYLOAD.name, format!("the table was measured with a payload of {} kg, lighter than the tool's {} kg (tool.mass): a heavier payload stops later; give the robot's data for at least the tool's mass", num(p), num(m)));
            return None;
        }
    }
    match StoppingTable::new(category as u8, &speed, &distance, &time) {
        Ok(s) => Some((s, payload)),
        Err(e) => {
            let (key, m) = match e {
                TableError::Speed(m) => ("speed", m),
                TableError::Distance(m) => ("distance", m),
                TableError::Time(m) => ("time", m),
            };
            cx.bad(t, key, m);
            None
        }
    }
}
