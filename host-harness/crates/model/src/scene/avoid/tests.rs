//! The avoidance loader's unit tests: every refusal names its key and line.

use super::{parse::*, checks::*};


const SHIPPED: &str = include_str!("../../../../../../scenes/avoid_thesis_reach.toml");

/// The scene's problems as `flinch avoid` prints them (`line N:` without a file name).
fn check(text: &str, file: &str) -> Result<(), String> {
    parse(text, file).map(|_| ()).map_err(|e| if file.is_empty() { without_file(&e) } else { e.to_string() })
}

fn refused(from: &str, to: &str) -> String {
    let mut text = SHIPPED.to_string();
    for (f, t) in from.split(';').zip(to.split(';')) {
        assert!(text.contains(f), "{f} not in the scene");
        text = text.replacen(f, t, 1);
    }
    check(&text, "s.toml").expect_err(to)
}

#[test]
fn shipped_avoid_scenes_pass() {
    for f in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../scenes")).unwrap() {
        let p = f.unwrap().path();
        if p.file_name().unwrap().to_string_lossy().starts_with("avoid_") {
            let text = std::fs::read_to_string(&p).unwrap();
            check(&text, "x").unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        }
    }
}

#[test]
fn refusals_name_file_line_key_range_and_source() {
    let e = refused("k_rep = 0.6 ", "k_rep = 1e9 ");
    assert!(e.starts_with("s.toml:12: avoid.k_rep: allowed range [0, 100] m/s (k_r of eq 75/76"), "{e}");
    assert!(e.ends_with("got 1e9"), "{e}");
    let e = refused("start_m = [0.12, 0.50]", "start_m = [0.12, 0.50, 0.3]");
    assert!(e.starts_with("s.toml:9: avoid.start_m: must be [x, y], exactly two numbers, got 3 values"), "{e}");
    let e = refused("hand_radius_m = 0.05", "hand_radius_m = nan");
    assert!(e.contains("avoid.operator.hand_radius_m: must be a finite number; allowed range (0, 0.5] m") && e.contains("got NaN"), "{e}");
    // Every problem at once, in line order.
    let text = SHIPPED.replacen("speed_mps = 0.25 ", "speed_mps = 1e9 ", 1).replacen("noise_mm = 3.0", "noise_mm = nan", 1).replacen("t_s = 1.2", "t_s = -1", 1);
    let all = check(&text, "s.toml").unwrap_err();
    assert_eq!(all.lines().count(), 3, "{all}");
    assert!(all.lines().next().unwrap().starts_with("s.toml:11: avoid.speed_mps: allowed range (0, 3] m/s"), "{all}");
    assert!(all.lines().nth(2).unwrap().contains("avoid.operator.keyframes[1].t_s: allowed range [0, 600] s"), "{all}");
    // Without a file name, `line N:` as `avoid::scene::Avoid::parse` reports.
    let e = check(&SHIPPED.replacen("dt_s = 0.01", "dt_s = 1e9", 1), "").unwrap_err();
    assert!(e.starts_with("line 14: avoid.dt_s: allowed range [1e-4, 0.1] s"), "{e}");
}

/// sigma' > spacing used to pass the loader and then be refused by the MCU on every frame (the
/// robot never moved, silently). Refused here with the file, line and key; at the bound the
/// firmware's receiver accepts the frame, just past it it refuses it: the two limits agree.
#[test]
fn sigma_wider_than_the_spacing_is_refused_where_the_mcu_would_refuse_it() {
    let e = refused("eval_sigma_factor = 1.5 ", "eval_sigma_factor = 2.5 ");
    assert!(e.starts_with("s.toml:37: avoid.fit.eval_sigma_factor: sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = 1.25 x spacing"), "{e}");
    assert!(e.contains("at most 1 x spacing") && e.contains("got eval_sigma_factor = 2.5 with sigma_factor = 1"), "{e}");
    let e = refused("sigma_factor = 1.0 ", "sigma_factor = 1.5 ");
    assert!(e.contains("avoid.fit.eval_sigma_factor: sigma' = sigma_factor x eval_sigma_factor x spacing / 2 = 1.125 x spacing"), "{e}");
    // At the bound (the shipped demo's 1.0 x 2.0) the loader passes it.
    check(&SHIPPED.replacen("eval_sigma_factor = 1.5 ", "eval_sigma_factor = 2.0 ", 1), "s.toml").unwrap();
    // The firmware, through the wire's Q16.16 geometry, for every grid the loader allows.
    use flinch_firmware::avoidance::{self as fw, num::I16F16};
    for n in 1..=30usize {
        let spacing = 1.05 / n as f64;
        for (ratio, accepted) in [(MAX_EVAL_SIGMA_OVER_SPACING, true), (MAX_EVAL_SIGMA_OVER_SPACING * 1.01, false)] {
            let q = |v: f64| (v * 65536.0).round() as i32;
            let h = fw::FrameHeader { session: 0, nx: n as u8, ny: n as u8, seq: 1, age_ms: 0, x0_q16: q(spacing / 2.0), y0_q16: q(spacing / 2.0), spacing_q16: q(spacing), sigma_q16: q(ratio * spacing), ..fw::FrameHeader::default() };
            let mut out = vec![0u8; fw::frame::MAX_FRAME];
            let len = fw::encode_frame(&h, &vec![0; n * n], &mut out).unwrap();
            let mut rx = Box::new(fw::Receiver::<I16F16>::new(100, 10));
            rx.feed(&out[..len], 0);
            assert_eq!(rx.stats.good == 1, accepted, "grid {n}, sigma'/s = {ratio}: {:?}", rx.stats);
        }
    }
}

