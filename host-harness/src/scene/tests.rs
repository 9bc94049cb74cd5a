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
        Some(Controller {
            scan_cycle: 0.016,
            phase: 0.5,
            firmware_tick: 1e-4
        })
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

// Decoupler kinds.
case!(
    decoupler_kind_bad,
    BASE,
    "kind = \"bistable\"",
    "kind = \"springy\"",
    "decoupler.kind",
    "springy",
    "must be one of \"rigid\" | \"linear\" | \"bistable\" | \"hydraulic\", got \"springy\""
);
case!(
    decoupler_kind_missing,
    BASE,
    "kind = \"bistable\"\n",
    "",
    "decoupler.kind",
    "[decoupler]",
    "missing required key: one of \"rigid\" | \"linear\""
);
case!(
    decoupler_missing,
    BASE,
    "[decoupler]\nkind = \"bistable\"\n",
    "[decoupler2]\n",
    "decoupler",
    "name",
    "missing required key: a table"
);
case!(
    rigid_with_bistable_keys,
    BASE,
    "kind = \"bistable\"",
    "kind = \"rigid\"",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"rigid\"; allowed keys: kind"
);
case!(linear_stiffness_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = -5\ndamping_ratio = 1\n", "decoupler.stiffness", "stiffness = -5", "allowed range [0, 1e7] N/m (0 (a free tool, Fig. 1b) to 1e7 N/m, as stiff as the stiffest robot flange in range), got -5");
case!(linear_damping_ratio_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = 50\ndamping_ratio = -1\n", "decoupler.damping_ratio", "damping_ratio", "allowed range [0, 10] (undamped to 10 times critical; the thesis uses 0-1 (Table 2)), got -1");
case!(
    linear_unknown_key,
    BASE,
    "kind = \"bistable\"",
    "kind = \"linear\"",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"linear\"; allowed keys: kind, stiffness, damping_ratio"
);

// Bi-stable.
case!(
    springs_float,
    BASE,
    "springs = 2",
    "springs = 2.0",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16] (write it without a decimal point), got 2.0"
);
case!(
    springs_zero,
    BASE,
    "springs = 2",
    "springs = 0",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16], got 0"
);
case!(
    springs_string,
    BASE,
    "springs = 2",
    "springs = \"two\"",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16], got string"
);
case!(
    springs_missing,
    BASE,
    "springs = 2\n",
    "",
    "decoupler.springs",
    "[decoupler]",
    "missing required key: an integer in [1, 16]"
);
case!(
    spring_rate_zero,
    BASE,
    "spring_rate = 200.0",
    "spring_rate = 0",
    "decoupler.spring_rate",
    "spring_rate",
    "allowed range [1, 100000] N/m (compression springs of a hand-sized module: 50-490 N/m in Tables 2-15), got 0"
);
case!(
    free_length_negative,
    BASE,
    "free_length = 0.05",
    "free_length = -0.05",
    "decoupler.free_length",
    "free_length",
    "allowed range [0.001, 0.5] m (a hand-sized module: 0.05-0.07 m in Tables 2-15), got -0.05"
);
case!(
    height_zero,
    BASE,
    "height = 0.03",
    "height = 0",
    "decoupler.height",
    "height",
    "allowed range [1e-6, 0.5] m (a hand-sized module: 0.028-0.053 m in Tables 2-15; must also be < free_length), got 0"
);
case!(
    front_stroke_zero,
    BASE,
    "front_stroke = 0.015",
    "front_stroke = 0",
    "decoupler.front_stroke",
    "front_stroke",
    "allowed range [1e-4, 0.2] m (a hand-sized module: 0.015-0.024 m in Tables 2-15), got 0"
);
case!(
    back_stroke_zero,
    BASE,
    "back_stroke = 0.015",
    "back_stroke = 0.0",
    "decoupler.back_stroke",
    "back_stroke",
    "allowed range [1e-4, 0.2] m (a hand-sized module: 0.015-0.025 m in Tables 2-15), got 0"
);
case!(
    bistable_unknown_key,
    BASE,
    "springs = 2\n",
    "springs = 2\nstroke = 0.02\n",
    "decoupler.stroke",
    "stroke",
    "unknown key for kind = \"bistable\"; allowed keys: kind, springs, spring_rate"
);
case!(
    springs_do_not_hold_the_tool,
    BASE,
    "free_length = 0.05",
    "free_length = 0.032",
    "decoupler.free_length",
    "free_length",
    "need free_length > sqrt(height^2 + front_stroke^2) = 0.033541 m"
);
case!(
    front_stop_missing,
    BASE,
    "front_stop = { stiffness = 1e6, damping = 278.0 }\n",
    "",
    "decoupler.front_stop",
    "[decoupler]",
    "missing required key: a table ({ stiffness, damping } or { stiffness, restitution })"
);
case!(
    front_stop_not_table,
    BASE,
    "front_stop = { stiffness = 1e6, damping = 278.0 }",
    "front_stop = 1e6",
    "decoupler.front_stop",
    "front_stop",
    "must be a table ({ stiffness, damping } or { stiffness, restitution }), got float"
);
case!(
    front_stop_damping_negative,
    BASE,
    "damping = 278.0 }",
    "damping = -278.0 }",
    "decoupler.front_stop.damping",
    "front_stop",
    "allowed range [0, 100000] N s/m (235-278 N s/m in Tables 2-15; 1e5 N s/m is beyond critical for the stiffest stop and heaviest tool in range), got -278"
);
case!(
    front_stop_stiffness_zero,
    BASE,
    "front_stop = { stiffness = 1e6",
    "front_stop = { stiffness = 0",
    "decoupler.front_stop.stiffness",
    "front_stop",
    "allowed range [1000, 1e9] N/m (soft elastomer to a hard pad: 1e6-2.25e6 N/m in Tables 2-15; stiffer gives wrong forces at the default tolerances), got 0"
);
case!(
    front_stop_both,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, restitution = 0.4 }",
    "decoupler.front_stop.restitution",
    "front_stop",
    "give either damping (N s/m) or restitution, not both"
);
case!(
    front_stop_neither,
    BASE,
    ", damping = 278.0 }",
    " }",
    "decoupler.front_stop.damping",
    "front_stop",
    "missing required key: damping (N s/m >= 0), or restitution in [0, 1]"
);
case!(
    front_stop_restitution_high,
    BASE,
    "damping = 278.0 }",
    "restitution = 1.5 }",
    "decoupler.front_stop.restitution",
    "front_stop",
    "allowed range [0, 1] (a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)), got 1.5"
);
case!(
    front_stop_unknown_key,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, chi = 3 }",
    "decoupler.front_stop.chi",
    "front_stop",
    "allowed keys: stiffness, damping, restitution"
);
case!(
    front_stop_law_unknown,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, law = \"hertz\" }",
    "decoupler.front_stop.law",
    "front_stop",
    "must be one of \"linear\" | \"hunt-crossley\", got \"hertz\""
);
case!(
    front_stop_exponent_without_hunt_crossley,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, exponent = 1.5 }",
    "decoupler.front_stop.exponent",
    "front_stop",
    "only with law = \"hunt-crossley\""
);
case!(
    front_stop_exponent_out_of_range,
    BASE,
    "damping = 278.0 }",
    "restitution = 0.5, law = \"hunt-crossley\", exponent = 3 }",
    "decoupler.front_stop.exponent",
    "front_stop",
    "allowed range [1, 2]"
);
case!(
    front_stop_exponent_with_damping,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, law = \"hunt-crossley\", exponent = 1.5 }",
    "decoupler.front_stop.damping",
    "front_stop",
    "give restitution instead"
);

