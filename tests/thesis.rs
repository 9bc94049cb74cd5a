//! The thesis's results reproduced end to end, from the shipped scene files (MODEL.md, "Results in
//! the thesis to reproduce"). Tolerances are stated with their reason at each assertion.

use flinch_harness::scene::{self, DampingLaw};
use flinch_harness::sim::{self, Summary};
use flinch_tests::scene_path;

fn run(name: &str) -> Summary {
    let s = scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    sim::run(&s, false).unwrap_or_else(|e| panic!("{name}: {e}")).0
}

fn run_text(text: &str) -> Summary {
    let s = scene::parse(text, "inline.toml").unwrap_or_else(|e| panic!("{e}"));
    sim::run(&s, false).unwrap_or_else(|e| panic!("{e}")).0
}

// ---- Tables 5-7, Fig. 39-40: rigid tool against the bi-stable module, V_c = 0.05 m/s, DT = 16 ms

#[test]
fn bistable_module_reacts_in_about_120_ms() {
    let b = run("tables5-7_bistable.toml");
    let r = b.reaction_time.unwrap();
    // Fig. 40: t_r = 120 ms, read off a plot: +-10 ms.
    assert!((0.110..=0.130).contains(&r), "reaction {r}");
    // The dead time is exactly the scene's: detection + DT = reaction.
    assert!((b.detection_delay.unwrap() + 0.016 - r).abs() < 1e-9);
    assert_eq!(b.mode, Some(1), "Fig. 40 is scenario 1: no back-stop impact");
    assert!(!b.stroke_exhausted);
}

#[test]
fn rigid_tool_reacts_within_detection_plus_one_scan_cycle() {
    let r = run("tables5-7_rigid.toml");
    let det = r.detection_delay.unwrap();
    // Thesis: detection 4 ms, reaction 20 ms. With Table 6 (k_c = 1e8 N/m^1.5) 25 N is reached
    // after (25 / 1e8)^(2/3) = 40 um of penetration, 0.7 ms at 0.05 m/s: 4 ms cannot follow from
    // the printed values (docs/validation.md). We assert the physics: well under the bi-stable's
    // 100 ms, and reaction = detection + DT.
    assert!(det < 0.004, "detection {det}");
    assert!((r.reaction_time.unwrap() - det - 0.016).abs() < 1e-9);
    assert!(r.reaction_time.unwrap() <= 0.020 + 1e-9);
}

#[test]
fn bistable_module_cuts_the_peak_contact_force_by_about_85_percent() {
    let rigid = run("tables5-7_rigid.toml").peak_contact_force;
    let bist = run("tables5-7_bistable.toml").peak_contact_force;
    let cut = 1.0 - bist / rigid;
    // "reduces the contact force by about 85 %" (Ch. 3.1.2): +-5 points.
    assert!((0.80..=0.90).contains(&cut), "cut {cut}: rigid {rigid} N, bi-stable {bist} N");
}

// ---- Fig. 46-48: the three working modes at m_t = 0.75 kg

#[test]
fn working_modes_at_005_020_025_m_per_s() {
    assert_eq!(run("tables5-7_bistable.toml").mode, Some(1));
    assert_eq!(run("tables5-7_bistable_v020.toml").mode, Some(2));
    assert_eq!(run("tables5-7_bistable_v025.toml").mode, Some(3));
}

// ---- Eq 1-4: instantaneous-impact limits

fn free_object_scene(decoupler: &str, restitution: f64, law: &str, m_t: f64, m_p: f64) -> String {
    format!(
        r#"name = "limit"
duration = 0.05
[motion]
speed = 1.0
accel = 1.0
decel = 1.0
dead_time = 0.0
gravity = 0.0
start_at_speed = true
[tool]
mass = {m_t}
[decoupler]
{decoupler}
[target]
kind = "object"
mass = {m_p}
gap = 0.001
stiffness = 1e5
restitution = {restitution}
damping_law = "{law}"
"#
    )
}

