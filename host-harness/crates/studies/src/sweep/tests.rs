//! The sweep's unit tests.

use super::{axis::*, template::*, grid::*};
#[allow(unused_imports)]
use super::table::*;


#[test]
fn linear_and_log_values_hit_both_ends() {
    let a = Axis::parse("motion.speed=0.01:0.3:30", false).unwrap();
    let v = a.values();
    assert_eq!(v.len(), 30);
    assert_eq!((v[0], v[29]), (0.01, 0.3));
    let l = Axis::parse("target.stiffness=log:1e3:1e5:3", false).unwrap();
    let v = l.values();
    assert_eq!(v[0], 1e3);
    assert!((v[1] - 1e4).abs() < 1e-6);
    assert_eq!(v[2], 1e5);
    assert_eq!(Axis::parse("target.stiffness=1e3:1e5:3", true).unwrap().spacing, Spacing::Log);
}

#[test]
fn edit_distance() {
    assert_eq!(distance("speed", "sped"), 1);
    assert_eq!(distance("", "abc"), 3);
    assert_eq!(close_matches("motion.sped", &["motion.speed".into(), "motion.decel".into(), "tool.mass".into()]), vec!["motion.speed".to_string()]);
}

/// A point's spliced text is the text the edited document prints, for every shipped scene
/// and a number of every kind (float, integer kept whole, integer made fractional, an array
/// element), so the fast path validates exactly what the slow one did.
#[test]
fn spliced_text_is_the_edited_documents_text() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes");
    let mut checked = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let path = e.path();
        if path.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let Ok(t) = Template::from_text(&text, "x.toml") else { continue };
        assert!(t.text.is_some(), "{}: the document does not print back its text", path.display());
        let keys = t.numeric_keys();
        for key in &keys {
            for x in [0.25, 3.0, 1e-7, 12345.678] {
                let plan = t.splice_plan(&[key.as_str()]).unwrap_or_else(|| panic!("{}: {key}", path.display()));
                let mut doc = t.doc.clone();
                assert!(set(&mut doc, key, x));
                assert_eq!(t.spliced(&plan, &[x]), doc.to_string(), "{}: {key} = {x}", path.display());
                checked += 1;
            }
        }
        if keys.len() >= 2 {
            let (a, b) = (keys[keys.len() - 1].as_str(), keys[0].as_str());
            let plan = t.splice_plan(&[a, b]).unwrap();
            let mut doc = t.doc.clone();
            assert!(set(&mut doc, a, 0.5) && set(&mut doc, b, 7.0));
            assert_eq!(t.spliced(&plan, &[0.5, 7.0]), doc.to_string(), "{}: {a}, {b}", path.display());
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn grid_is_row_major() {
    assert_eq!(grid_index(&[2, 3], 0), vec![0, 0]);
    assert_eq!(grid_index(&[2, 3], 2), vec![0, 2]);
    assert_eq!(grid_index(&[2, 3], 3), vec![1, 0]);
}

/// A sweep of Tables 5-7 over speed with `--set` overrides applied.
fn speed_sweep(sets: &[&str], vary: &str) -> SweepResult {
    let sets: Vec<flinch_model::overrides::Set> = sets.iter().map(|s| flinch_model::overrides::Set::parse(s).unwrap()).collect();
    let t = Template::load_with(std::path::Path::new("tables5-7_bistable"), &sets).unwrap();
    Sweep::keep_going(&t, vec![Axis::parse(vary, false).unwrap()]).unwrap().run(Progress::Hidden)
}

fn svg_of(r: &SweepResult, metric: &str, name: &str) -> String {
    let p = std::env::temp_dir().join(format!("flinch-sweep-marks-{}-{name}.svg", std::process::id()));
    super::plot::draw(&p, r, metric).unwrap();
    let s = std::fs::read_to_string(&p).unwrap();
    let _ = std::fs::remove_file(&p);
    s
}

/// Every NOT SAFE, not concluded and not-as-commanded point is marked, and each legend entry is
/// there exactly when such a point exists (issue 26 item 3; before it, none of these entries
/// existed and a point whose flange never reached V_c looked like any other).
#[test]
fn not_safe_inconclusive_and_not_as_commanded_points_are_marked() {
    // The README's old sweep: 10 mm gap, so above sqrt(2 a_c gap) = 0.141 m/s V_c is never reached;
    // 0.02 m/s is too slow to stop within the run (not concluded, NOT SAFE).
    let r = speed_sweep(&[], "motion.speed=0.02:0.3:8");
    let s = svg_of(&r, "peak_robot_force", "old");
    for entry in ["NOT SAFE", "not concluded (counts as NOT", "not as commanded: V_c not"] {
        assert!(s.contains(entry), "missing legend entry {entry}");
    }
    let csv = r.csv();
    let mut rd = csv::Reader::from_reader(csv.as_bytes());
    let h = rd.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|x| x == n).unwrap_or_else(|| panic!("no column {n}"));
    let (v, a, ac, st, why) = (col("motion.speed"), col("approach_speed_mps"), col("as_commanded"), col("status"), col("reason"));
    let mut short = 0;
    for row in rd.records().map(Result::unwrap) {
        let speed: f64 = row[v].parse().unwrap();
        let reached = (2.0f64 * 1.0 * 0.010).sqrt();
        if row[st].is_empty() || &row[st] == "refused" {
            continue;
        }
        if speed > reached + 1e-3 {
            short += 1;
            assert_eq!(&row[ac], "false", "{speed}");
            assert!(row[why].contains("not as commanded: the flange had reached only 0.14"), "{}", &row[why]);
            assert!(row[a].parse::<f64>().unwrap() < 0.15);
        } else if speed < reached - 1e-3 {
            assert_eq!(&row[ac], "true", "{speed}");
        }
    }
    assert_eq!(short, 4, "0.18, 0.22, 0.26 and 0.30 m/s");
    assert!(csv.lines().skip(1).any(|l| l.contains(",inconclusive,")), "the 0.02 m/s point is not concluded");
    // A sweep where every speed is reached and every point is safe: none of those entries.
    let r = speed_sweep(&["target.gap=0.05", "duration=1.5"], "motion.speed=0.05:0.25:3");
    let s = svg_of(&r, "peak_robot_force", "clean");
    for entry in ["NOT SAFE", "not concluded", "not as commanded"] {
        assert!(!s.contains(entry), "an entry {entry} without such a point");
    }
}

