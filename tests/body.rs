//! ISO/TS 15066 Annex A body regions (host-harness/crates/model/src/body.rs, crates/studies/src/body_design.rs): the target kind,
//! the limits in the verdict, the closed form against the simulation, and `design --body-region`.

use flinch_harness::body_design;
use flinch_harness::scene::{self, Scene};
use flinch_harness::sim;
use flinch_harness::sweep::Template;
use flinch_harness::verdict;
use flinch_tests::scene_path;

fn hand_text() -> String {
    std::fs::read_to_string(scene_path("body_hand.toml")).unwrap()
}

/// body_hand.toml with `from` replaced by `to` (each must occur once).
fn variant(edits: &[(&str, &str)]) -> String {
    let mut t = hand_text();
    for (from, to) in edits {
        assert_eq!(t.matches(from).count(), 1, "{from}");
        t = t.replacen(from, to, 1);
    }
    t
}

fn parse(text: &str) -> Scene {
    scene::parse(text, "body.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// A rigid tool on a prescribed flange (no [robot]) hitting a free hand at `v`: the Annex A model
/// exactly, m_R infinite, so mu = m_H.
fn rigid_free_hand(v: f64) -> Scene {
    let robot = "[robot]                         # Viper s650 at q = [0, -87, -105, 0, -78, 0] deg\nmass = 8.4                      # m_r, kg, Table 7\nstiffness = 2.3e5               # k_r, N/m, Table 7\ndamping = 71.0                  # c_r, N s/m, Table 7\n";
    let speed = format!("speed = {v} ");
    let mut t = variant(&[(robot, ""), ("contact = \"quasi_static\" ", "contact = \"transient\" "), ("speed = 0.2 ", &speed)]);
    let dec = t.find("[decoupler]").unwrap();
    let tgt = t.find("[target]").unwrap();
    t.replace_range(dec..tgt, "[decoupler]\nkind = \"rigid\"\n\n");
    let sen = t.find("[sensor]").unwrap();
    t.replace_range(sen.., "[sensor]\nkind = \"force\"\nthreshold = 25.0\n");
    t = t.replacen("[motion]\n", "[motion]\nstart_at_speed = true\n", 1);
    t = t.replacen("gap = 0.05 ", "gap = 0.005 ", 1);
    parse(&t)
}

#[test]
fn the_shipped_hand_scene_passes_with_its_margins() {
    let sc = flinch_harness::shipped::load(&scene_path("body_hand.toml")).unwrap();
    let (s, _) = sim::run(&sc, false).unwrap();
    assert_eq!(s.body_region.as_deref(), Some("hand"));
    assert_eq!(s.body_contact.as_deref(), Some("quasi_static"));
    assert_eq!(s.body_force_limit_n, Some(140.0));
    assert_eq!(s.body_pressure_limit_pa, Some(190e4));
    let (f, m) = (s.body_peak_force_n.unwrap(), s.body_force_margin_n.unwrap());
    assert_eq!(f, s.peak_contact_force);
    assert!((m - (140.0 - f)).abs() < 1e-9 && m > 0.0, "{f} {m}");
    assert!((s.body_peak_pressure_pa.unwrap() - f / 1e-4).abs() < 1e-6);
    assert_eq!(s.body_limits_pass, Some(true));
    assert!(s.safe, "{:?}", s.failures);
    let line = verdict::body_line(&s).unwrap();
    assert!(line.contains("PASS") && line.contains("of 140.0 N"), "{line}");
    // Any other target: every body field null.
    let (o, _) = sim::run(&flinch_harness::shipped::load(&scene_path("tables5-7_bistable.toml")).unwrap(), false).unwrap();
    assert!(o.body_region.is_none() && o.body_peak_force_n.is_none() && o.body_limits_pass.is_none());
}

#[test]
fn a_limit_exceeded_fails_the_verdict() {
    // The rigid tool on the Viper presses the clamped hand at 0.2 m/s: far over 140 N.
    let text = variant(&[]);
    let dec = text.find("[decoupler]").unwrap();
    let tgt = text.find("[target]").unwrap();
    let mut t = text.clone();
    t.replace_range(dec..tgt, "[decoupler]\nkind = \"rigid\"\n\n");
    let sen = t.find("[sensor]").unwrap();
    t.replace_range(sen.., "[sensor]\nkind = \"force\"\nthreshold = 25.0\n");
    let (s, _) = sim::run(&parse(&t), false).unwrap();
    assert!(s.body_peak_force_n.unwrap() > 140.0, "{:?}", s.body_peak_force_n);
    assert!(s.body_force_margin_n.unwrap() < 0.0);
    assert_eq!(s.body_limits_pass, Some(false));
    assert!(!s.safe);
    assert!(s.failures.iter().any(|f| f.contains("hand and fingers") && f.contains("exceeds the quasi-static limit 140.0 N")), "{:?}", s.failures);
    assert!(flinch_harness::report::human(&s).contains("FAIL"));

    // The module passes on force, but a 0.2 cm^2 edge puts the pressure over 190 N/cm^2.
    let edge = variant(&[("area = 1e-4 ", "area = 0.2e-4 ")]);
    let (e, _) = sim::run(&parse(&edge), false).unwrap();
    assert!(e.body_force_margin_n.unwrap() > 0.0 && e.body_pressure_margin_pa.unwrap() < 0.0, "{e:?}");
    assert!(!e.safe && e.failures.iter().any(|f| f.contains("peak pressure")), "{:?}", e.failures);
}

#[test]
fn transient_contact_with_the_face_or_skull_always_fails() {
    for region in ["face", "skull"] {
        let t = variant(&[("region = \"hand\" ", &format!("region = \"{region}\" ")), ("contact = \"quasi_static\" ", "contact = \"transient\" "), ("speed = 0.2 ", "speed = 0.01 "), ("gap = 0.05 ", "gap = 0.002 ")]);
        let (s, _) = sim::run(&parse(&t), false).unwrap();
        assert!(s.t_contact.is_some());
        assert_eq!(s.body_force_limit_n, None);
        assert_eq!(s.body_limits_pass, Some(false));
        assert!(!s.safe && s.failures.iter().any(|f| f.contains("not permitted")), "{region}: {:?}", s.failures);
        // Clamped, the same region is held against its quasi-static limit instead.
        let q = variant(&[("region = \"hand\" ", &format!("region = \"{region}\" "))]);
        let (sq, _) = sim::run(&parse(&q), false).unwrap();
        assert!(sq.body_force_limit_n.is_some());
    }
}

#[test]
fn the_contact_is_the_linear_annex_a_spring_and_matches_the_closed_form() {
    // Rigid tool, prescribed flange, free hand: the peak is at a quarter period (4.4 ms), before
    // the 25 N sensor's 16 ms dead time ends, so braking does not enter: F = v sqrt(m_H k) exactly
    // for the undamped linear spring. Tolerance 0.1 % (integration and the in-step peak search).
    for v in [0.2, 0.8, 1.5] {
        let sc = rigid_free_hand(v);
        let (s, _) = sim::run(&sc, false).unwrap();
        let expected = v * (0.6f64 * 75e3).sqrt();
        let f = s.body_peak_force_n.unwrap();
        assert_eq!(s.body_force_limit_n, Some(280.0), "transient: twice Table A.2's 140 N");
        assert!((f / expected - 1.0).abs() < 1e-3, "v = {v}: simulated {f} N, energy formula {expected} N");
        // An elastic contact: the hand leaves at 2 v (m_R infinite).
        assert!((s.object_final_velocity.unwrap() / (2.0 * v) - 1.0).abs() < 1e-3);
    }
    // So the speed at the limit (280 N, transient) is the closed form's.
    let b = match rigid_free_hand(1.0).target.kind {
        scene::TargetKind::BodyRegion(b) => b,
        _ => unreachable!(),
    };
    let v_cf = b.closed_form_speed(f64::INFINITY).unwrap();
    let at = |v: f64| sim::run(&rigid_free_hand(v), false).unwrap().0;
    assert_eq!(at(v_cf * 0.995).body_limits_pass, Some(true));
    assert_eq!(at(v_cf * 1.005).body_limits_pass, Some(false));
}

#[test]
fn design_answers_per_region_with_and_without_the_module() {
    let t = Template::load(&scene_path("body_hand.toml")).unwrap();
    let r = body_design::design(&t, "hand", None, body_design::RIGID_SENSOR_N).unwrap();
    assert_eq!(r.regions.len(), 1);
    let h = &r.regions[0];
    let m = h.with_module.as_ref().unwrap();
    let (v_safe, v_mod, v_rigid) = (m.speed_safe_mps.unwrap(), m.speed_simulated_mps.unwrap(), h.rigid_tool.speed_simulated_mps.unwrap());
    // The module is credited: the clamped hand tolerates several times the rigid tool's speed.
    assert!(v_safe > 3.0 * v_rigid, "module {v_safe} vs rigid {v_rigid}");
    assert!(v_safe <= v_mod + 1e-9);
    assert_eq!(m.moving_mass_kg, Some(0.75));
    assert_eq!(h.rigid_tool.moving_mass_kg, Some(9.15));
    // Clamped: mu = m_R; closed form 140 / sqrt(m_R k).
    assert!((m.speed_closed_form_mps.unwrap() - 140.0 / (0.75f64 * 75e3).sqrt()).abs() < 1e-12);
    assert!((h.rigid_tool.speed_closed_form_mps.unwrap() - 140.0 / (9.15f64 * 75e3).sqrt()).abs() < 1e-12);
    // The closed form counts the impact only; the robot driving on until it brakes adds force, so
    // the simulated limits are below it.
    assert!(v_rigid < h.rigid_tool.speed_closed_form_mps.unwrap());

    // Transient hand, rigid tool on the compliant Viper: the closed form with m_R = m_r + m_t
    // agrees with the simulation within 1 % (measured 0.15 %: the impact, 8.6 ms, is short against
    // the robot's mode).
    let tr = Template::from_text(&variant(&[("contact = \"quasi_static\" ", "contact = \"transient\" ")]), "body.toml").unwrap();
    let r = body_design::design(&tr, "hand", None, body_design::RIGID_SENSOR_N).unwrap();
    let g = &r.regions[0].rigid_tool;
    let (sim_v, cf) = (g.speed_simulated_mps.unwrap(), g.speed_closed_form_mps.unwrap());
    assert!((sim_v / cf - 1.0).abs() < 0.01, "simulated {sim_v} vs closed form {cf}");

    // All regions; the face and skull in transient contact get no speed.
    let all = body_design::design(&tr, "all", None, body_design::RIGID_SENSOR_N).unwrap();
    assert_eq!(all.regions.len(), 12);
    for g in &all.regions {
        let banned = g.region == "face" || g.region == "skull";
        assert_eq!(g.force_limit_n.is_none(), banned, "{}", g.region);
        if banned {
            assert!(g.rigid_tool.speed_simulated_mps.is_none() && g.with_module.as_ref().unwrap().speed_safe_mps.is_none());
        }
    }
    assert!(body_design::design(&t, "elbow", None, 25.0).unwrap_err().contains("\"upper_arm\""));
    let not_body = Template::load(&scene_path("tables5-7_bistable.toml")).unwrap();
    assert!(body_design::design(&not_body, "hand", None, 25.0).unwrap_err().contains("body_region"));
}

#[test]
fn body_keys_are_checked() {
    let bad = variant(&[("area = 1e-4 ", "area = 1e-4\nrestitution = 0.5 ")]);
    let e = scene::parse(&bad, "b.toml").unwrap_err().to_string();
    assert!(e.contains("target.restitution") && e.contains("body_region"), "{e}");
    let e = scene::parse(&variant(&[("region = \"hand\" ", "region = \"finger\" ")]), "b.toml").unwrap_err().to_string();
    assert!(e.contains("target.region") && e.contains("\"hand\"") && e.contains("finger"), "{e}");
    let e = scene::parse(&variant(&[("area = 1e-4 ", "area = 0.5 ")]), "b.toml").unwrap_err().to_string();
    assert!(e.contains("target.area") && e.contains("m^2"), "{e}");
    let e = scene::parse(&variant(&[("area = 1e-4 ", "")]), "b.toml").unwrap_err().to_string();
    assert!(e.contains("target.area"), "{e}");
    // Overrides replace the preset.
    let o = parse(&variant(&[("area = 1e-4 ", "area = 1e-4\nmass = 1.0\nstiffness = 5e4 ")]));
    match o.target.kind {
        scene::TargetKind::BodyRegion(b) => assert_eq!((b.mass_kg, b.stiffness_n_per_m, b.region.mass_kg), (1.0, 5e4, 0.6)),
        _ => panic!("not a body region"),
    }
}