#[test]
fn front_stop_hunt_crossley_keeps_k_and_matches_the_linear_restitution() {
    use crate::plant::damping_law::{hunt_crossley_restitution, linear_restitution};
    let stop = |text: &str| {
        let s = parse(&mutate(BASE, "damping = 278.0 }", text), "hc.toml").unwrap();
        let Decoupler::Bistable(b) = s.decoupler else { panic!("not bistable") };
        b.front_stop
    };
    let lin = stop("damping = 278.0 }");
    assert_eq!(lin.law, FrontStopLaw::Linear);
    let hc = stop("damping = 278.0, law = \"hunt-crossley\" }");
    assert_eq!((hc.stiffness, hc.damping), (lin.stiffness, lin.damping));
    let FrontStopLaw::HuntCrossley { exponent, alpha, restitution } = hc.law else { panic!("{:?}", hc.law) };
    assert_eq!(exponent, 1.0);
    // BASE's tool is 0.75 kg: zeta = 278 / (2 sqrt(1e6 x 0.75)).
    let e = linear_restitution(278.0 / (2.0 * (1e6_f64 * 0.75).sqrt()));
    assert!((restitution - e).abs() < 1e-12 && (0.5..0.95).contains(&e), "{restitution} {e}");
    assert!((hunt_crossley_restitution(alpha, 1.0) - e).abs() < 1e-4);
    // A restitution given is matched as asked, at any exponent.
    let h15 = stop("restitution = 0.4, law = \"hunt-crossley\", exponent = 1.5 }");
    let FrontStopLaw::HuntCrossley { exponent, alpha, .. } = h15.law else { panic!() };
    assert_eq!(exponent, 1.5);
    assert!((hunt_crossley_restitution(alpha, 1.5) - 0.4).abs() < 1e-4);
}
case!(
    back_stop_stiffness_negative,
    BASE,
    "back_stop = { stiffness = 1e6",
    "back_stop = { stiffness = -1",
    "decoupler.back_stop.stiffness",
    "back_stop",
    "allowed range [1000, 1e10] N/m^1.5 (foam to metal on metal: 1e6-2.25e6 N/m^1.5 in Tables 2-15), got -1"
);
case!(
    back_stop_restitution_negative,
    BASE,
    "restitution = 0.6 }",
    "restitution = -0.6 }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "allowed range [0, 1] (a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)), got -0.6"
);
case!(
    back_stop_chi_and_restitution,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0.6, chi = 5.0 }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "give either chi (a fixed damping) or restitution with damping_law, not both"
);
case!(
    back_stop_chi_and_law,
    BASE,
    "restitution = 0.6 }",
    "damping_law = \"flores\", chi = 5.0 }",
    "decoupler.back_stop.damping_law",
    "back_stop",
    "give either chi"
);
case!(
    back_stop_chi_negative,
    BASE,
    "restitution = 0.6 }",
    "chi = -5.0 }",
    "decoupler.back_stop.chi",
    "back_stop",
    "allowed range [0, 1e8] N s/m^2.5 (4.5e4-1.35e6 N s/m^2.5 in Table 12; 1e8 is overdamped for every stiffness in range), got -5"
);
case!(
    back_stop_no_damping,
    BASE,
    ", restitution = 0.6 }",
    " }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "missing required key: restitution in [0, 1] (with damping_law), or chi"
);
case!(back_stop_law_bad, BASE, "restitution = 0.6 }", "restitution = 0.6, damping_law = \"hertz\" }", "decoupler.back_stop.damping_law", "back_stop", "must be one of \"hunt-crossley\" | \"lankarani-nikravesh\" | \"flores\" | \"gonthier\" | \"exact\", got \"hertz\"");
case!(
    back_stop_law_without_restitution,
    BASE,
    "restitution = 0.6 }",
    "damping_law = \"hertz\" }",
    "decoupler.back_stop.damping_law",
    "back_stop",
    "must be one of"
);
case!(
    back_stop_unknown_key,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0.6, damping = 3 }",
    "decoupler.back_stop.damping",
    "back_stop",
    "allowed keys: stiffness, restitution, damping_law, chi"
);
case!(
    back_stop_gonthier_zero,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0, damping_law = \"gonthier\" }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "must be in (0, 1] with damping_law \"flores\" or \"gonthier\""
);
case!(
    friction_unknown_key,
    BASE,
    "v0 = 0.001 }",
    "v0 = 0.001, static = 0.2 }",
    "decoupler.friction.static",
    "friction",
    "allowed keys: mu, v0"
);
case!(
    friction_mu_negative,
    BASE,
    "mu = 0.12",
    "mu = -0.12",
    "decoupler.friction.mu",
    "friction",
    "allowed range [0, 1] (dry sliding friction: 0.04 (PTFE) to about 1 (rubber on steel); 0.12-0.23 in Tables 5-15), got -0.12"
);
case!(
    friction_v0_negative,
    BASE,
    "v0 = 0.001 }",
    "v0 = -0.001 }",
    "decoupler.friction.v0",
    "friction",
    "allowed range [0, 0.1] m/s (0 is the Coulomb limit (regularised); 1e-3 m/s in the thesis (eq 41); beyond 0.1 m/s friction is no longer dry), got -0.001"
);
case!(
    friction_v0_missing,
    BASE,
    ", v0 = 0.001 }",
    " }",
    "decoupler.friction.v0",
    "friction",
    "missing required key: a number in [0, 0.1] m/s"
);
case!(
    friction_not_table,
    BASE,
    "friction = { mu = 0.12, v0 = 0.001 }",
    "friction = 0.12",
    "decoupler.friction",
    "friction",
    "must be a table ({ mu, v0 }"
);