#[test]
fn rigid_tool_on_a_rigid_robot_gives_eq1() {
    // Eq 1 with v_t = 1 m/s: V_p = 2 m/s for e = 1, 1 m/s for e = 0; the robot keeps its speed.
    let e1 = run_text(&free_object_scene(r#"kind = "rigid""#, 1.0, "exact", 0.125, 0.25));
    assert!((e1.object_final_velocity.unwrap() - 2.0).abs() < 1e-4, "{e1:?}");
    let e0 = run_text(&free_object_scene(r#"kind = "rigid""#, 0.0, "exact", 0.125, 0.25));
    // e = 0 is approached, not reached, by any law with finite damping (ALPHA_MAX): 1 %.
    assert!((e0.object_final_velocity.unwrap() - 1.0).abs() < 0.01, "{e0:?}");
}

#[test]
fn free_tool_gives_eq3_and_eq4() {
    let free = r#"kind = "linear"
stiffness = 0.0
damping_ratio = 0.0"#;
    for e in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let s = run_text(&free_object_scene(free, e, "exact", 0.125, 0.25));
        // At e = 0 the bodies move on together: no separation, so no achieved restitution.
        let achieved = s.achieved_restitution.unwrap_or(0.0);
        let expect = 0.125 / 0.375 * (1.0 + achieved);
        // Still in contact at e = 0 (separating at the capped law's ~0.5 %): 1 % there.
        let tol = if s.achieved_restitution.is_some() { 1e-6 } else { 0.01 * expect };
        assert!((s.object_final_velocity.unwrap() - expect).abs() < tol, "e {e}: {s:?}");
        // The exact law delivers the restitution asked (e = 0 within the cap's 1 %).
        assert!((achieved - e).abs() < 0.01, "asked {e}, achieved {achieved}");
    }
}

#[test]
fn energy_is_conserved_in_an_elastic_undamped_impact() {
    let free = r#"kind = "linear"
stiffness = 0.0
damping_ratio = 0.0"#;
    let s = run_text(&free_object_scene(free, 1.0, "hunt-crossley", 0.125, 0.25));
    let vp = s.object_final_velocity.unwrap();
    // Tool velocity after: from momentum, m_t v_t = m_t V_t + m_p V_p.
    let vt = (0.125 * 1.0 - 0.25 * vp) / 0.125;
    let before = 0.5 * 0.125;
    let after = 0.5 * 0.125 * vt * vt + 0.5 * 0.25 * vp * vp;
    // The default tolerance integrates the impact to about 1e-6 in energy (docs/accuracy.md).
    assert!(((after - before) / before).abs() < 1e-5, "before {before} J, after {after} J");
}

#[test]
fn achieved_restitution_of_every_damping_law_over_e() {
    let free = r#"kind = "linear"
stiffness = 0.0
damping_ratio = 0.0"#;
    let laws = [("hunt-crossley", DampingLaw::HuntCrossley), ("lankarani-nikravesh", DampingLaw::LankaraniNikravesh), ("flores", DampingLaw::Flores), ("gonthier", DampingLaw::Gonthier), ("exact", DampingLaw::Exact)];
    let mut table = Vec::new();
    for (name, _) in laws {
        let mut prev = -1.0;
        let mut row = Vec::new();
        // Flores and Gonthier divide by e: the validator refuses e = 0 for them.
        let first = if matches!(name, "flores" | "gonthier") { 1 } else { 0 };
        for i in first..=10 {
            let e = i as f64 / 10.0;
            let a = run_text(&free_object_scene(free, e, name, 0.125, 0.25)).achieved_restitution;
            // e = 0 may not separate within the run: the bodies move on together (achieved 0).
            let a = if e == 0.0 { a.unwrap_or(0.0) } else { a.unwrap() };
            // 1e-5: the integration error of the default tolerance (see the energy test).
            assert!(a.is_finite() && (0.0..=1.0 + 1e-5).contains(&a), "{name} e {e}: {a}");
            assert!(a >= prev - 1e-5, "{name}: achieved restitution must grow with e");
            prev = a;
            row.push(a);
        }
        let last = row[row.len() - 1];
        assert!((last - 1.0).abs() < 1e-5, "{name} at e = 1: {last}");
        table.push((name, row));
    }
    let get = |n: &str, i: usize| {
        let row = &table.iter().find(|(m, _)| *m == n).unwrap().1;
        row[i + row.len() - 11]
    };
    // MODEL.md: eq 7 cannot go below about 0.5; asking 0.1 gives about 0.52.
    assert!((0.50..0.55).contains(&get("hunt-crossley", 1)));
    // Exact delivers what is asked.
    for i in 1..=10 {
        assert!((get("exact", i) - i as f64 / 10.0).abs() < 2e-3);
    }
    // Gonthier is the closest closed-form law for e <= 0.3.
    for i in 1..=3 {
        let e = i as f64 / 10.0;
        let err = |n: &str| (get(n, i) - e).abs();
        for other in ["hunt-crossley", "lankarani-nikravesh", "flores"] {
            assert!(err("gonthier") <= err(other), "e {e}: gonthier {} vs {other} {}", get("gonthier", i), get(other, i));
        }
    }
}

// ---- Ch. 2: the bi-stable mechanism against the rigid tool (Fig. 24-26)

#[test]
fn bistable_halves_the_object_velocity_of_a_rigid_tool() {
    let b = run("table2_bistable.toml").object_final_velocity.unwrap();
    let r = run("table2_rigid.toml").object_final_velocity.unwrap();
    let cut = 1.0 - b / r;
    // Fig. 24a vs 26: "a 51 % reduction in the final velocity of the object"; +-8 points.
    assert!((0.43..=0.59).contains(&cut), "cut {cut}: bi-stable {b}, rigid {r}");
}

#[test]
fn rigid_tool_matches_the_table4_experiment() {
    // Ch. 2.5: 1.798 +- 0.037 m/s measured (136 g, rigid tool); within two standard deviations.
    let v = run("table4_rigid_136g.toml").object_peak_velocity.unwrap();
    assert!((v - 1.798).abs() < 2.0 * 0.037, "{v}");
}

// ---- Ch. 4: hydraulic against bi-stable

#[test]
fn with_70ms_dead_time_the_hydraulic_module_is_gentler_on_small_objects() {
    let h = run("table12_hydraulic_object.toml");
    let b = run("table13_bistable_object.toml");
    assert!(h.object_final_velocity.unwrap() < b.object_final_velocity.unwrap(), "hydraulic {h:?}\nbistable {b:?}");
    assert!(h.peak_robot_force < b.peak_robot_force);
}

#[test]
fn with_10ms_dead_time_the_bistable_module_transfers_less_momentum() {
    let h = run("table12_hydraulic_object_dt10.toml");
    let b = run("table13_bistable_object_dt10.toml");
    assert!(b.object_final_velocity.unwrap() < h.object_final_velocity.unwrap(), "hydraulic {h:?}\nbistable {b:?}");
}

#[test]
fn with_10ms_dead_time_on_a_hard_surface_the_bistable_module_no_longer_switches() {
    let b = run("table15_bistable_surface_dt10.toml");
    assert_eq!(b.mode, Some(1));
    let h = run("table14_hydraulic_surface_dt10.toml");
    assert!(b.peak_robot_force < h.peak_robot_force, "Fig. 80: the bi-stable is gentler on the robot at 10 ms");
}

// ---- Issue 15: the first impact's force on the robot is not the whole run's

/// Largest |f_robot| of a run recorded every 10 us within `half` seconds of `t`.
fn recorded_robot_force_near(name: &str, t: f64, half: f64) -> f64 {
    let mut s = scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    s.solver.output_interval = 1e-5;
    let (_, h) = sim::run(&s, true).unwrap_or_else(|e| panic!("{name}: {e}"));
    h.iter().filter(|x| (x.t - t).abs() <= half).map(|x| x.f_robot.abs()).fold(0.0, f64::max)
}

#[test]
fn fig76_hydraulic_peak_on_the_robot_is_the_front_stop_return_not_the_first_impact() {
    // Issue 15: the first impact puts about 30 N on the robot 2.5 ms after contact; the whole
    // run's 34.8 N is the tool landing back on the front end-stop (eq 28's c_fe s' jump) 80 ms
    // (DT = 10 ms) or 105 ms (DT = 70 ms) after contact.
    for (name, after) in [("table12_hydraulic_object_dt10.toml", 0.080), ("table12_hydraulic_object.toml", 0.105)] {
        let h = run(name);
        let tc = h.t_contact.unwrap();
        let f1 = h.first_impact_peak_robot_force_n.unwrap();
        let t1 = h.first_impact_peak_robot_force_t_s.unwrap() - tc;
        assert!((29.0..31.0).contains(&f1), "{name}: first impact {f1} N");
        assert!((0.0015..0.0035).contains(&t1), "{name}: first impact at +{t1} s");
        assert_eq!(h.peak_robot_force_event, "front_stop", "{name}");
        let tp = h.peak_robot_force_t_s - tc;
        assert!((tp - after).abs() < 0.003, "{name}: whole-run peak at +{tp} s");
        assert!(h.peak_robot_force > f1 + 4.0, "{name}: {} vs {f1}", h.peak_robot_force);
        // The reported instant is where the recorded history has that force (to 1 %).
        let seen = recorded_robot_force_near(name, h.peak_robot_force_t_s, 2e-5);
        assert!((seen / h.peak_robot_force - 1.0).abs() < 0.01, "{name}: history {seen} N near the reported instant, summary {} N", h.peak_robot_force);
        let seen1 = recorded_robot_force_near(name, h.first_impact_peak_robot_force_t_s.unwrap(), 2e-5);
        assert!((seen1 / f1 - 1.0).abs() < 0.01, "{name}: history {seen1} N near the first impact's instant, summary {f1} N");
    }
}

#[test]
fn table4_246g_peak_on_the_robot_is_the_second_hit() {
    let b = run("table4_bistable_246g.toml");
    assert_eq!(b.contacts, 2);
    let f1 = b.first_impact_peak_robot_force_n.unwrap();
    assert!(f1 < 0.1 * b.peak_robot_force, "the first impact ({f1} N) is a small part of the run's {} N", b.peak_robot_force);
    // Issue 15: the peak comes during the second hit, but the back stop carries most of it, so the
    // event is named by the largest part of the force, not by the contact being on.
    let mut s = scene::load(&scene_path("table4_bistable_246g.toml")).unwrap();
    s.solver.output_interval = 1e-5;
    let h = sim::run(&s, true).unwrap().1;
    let at = h.iter().min_by(|a, c| (a.t - b.peak_robot_force_t_s).abs().total_cmp(&(c.t - b.peak_robot_force_t_s).abs())).unwrap();
    assert!(at.f_contact > 0.0, "the tool still touches the object at the peak");
    assert!(at.f_stops > 0.8 * at.f_robot.abs() && at.f_stops > at.f_spring.abs(), "back stop {} N of {} N", at.f_stops, at.f_robot);
    assert_eq!(b.peak_robot_force_event, "back_stop");
}

#[test]
fn a_contact_carried_by_the_decoupler_keeps_its_name() {
    // The hydraulic's first impact (about 30 N) is carried by the orifice, not an end-stop, while
    // the tool touches the object: still "first_impact" when it is the run's peak (a run ending
    // before the tool returns onto the front stop).
    let mut s = scene::load(&scene_path("table12_hydraulic_object_dt10.toml")).unwrap();
    s.duration_s = s.duration_s.min(0.27);
    let r = sim::run(&s, false).unwrap().0;
    assert_eq!(r.peak_robot_force_event, "first_impact");
    assert_eq!(r.first_impact_peak_robot_force_n, Some(r.peak_robot_force));
}

#[test]
fn rigid_tool_first_impact_is_the_whole_run_peak() {
    let r = run("table1_rigid_tool.toml");
    assert_eq!(r.peak_robot_force_event, "first_impact");
    assert_eq!(r.first_impact_peak_robot_force_n, Some(r.peak_robot_force));
    assert_eq!(r.first_impact_peak_robot_force_t_s, Some(r.peak_robot_force_t_s));
    assert!(r.first_impact_peak_robot_force_null_reason.is_none());
}

#[test]
fn no_contact_leaves_the_first_impact_null_with_its_reason() {
    // The loader refuses a scene whose target is out of reach; the simulator must still say why
    // the first impact is null when it is handed one (a caller building a Scene in code).
    let mut s = scene::load(&scene_path("table1_rigid_tool.toml")).unwrap();
    s.duration_s = 0.005;
    let r = sim::run(&s, false).unwrap().0;
    assert_eq!(r.t_contact, None, "the target is out of reach");
    assert_eq!(r.first_impact_peak_robot_force_n, None);
    assert_eq!(r.first_impact_peak_robot_force_t_s, None);
    assert!(r.first_impact_peak_robot_force_null_reason.as_deref().is_some_and(|s| s.contains("no tool-target contact")));
    assert_ne!(r.peak_robot_force_event, "first_impact");
}

#[test]
fn every_shipped_scene_reports_a_first_impact_no_larger_than_the_run_and_inside_its_window() {
    let dir = scene_path("");
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "toml") || p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("avoid")) {
            continue;
        }
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let s = run(&name);
        assert!(["first_impact", "later_contact", "front_stop", "back_stop", "decoupler", "none"].contains(&s.peak_robot_force_event.as_str()), "{name}: {}", s.peak_robot_force_event);
        if let (Some(f1), Some(t1), Some(tc)) = (s.first_impact_peak_robot_force_n, s.first_impact_peak_robot_force_t_s, s.t_contact) {
            assert!(f1 <= s.peak_robot_force, "{name}: first impact {f1} > run {}", s.peak_robot_force);
            assert!(t1 >= tc, "{name}: first impact's peak at {t1} before contact {tc}");
            if s.peak_robot_force_event == "first_impact" {
                assert_eq!(f1, s.peak_robot_force, "{name}");
            }
        } else {
            assert!(s.t_contact.is_none() && s.first_impact_peak_robot_force_null_reason.is_some(), "{name}");
        }
    }
}

