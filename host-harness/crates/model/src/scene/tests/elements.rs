//! Target, sensor, solver and controller tables, and the range table as a whole.

use super::*;

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
    controller_reaction_time_negative,
    BASE,
    "phase = 0.5\n",
    "phase = 0.5\nreaction_time = -0.01\n",
    "controller.reaction_time",
    "reaction_time",
    "allowed range [0, 1] s"
);
case!(
    controller_reaction_time_beyond_a_second,
    BASE,
    "phase = 0.5\n",
    "phase = 0.5\nreaction_time = 1.5\n",
    "controller.reaction_time",
    "reaction_time",
    "part of motion.dead_time, at most 1 s"
);

/// `[controller] reaction_time` is read as given; without it the controller splits the scene's DT.
#[test]
fn controller_reaction_time_is_read_and_splits_the_dead_time_by_default() {
    let s = parse(&mutate(BASE, "phase = 0.5\n", "phase = 0.5\nreaction_time = 0.03\n"), "r.toml").unwrap();
    let c = s.controller.unwrap();
    assert_eq!(c.reaction_time, Some(0.03));
    assert_eq!(c.reaction(0.016), (0.03, ReactionSource::Given));
    let c = Controller::new(0.016, 0.0, 1e-4);
    assert_eq!(c.reaction(0.046).1, ReactionSource::DeadTimeLessScan);
    assert!((c.reaction(0.046).0 - 0.03).abs() < 1e-15);
    assert_eq!(c.reaction(0.01), (0.0, ReactionSource::DeadTimeShorterThanScan));
}
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
                    // A random seed is no physical quantity: any value is as good (it only picks
                    // the synthetic noise).
                    assert!(hi <= 2000 || at == "avoid.camera.seed (avoidance scene)", "{at}: no physical upper bound");
                    assert!(!source.trim().is_empty(), "{at}: no source for the range");
                }
                _ => {}
            }
        }
    }
}
