//! Checks across elements, made once the whole scene is read: the integration cost (a scene the
//! solver would grind through for minutes is refused before it starts, saying which key sets the
//! cost), the number of recorded samples, and the hydraulic module's rest position against its
//! travel switch (a tool that starts past the switch would be detected at t = 0).
use super::check::{approx, num, Ctx, Tab};
use super::model::{Decoupler, Method, Scene, Sensor};
use super::solver;
use super::tables::DURATION;

/// The largest number of steps a scene may need (estimated, see [`estimated_steps`]). A step of the
/// adaptive solver costs about 0.5 us in release builds (docs/accuracy.md: Tables 5-7, 861 steps
/// in 0.4 ms), so the budget is a few seconds of release run time.
pub const MAX_STEPS: f64 = 1e7;
/// The largest number of recorded samples, `duration / output_interval`: 1e7 rows of the time
/// history is about 2 GB of CSV.
pub const MAX_SAMPLES: f64 = 1e7;

/// The fastest rate of the plant (rad/s or 1/s), and what sets it, for the step estimate: the
/// natural frequencies sqrt(k/m) and damping rates c/m of the elements that act all the run (the
/// robot, the linear decoupler, the front stop the tool rests on, the regularised dry friction).
/// Contacts are not counted here: most are transient and set their own steps. A contact that
/// persists once the stroke is used up (the tool pressed into its back stop and the target by a
/// slow brake) is held at its stability limit until the rest check (`sim`, `at_rest_from_s`)
/// holds: [`pressed_steps`] estimates it for the bi-stable decoupler against an obstacle (table11
/// with decel = 0.159 m/s^2: 8.9e5 steps, 9e3 before it, 2.7e6 with it; tests/box.rs).
pub fn fastest_rate(s: &Scene) -> (f64, &'static str) {
    let mt = s.tool.mass;
    let mut best = (0.0, "");
    let mut see = |rate: f64, what: &'static str| {
        if rate > best.0 {
            best = (rate, what);
        }
    };
    if let Some(r) = s.robot {
        see((r.stiffness / r.mass).sqrt(), "sqrt(robot.stiffness / robot.mass)");
        see(r.damping / r.mass, "robot.damping / robot.mass");
    }
    match &s.decoupler {
        Decoupler::Rigid => {}
        Decoupler::Linear(l) => {
            let w = (l.stiffness / mt).sqrt();
            see(w, "sqrt(decoupler.stiffness / tool.mass)");
            see(2.0 * l.damping_ratio * w, "2 decoupler.damping_ratio sqrt(decoupler.stiffness / tool.mass)");
        }
        Decoupler::Bistable(b) => {
            see((b.front_stop.stiffness / mt).sqrt(), "sqrt(decoupler.front_stop.stiffness / tool.mass)");
            see(b.front_stop.damping / mt, "decoupler.front_stop.damping / tool.mass");
        }
        Decoupler::Hydraulic(h) => {
            see((h.front_stop.stiffness / mt).sqrt(), "sqrt(decoupler.front_stop.stiffness / tool.mass)");
            see(h.front_stop.damping / mt, "decoupler.front_stop.damping / tool.mass");
            see(h.viscous_friction / mt, "decoupler.viscous_friction / tool.mass");
            see(h.dry_friction / (h.friction_v0 * mt), "decoupler.dry_friction / (decoupler.friction_v0 tool.mass)");
        }
    }
    best
}

/// Safety factor on [`pressed_steps`]: the largest measured `actual / estimate` over the settling
/// corners of tests/box.rs was 2.18 (low stop damping, where accuracy on the stiff oscillation, not
/// stability, sets the step); 3 covers it. Empirical, from those 24 corners only.
pub const PRESSED_FACTOR: f64 = 3.0;

