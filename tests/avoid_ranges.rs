//! Issue 18, avoidance scenes: every number has a physical range and the work a scene asks for is
//! capped, so what used to crash or hang `flinch avoid` (with `--thesis`, which runs the calibration
//! pass) is refused by the loader with `file:line: key: ...`, never a panic, an abort or a minute of
//! CPU. One test per case the audit found; the ranges themselves are `scene::avoid` (one table,
//! also listed in docs/SCENES.md).
use flinch_harness::avoid::path::{simulate, Engine, Setup};
use flinch_harness::avoid::scene::Avoid;
use flinch_tests::scene_path;
use std::time::Instant;

fn shipped() -> String {
    std::fs::read_to_string(scene_path("avoid_thesis_reach.toml")).unwrap()
}

/// The shipped scene with `from` replaced by `to`, loaded from a file as `flinch avoid` does.
fn load(from: &str, to: &str) -> Result<Avoid, String> {
    let text = shipped();
    assert!(text.contains(from), "{from}");
    let dir = std::env::temp_dir().join(format!("flinch-avoid-ranges-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let name = to.split([' ', '=']).next().unwrap().to_string();
    let path = dir.join(format!("{name}-{}.toml", to.len()));
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    let r = Avoid::load(&path);
    let _ = std::fs::remove_file(&path);
    r.map_err(|e| e.replace(&path.display().to_string(), "scene.toml"))
}

fn refused(from: &str, to: &str, key: &str) -> String {
    let e = load(from, to).err().unwrap_or_else(|| panic!("{to} accepted"));
    let line = shipped().lines().position(|l| l.contains(from)).unwrap() + 1;
    assert!(e.starts_with(&format!("scene.toml:{line}: {key}: ")), "{to}: {e}");
    e
}

#[test]
fn pixel_size_1e9_is_refused_not_an_overflow() {
    let e = refused("m_per_px = 0.005", "m_per_px = 1e9", "avoid.camera.m_per_px");
    assert!(e.contains("allowed range [2e-4, 0.05] m (a depth camera") && e.ends_with("got 1e9"), "{e}");
}

#[test]
fn pixel_size_5_is_refused_not_gigabytes() {
    refused("m_per_px = 0.005", "m_per_px = 5", "avoid.camera.m_per_px");
}

#[test]
fn an_image_wider_than_a_camera_sees_is_refused() {
    let e = refused("m_per_px = 0.005", "m_per_px = 0.049", "avoid.camera.m_per_px");
    assert!(e.contains("the image covers 10.29 m x 10.29 m"), "{e}");
}

#[test]
fn calibration_step_1e_9_is_refused_not_a_capacity_overflow() {
    refused("calibration_step_m = 0.05", "calibration_step_m = 1e-9", "avoid.robot.calibration_step_m");
}

#[test]
fn a_calibration_grid_beyond_the_work_cap_is_refused() {
    let text = shipped().replacen("calibration_dilate_m = 0.035", "calibration_dilate_m = 0.01", 1);
    let e = Avoid::parse(&text.replacen("calibration_step_m = 0.05", "calibration_step_m = 0.01", 1)).unwrap_err();
    assert!(e.contains("avoid.robot.calibration_step_m: the calibration zig-zag has 11025 positions") && e.contains("--thesis"), "{e}");
}

#[test]
fn mask_growth_1e9_35_and_negative_are_refused() {
    refused("calibration_dilate_m = 0.035", "calibration_dilate_m = 1e9", "avoid.robot.calibration_dilate_m");
    refused("calibration_dilate_m = 0.035", "calibration_dilate_m = -1", "avoid.robot.calibration_dilate_m");
    // 35 m ran for more than 30 s.
    refused("calibration_dilate_m = 0.035", "calibration_dilate_m = 35", "avoid.robot.calibration_dilate_m");
    let e = refused("calibration_dilate_m = 0.035", "calibration_dilate_m = 0.2", "avoid.robot.calibration_dilate_m");
    assert!(e.contains("must be at most calibration_step_m = 0.05 m"), "{e}");
}

#[test]
fn speed_gain_and_period_1e9_are_refused() {
    refused("speed_mps = 0.25 ", "speed_mps = 1e9 ", "avoid.speed_mps");
    refused("k_rep = 0.6 ", "k_rep = 1e9 ", "avoid.k_rep");
    refused("dt_s = 0.01 ", "dt_s = 1e9 ", "avoid.dt_s");
}

#[test]
fn nan_is_refused_where_it_came_out_as_null() {
    for (from, to, key) in [
        ("k_rep = 0.6 ", "k_rep = nan ", "avoid.k_rep"),
        ("hand_radius_m = 0.05", "hand_radius_m = nan", "avoid.operator.hand_radius_m"),
        ("noise_mm = 3.0", "noise_mm = nan", "avoid.camera.noise_mm"),
        ("noise_mm = 3.0", "noise_mm = -1", "avoid.camera.noise_mm"),
    ] {
        refused(from, to, key);
    }
}

#[test]
fn a_point_has_exactly_two_coordinates() {
    let e = refused("start_m = [0.12, 0.50]", "start_m = [0.12, 0.50, 0.3]", "avoid.start_m");
    assert!(e.contains("exactly two numbers, got 3 values"), "{e}");
    refused("start_m = [0.12, 0.50]", "start_m = [0.12]", "avoid.start_m");
    refused("base_m = [0.55, 1.30]", "base_m = [0.55, 1e9]", "avoid.robot.base_m");
    let e = refused("{ t_s = 1.2, hand_m = [0.50, 0.42] }", "{ t_s = 1.2, hand_m = [0.50, inf] }", "avoid.operator.keyframes[1].hand_m");
    assert!(e.contains("y: allowed range [-10, 10] m"), "{e}");
}

#[test]
fn every_problem_is_reported_at_once() {
    let text = shipped()
        .replacen("speed_mps = 0.25 ", "speed_mps = 1e9 ", 1)
        .replacen("k_rep = 0.6 ", "k_rep = nan ", 1)
        .replacen("m_per_px = 0.005", "m_per_px = 5", 1)
        .replacen("calibration_dilate_m = 0.035", "calibration_dilate_m = -1", 1);
    let e = Avoid::parse(&text).unwrap_err();
    assert_eq!(e.lines().count(), 4, "{e}");
    for key in ["avoid.speed_mps", "avoid.k_rep", "avoid.camera.m_per_px", "avoid.robot.calibration_dilate_m"] {
        assert!(e.contains(key), "{key}: {e}");
    }
}

/// Every numeric key of every shipped avoidance scene has a range in the table (a key added to the
/// scenes without one fails here).
#[test]
fn every_number_in_the_shipped_scenes_has_a_range() {
    let tables = flinch_harness::scene::key_tables();
    fn walk(path: &str, v: &toml_edit::Item, out: &mut Vec<String>) {
        if let Some(t) = v.as_table_like() {
            for (k, item) in t.iter() {
                walk(&if path.is_empty() { k.to_string() } else { format!("{path}.{k}") }, item, out);
            }
        } else if let Some(a) = v.as_value().and_then(|v| v.as_array()) {
            if let Some(t) = a.get(0).and_then(|x| x.as_inline_table()) {
                for (k, x) in t.iter() {
                    walk(&format!("{path}[].{k}"), &toml_edit::Item::Value(x.clone()), out);
                }
            } else if a.iter().all(|x| x.is_float() || x.is_integer()) {
                out.push(path.to_string());
            }
        } else if v.as_float().is_some() || v.as_integer().is_some() {
            out.push(path.to_string());
        }
    }
    for f in std::fs::read_dir(scene_path("")).unwrap() {
        let p = f.unwrap().path();
        if !p.file_name().unwrap().to_string_lossy().starts_with("avoid_") {
            continue;
        }
        let doc: toml_edit::DocumentMut = std::fs::read_to_string(&p).unwrap().parse().unwrap();
        let mut keys = Vec::new();
        walk("", doc.as_item(), &mut keys);
        for k in keys.iter().filter(|k| !k.ends_with(".seed")) {
            let (table, name) = k.rsplit_once('.').unwrap();
            assert!(
                tables.iter().any(|t| t.path == table && t.keys.iter().any(|key| key.name == name && key.span().is_some() || matches!(key.ty, flinch_harness::scene::Ty::Integer { .. }) && key.name == name)),
                "{}: {k} has no range in scene::key_tables()",
                p.display()
            );
        }
    }
}

/// The corners of the work caps run, and in bounded time: the calibration at its cap (9.7e7
/// pixels, 7.8 s in release) is the slowest accepted; here a smaller grid at the largest growth
/// allowed, in debug.
#[test]
fn an_accepted_corner_runs_with_thesis_calibration() {
    let mut scene = load("calibration_dilate_m = 0.035", "calibration_dilate_m = 0.05").unwrap();
    scene.camera.width_px = 105;
    scene.camera.height_px = 105;
    scene.camera.m_per_px = 0.01;
    scene.robot.calibration_step_m = 0.25;
    scene.robot.calibration_dilate_m = 0.25;
    scene.thesis_mode();
    let t0 = Instant::now();
    let setup = Setup::new(&scene, None).unwrap();
    let r = simulate(&scene, &setup, Engine::Reference).unwrap();
    assert!(r.min_signed_distance_m.is_finite());
    assert!(t0.elapsed().as_secs_f64() < 60.0, "{:?}", t0.elapsed());
}

/// Review finding: the verdict and the monitor take v_h, T_r and T_s from the scene, so a scene with
/// `human_speed_mps = 0` reached the goal at cruise speed 75 mm from a moving hand and called it
/// safe. A person is at least 1.6 m/s (ISO 13855:2010 6.2), and T_r holds at least one control
/// period (a command stands for a whole step): both are refused by name.
#[test]
fn a_human_slower_than_iso_13855_or_a_reaction_shorter_than_a_step_is_refused() {
    let with = |dt: &str, safety: &str| {
        let text = shipped().replacen("dt_s = 0.01", dt, 1) + "\n[avoid.safety]\n" + safety + "\n";
        let path = std::env::temp_dir().join(format!("flinch-avoid-ssm-{}-{}.toml", std::process::id(), text.len()));
        std::fs::write(&path, &text).unwrap();
        let r = Avoid::load(&path);
        let _ = std::fs::remove_file(&path);
        r.map_err(|e| e.replace(&path.display().to_string(), "scene.toml"))
    };
    let lines = shipped().lines().count();
    let e = with("dt_s = 0.01", "human_speed_mps = 0.0").unwrap_err();
    assert!(e.starts_with(&format!("scene.toml:{}: avoid.safety.human_speed_mps: ", lines + 3)), "{e}");
    assert!(e.contains("allowed range [1.6, 10] m/s") && e.contains("ISO 13855"), "{e}");
    let e = with("dt_s = 0.05", "reaction_time_s = 0.02").unwrap_err();
    assert!(e.contains("avoid.safety.reaction_time_s: T_r must cover at least one control period (dt_s = 0.05 s"), "{e}");
    // At the edges: accepted.
    with("dt_s = 0.02", "reaction_time_s = 0.02\nhuman_speed_mps = 1.6").unwrap();
}

/// One loader for impact and avoidance scenes (issue 18): the structure of an avoidance scene is
/// checked by the same key tables as its numbers, so an unknown key, a wrong type and key frames
/// out of order are refused as the impact loader refuses them, `file:line: key: what is allowed,
/// got what`, every problem at once and in line order.
#[test]
fn structure_errors_name_file_line_key_and_what_is_allowed() {
    // An unknown key, with the list of the allowed ones.
    let e = load("k_rep = 0.6 ", "k_rep = 0.6\nk_repp = 0.6 ").unwrap_err();
    assert!(e.starts_with("scene.toml:13: avoid.k_repp: unknown key; allowed keys: start_m, goal_m, speed_mps, k_rep, repulsion,"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    let e = load("noise_mm = 3.0", "noise_mm = 3.0\nnoise = 3.0").unwrap_err();
    assert!(e.starts_with("scene.toml:31: avoid.camera.noise: unknown key; allowed keys: width_px, height_px, m_per_px, camera_height_m, noise_mm, null_fraction, seed"), "{e}");
    let e = refused("{ t_s = 1.2, hand_m = [0.50, 0.42] }", "{ t_s = 1.2, hand = [0.50, 0.42] }", "avoid.operator.keyframes[1].hand");
    assert!(e.contains("unknown key; allowed keys: t_s, hand_m"), "{e}");
    // The top level holds only [avoid].
    let e = load("[avoid]\n", "name = \"x\"\n[avoid]\n").unwrap_err();
    assert!(e.starts_with("scene.toml:8: name: unknown key; an avoidance scene holds only the table [avoid]"), "{e}");
    // Wrong types.
    let e = refused("seed = 7", "seed = 7.5", "avoid.camera.seed");
    assert!(e.contains("must be an integer >= 0, a whole number (write it without a decimal point), got 7.5"), "{e}");
    let e = refused("seed = 7", "seed = -7", "avoid.camera.seed");
    assert!(e.ends_with("must be an integer >= 0, got -7"), "{e}");
    let e = refused("repulsion = \"vortex\"", "repulsion = 1", "avoid.repulsion");
    assert!(e.contains("must be one of \"vortex\" | \"vortex_cw\" | \"vortex_ccw\" | \"gradient\", got integer"), "{e}");
    let e = refused("speed_mps = 0.25 ", "speed_mps = \"fast\" ", "avoid.speed_mps");
    assert!(e.contains("must be a number in (0, 3] m/s, got string"), "{e}");
    let e = refused("grid = 15 ", "grid = 15.0 ", "avoid.fit.grid");
    assert!(e.contains("write it without a decimal point"), "{e}");
    let e = load("offset_m = 0.065 ", "offset_m = 0.065\nremove_plane = \"yes\" ").unwrap_err();
    assert_eq!(e, "scene.toml:39: avoid.fit.remove_plane: must be true or false, got string");
    let e = load("stall_move_m = 0.005", "stall_move_m = 0.005\nbaud = 9600.0").unwrap_err();
    assert_eq!(e, "scene.toml:24: avoid.baud: must be a number in [300, 2e7] bit/s, a whole number (write it without a decimal point), got 9600.0");
    const FRAMES: &str = "keyframes = [\n  { t_s = 0.0, hand_m = [0.48, 0.10] },\n  { t_s = 1.2, hand_m = [0.50, 0.42] },\n  { t_s = 5.0, hand_m = [0.53, 0.44] },\n]";
    let e = load(FRAMES, "keyframes = 3").unwrap_err();
    assert_eq!(e, "scene.toml:56: avoid.operator.keyframes: must be a list of at least one key frame { t_s, hand_m }, t_s increasing, got integer");
    let e = load(FRAMES, "keyframes = [1, { t_s = 0.0, hand_m = [0.48, 0.10] }]").unwrap_err();
    assert!(e.starts_with("scene.toml:56: avoid.operator.keyframes: must be a list of at least one key frame") && e.ends_with("got integer at position 1"), "{e}");
    // Key frames out of order, each refusal at its own line.
    let e = refused("{ t_s = 5.0, hand_m = [0.53, 0.44] }", "{ t_s = 1.0, hand_m = [0.53, 0.44] }", "avoid.operator.keyframes[2].t_s");
    assert!(e.contains("must be after the key frame before it (avoid.operator.keyframes[1].t_s = 1.2 s): key frames' t_s must increase, got 1"), "{e}");
    let e = load(FRAMES, "keyframes = []").unwrap_err();
    assert_eq!(e, "scene.toml:56: avoid.operator.keyframes: must hold at least one key frame { t_s, hand_m }, got none");
    // Everything at once, in line order: an unknown key, a wrong type, a range, an order.
    let text = shipped()
        .replacen("k_rep = 0.6 ", "k_repp = 0.6 ", 1)
        .replacen("seed = 7", "seed = \"seven\"", 1)
        .replacen("grid = 15 ", "grid = 40 ", 1)
        .replacen("{ t_s = 5.0,", "{ t_s = 0.5,", 1);
    let e = Avoid::parse(&text).unwrap_err();
    let lines: Vec<&str> = e.lines().collect();
    assert_eq!(lines.len(), 5, "{e}");
    for (l, want) in lines.iter().zip(["line 8: avoid.k_rep: missing required key: a number in [0, 100] m/s", "line 12: avoid.k_repp: unknown key", "line 32: avoid.camera.seed: must be an integer >= 0, got string", "line 35: avoid.fit.grid: must be an integer in [1, 30], got 40", "line 59: avoid.operator.keyframes[2].t_s: must be after"]) {
        assert!(l.starts_with(want), "{l}\n{e}");
    }
}