/// A boolean metric is two colours with words, not a colour bar from 0 to 1.
#[test]
fn a_boolean_metric_gets_a_two_colour_legend() {
    let sets: Vec<flinch_model::overrides::Set> = ["target.gap=0.05", "duration=1.5"].iter().map(|s| flinch_model::overrides::Set::parse(s).unwrap()).collect();
    let t = Template::load_with(std::path::Path::new("tables5-7_bistable"), &sets).unwrap();
    let axes = vec![Axis::parse("motion.speed=0.2:0.32:3", false).unwrap(), Axis::parse("motion.dead_time=0.016:0.03:2", false).unwrap()];
    let r = Sweep::keep_going(&t, axes).unwrap().run(Progress::Hidden);
    let s = svg_of(&r, "safe", "bool");
    // plotters writes a text element's content on its own line.
    assert!(s.contains("\nSAFE\n") && s.contains("\nNOT SAFE\n"), "the two words of the key");
    // No colour bar: its label is the one drawn rotated beside the bar (the y axis's is the other).
    assert_eq!(s.matches("rotate(270").count(), 1, "a colour bar on a boolean metric");
    // A number keeps its colour bar.
    let s = svg_of(&r, "peak_robot_force", "num");
    assert_eq!(s.matches("rotate(270").count(), 2, "the colour bar of a number");
}

/// Issue 27: the streamed sweep writes the same bytes as the in-memory one, with refused points
/// (and a first point refused, so rows wait for the header) and on 1 and 2 threads; blocks keep
/// grid order.
#[test]
fn streamed_rows_are_the_in_memory_csv_byte_for_byte() {
    let text = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes/table1_rigid_tool.toml")).unwrap();
    let t = Template::from_text(&text, "table1_rigid_tool.toml").unwrap();
    // tool.mass from -0.1 (refused) up: the first points are refused rows.
    let axes = || vec![Axis::parse("tool.mass=-0.1:1:300", false).unwrap()];
    let whole = Sweep::keep_going(&t, axes()).unwrap().run(Progress::Hidden);
    assert!(whole.refused() > 0 && whole.points[0].status == Status::Refused);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut out = Vec::new();
        let mut w = super::table::RowWriter::new(&mut out, &axes());
        let st = super::stream::stream(&t, axes(), false, Progress::Hidden, Some(&pool), &mut |p| w.push(p)).unwrap().unwrap();
        w.finish().unwrap();
        drop(w);
        assert_eq!((st.done, st.total, st.refused), (300, 300, whole.refused()));
        assert_eq!(String::from_utf8(out).unwrap(), whole.csv(), "{threads} threads");
    }
    // --strict: refused before any point runs.
    let e = super::stream::stream(&t, axes(), true, Progress::Hidden, None, &mut |_| panic!("a point ran")).unwrap_err();
    assert!(e.0.contains("points refused; the first:"), "{e}");
}
