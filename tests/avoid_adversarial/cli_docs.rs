//! `flinch avoid`'s verdict, exit code and CSV, and docs/avoidance.md's table kept current.

use super::*;
use flinch_harness::avoid::path::{Engine, PathResult, Reason, Status, Verdict};
use flinch_harness::avoid::scene::Avoid;
use flinch_harness::avoid::{self, AvoidArgs};
use flinch_tests::scene_path;

/// `flinch avoid` exits 1 on a collision, 4 on a safe stop before the goal (the wall with the
/// monitor: it was exit 1, the same as the collision) and 0 on the empty diagonal, and the CSV has
/// the documented columns, one row per step.
#[test]
fn cli_verdict_and_csv() {
    let csv = std::env::temp_dir().join(format!("flinch-avoid-{}.csv", std::process::id()));
    let args = |name: &str, csv: Option<std::path::PathBuf>, thesis: bool| AvoidArgs { csv, thesis, ..flinch_tests::avoid::args(scene_path(name)) };
    assert_eq!(avoid::run(&args("avoid_wall.toml", Some(csv.clone()), true)), Ok(Verdict::Unsafe), "a collision: exit 1");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,x_m,y_m,vx_mps,vy_mps,separation_m,speed_limit_mps,state,swept_separation_m,ssm_bound_mps"));
    assert_eq!(avoid::CSV_HEADER.split(',').count(), 10);
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').enumerate().filter(|(k, _)| *k != 7).map(|(_, v)| v.parse().unwrap()).collect()).collect();
    assert!(rows.iter().any(|r| r[5] < 0.0), "the crossing shows in the CSV's separation");
    assert!(rows.iter().all(|r| r[7] <= r[5]), "swept separation never above the step's end");
    assert!(rows.iter().any(|r| r[3].hypot(r[4]) > r[8] + 1e-6), "the thesis's law exceeds the SSM bound: the CSV shows where");
    std::fs::remove_file(&csv).ok();
    // With the monitor the wall is a safe stop: exit 4, told apart from the unsafe exit 1.
    let stop = avoid::run(&args("avoid_wall.toml", None, false));
    assert_eq!(stop, Ok(Verdict::SafeStop));
    assert_eq!(stop.map(|v| v.code()), Ok(4));
    let mut empty = args("avoid_empty_diagonal.toml", None, false);
    empty.json = false;
    assert_eq!(avoid::run(&empty).map(|v| v.code()), Ok(0));
}

/// One row of the docs' table: `| scene | law | status | reason | min_signed_distance_m |
/// max_speed_near_operator_mps | time_to_goal_s | ssm_violations | max_speed_over_ssm_mps |`.
fn table_row(name: &str, law: &str, r: &PathResult) -> String {
    format!(
        "| `{name}` | {law} | {} | {} | {:.4} | {:.3} | {} | {} | {:.3} |",
        r.status.name(),
        r.status.reason().map_or("-", |x| x.name()),
        r.min_signed_distance_m,
        r.max_speed_near_operator_mps,
        r.time_to_goal_s.map_or("-".to_string(), |t| format!("{t:.2}")),
        r.ssm_violations,
        r.max_speed_over_ssm_mps
    )
}

/// docs/avoidance.md's per-scene table (every `scenes/avoid_*.toml`, the thesis's law against ours)
/// is what the scenes give now: it cannot drift. `FLINCH_BLESS=1` rewrites it (then review the
/// diff). Every row of ours is also checked safe, every row of the thesis's honest.
#[test]
fn docs_table_is_current() {
    let names = flinch_tests::avoid::scene_names();
    let mut rows = vec![
        "| scene | law | status | reason | min_signed_distance_m | max_speed_near_operator_mps | time_to_goal_s | ssm_violations | max_speed_over_ssm_mps |".to_string(),
        "|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    for name in &names {
        let (ts, t) = thesis(name);
        honest(name, &ts, &t);
        let (os, o) = run(name);
        safe(name, &os, &o);
        rows.push(table_row(name, "thesis (`--thesis`)", &t));
        rows.push(table_row(name, "ours", &o));
    }
    let table = rows.join("\n");
    let doc_path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/avoidance.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap();
    let (begin, end) = ("<!-- avoid-table:begin -->\n", "\n<!-- avoid-table:end -->");
    let (a, b) = (doc.find(begin).expect("begin marker") + begin.len(), doc.find(end).expect("end marker"));
    if std::env::var_os("FLINCH_BLESS").is_some() {
        std::fs::write(&doc_path, format!("{}{table}{}", &doc[..a], &doc[b..])).unwrap();
    } else {
        assert_eq!(&doc[a..b], table, "docs/avoidance.md's table is out of date: FLINCH_BLESS=1 cargo test -p flinch-tests --test avoid_adversarial docs_table_is_current");
    }
}

/// Follow-up to issue 9 (item 3): the CSV's last row is a control step like any other; it was
/// labelled `stopped` whenever the run ended, even when the tool moved in that step (a timeout at
/// cruise speed). Now `stopped` only where the step's command was zero.
#[test]
fn the_last_csv_row_is_stopped_only_when_the_tool_stood_still() {
    let mut s = Avoid::load(&scene_path("avoid_empty_diagonal.toml")).unwrap();
    s.max_time_s = 0.5;
    let (_, r) = run_scene(s);
    assert_eq!(r.status, Status::Stopped(Reason::Timeout), "{:?}", r.status);
    // The last control step (the braking after it is in rows of its own, `braking`).
    let last = r.rows.iter().rev().find(|w| w.state != "braking").unwrap();
    assert!(last.v_mps[0].hypot(last.v_mps[1]) > 0.1, "moving at the timeout: {:?}", last.v_mps);
    let tail = r.rows.last().unwrap();
    assert_eq!((tail.state, tail.v_mps), ("braking", [0.0, 0.0]), "then the drive brakes: {tail:?}");
    assert_ne!(last.state, "stopped", "it moved in that step: {:?}", last);
    for w in &r.rows {
        if w.state == "stopped" {
            assert_eq!(w.v_mps, [0.0, 0.0], "{w:?}");
        }
    }
}

/// Issue 29 (item 4): `goal_reached` is the plain fact (the tool got to the goal, with
/// `time_to_goal_s`), whatever the verdict; `status` is the verdict (a run that crossed the
/// operator and then arrived is `collision` with `goal_reached` true). It replaced `reached_goal`,
/// which meant `status` = `reached` under a name that said something else.
#[test]
fn goal_reached_is_the_plain_fact_and_status_the_verdict() {
    let schema: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(scene_path("../docs/schema/avoid.json")).unwrap()).unwrap();
    assert!(schema["properties"]["reached_goal"].is_null(), "renamed");
    let d = schema["properties"]["goal_reached"]["description"].as_str().unwrap().to_string();
    assert!(d.contains("plain fact") && d.contains("`status`"), "{d}");
    for name in ["avoid_wall.toml", "avoid_empty_diagonal.toml", "avoid_head_on.toml"] {
        let (scene, r) = thesis(name);
        let m = avoid::metrics_json(&r, Engine::Reference, scene.safety.on());
        assert_eq!(m["goal_reached"], !m["time_to_goal_s"].is_null(), "{name}: {m}");
        if m["status"] == "reached" {
            assert_eq!(m["goal_reached"], true, "{name}");
        }
    }
}
