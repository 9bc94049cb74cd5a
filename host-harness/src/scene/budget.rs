//! Checks across elements, made once the whole scene is read: the integration cost (a scene the
//! solver would grind through for minutes is refused before it starts, saying which key sets the
//! cost), the number of recorded samples, and the hydraulic module's rest position against its
//! travel switch (a tool that starts past the switch would be detected at t = 0).
use super::check::{approx, num, Ctx, Tab};
use super::model::{Decoupler, Method, Scene, Sensor};
use super::{solver, DURATION};

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
/// Contacts are not counted: most are transient and set their own steps. Known gap (tests/box.rs):
/// a contact that persists after the robot has stopped (a tool pressed into its back stop and the
/// target) has a Hunt-Crossley damping chi d^1.5 that grows with the penetration, about 7e5 1/s
/// over the tool's mass for table11 with decel = 0.159 m/s^2; until the plant settles and is held
/// (`sim`'s rest check, `at_rest_from_s`) an explicit method is stability-limited there: 9e5 steps
/// for 3.4 s of settling against 3e4 estimated. The penetration, hence that rate, is only known
/// once the run has found when it detects and stops.
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

/// Estimated steps of a run: `duration` times the larger of `1 / max_step` and half the fastest
/// rate (an explicit Runge-Kutta step stays stable up to about h * rate = 3; half of it leaves
/// room for accuracy). A fixed-step method takes `duration / max_step` steps whatever the plant.
pub fn estimated_steps(s: &Scene) -> f64 {
    let per_s = match s.solver.method {
        Method::Dopri5 => (1.0 / s.solver.max_step).max(0.5 * fastest_rate(s).0),
        Method::Rk4 | Method::SemiImplicitEuler => 1.0 / s.solver.max_step,
    };
    s.duration_s * per_s
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
    if steps > MAX_STEPS {
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
