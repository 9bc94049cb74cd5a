//! `flinch avoid --depth` (issue 11, item 1): recorded depth frames in the loop.
//!
//! The fixtures are the project's own: the shipped demo (`avoid_operator_hand.toml`) rendered
//! through a pinhole camera 1.5 m over the middle of the plane (240 x 240 px, f = 160 px: 9.4 mm a
//! pixel on the plane), with the robot where the synthetic run put it at each frame, written in both
//! depth conventions (RealSense's 1 mm and TUM's 0.2 mm a count). Generated at test time into a
//! temporary directory.

use std::path::{Path, PathBuf};

use flinch_harness::avoid::path::{simulate, Engine, PathResult, Setup, Status};
use flinch_harness::avoid::recorded::{self, render_recording};
use flinch_harness::avoid::scene::Avoid;
use flinch_harness::avoid::{self, AvoidArgs, AvoidMetrics};

const CAMERA: &str = "
[avoid.depth_camera]
fx_px = 160.0
fy_px = 160.0
cx_px = 119.5
cy_px = 119.5
depth_scale_m = 0.001
position_m = [1.05, 1.05]
height_m = 1.5
";

fn scene() -> (String, Avoid) {
    let text = std::fs::read_to_string(flinch_tests::scene_path("avoid_operator_hand.toml")).unwrap() + CAMERA;
    let s = Avoid::parse(&text).unwrap();
    (text, s)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flinch-avoid-recorded-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The synthetic reference run's tool at every camera period (30 Hz), one second past its end.
fn track(scene: &Avoid, res: &PathResult) -> Vec<(f64, [f64; 2])> {
    let end = res.points.len() as f64 * scene.dt_s + 1.0;
    let n = (end / scene.frame_period_s).ceil() as usize;
    (0..n)
        .map(|k| {
            let t = k as f64 * scene.frame_period_s;
            let i = ((t / scene.dt_s).round() as usize).min(res.points.len() - 1);
            (t, res.points[i])
        })
        .collect()
}

fn metrics(res: &PathResult) -> serde_json::Value {
    serde_json::to_value(AvoidMetrics::new(res, Engine::Reference, true)).unwrap()
}

fn args(scene: &Path, depth: &Path, poses: Option<PathBuf>) -> AvoidArgs {
    AvoidArgs { depth: Some(depth.to_path_buf()), robot_poses: poses, ..flinch_tests::avoid::args(scene.to_path_buf()) }
}

/// Recorded frames of the demo, in both conventions, give one and the same run, which arrives as the
/// synthetic one does; through the CLI's entry point too.
#[test]
fn recorded_frames_in_both_conventions_give_the_same_run() {
    let (text, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let synthetic = simulate(&scene, &setup, Engine::Reference).unwrap();
    assert_eq!(synthetic.status, Status::Reached);
    let root = tmp("conventions");
    let (mm, tum) = (root.join("realsense"), root.join("tum"));
    render_recording(&scene, &[(&mm, 0.001), (&tum, 0.0002)], 240, 240, &track(&scene, &synthetic)).unwrap();

    let mut tum_scene = scene.clone();
    tum_scene.depth_camera.as_mut().unwrap().depth_scale_m = 0.0002;
    let poses = mm.join("poses.csv");
    let (a, sa) = recorded::simulate(&scene, &setup, Engine::Reference, &mm, Some(&poses)).unwrap();
    let (b, sb) = recorded::simulate(&tum_scene, &setup, Engine::Reference, &tum, Some(&poses)).unwrap();
    assert_eq!(metrics(&a), metrics(&b), "the two conventions differ");
    assert_eq!(a.points, b.points);
    assert_eq!((sa.frames_used, sa.max_filled_cells), (sb.frames_used, sb.max_filled_cells));

    // The same outcome as the synthetic camera (the recorded frames hold the same scene), but
    // unverified: the verdict is the scene model's, not the recording's.
    assert_eq!(a.status, Status::Unverified(None), "{:?}", metrics(&a));
    assert!(a.min_signed_distance_m >= scene.clearance_m, "{}", a.min_signed_distance_m);
    let (ta, ts) = (a.time_to_goal_s.unwrap(), synthetic.time_to_goal_s.unwrap());
    assert!((ta - ts).abs() < 2.0, "recorded {ta} s, synthetic {ts} s");
    assert!((a.min_signed_distance_m - synthetic.min_signed_distance_m).abs() < 0.05, "recorded {} m, synthetic {} m", a.min_signed_distance_m, synthetic.min_signed_distance_m);
    // The random null pixels (1 %) were filled, and little of the plane is ever unknown.
    assert!(sa.max_filled_cells > 0 && sa.max_unknown_fraction < 0.01, "{sa:?}");

    // Same through the CLI's entry point, and with the MCU engine.
    let file = root.join("scene.toml");
    std::fs::write(&file, &text).unwrap();
    assert_eq!(avoid::run(&args(&file, &mm, Some(poses.clone()))).map(|v| v.code()), Ok(5));
    let (m, _) = recorded::simulate(&scene, &setup, Engine::Mcu, &mm, Some(&poses)).unwrap();
    assert_eq!(m.status, Status::Unverified(None), "--mcu on the recording");
    let rx = m.rx.unwrap();
    assert_eq!((rx.bad_crc, rx.bad_header, rx.short), (0, 0, 0));
    std::fs::remove_dir_all(&root).ok();
}

/// A hole in the depth image over the hand (a 0.3 m square of null pixels, as glare or a black
/// glove gives): unknown is an obstacle, so the tool never enters the hand. Painted over as table
/// instead (what the neighbour-mean fill did), the same frames send it through the hand: the test
/// can tell the two apart.
#[test]
fn a_null_hole_over_the_hand_is_an_obstacle() {
    let (_, mut scene) = scene();
    // Straight at the hand, no field: only what is sensed can stop it.
    scene.k_rep = 0.0;
    scene.max_time_s = 12.0;
    let setup = Setup::new(&scene, None).unwrap();
    // The robot stays where it starts; the hole covers everything the camera sees within 0.15 m
    // of the operator (hand, forearm, the floor round them): the operator is not seen at all.
    let track: Vec<(f64, [f64; 2])> = (0..(12.0 / scene.frame_period_s) as usize).map(|k| (k as f64 * scene.frame_period_s, scene.start_m)).collect();
    let root = tmp("hole");
    let (dir, table) = (root.join("hole"), root.join("table"));
    render_recording(&scene, &[(&dir, 0.001), (&table, 0.001)], 240, 240, &track).unwrap();
    let cam = flinch_harness::avoid::camera::Pinhole::new(scene.depth_camera.as_ref().unwrap());
    let hand = scene.hand_at(0.0);
    for k in 0..track.len() {
        let name = format!("{k:05}.png");
        for (d, as_table) in [(&dir, false), (&table, true)] {
            let p = d.join(&name);
            let mut img = flinch_harness::avoid::depth::DepthImage::load(&p).unwrap();
            for v in 0..img.height {
                for u in 0..img.width {
                    let c = &mut img.mm[v * img.width + u];
                    let q = cam.unproject(u as f64, v as f64, cam.depth_m(*c));
                    if (q[0] - hand[0]).abs() < 0.15 && q[1] < hand[1] + 0.15 {
                        // Null, or the plane's depth along this ray (the hand erased).
                        *c = if as_table { (cam.origin[2] / -cam.ray(u as f64, v as f64)[2] * 1e3).round() as u16 } else { 0 };
                    }
                }
            }
            img.save(&p).unwrap();
        }
    }
    let poses = dir.join("poses.csv");
    let (hole, st) = recorded::simulate(&scene, &setup, Engine::Reference, &dir, Some(&poses)).unwrap();
    assert!(st.max_unknown_fraction > 0.015, "the hole is unknown: {st:?}");
    assert!(hole.min_signed_distance_m > 0.0, "never inside the hand: {}", hole.min_signed_distance_m);
    // The unknown region is an obstacle: the tool stops short of it, or the steering takes it
    // round with the clearance asked for (issue 9's barrier on the sensed separation).
    match hole.status {
        Status::Unverified(Some(_)) => {}
        Status::Unverified(None) => assert!(hole.min_signed_distance_m >= scene.clearance_m, "reached, but {} from the hand", hole.min_signed_distance_m),
        ref s => panic!("{s:?}"),
    }
    let (erased, _) = recorded::simulate(&scene, &setup, Engine::Reference, &table, Some(&poses)).unwrap();
    assert!(erased.min_signed_distance_m < 0.0, "painted as table, it goes in: {}", erased.min_signed_distance_m);
    std::fs::remove_dir_all(&root).ok();
}

/// Without `--robot-poses` nothing is removed: the robot at the tool is an obstacle at zero
/// separation all round it, inside the protective separation in every direction from the first
/// frame: the tool never moves (held in a protective stop, `blocked`; a start inside `S_p(0)` is
/// no longer `no_room` since moving away is free where there is an away, issue 29).
#[test]
fn without_poses_the_robot_is_an_obstacle() {
    let (_, mut scene) = scene();
    scene.max_time_s = 2.0;
    let setup = Setup::new(&scene, None).unwrap();
    let track: Vec<(f64, [f64; 2])> = (0..61).map(|k| (k as f64 * scene.frame_period_s, scene.start_m)).collect();
    let root = tmp("noposes");
    render_recording(&scene, &[(&root, 0.001)], 240, 240, &track).unwrap();
    let (res, _) = recorded::simulate(&scene, &setup, Engine::Reference, &root, None).unwrap();
    assert_eq!(res.status, Status::Unverified(Some(flinch_harness::avoid::path::Reason::Blocked)));
    assert!(res.path_length_m < 1e-9, "{}", res.path_length_m);
    std::fs::remove_dir_all(&root).ok();
}

/// An 8-bit image, a truncated PNG and PGM, a name that is no time: refused, naming the file.
#[test]
fn bad_files_are_refused_naming_them() {
    let (_, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let root = tmp("bad");
    let run = |d: &Path| recorded::simulate(&scene, &setup, Engine::Reference, d, None).map(|_| ()).unwrap_err();

    let eight = root.join("eight.png");
    image::GrayImage::new(16, 16).save(&eight).unwrap();
    let e = run(&eight);
    assert!(e.contains("eight.png") && e.contains("16-bit"), "{e}");

    let eight_pgm = root.join("eight.pgm");
    std::fs::write(&eight_pgm, [b"P5\n4 4\n255\n".as_slice(), &[7u8; 16]].concat()).unwrap();
    let e = run(&eight_pgm);
    assert!(e.contains("eight.pgm") && e.contains("16-bit"), "{e}");

    let good = flinch_harness::avoid::depth::DepthImage { width: 64, height: 48, mm: vec![1500; 64 * 48] };
    for name in ["cut.png", "cut.pgm"] {
        let p = root.join(name);
        good.save(&p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        let e = run(&p);
        assert!(e.contains(name) && e.contains("cannot read depth image"), "{e}");
    }

    let dir = root.join("names");
    std::fs::create_dir_all(&dir).unwrap();
    good.save(&dir.join("frame-a.png")).unwrap();
    let e = run(&dir);
    assert!(e.contains("frame-a.png") && e.contains("index.csv"), "{e}");

    // A scene without [avoid.depth_camera] says what is missing.
    let plain = Avoid::parse(&std::fs::read_to_string(flinch_tests::scene_path("avoid_operator_hand.toml")).unwrap()).unwrap();
    let e = recorded::simulate(&plain, &setup, Engine::Reference, &root.join("eight.png"), None).map(|_| ()).unwrap_err();
    assert!(e.contains("[avoid.depth_camera]"), "{e}");
    std::fs::remove_dir_all(&root).ok();
}

/// The camera's keys go through the loader: out of range, named with the line.
#[test]
fn camera_keys_are_range_checked() {
    let (text, _) = scene();
    for (from, to, key) in [
        ("depth_scale_m = 0.001", "depth_scale_m = 0.5", "avoid.depth_camera.depth_scale_m: allowed range"),
        ("fx_px = 160.0", "fx_px = 0", "avoid.depth_camera.fx_px: allowed range"),
        ("\nheight_m = 1.5", "\nheight_m = 50", "avoid.depth_camera.height_m: allowed range"),
        ("position_m = [1.05, 1.05]", "position_m = [1.05]", "avoid.depth_camera.position_m: must be [x, y]"),
        ("\nheight_m = 1.5", "\nheight_m = 1.5\npitch_deg = 80", "avoid.depth_camera.pitch_deg: allowed range [-60, 60] deg"),
    ] {
        let e = Avoid::parse(&text.replacen(from, to, 1)).unwrap_err();
        assert!(e.contains(key) && e.starts_with("line "), "{to}: {e}");
    }
}

/// Writes the demo's recording (both conventions) and its scene into `$FLINCH_FIXTURE_DIR`, for a
/// look with the CLI: `FLINCH_FIXTURE_DIR=/tmp/rec cargo test -p flinch-tests --test avoid_recorded
/// -- --ignored write_fixtures`, then `flinch avoid /tmp/rec/scene.toml --depth /tmp/rec/realsense
/// --robot-poses /tmp/rec/realsense/poses.csv`.
#[test]
#[ignore]
fn write_fixtures() {
    let root = PathBuf::from(std::env::var("FLINCH_FIXTURE_DIR").expect("FLINCH_FIXTURE_DIR"));
    let (text, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let synthetic = simulate(&scene, &setup, Engine::Reference).unwrap();
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(root.join("scene.toml"), &text).unwrap();
    std::fs::write(root.join("scene_tum.toml"), text.replace("depth_scale_m = 0.001", "depth_scale_m = 0.0002")).unwrap();
    render_recording(&scene, &[(&root.join("realsense"), 0.001), (&root.join("tum"), 0.0002)], 240, 240, &track(&scene, &synthetic)).unwrap();
}

/// The demo's first frame rendered through the pinhole camera (no noise, no nulls), the separation
/// from the tool and the nearest obstacle cell.
fn first_frame(scene: &Avoid) -> (flinch_harness::avoid::depth::DepthImage, flinch_harness::avoid::camera::Pinhole) {
    use flinch_harness::avoid::camera::{render_depth, to_counts, Pinhole};
    let cam = Pinhole::new(scene.depth_camera.as_ref().unwrap());
    let z = render_depth(&cam, 240, 240, Some((&scene.robot_shape(), scene.start_m)), Some((&scene.operator_shape_at(0.0), scene.hand_at(0.0))));
    (to_counts(&z, 240, 240, scene.depth_camera.as_ref().unwrap().depth_scale_m), cam)
}

/// Review finding (issue 11 follow-up, 6a): the fill took the highest seen neighbour, so a null
/// strip two cells wide over the hand's edge nearest the tool (a black glove's rim) had its outer
/// cells painted as table and the separation came out one cell too large. Wanted: the separation the
/// monitor gets is never larger than the true one (the fill's reach is taken off it
/// whenever the fill paints floor; refusing to fill any 2 x 2 block of unknown cells also fixed this
/// case but blocked the demo's recorded run).
#[test]
fn a_null_strip_over_the_hands_edge_is_not_painted_as_table() {
    use flinch_harness::avoid::recorded::process_frame;
    let (_, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let (clean, cam) = first_frame(&scene);
    let tool = scene.start_m;
    let cell = scene.camera.m_per_px;
    let (_, sep0, near0, _) = process_frame(&scene, &setup, &cam, &clean, Some(tool), tool);
    let r0 = ((near0[0] - tool[0]).powi(2) + (near0[1] - tool[1]).powi(2)).sqrt();
    for cells in [1.0, 2.0] {
        // Null every pixel whose point lies in a band `cells` wide along the hand's edge nearest the
        // tool (the edge and the floor just before it), within 0.1 m of the nearest point.
        let mut img = clean.clone();
        let mut nulled = 0;
        for v in 0..img.height {
            for u in 0..img.width {
                let c = &mut img.mm[v * img.width + u];
                let q = cam.unproject(u as f64, v as f64, cam.depth_m(*c));
                let r = ((q[0] - tool[0]).powi(2) + (q[1] - tool[1]).powi(2)).sqrt();
                let near = ((q[0] - near0[0]).powi(2) + (q[1] - near0[1]).powi(2)).sqrt() < 0.1;
                if near && r > r0 - (cells - 0.5) * cell && r < r0 + 1.5 * cell {
                    *c = 0;
                    nulled += 1;
                }
            }
        }
        assert!(nulled > 20, "{nulled}");
        let (_, sep, _, info) = process_frame(&scene, &setup, &cam, &img, Some(tool), tool);
        // Against the truth, not the clean frame (whose own sampling gaps are filled and shortened
        // alike): the separation the monitor gets never exceeds the true one.
        let truth = scene.operator_shape_at(0.0).signed_distance(scene.hand_at(0.0), tool) - scene.robot.wrist_radius_m;
        assert!(info.filled_cells > 0, "{info:?}");
        assert!(sep <= truth, "{cells}-cell strip: separation {sep} m, true {truth} m, seen whole {sep0} m ({info:?})");
    }
}

/// Review finding (6b): a point under the work plane (multipath, a reflection) read as floor seen,
/// painting over the hand. Now it is dropped like a null pixel (counted) and the hand's cells are
/// unknown: an obstacle.
#[test]
fn points_under_the_plane_are_unknown_not_floor() {
    use flinch_harness::avoid::recorded::process_frame;
    let (_, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let (clean, cam) = first_frame(&scene);
    let tool = scene.start_m;
    let (_, sep0, _, _) = process_frame(&scene, &setup, &cam, &clean, Some(tool), tool);
    let hand = scene.hand_at(0.0);
    let scale = scene.depth_camera.as_ref().unwrap().depth_scale_m;
    let mut img = clean.clone();
    for v in 0..img.height {
        for u in 0..img.width {
            let c = &mut img.mm[v * img.width + u];
            let q = cam.unproject(u as f64, v as f64, cam.depth_m(*c));
            if (q[0] - hand[0]).abs() < 0.15 && (q[1] - hand[1]).abs() < 0.15 {
                // 0.1 m beyond the plane along this ray.
                let plane = cam.origin[2] / -cam.ray(u as f64, v as f64)[2];
                *c = ((plane + 0.1) / scale).round() as u16;
            }
        }
    }
    let (_, sep, _, info) = process_frame(&scene, &setup, &cam, &img, Some(tool), tool);
    assert!(info.below_plane_points > 100, "{info:?}");
    assert!(info.unknown_cells > 100, "{info:?}");
    assert!(sep <= sep0 + 1e-9, "separation {sep} m, hand seen {sep0} m");
    // A point within the sense height under the plane is the floor through the noise: not counted.
    let (_, _, _, info0) = process_frame(&scene, &setup, &cam, &clean, Some(tool), tool);
    assert_eq!(info0.below_plane_points, 0);
}

/// Follow-up to issue 9 (item 1): with `--depth` the verdict is judged against the scene file's
/// model operator, not against what the recording shows. Adversarial case: the recording holds the
/// demo's hand on the straight line; the scene file's operator stands in a far corner. The tool
/// goes round the recorded hand (the sensing sees it) and the model says it never came near anyone:
/// without a marker that read `reached`, exit 0, for a run whose ground truth nobody checked. Wanted:
/// `reached_unverified`, `verdict_basis` naming the scene model, not the favourable verdict, in the
/// JSON and through the CLI's entry point.
#[test]
fn a_verdict_on_a_recording_is_not_verified() {
    let (text, scene) = scene();
    let setup = Setup::new(&scene, None).unwrap();
    let synthetic = simulate(&scene, &setup, Engine::Reference).unwrap();
    let root = tmp("elsewhere");
    let rec = root.join("rec");
    render_recording(&scene, &[(&rec, 0.001)], 240, 240, &track(&scene, &synthetic)).unwrap();
    // The scene file's operator: in the far corner, 0.8 m from the path, with nothing in the way.
    let elsewhere_text = text.replace("{ t_s = 0.0, hand_m = [1.05, 1.05] }", "{ t_s = 0.0, hand_m = [1.9, 0.15] }").replace("entry_m = [1.05, 0.0]", "entry_m = [2.1, 0.0]");
    assert_ne!(elsewhere_text, text);
    let elsewhere = Avoid::parse(&elsewhere_text).unwrap();
    let poses = rec.join("poses.csv");
    let (r, _) = recorded::simulate(&elsewhere, &setup, Engine::Reference, &rec, Some(&poses)).unwrap();
    let m = metrics(&r);
    assert!(r.time_to_goal_s.is_some(), "the tool gets to the goal round the recorded hand: {m}");
    assert!(r.min_signed_distance_m > 0.5, "the model operator is far from the path: {m}");
    assert_ne!(m["status"], "reached", "a recording is no ground truth: {m}");
    assert_eq!(m["status"], "reached_unverified", "{m}");
    assert_eq!(m["verdict_basis"], "scene_model_not_recording", "{m}");
    assert_ne!(m["status"], "reached", "{m}");
    // The synthetic run's basis is the model that drew its frames.
    assert_eq!(metrics(&synthetic)["verdict_basis"], "scene_model");
    // Through the CLI's entry point: not the favourable verdict (exit 5, docs/conventions.md), and
    // the human output says so in words.
    let file = root.join("scene.toml");
    std::fs::write(&file, &elsewhere_text).unwrap();
    let got = avoid::run(&args(&file, &rec, Some(poses.clone())));//X
    assert_eq!(got.map(|v| v.code()), Ok(5), "exit 5: unverified");
    std::fs::remove_dir_all(&root).ok();
}

/// Honest edges (issue 29 item 7): a recording whose frames are mis-timed (median interval over
/// 1 s: here the capture times of a 30 Hz recording written 60 times too far apart) or mis-scaled
/// (most valid points under the work plane: here read with `depth_scale_m` doubled, so the table at
/// 1.5 m reads 3 m away) gets a warning naming why, in the result and in the JSON's `warnings`; a
/// right one gets none. Before, both ran silently.
#[test]
fn mis_timed_or_mis_scaled_recordings_are_warned_of() {
    let (_, mut scene) = scene();
    scene.max_time_s = 0.5;
    let setup = Setup::new(&scene, None).unwrap();
    let root = tmp("warnings");
    let good = root.join("good");
    let still: Vec<(f64, [f64; 2])> = (0..12).map(|k| (k as f64 / 30.0, scene.start_m)).collect();
    render_recording(&scene, &[(&good, 0.001)], 240, 240, &still).unwrap();
    let (r, _) = recorded::simulate(&scene, &setup, Engine::Reference, &good, Some(&good.join("poses.csv"))).unwrap();
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(metrics(&r)["warnings"], serde_json::json!([]));

    // Mis-timed: the same frames, their capture times 2 s apart.
    let slow = root.join("slow");
    let stretched: Vec<(f64, [f64; 2])> = still.iter().map(|&(t, p)| (60.0 * t, p)).collect();
    render_recording(&scene, &[(&slow, 0.001)], 240, 240, &stretched).unwrap();
    let (r, _) = recorded::simulate(&scene, &setup, Engine::Reference, &slow, Some(&slow.join("poses.csv"))).unwrap();
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("mis-timed") && r.warnings[0].contains("2.000 s"), "{}", r.warnings[0]);
    assert!(metrics(&r)["warnings"][0].as_str().unwrap().contains("median interval"));

    // Mis-scaled: the good frames read with twice the depth scale.
    let mut wrong = scene.clone();
    wrong.depth_camera.as_mut().unwrap().depth_scale_m = 0.002;
    let (r, _) = recorded::simulate(&wrong, &setup, Engine::Reference, &good, Some(&good.join("poses.csv"))).unwrap();
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("mis-scaled") && r.warnings[0].contains("under the work plane") && r.warnings[0].contains("depth_scale_m"), "{}", r.warnings[0]);
    let _ = std::fs::remove_dir_all(&root);
}