/// Steps spent with the tool pressed into its back stop and the obstacle after the stroke is used
/// up, and the flange overtravel `D` (m) that sets them: `D = V dead_time + V^2 / (2 decel) -
/// (front_stroke + back_stroke)`. The two Hertz contacts (eq 37, eq 7) share `D` at equal force,
/// `k_b d_b^1.5 = k_c d_c^1.5`; there the tool sees a stiffness `K = 1.5 (k_b d_b^0.5 + k_c
/// d_c^0.5)` and a damping `C = chi_b d_b^1.5 + chi_c d_c^1.5` (chi at v_in = motion.speed), and
/// an explicit method is held near `max(sqrt(K / m_t), C / m_t) / 2` steps per second until the
/// rest check holds; bounded here by the whole `duration`, times [`PRESSED_FACTOR`]. Known gap:
/// only a bi-stable decoupler against an obstacle, braked by `decel`, without `[robot]`, is
/// covered (tests/box.rs `settling_corners`); `None` for every other scene.
pub fn pressed_steps(s: &Scene) -> Option<(f64, f64)> {
    use super::model::TargetKind;
    let Decoupler::Bistable(b) = &s.decoupler else { return None };
    if s.robot.is_some() || s.motion.stopping.is_some() || !matches!(s.target.kind, TargetKind::Obstacle) || s.motion.decel.is_nan() || s.motion.decel <= 0.0 {
        return None;
    }
    let v = s.motion.speed;
    let d = v * s.motion.dead_time + v * v / (2.0 * s.motion.decel) - (b.front_stroke + b.back_stroke);
    if d.is_nan() || d <= 0.0 {
        return Some((0.0, 0.0));
    }
    let (kb, kc) = (b.back_stop.stiffness, s.target.stiffness);
    let db = d / (1.0 + (kb / kc).powf(2.0 / 3.0));
    let dc = d - db;
    let chib = crate::damping_law::contact_chi(kb, &b.back_stop.damping, v);
    let chic = crate::damping_law::contact_chi(kc, &s.target.damping, v);
    let m = s.tool.mass;
    let k = 1.5 * (kb * db.sqrt() + kc * dc.sqrt());
    let c = chib * db.powf(1.5) + chic * dc.powf(1.5);
    Some((PRESSED_FACTOR * 0.5 * (k / m).sqrt().max(c / m) * s.duration_s, d))
}

/// Estimated steps of a run: `duration` times the larger of `1 / max_step` and half the fastest
/// rate (an explicit Runge-Kutta step stays stable up to about h * rate = 3; half of it leaves
/// room for accuracy), plus the steps with the tool pressed in ([`pressed_steps`]). A fixed-step
/// method takes `duration / max_step` steps whatever the plant.
pub fn estimated_steps(s: &Scene) -> f64 {
    match s.solver.method {
        Method::Dopri5 => s.duration_s * (1.0 / s.solver.max_step).max(0.5 * fastest_rate(s).0) + pressed_steps(s).map_or(0.0, |p| p.0),
        Method::Rk4 | Method::SemiImplicitEuler => s.duration_s / s.solver.max_step,
    }
}

/// Travel back from the front stop at which a hydraulic module's tool rests when its weight pulls
/// it back (gravity < 0: moving up), without friction: the gas force `p1(u) A_p` (eq 47) balances
/// `m_t |g|` at `u = V_g0 / A_p (1 - (p10 A_p / (m_t |g|))^(1 / kappa))`; 0 when the preload holds
/// it on the front stop. Friction could hold it nearer; the frictionless rest is the one a tool
/// reaches when the module is shaken, so it is the one checked.
pub fn hydraulic_rest_travel(h: &super::model::Hydraulic, tool_mass: f64, gravity: f64) -> f64 {
    let area = std::f64::consts::PI * h.piston_radius * h.piston_radius;
    let pull = -tool_mass * gravity;
    let preload = h.gas_pressure * area;
    if pull <= preload {
        return 0.0;
    }
    h.gas_volume / area * (1.0 - (preload / pull).powf(1.0 / h.adiabatic_exponent))
}

/// The sub-table `key` of the top level, to report on its line.
fn sub<'d>(root: &Tab<'d>, key: &str) -> Option<Tab<'d>> {
    root.t.get(key).and_then(|i| i.as_table_like()).map(|t| Tab {
        path: key.to_string(),
        t,
        line: None,
    })
}

