//! The loader's unit tests: every element's keys, each error path once (a mutation of a full
//! scene, the key, the line and what the message must say), defaults and conversions.
use super::check::{approx, line_at, num};
use super::decoupler::end_stop::zeta_from_restitution;
use super::solver::default_solver;
use super::*;
use std::path::Path;

/// Every element present: bi-stable module, compliant robot, sensor, solver, controller.
const BASE: &str = r#"name = "base"
duration = 0.6
[motion]
speed = 0.05
accel = 1.0
decel = 2.0
dead_time = 0.016
gravity = 0.0
[robot]
mass = 8.4
stiffness = 2.3e5
damping = 71.0
[tool]
mass = 0.75
[decoupler]
kind = "bistable"
springs = 2
spring_rate = 200.0
free_length = 0.05
height = 0.03
front_stroke = 0.015
back_stroke = 0.015
front_stop = { stiffness = 1e6, damping = 278.0 }
back_stop = { stiffness = 1e6, restitution = 0.6 }
friction = { mu = 0.12, v0 = 0.001 }
[target]
kind = "obstacle"
gap = 0.01
stiffness = 1e8
restitution = 0.65
damping_law = "hunt-crossley"
[sensor]
kind = "travel"
threshold = 0.005
[solver]
method = "rk4"
rtol = 1e-6
atol = 1e-9
max_step = 1e-4
output_interval = 1e-3
[controller]
scan_cycle = 0.016
phase = 0.5
firmware_tick = 1e-4
"#;

/// Hydraulic module against a free object, chi given directly.
const HYD: &str = r#"name = "hyd"
duration = 0.8
[motion]
speed = 1.0
accel = 5.0
decel = 5.0
dead_time = 0.07
gravity = 0.0
[tool]
mass = 0.048
[decoupler]
kind = "hydraulic"
stroke = 0.023
piston_radius = 0.020
orifice_radius = 0.008
gas_pressure = 1000.0
gas_volume = 7.63e-5
discharge_coefficient = 3.0
liquid_density = 900.0
dry_friction = 0.0
viscous_friction = 0.5
front_stop = { stiffness = 1e6, damping = 235.0 }
back_stop = { stiffness = 1e6, chi = 2e5 }
[target]
kind = "object"
mass = 0.246
gap = 0.15
stiffness = 0.6e6
chi = 1.35e6
[sensor]
kind = "travel"
threshold = 0.0015
"#;

/// `base` with the unique `from` replaced by `to`.
fn mutate(base: &str, from: &str, to: &str) -> String {
    assert_eq!(base.matches(from).count(), 1, "{from:?} must occur once");
    base.replacen(from, to, 1)
}

/// Expects `text` refused with an issue on `key`, at the line of `at`, whose message holds `allowed`.
fn refused(text: &str, key: &str, at: &str, allowed: &str) {
    let err = parse(text, "bad.toml").expect_err("scene should be refused");
    let line = line_at(
        text,
        text.find(at)
            .unwrap_or_else(|| panic!("{at:?} not in the text")),
    );
    let shown = err.to_string();
    let issue = err
        .issues
        .iter()
        .find(|i| i.key == key)
        .unwrap_or_else(|| panic!("no issue on {key}:\n{shown}"));
    assert_eq!(issue.line, Some(line), "{shown}");
    assert!(
        issue.message.contains(allowed),
        "{:?} lacks {allowed:?}",
        issue.message
    );
    assert!(
        shown.contains(&format!("bad.toml:{line}: {key}: ")),
        "{shown}"
    );
}

/// One test per error path: replace `from` by `to` in `base`, expect `key` refused at `at`.
macro_rules! case {
    ($name:ident, $base:expr, $from:expr, $to:expr, $key:expr, $at:expr, $allowed:expr) => {
        #[test]
        fn $name() {
            refused(&mutate($base, $from, $to), $key, $at, $allowed);
        }
    };
}

#[test]
fn bases_load() {
    let s = parse(BASE, "base.toml").unwrap();
    assert_eq!(s.solver.method, Method::Rk4);
    assert_eq!(
        s.controller,
        Some(Controller::new(0.016, 0.5, 1e-4))
    );
    let h = parse(HYD, "hyd.toml").unwrap();
    let Decoupler::Hydraulic(d) = h.decoupler else {
        panic!("not hydraulic")
    };
    assert_eq!(d.adiabatic_exponent, DEFAULT_ADIABATIC_EXPONENT);
    assert_eq!(d.friction_v0, DEFAULT_HYDRAULIC_FRICTION_V0);
    assert_eq!(d.back_stop.damping, ContactDamping::FixedChi(2e5));
    assert_eq!(
        h.target.kind,
        TargetKind::Object {
            mass: 0.246,
            floor_friction: None
        }
    );
    assert_eq!(h.robot, None);
}

