//! Issue 30: every shipped 1-D scene gives the same run through the planar plant
//! (`plant/planar/`, `Scene::planar = Planar::AXIAL`: beta = 0, theta = -90, no contact friction)
//! as through the 1-D plant. The planar plant does the 1-D plant's arithmetic in the same order
//! when every direction lies on one axis (`planar::frame::unit_deg` is exact at multiples of 90 deg),
//! so the two summaries agree to the last bit: every peak, instant, count, the steps and the
//! right-hand-side evaluations. A planar change that moves any 1-D result fails here.

use flinch_model::scene::{Planar, Scene};
use flinch_model::shipped;
use std::path::Path;

fn one_d_scenes() -> Vec<(String, Scene)> {
    let mut v = Vec::new();
    for name in shipped::names().filter(|n| !n.rsplit('/').next().unwrap_or(n).starts_with("avoid_")) {
        // Scenes are read from their files so that a robot's URDF resolves beside them.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes").join(format!("{name}.toml"));
        let sc = shipped::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The planar scenes (fig69_*, offaxis_*) are not 1-D scenes.
        if sc.planar.is_none() {
            v.push((name.to_string(), sc));
        }
    }
    assert!(v.len() >= 30, "only {} shipped 1-D scenes found", v.len());
    v
}

/// -0.0 and 0.0 are the same number (the robot force of an untouched tool is -0.0 in 1-D, the sign
/// of a zero vector's magnitude in the plane): the Debug text with negative zeros written as 0.0.
fn zeros(s: &str) -> String {
    s.replace("-0.0,", "0.0,").replace("-0.0 }", "0.0 }").replace("-0.0)", "0.0)")
}

#[test]
fn every_shipped_1d_scene_is_unchanged_through_the_planar_plant() {
    let mut checked = 0;
    for (name, sc) in one_d_scenes() {
        let (one_d, h1) = flinch_sim::run(&sc, true).unwrap_or_else(|e| panic!("{name}: 1-D: {e}"));
        let mut p = sc.clone();
        p.planar = Some(Planar::AXIAL);
        let (mut planar, h2) = flinch_sim::run(&p, true).unwrap_or_else(|e| panic!("{name}: planar: {e}"));
        // The planar run echoes its angles; everything else must be the 1-D run's.
        assert_eq!((planar.off_axis_deg.take(), planar.surface_angle_deg.take()), (Some(0.0), Some(-90.0)), "{name}");
        assert_eq!(zeros(&format!("{one_d:?}")), zeros(&format!("{planar:?}")), "{name}: the summaries differ");
        assert_eq!(h1.len(), h2.len(), "{name}: recorded rows");
        for (a, b) in h1.iter().zip(&h2) {
            assert_eq!(zeros(&format!("{a:?}")), zeros(&format!("{b:?}")), "{name}: a recorded row differs");
        }
        checked += 1;
    }
    eprintln!("{checked} shipped 1-D scenes identical through the planar plant");
}

#[test]
fn solver_plant_planar_reads_as_the_axial_planar_scene() {
    let text = shipped::get("tables5-7_bistable").unwrap();
    let text = format!("{text}\n");
    let sc = flinch_model::scene::parse(&text, "x.toml").unwrap();
    assert!(sc.planar.is_none());
    let with = if text.contains("[solver]") { text.replace("[solver]", "[solver]\nplant = \"planar\"") } else { format!("{text}\n[solver]\nplant = \"planar\"\n") };
    let sc = flinch_model::scene::parse(&with, "x.toml").unwrap();
    assert_eq!(sc.planar, Some(Planar::AXIAL));
}