// Hydraulic.
case!(
    stroke_zero,
    HYD,
    "stroke = 0.023",
    "stroke = 0",
    "decoupler.stroke",
    "stroke = 0",
    "allowed range [0.001, 0.2] m (a hand-sized module: 0.023 m in Tables 12 and 14), got 0"
);
case!(
    piston_radius_negative,
    HYD,
    "piston_radius = 0.020",
    "piston_radius = -0.02",
    "decoupler.piston_radius",
    "piston_radius",
    "allowed range [0.001, 0.1] m (a hand-sized module: 0.02 m in Tables 12 and 14), got -0.02"
);
case!(
    orifice_radius_zero,
    HYD,
    "orifice_radius = 0.008",
    "orifice_radius = 0",
    "decoupler.orifice_radius",
    "orifice_radius",
    "allowed range [1e-5, 0.1] m (0.008 m in Tables 12 and 14; must also be < piston_radius), got 0"
);
case!(
    orifice_not_smaller,
    HYD,
    "orifice_radius = 0.008",
    "orifice_radius = 0.02",
    "decoupler.orifice_radius",
    "orifice_radius",
    "must be < decoupler.piston_radius = 0.02 m, got 0.02"
);
case!(
    gas_pressure_zero,
    HYD,
    "gas_pressure = 1000.0",
    "gas_pressure = 0",
    "decoupler.gas_pressure",
    "gas_pressure",
    "allowed range [100, 1e7] Pa (1000 Pa in Tables 12 and 14; 100 bar is the top of small gas springs), got 0"
);
case!(
    gas_volume_negative,
    HYD,
    "gas_volume = 7.63e-5",
    "gas_volume = -1",
    "decoupler.gas_volume",
    "gas_volume",
    "allowed range [1e-9, 0.01] m^3 (7.63e-5 m^3 in Tables 12 and 14; 10 litres is far beyond a hand-sized module), got -1"
);
case!(
    gas_driven_to_zero,
    HYD,
    "gas_volume = 7.63e-5",
    "gas_volume = 2.8e-5",
    "decoupler.gas_volume",
    "gas_volume",
    "must be > the volume the piston sweeps, pi * piston_radius^2 * stroke = 2.89027e-5 m^3"
);
case!(
    discharge_coefficient_zero,
    HYD,
    "discharge_coefficient = 3.0",
    "discharge_coefficient = 0",
    "decoupler.discharge_coefficient",
    "discharge_coefficient",
    "allowed range [0.1, 10] (3.0 in Tables 12 and 14 (eq 50)), got 0"
);
case!(
    liquid_density_zero,
    HYD,
    "liquid_density = 900.0",
    "liquid_density = 0",
    "decoupler.liquid_density",
    "liquid_density",
    "allowed range [500, 2000] kg/m^3 (hydraulic oils 850-900 kg/m^3, water 1000, glycerol 1260; 900 in Tables 12 and 14), got 0"
);
case!(
    dry_friction_negative,
    HYD,
    "dry_friction = 0.0",
    "dry_friction = -1",
    "decoupler.dry_friction",
    "dry_friction",
    "allowed range [0, 1000] N (seal friction: 0-0.2 N in Tables 12 and 14; the solver gives up near 4000 N), got -1"
);
case!(
    viscous_friction_negative,
    HYD,
    "viscous_friction = 0.5",
    "viscous_friction = -0.5",
    "decoupler.viscous_friction",
    "viscous_friction",
    "allowed range [0, 10000] N s/m (0.5 N s/m in Tables 12 and 14), got -0.5"
);
case!(
    adiabatic_exponent_out_of_range,
    HYD,
    "viscous_friction = 0.5\n",
    "viscous_friction = 0.5\nadiabatic_exponent = 2\n",
    "decoupler.adiabatic_exponent",
    "adiabatic_exponent",
    "allowed range [1, 1.6666666666666667] (1 is isothermal, 5/3 a monatomic gas: nothing outside is a gas), got 2"
);
case!(
    friction_v0_zero,
    HYD,
    "viscous_friction = 0.5\n",
    "viscous_friction = 0.5\nfriction_v0 = 0\n",
    "decoupler.friction_v0",
    "friction_v0",
    "allowed range [1e-5, 0.1] m/s (regularisation of sgn() (eq 48), 1e-3 m/s by default; below 1e-5 m/s the solver grinds), got 0"
);
case!(
    hydraulic_missing_key,
    HYD,
    "liquid_density = 900.0\n",
    "",
    "decoupler.liquid_density",
    "[decoupler]",
    "missing required key: a number in [500, 2000] kg/m^3"
);
case!(
    hydraulic_unknown_key,
    HYD,
    "stroke = 0.023\n",
    "stroke = 0.023\nsprings = 1\n",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"hydraulic\"; allowed keys: kind, stroke, piston_radius"
);
case!(hydraulic_back_stop_missing, HYD, "back_stop = { stiffness = 1e6, chi = 2e5 }\n", "", "decoupler.back_stop", "[decoupler]", "missing required key: a table ({ stiffness, restitution, damping_law } or { stiffness, chi })");