#[test]
fn optional_elements_and_defaults() {
    let text = mutate(BASE, "[sensor]\nkind = \"travel\"\nthreshold = 0.005\n", "");
    let text = mutate(
        &text,
        "method = \"rk4\"\nrtol = 1e-6\natol = 1e-9\nmax_step = 1e-4\noutput_interval = 1e-3\n",
        "",
    );
    let text = mutate(&text, "friction = { mu = 0.12, v0 = 0.001 }\n", "");
    let text = mutate(
        &text,
        "[controller]\nscan_cycle = 0.016\nphase = 0.5\nfirmware_tick = 1e-4\n",
        "",
    );
    let s = parse(&text, "opt.toml").unwrap();
    assert_eq!(s.sensor, None);
    assert_eq!(s.controller, None);
    assert_eq!(s.solver, default_solver());
    assert_eq!(s.solver.rtol, DEFAULT_RTOL);
    assert!(!s.motion.start_at_speed);
    let Decoupler::Bistable(b) = s.decoupler else {
        panic!("not bistable")
    };
    assert_eq!(b.friction, None);
    assert_eq!(
        b.back_stop.damping,
        ContactDamping::Restitution {
            restitution: 0.6,
            law: DEFAULT_BACK_STOP_LAW
        }
    );
}

#[test]
fn integers_are_accepted_as_numbers() {
    let s = parse(
        &mutate(BASE, "stiffness = 1e8", "stiffness = 100000000"),
        "int.toml",
    )
    .unwrap();
    assert_eq!(s.target.stiffness, 1e8);
}

#[test]
fn front_stop_restitution_converts_with_the_tool_mass() {
    let with = |e: &str| {
        let s = parse(
            &mutate(BASE, "damping = 278.0 }", &format!("restitution = {e} }}")),
            "e.toml",
        )
        .unwrap();
        let Decoupler::Bistable(b) = s.decoupler else {
            panic!("not bistable")
        };
        b.front_stop.damping
    };
    let crit = 2.0 * (1e6_f64 * 0.75).sqrt();
    // e = 0.4: zeta = -ln 0.4 / sqrt(pi^2 + ln^2 0.4) = 0.27999...
    assert!(
        (with("0.4") / crit - 0.279_997).abs() < 1e-5,
        "{}",
        with("0.4") / crit
    );
    assert_eq!(with("0.0"), crit);
    assert_eq!(with("1.0"), 0.0);
    assert!((zeta_from_restitution(0.5) - 0.215_454).abs() < 1e-6);
}

#[test]
fn start_at_speed_travel() {
    let text = mutate(
        BASE,
        "gravity = 0.0\n",
        "gravity = 0.0\nstart_at_speed = true\n",
    );
    assert!(parse(&text, "s.toml").unwrap().motion.start_at_speed);
    // Cruising from t = 0, 0.6 s at 0.05 m/s covers 0.03 m: a 0.029 m gap is reached, 0.031 m is not.
    assert!(parse(&mutate(&text, "gap = 0.01", "gap = 0.029"), "s.toml").is_ok());
    refused(
        &mutate(&text, "gap = 0.01", "gap = 0.031"),
        "target.gap",
        "gap = 0.031",
        "covers only 0.03 m",
    );
}

#[test]
fn all_errors_are_reported_in_line_order() {
    let text = mutate(BASE, "mass = 0.75", "mass = -1");
    let text = mutate(&text, "speed = 0.05", "speed = \"fast\"");
    let text = mutate(&text, "phase = 0.5", "phase = 1.0");
    let err = parse(&text, "many.toml").unwrap_err();
    let keys: Vec<_> = err.issues.iter().map(|i| i.key.as_str()).collect();
    assert_eq!(keys, ["motion.speed", "tool.mass", "controller.phase"]);
    assert_eq!(err.to_string().lines().count(), 3);
    assert!(err.to_string().lines().all(|l| l.starts_with("many.toml:")));
}

#[test]
fn toml_syntax_error_names_the_line() {
    let text = mutate(BASE, "decel = 2.0", "decel = = 2.0");
    let err = parse(&text, "syntax.toml").unwrap_err();
    assert_eq!(err.issues.len(), 1);
    assert_eq!(err.issues[0].line, Some(6));
    assert!(
        err.to_string().starts_with("syntax.toml:6: not valid TOML"),
        "{err}"
    );
}