/// The checks across elements; `root` is the top-level table.
pub(super) fn check(cx: &mut Ctx, root: &Tab, s: &Scene) {
    let d = s.duration_s;
    let solver_tab = sub(root, "solver");
    let report = |cx: &mut Ctx, key: &str, message: String| match (&solver_tab, key) {
        (Some(t), k) if k != DURATION.name && t.has(k) => cx.bad(t, k, message),
        _ => cx.bad(root, DURATION.name, message),
    };

    // Recorded samples.
    let oi = s.solver.output_interval;
    if oi > 0.0 && d / oi > MAX_SAMPLES {
        report(
            cx,
            solver::OUTPUT_INTERVAL.name,
            format!(
                "duration / output_interval = {} / {} = {} samples, above the budget of {} (about 2 GB of CSV); must be >= {} s for duration = {} s",
                num(d),
                num(oi),
                approx(d / oi),
                num(MAX_SAMPLES),
                approx(d / MAX_SAMPLES),
                num(d)
            ),
        );
    }

    // Integration cost.
    let steps = estimated_steps(s);
    let pressed = pressed_steps(s).filter(|p| matches!(s.solver.method, Method::Dopri5) && p.0 > 0.5 * steps);
    if let (true, Some((p, over)), Some(t)) = (steps > MAX_STEPS, pressed, sub(root, "motion")) {
        cx.bad(
            &t,
            "decel",
            format!(
                "the flange would travel {} m past the decoupler's stroke (speed x dead_time + speed^2 / (2 decel) - front_stroke - back_stroke), pressing the tool into its back stop and the target: about {} steps at the stability limit of those contacts for duration = {} s ({} with the other elements), above the budget of {}; raise motion.decel, shorten duration, or lengthen the stroke",
                approx(over),
                approx(p),
                num(d),
                approx(steps),
                num(MAX_STEPS)
            ),
        );
    } else if steps > MAX_STEPS {
        let fixed = !matches!(s.solver.method, Method::Dopri5);
        let (rate, what) = fastest_rate(s);
        let message = if fixed || 1.0 / s.solver.max_step >= 0.5 * rate {
            format!(
                "the run would take duration / max_step = {} / {} = {} steps, above the budget of {}; must be: duration / max_step <= {}",
                num(d),
                num(s.solver.max_step),
                approx(steps),
                num(MAX_STEPS),
                num(MAX_STEPS)
            )
        } else {
            format!(
                "the run would take about {} steps (duration x the plant's fastest rate / 2, the rate {} = {} 1/s), above the budget of {}: shorten duration to <= {} s or soften that element",
                approx(steps),
                what,
                approx(rate),
                num(MAX_STEPS),
                approx(d * MAX_STEPS / steps)
            )
        };
        let key = if fixed || 1.0 / s.solver.max_step >= 0.5 * rate {
            solver::MAX_STEP.name
        } else {
            DURATION.name
        };
        report(cx, key, message);
    }

    // A hydraulic module pulled back by the tool's weight must not start past its travel switch.
    if let (Decoupler::Hydraulic(h), Some(Sensor::Travel { threshold })) = (&s.decoupler, s.sensor) {
        let u = hydraulic_rest_travel(h, s.tool.mass, s.motion.gravity);
        if u >= threshold {
            let area = std::f64::consts::PI * h.piston_radius * h.piston_radius;
            let message = format!(
                "the tool's weight (tool.mass x |motion.gravity| = {} N) is above the gas preload (gas_pressure x pi piston_radius^2 = {} N): at rest it hangs {} m back from the front stop, at or past the switch, which would fire at t = 0 and never detect the collision; must be > {} m, or raise decoupler.gas_pressure above {} Pa, got {}",
                approx(-s.tool.mass * s.motion.gravity),
                approx(h.gas_pressure * area),
                approx(u),
                approx(u),
                approx(-s.tool.mass * s.motion.gravity / area),
                num(threshold)
            );
            if let Some(t) = sub(root, "sensor") {
                cx.bad(&t, "threshold", message);
            }
        }
    }
}