// Target.
case!(
    target_kind_bad,
    BASE,
    "kind = \"obstacle\"",
    "kind = \"wall\"",
    "target.kind",
    "wall",
    "must be one of \"obstacle\" | \"object\" | \"body_region\", got \"wall\""
);
case!(
    target_gap_zero,
    BASE,
    "gap = 0.01",
    "gap = 0",
    "target.gap",
    "gap",
    "allowed range [1e-6, 2] m (1 um to 2 m, within the reach of an arm; 0.005-0.15 m in the thesis), got 0"
);
case!(target_gap_never_closed, BASE, "gap = 0.01", "gap = 1", "target.gap", "gap", "the commanded motion covers only 0.02875 m in duration = 0.6 s, so the tool never reaches the target; must be < 0.02875 m, got 1");
case!(
    target_stiffness_zero,
    BASE,
    "stiffness = 1e8",
    "stiffness = 0",
    "target.stiffness",
    "stiffness = 0",
    "allowed range [1000, 1e10] N/m^1.5 (Hertz contact from foam (1e3 N/m^1.5) to metal on metal; 1e3-1e8 in the thesis), got 0"
);
case!(
    target_restitution_high,
    BASE,
    "restitution = 0.65",
    "restitution = 1.2",
    "target.restitution",
    "restitution = 1.2",
    "allowed range [0, 1] (a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)), got 1.2"
);
case!(
    target_law_missing,
    BASE,
    "damping_law = \"hunt-crossley\"\n",
    "",
    "target.damping_law",
    "[target]",
    "missing required key: one of \"hunt-crossley\" | \"lankarani-nikravesh\""
);
case!(
    target_law_bad,
    BASE,
    "damping_law = \"hunt-crossley\"",
    "damping_law = \"kelvin\"",
    "target.damping_law",
    "kelvin",
    "must be one of \"hunt-crossley\""
);
case!(
    target_flores_zero,
    BASE,
    "restitution = 0.65\ndamping_law = \"hunt-crossley\"",
    "restitution = 0\ndamping_law = \"flores\"",
    "target.restitution",
    "restitution = 0\n",
    "the law divides by e"
);
case!(
    target_chi_and_restitution,
    HYD,
    "chi = 1.35e6",
    "chi = 1.35e6\nrestitution = 0.5",
    "target.restitution",
    "restitution",
    "give either chi"
);
case!(
    target_chi_negative,
    HYD,
    "chi = 1.35e6",
    "chi = -1.35e6",
    "target.chi",
    "chi = -1.35e6",
    "allowed range [0, 1e8] N s/m^2.5 (4.5e4-1.35e6 N s/m^2.5 in Table 12; 1e8 is overdamped for every stiffness in range), got -1.35e6"
);
case!(
    target_no_damping,
    HYD,
    "chi = 1.35e6\n",
    "",
    "target.restitution",
    "[target]",
    "missing required key: restitution in [0, 1] (with damping_law), or chi"
);
case!(obstacle_with_mass, BASE, "kind = \"obstacle\"\n", "kind = \"obstacle\"\nmass = 1\n", "target.mass", "mass = 1", "unknown key for kind = \"obstacle\"; allowed keys: kind, gap, stiffness, restitution, damping_law, chi");
case!(
    obstacle_with_floor_friction,
    BASE,
    "kind = \"obstacle\"\n",
    "kind = \"obstacle\"\nfloor_friction = 0.3\n",
    "target.floor_friction",
    "floor_friction",
    "unknown key for kind = \"obstacle\""
);
case!(
    object_mass_missing,
    HYD,
    "mass = 0.246\n",
    "",
    "target.mass",
    "[target]",
    "missing required key: a number in [0.001, 1000] kg"
);
case!(
    object_mass_zero,
    HYD,
    "mass = 0.246",
    "mass = 0",
    "target.mass",
    "mass = 0\n",
    "allowed range [0.001, 1000] kg (1 g to 1 t; 0.136-0.25 kg in Tables 4-15), got 0"
);
case!(
    object_floor_friction_negative,
    HYD,
    "mass = 0.246\n",
    "mass = 0.246\nfloor_friction = -0.2\n",
    "target.floor_friction",
    "floor_friction",
    "allowed range [0, 1] (dry friction coefficients: 0 (ice) to about 1 (rubber on concrete)), got -0.2"
);
case!(
    object_unknown_key,
    HYD,
    "mass = 0.246\n",
    "mass = 0.246\nradius = 0.02\n",
    "target.radius",
    "radius = 0.02\n",
    "allowed keys: kind, gap, stiffness, restitution, damping_law, chi, mass, floor_friction"
);