#[test]
fn work_caps_refuse_what_would_crash_or_hang() {
    for (from, to, key) in [
        ("m_per_px = 0.005", "m_per_px = 1e9", "avoid.camera.m_per_px: allowed range"),
        ("m_per_px = 0.005", "m_per_px = 0.05", "avoid.camera.m_per_px: the image covers 10.5 m x 10.5 m"),
        ("calibration_step_m = 0.05", "calibration_step_m = 1e-9", "avoid.robot.calibration_step_m: allowed range"),
        ("calibration_step_m = 0.05;calibration_dilate_m = 0.035", "calibration_step_m = 0.005;calibration_dilate_m = 0.004", "avoid.robot.calibration_step_m: the calibration zig-zag has"),
        ("calibration_dilate_m = 0.035", "calibration_dilate_m = 1e9", "avoid.robot.calibration_dilate_m: allowed range"),
        ("calibration_dilate_m = 0.035", "calibration_dilate_m = -1", "avoid.robot.calibration_dilate_m: allowed range"),
        ("calibration_dilate_m = 0.035", "calibration_dilate_m = 0.35", "avoid.robot.calibration_dilate_m: must be at most calibration_step_m"),
        ("calibration_threshold_m = 0.10", "calibration_threshold_m = 0.05", "avoid.robot.calibration_threshold_m: must be above fit.offset_m"),
        ("max_time_s = 12.0", "max_time_s = 600", "avoid.frame_period_s: 18183 frames"),
        ("max_time_s = 12.0;dt_s = 0.01", "max_time_s = 200;dt_s = 0.0001", "avoid.dt_s: max_time_s / dt_s = 2e6 control steps"),
        ("camera_height_m = 1.2", "camera_height_m = 0.3", "avoid.robot.wrist_height_m: must be below the camera"),
    ] {
        let e = refused(from, to);
        assert!(e.contains(key), "{to}: {e}");
    }
}

/// Issue 29 item 7: a start or a goal inside the edge margin (the steering keeps the tool's centre
/// `robot.wrist_radius_m` inside the view) is refused by name, the margin and the allowed box said;
/// on the margin's inner edge it is accepted.
#[test]
fn start_or_goal_in_the_edge_margin_is_refused() {
    let e = refused("start_m = [0.12, 0.50]", "start_m = [0.02, 0.50]");
    assert!(e.contains("avoid.start_m") && e.contains("wrist_radius_m = 0.045") && e.contains("edge margin"), "{e}");
    let e = refused("goal_m = [0.93, 0.50]", "goal_m = [0.93, 1.04]");
    assert!(e.contains("avoid.goal_m") && e.contains("[0.045, 1.005]"), "{e}");
    check(&SHIPPED.replace("goal_m = [0.93, 0.50]", "goal_m = [1.005, 0.50]"), "x").unwrap();
}

/// Obstacle classes (issue 29 item 2): `class = "fixture"` is read, a moving fixture is refused
/// on `class` with the file and line, an unknown class on `class` with the choices.
#[test]
fn a_fixture_must_stand_and_the_class_is_checked() {
    let tray = include_str!("../../../../../../scenes/avoid_tray_beside_goal.toml");
    let s = parse(tray, "t.toml").unwrap();
    assert!(s.operator.obstacles[0].fixture);
    assert_eq!(s.safety.fixture_tolerance_m, 0.01);
    let moving = tray.replacen("center_m = [0.80, 0.25]", "keyframes = [{ t_s = 0.0, x_m = 0.8, y_m = 0.25 }, { t_s = 1.0, x_m = 0.7, y_m = 0.25 }]", 1);
    let e = check(&moving, "t.toml").unwrap_err();
    assert!(e.contains("t.toml:") && e.contains("avoid.operator.obstacles[0].class: a fixture stands still"), "{e}");
    let e = check(&tray.replacen("\nclass = \"fixture\"", "\nclass = \"tray\"", 1), "t.toml").unwrap_err();
    assert!(e.contains("avoid.operator.obstacles[0].class") && e.contains("fixture"), "{e}");
    let e = check(&tray.replacen("[avoid.camera]", "[avoid.safety]\nfixture_tolerance_m = 0.5\n\n[avoid.camera]", 1), "t.toml").unwrap_err();
    assert!(e.contains("avoid.safety.fixture_tolerance_m: allowed range [0, 0.1] m"), "{e}");
}
