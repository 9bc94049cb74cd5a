//! `kind = "bistable"`: the bi-stable spring mechanism (eq 24-42, Tables 2, 4, 5, 8, 13, 15;
//! `plant/decoupler/bistable.rs`): N springs of rate k_b and free length L0 at height H, the tool
//! between a front stop at s = C1 and the flange at s = -C2, optional slide friction.
use super::super::check::{approx, num, Bound::*, Ctx, Key, Tab};
use super::super::friction;
use super::super::model::Bistable;
use super::end_stop::{self, end_stops};
use super::kind::KIND;

/// N.
pub const SPRINGS: Key = Key::integer("springs", 1, 16, "1-2 springs in Tables 2-15; 16 fill the circumference of a hand-sized module", "N, the number of springs");
/// k_b.
pub const SPRING_RATE: Key = Key::number("spring_rate", "N/m", Incl(1.0), Incl(1e5), "compression springs of a hand-sized module: 50-490 N/m in Tables 2-15", "k_b, the rate of one spring");
/// L0.
pub const FREE_LENGTH: Key = Key::number("free_length", "m", Incl(1e-3), Incl(0.5), "a hand-sized module: 0.05-0.07 m in Tables 2-15", "L0, the free length of one spring");
/// H.
pub const HEIGHT: Key = Key::number("height", "m", Incl(1e-6), Incl(0.5), "a hand-sized module: 0.028-0.053 m in Tables 2-15; must also be < free_length", "H, the height of the spring's anchor above the slide");
/// C1.
pub const FRONT_STROKE: Key = Key::number("front_stroke", "m", Incl(1e-4), Incl(0.2), "a hand-sized module: 0.015-0.024 m in Tables 2-15", "C1, the front end-stop at s = +C1");
/// C2.
pub const BACK_STROKE: Key = Key::number("back_stroke", "m", Incl(1e-4), Incl(0.2), "a hand-sized module: 0.015-0.025 m in Tables 2-15", "C2, the back end-stop (flange) at s = -C2");

/// The keys of a bi-stable decoupler.
pub const KEYS: &[Key] = &[
    KIND,
    SPRINGS,
    SPRING_RATE,
    FREE_LENGTH,
    HEIGHT,
    FRONT_STROKE,
    BACK_STROKE,
    end_stop::FRONT,
    end_stop::BACK,
    friction::TABLE,
    super::rotational::TABLE,
];

/// Reads a bi-stable decoupler and checks that the tool rests on the front stop at t = 0.
pub(in super::super) fn bistable(
    cx: &mut Ctx,
    t: &Tab,
    tool_mass: Option<f64>,
    gravity: Option<f64>,
) -> Option<Bistable> {
    let springs = cx.integer(t, &SPRINGS);
    let spring_rate = cx.number(t, &SPRING_RATE);
    let free_length = cx.number(t, &FREE_LENGTH);
    let height = cx.number(t, &HEIGHT);
    let front_stroke = cx.number(t, &FRONT_STROKE);
    let back_stroke = cx.number(t, &BACK_STROKE);
    let (front_stop, back_stop) = end_stops(cx, t, tool_mass);
    let friction = friction::friction(cx, t);

    // H < L0: the springs are compressed as the tool passes s = 0, which is what makes the
    // mechanism bi-stable (eq 24-25); with H >= L0 there is one stable position and no switching.
    if let (Some(l0), Some(h)) = (free_length, height) {
        if h >= l0 {
            cx.bad(
                t,
                HEIGHT.name,
                format!(
                    "must be < decoupler.free_length = {} m (H < L0: else the springs are never compressed and the mechanism is not bi-stable, eq 24-25), got {}",
                    num(l0),
                    num(h)
                ),
            );
            return None;
        }
    }
    // At t = 0 the tool rests on the front stop: spring force at s = C1 plus its weight must push it there.
    if let (Some(n), Some(kb), Some(l0), Some(h), Some(c1), Some(mt), Some(gravity)) = (
        springs,
        spring_rate,
        free_length,
        height,
        front_stroke,
        tool_mass,
        gravity,
    ) {
        let l1 = (h * h + c1 * c1).sqrt();
        let f_spring = f64::from(n) * kb * (l0 - l1) * c1 / l1;
        let weight = mt * gravity;
        if f_spring + weight <= 0.0 {
            cx.bad(
                t,
                FREE_LENGTH.name,
                format!(
                    "the tool would not rest on the front stop at t = 0: the springs push it with {} N at s = C1 and its weight with {} N; need free_length > sqrt(height^2 + front_stroke^2) = {} m (or enough gravity), got {}",
                    approx(f_spring),
                    approx(weight),
                    approx(l1),
                    num(l0)
                ),
            );
            return None;
        }
    }
    Some(Bistable {
        springs: springs?,
        spring_rate: spring_rate?,
        free_length: free_length?,
        height: height?,
        front_stroke: front_stroke?,
        back_stroke: back_stroke?,
        front_stop: front_stop?,
        back_stop: back_stop?,
        friction: friction?,
    })
}