#[test]
fn duplicate_key_is_a_syntax_error() {
    let text = mutate(BASE, "decel = 2.0", "decel = 2.0\ndecel = 3.0");
    let err = parse(&text, "dup.toml").unwrap_err();
    assert_eq!(err.issues[0].line, Some(7), "{err}");
    assert!(err.issues[0].message.contains("duplicate key"), "{err}");
}

#[test]
fn unreadable_file_names_the_file() {
    let err = load(Path::new("/nonexistent/flinch/none.toml")).unwrap_err();
    assert_eq!(err.file, "/nonexistent/flinch/none.toml");
    assert_eq!(err.issues[0].line, None);
    assert!(
        err.to_string()
            .starts_with("/nonexistent/flinch/none.toml: cannot read"),
        "{err}"
    );
}

#[test]
fn number_rendering() {
    assert_eq!(num(-1.0), "-1");
    assert_eq!(num(1e-10), "1e-10");
    assert_eq!(num(2.3e5), "230000");
    assert_eq!(num(1e8), "1e8");
    assert_eq!(approx(0.028749999999999998), "0.02875");
}

// Top level.
case!(
    root_unknown_key,
    BASE,
    "duration = 0.6\n",
    "duration = 0.6\ncolour = 1\n",
    "colour",
    "colour",
    "allowed keys: name, duration, motion"
);
case!(
    name_missing,
    BASE,
    "name = \"base\"\n",
    "",
    "name",
    "duration",
    "missing required key: a non-empty string"
);
case!(
    name_empty,
    BASE,
    "name = \"base\"",
    "name = \" \"",
    "name",
    "name",
    "must be a non-empty string"
);
case!(
    name_wrong_type,
    BASE,
    "name = \"base\"",
    "name = 3",
    "name",
    "name",
    "must be a non-empty string, got integer"
);
case!(
    duration_missing,
    BASE,
    "duration = 0.6\n",
    "",
    "duration",
    "name",
    "missing required key: a number in (0, 60] s"
);
case!(
    duration_zero,
    BASE,
    "duration = 0.6",
    "duration = 0",
    "duration",
    "duration",
    "allowed range (0, 60] s (a collision and the stop that follows last under a second (the thesis runs 0.06-0.8 s); 60 s bounds run time and output), got 0"
);
case!(
    duration_nan,
    BASE,
    "duration = 0.6",
    "duration = nan",
    "duration",
    "duration",
    "must be a finite number; allowed range (0, 60] s (a collision and the stop that follows last under a second (the thesis runs 0.06-0.8 s); 60 s bounds run time and output), got NaN"
);
case!(
    duration_inf,
    BASE,
    "duration = 0.6",
    "duration = inf",
    "duration",
    "duration",
    "must be a finite number; allowed range (0, 60] s (a collision and the stop that follows last under a second (the thesis runs 0.06-0.8 s); 60 s bounds run time and output), got inf"
);
case!(
    duration_string,
    BASE,
    "duration = 0.6",
    "duration = \"0.6\"",
    "duration",
    "duration",
    "must be a number in (0, 60] s, got string"
);
case!(
    motion_missing,
    BASE,
    "[motion]\nspeed = 0.05\naccel = 1.0\ndecel = 2.0\ndead_time = 0.016\ngravity = 0.0\n",
    "",
    "motion",
    "name",
    "missing required key: a table"
);
case!(
    tool_not_a_table,
    BASE,
    "[tool]\nmass = 0.75\n",
    "",
    "tool",
    "name",
    "missing required key: a table"
);
case!(
    tool_array_of_tables,
    BASE,
    "[tool]\n",
    "[[tool]]\n",
    "tool",
    "[[tool]]",
    "must be a table (the tool), got array of tables"
);
case!(target_inline_wrong_type, BASE, "[target]\nkind = \"obstacle\"\ngap = 0.01\nstiffness = 1e8\nrestitution = 0.65\ndamping_law = \"hunt-crossley\"\n", "", "target", "name", "missing required key: a table");
case!(
    robot_not_a_table,
    HYD,
    "duration = 0.8\n",
    "duration = 0.8\nrobot = 5\n",
    "robot",
    "robot = 5",
    "must be a table"
);