// Sensor.
case!(
    sensor_kind_bad,
    BASE,
    "kind = \"travel\"",
    "kind = \"camera\"",
    "sensor.kind",
    "camera",
    "must be one of \"travel\" | \"force\", got \"camera\""
);
case!(
    sensor_threshold_zero,
    BASE,
    "threshold = 0.005",
    "threshold = 0",
    "sensor.threshold",
    "threshold",
    "allowed range [1e-5, 0.2] m (10 um (the repeatability of an inductive switch) to the longest stroke in range; 0.5-5 mm in the thesis), got 0"
);
case!(
    sensor_force_threshold_negative,
    BASE,
    "kind = \"travel\"\nthreshold = 0.005",
    "kind = \"force\"\nthreshold = -25",
    "sensor.threshold",
    "threshold",
    "allowed range [0.1, 10000] N (0.1 N to 10 kN; 1-25 N in the thesis, ISO/TS 15066 Table A.2 limits are 65-280 N), got -25"
);
case!(
    sensor_threshold_missing,
    BASE,
    "threshold = 0.005\n",
    "",
    "sensor.threshold",
    "[sensor]",
    "missing required key: a number in [1e-5, 0.2] m"
);
case!(
    sensor_beyond_bistable_stroke,
    BASE,
    "threshold = 0.005",
    "threshold = 0.03",
    "sensor.threshold",
    "threshold",
    "must be < the decoupler's total stroke front_stroke + back_stroke = 0.03 m, got 0.03"
);
case!(
    sensor_beyond_hydraulic_stroke,
    HYD,
    "threshold = 0.0015",
    "threshold = 0.03",
    "sensor.threshold",
    "threshold",
    "must be < the decoupler's stroke = 0.023 m, got 0.03"
);
case!(sensor_travel_on_rigid_tool, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"rigid\"\n", "sensor.kind", "kind = \"travel\"", "must be \"force\" for decoupler.kind = \"rigid\"");
case!(
    sensor_unknown_key,
    BASE,
    "threshold = 0.005\n",
    "threshold = 0.005\nhysteresis = 0.001\n",
    "sensor.hysteresis",
    "hysteresis",
    "allowed keys: kind, threshold"
);