// ---- Issue 15: the thesis's own account of Table 4 (braking after the object has left)

#[test]
fn table4_braking_held_until_the_second_hit_ends_matches_the_measured_peaks() {
    for (name, measured, sd) in [("figures/table4_bistable_136g_detached.toml", 1.231, 0.054), ("figures/table4_bistable_246g_detached.toml", 1.430, 0.040)] {
        let mut s = scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
        s.solver.output_interval = 1e-5;
        let (r, h) = sim::run(&s, true).unwrap();
        let tb = r.t_brake.expect("it brakes once the second hit is over");
        // No tool-object contact once braking has started, and braking not before detection + DT.
        assert!(h.iter().filter(|x| x.t > tb + 1e-5).all(|x| x.f_contact == 0.0), "{name}: contact after braking");
        assert!(tb >= r.t_detect.unwrap() + s.motion.dead_time - 1e-12, "{name}");
        assert_eq!(r.contacts, 2, "{name}");
        let v = r.object_peak_velocity.unwrap();
        assert!((v - measured).abs() <= 2.0 * sd, "{name}: {v} m/s against the measured {measured} +- {sd}");
        assert!(r.warnings.iter().any(|w| w.contains("brake_after_contact")), "{name}: the held braking is reported");
    }
}

#[test]
fn brake_held_for_a_contact_that_never_comes_never_brakes_and_says_so() {
    let text = std::fs::read_to_string(scene_path("figures/table4_bistable_136g_detached.toml")).unwrap().replace("brake_after_contact = 2 ", "brake_after_contact = 9 ");
    let r = run_text(&text);
    assert_eq!(r.t_brake, None, "only 2 contacts happen: braking must stay held, visibly");
    assert!(r.warnings.iter().any(|w| w.contains("never brakes")), "{:?}", r.warnings);
}