// Motion.
case!(
    motion_unknown_key,
    BASE,
    "gravity = 0.0\n",
    "gravity = 0.0\njerk = 3\n",
    "motion.jerk",
    "jerk",
    "allowed keys: speed, accel, decel, dead_time, gravity, start_at_speed"
);
case!(
    speed_zero,
    BASE,
    "speed = 0.05",
    "speed = 0",
    "motion.speed",
    "speed",
    "allowed range [1e-4, 5] m/s (0.1 mm/s (a creep, not a collision) to 5 m/s, beyond the 0.05-1 m/s of the thesis and the fastest flange speeds of arms of the Viper s650 class (Table 7)), got 0"
);
case!(
    speed_missing,
    BASE,
    "speed = 0.05\n",
    "",
    "motion.speed",
    "[motion]",
    "missing required key: a number in [1e-4, 5] m/s"
);
case!(
    accel_negative,
    BASE,
    "accel = 1.0",
    "accel = -1",
    "motion.accel",
    "accel",
    "allowed range [0.001, 500] m/s^2 (up to about 50 g, beyond what the drives of arms in the Table 7 class reach (a few 10 m/s^2)), got -1"
);
case!(
    decel_zero,
    BASE,
    "decel = 2.0",
    "decel = 0.0",
    "motion.decel",
    "decel",
    "allowed range [0.001, 500] m/s^2 (up to about 50 g, beyond any robot stop (the thesis brakes at 2-9 m/s^2)), got 0"
);
case!(
    dead_time_negative,
    BASE,
    "dead_time = 0.016",
    "dead_time = -0.01",
    "motion.dead_time",
    "dead_time",
    "allowed range [0, 1] s (controller reaction times: 10-70 ms in the thesis, well under 1 s for any stop category 0/1 robot (ISO 13855 stopping performance)), got -0.01"
);
case!(
    gravity_missing,
    BASE,
    "gravity = 0.0\n",
    "",
    "motion.gravity",
    "[motion]",
    "missing required key: a number in [-9.81, 9.81] m/s^2"
);
case!(
    gravity_inf,
    BASE,
    "gravity = 0.0",
    "gravity = -inf",
    "motion.gravity",
    "gravity",
    "must be a finite number"
);
case!(
    start_at_speed_wrong_type,
    BASE,
    "gravity = 0.0\n",
    "gravity = 0.0\nstart_at_speed = 1\n",
    "motion.start_at_speed",
    "start_at_speed",
    "must be true or false, got integer"
);

// Robot and tool.
case!(
    robot_unknown_key,
    BASE,
    "damping = 71.0\n",
    "damping = 71.0\ninertia = 2\n",
    "robot.inertia",
    "inertia",
    "allowed keys: mass, stiffness, damping"
);
case!(
    robot_mass_zero,
    BASE,
    "mass = 8.4",
    "mass = 0",
    "robot.mass",
    "mass = 0",
    "allowed range [0.1, 500] kg (effective mass at the flange: 8.4 kg for the Viper s650 (Table 7), a few hundred kg for the largest arms), got 0"
);
case!(
    robot_stiffness_negative,
    BASE,
    "stiffness = 2.3e5",
    "stiffness = -2.3e5",
    "robot.stiffness",
    "stiffness = -2.3e5",
    "allowed range [1000, 1e8] N/m (flange stiffness of arms: 2.3e5 N/m for the Viper s650 (Table 7), 1e5-1e7 N/m for industrial arms), got -230000"
);
case!(
    robot_damping_negative,
    BASE,
    "damping = 71.0",
    "damping = -71",
    "robot.damping",
    "damping = -71",
    "allowed range [0, 100000] N s/m (71 N s/m for the Viper s650 (Table 7); 1e5 N s/m is beyond critical for the stiffest, heaviest arm in range), got -71"
);
case!(
    robot_damping_missing,
    BASE,
    "damping = 71.0\n",
    "",
    "robot.damping",
    "[robot]",
    "missing required key: a number in [0, 100000] N s/m"
);
case!(
    tool_mass_negative,
    BASE,
    "mass = 0.75",
    "mass = -1",
    "tool.mass",
    "mass = -1",
    "allowed range [0.001, 50] kg (1 g to 50 kg: the largest payload of arms in the Table 7 class and beyond (the thesis: 0.048-0.75 kg)), got -1"
);
case!(
    tool_mass_missing,
    BASE,
    "mass = 0.75\n",
    "",
    "tool.mass",
    "[tool]",
    "missing required key: a number in [0.001, 50] kg"
);
case!(
    tool_unknown_key,
    BASE,
    "mass = 0.75\n",
    "mass = 0.75\nlength = 1\n",
    "tool.length",
    "length",
    "allowed keys: mass"
);

// The rest, by element (after the `case!` macro, which they use).
mod decoupler;
mod elements;
mod inputs;