// Solver.
case!(
    solver_method_bad,
    BASE,
    "method = \"rk4\"",
    "method = \"euler\"",
    "solver.method",
    "euler",
    "must be one of \"dopri5\" | \"rk4\" | \"semi-implicit-euler\", got \"euler\""
);
case!(
    solver_rtol_too_loose,
    BASE,
    "rtol = 1e-6",
    "rtol = 0.5",
    "solver.rtol",
    "rtol",
    "allowed range [1e-12, 1e-5] (tighter than 1e-12 is below what f64 resolves over a run; looser than 1e-5 (fidelity = \"fast\") loses contacts and modes (docs/accuracy.md)), got 0.5"
);
case!(
    solver_rtol_zero,
    BASE,
    "rtol = 1e-6",
    "rtol = 0",
    "solver.rtol",
    "rtol",
    "allowed range [1e-12, 1e-5] (tighter than 1e-12 is below what f64 resolves over a run; looser than 1e-5 (fidelity = \"fast\") loses contacts and modes (docs/accuracy.md)), got 0"
);
case!(
    solver_atol_negative,
    BASE,
    "atol = 1e-9",
    "atol = -1e-9",
    "solver.atol",
    "atol",
    "allowed range [1e-15, 1e-8] (tighter than 1e-15 is below f64 resolution; looser than 1e-8 (fidelity = \"fast\") loses contacts and modes (docs/accuracy.md)), got -1e-9"
);
case!(
    solver_max_step_zero,
    BASE,
    "max_step = 1e-4",
    "max_step = 0",
    "solver.max_step",
    "max_step",
    "allowed range [1e-7, 0.1] s (10 ms by default; below 0.1 us a fixed-step run grinds, above 0.1 s a step can jump a whole contact; also <= duration), got 0"
);
case!(
    solver_max_step_beyond_duration,
    BASE,
    "max_step = 1e-4",
    "max_step = 1",
    "solver.max_step",
    "max_step",
    "allowed range [1e-7, 0.1] s (10 ms by default; below 0.1 us a fixed-step run grinds, above 0.1 s a step can jump a whole contact; also <= duration), got 1"
);
case!(
    solver_output_interval_negative,
    BASE,
    "output_interval = 1e-3",
    "output_interval = -1",
    "solver.output_interval",
    "output_interval",
    "allowed range [0, 1] s (0 records every step; 0.1 ms by default; also <= duration and at most 1e7 samples), got -1"
);
case!(
    solver_output_interval_beyond_duration,
    BASE,
    "output_interval = 1e-3",
    "output_interval = 2",
    "solver.output_interval",
    "output_interval",
    "allowed range [0, 1] s (0 records every step; 0.1 ms by default; also <= duration and at most 1e7 samples), got 2"
);
case!(
    solver_unknown_key,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\norder = 4\n",
    "solver.order",
    "order",
    "allowed keys: method, rtol, atol, max_step, output_interval, fidelity, simplify"
);
case!(
    solver_fidelity_bad,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\nfidelity = \"exact\"\n",
    "solver.fidelity",
    "fidelity",
    "must be one of \"fast\" | \"default\" | \"reference\", got \"exact\""
);
case!(
    solver_reference_refuses_a_method,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\nfidelity = \"reference\"\n",
    "solver.method",
    "method = \"rk4\"",
    "must not be set with fidelity = \"reference\""
);
case!(
    solver_simplify_unknown,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\nsimplify = [\"rigid-tool\"]\n",
    "solver.simplify",
    "simplify",
    "must be a list of \"rigid-robot\" | \"no-friction\", got \"rigid-tool\""
);
case!(
    solver_simplify_twice,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\nsimplify = [\"no-friction\", \"no-friction\"]\n",
    "solver.simplify",
    "simplify",
    "lists \"no-friction\" twice"
);
case!(
    solver_simplify_not_a_list,
    BASE,
    "method = \"rk4\"\n",
    "method = \"rk4\"\nsimplify = \"no-friction\"\n",
    "solver.simplify",
    "simplify",
    "must be a list of"
);

#[test]
fn fidelity_sets_the_tolerance_defaults_and_explicit_keys_win() {
    let no_tol = BASE.replace("rtol = 1e-6\n", "").replace("atol = 1e-9\n", "").replace("method = \"rk4\"\n", "");
    let with = |extra: &str| parse(&no_tol.replace("[solver]\n", &format!("[solver]\n{extra}")), "f.toml").unwrap().solver;
    let r = with("fidelity = \"reference\"\n");
    assert_eq!((r.method, r.rtol, r.atol, r.fidelity), (Method::Dopri5, REFERENCE_RTOL, REFERENCE_ATOL, Fidelity::Reference));
    let f = with("fidelity = \"fast\"\n");
    assert_eq!((f.rtol, f.atol), (FAST_RTOL, FAST_ATOL));
    let f = with("fidelity = \"fast\"\nrtol = 3e-6\nsimplify = [\"rigid-robot\"]\n");
    assert_eq!((f.rtol, f.atol), (3e-6, FAST_ATOL));
    assert_eq!(f.simplify, Simplify { rigid_robot: true, no_friction: false });
    let d = with("");
    assert_eq!((d.rtol, d.atol, d.fidelity), (DEFAULT_RTOL, DEFAULT_ATOL, Fidelity::Default));
}

// Controller.
case!(
    controller_scan_cycle_zero,
    BASE,
    "scan_cycle = 0.016",
    "scan_cycle = 0",
    "controller.scan_cycle",
    "scan_cycle",
    "allowed range [1e-5, 0.1] s (robot controller cycles: 10 us to 100 ms (safety PLCs scan in 1-20 ms)), got 0"
);
case!(
    controller_phase_one,
    BASE,
    "phase = 0.5",
    "phase = 1.0",
    "controller.phase",
    "phase",
    "allowed range [0, 1) of a scan cycle (a phase is a fraction of one cycle), got 1"
);
case!(
    controller_phase_negative,
    BASE,
    "phase = 0.5",
    "phase = -0.1",
    "controller.phase",
    "phase",
    "allowed range [0, 1) of a scan cycle (a phase is a fraction of one cycle), got -0.1"
);
case!(
    controller_tick_missing,
    BASE,
    "firmware_tick = 1e-4\n",
    "",
    "controller.firmware_tick",
    "[controller]",
    "missing required key: a number in [1e-6, 0.01] s"
);
case!(
    controller_unknown_key,
    BASE,
    "phase = 0.5\n",
    "phase = 0.5\nlatency = 0.01\n",
    "controller.latency",
    "latency",
    "allowed keys: scan_cycle, phase, firmware_tick"
);


/// Issue 18: every number a scene can hold is bounded on both sides, with where the bounds come
/// from, so nothing like 1e308 or a gravity of 9.2e18 can be accepted; every integer too.
#[test]
fn every_numeric_key_has_a_physical_range_with_its_source() {
    for table in super::key_tables() {
        for key in table.keys {
            let at = format!("{}.{} ({})", table.path, key.name, table.when);
            match key.ty {
                super::Ty::Number(s) => {
                    assert!(s.lo.value().is_some_and(f64::is_finite), "{at}: no lower bound");
                    assert!(s.hi.value().is_some_and(f64::is_finite), "{at}: no upper bound");
                    assert!(!s.source.trim().is_empty(), "{at}: no source for the range");
                    assert!(s.refuse(1e308).contains(s.source), "{at}");
                }
                super::Ty::Integer { hi, source, .. } => {
                    assert!(hi <= 2000, "{at}: no physical upper bound");
                    assert!(!source.trim().is_empty(), "{at}: no source for the range");
                }
                _ => {}
            }
        }
    }
}