#[test]
fn brake_after_contact_refuses_zero_and_fractions_with_file_line_key() {
    let base = std::fs::read_to_string(scene_path("figures/table4_bistable_136g_detached.toml")).unwrap();
    for bad in ["brake_after_contact = 0 ", "brake_after_contact = 1.5 ", "brake_after_contact = -2 "] {
        let e = scene::parse(&base.replace("brake_after_contact = 2 ", bad), "v.toml").err().unwrap_or_else(|| panic!("{bad} accepted")).to_string();
        assert!(e.contains("v.toml:") && e.contains("brake_after_contact"), "{bad}: {e}");
    }
}

// ---- Issue 15: the Z prototype's statics (Tables 9-11)

#[test]
fn z_prototype_spring_cannot_hold_the_tool_on_the_back_stop_but_the_module_switches() {
    use flinch_harness::validate::z_statics;
    let s = scene::load(&scene_path("table11_z_prototype.toml")).unwrap();
    let z = z_statics(&s).unwrap();
    assert!((z.hold_n - 1.91).abs() < 0.01 && (z.weight_n - 2.2563).abs() < 1e-3, "{z:?}");
    assert!(z.hold_n < z.weight_n, "at C2 = 25.25 mm the weight wins");
    let (centre, rest) = z.holds_m.expect("some back strokes hold");
    assert!((centre - 0.0153).abs() < 2e-4 && (rest - 0.0209).abs() < 2e-4, "{centre} {rest}");
    // The run: past the weight-shifted dead centre, short of the back stop, in mode 1.
    let (r, h) = sim::run(&s, true).unwrap();
    let end = h.last().unwrap().s;
    assert!(end < -centre && end > -s_back(&s), "ends at {end}");
    assert_eq!(r.mode, Some(1));
}

fn s_back(s: &scene::Scene) -> f64 {
    match &s.decoupler {
        scene::Decoupler::Bistable(b) => b.back_stroke,
        _ => f64::NAN,
    }
}
