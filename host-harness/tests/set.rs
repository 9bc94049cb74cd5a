//! `--set KEY=VALUE` on every scene command, and the headline each prints first: the scene's
//! name, what was simulated, and a `NAME MISMATCH` line for each claim of the name the scene
//! contradicts (issue 26 item 1). On the code before issue 26 every one of these fails: no
//! command took `--set`, and an edited copy of a shipped scene kept its stale title everywhere.

mod common;
use common::{flinch, text};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    common::tmp_in("set", name).join(name)
}

const MISMATCH: &str = "NAME MISMATCH: the name says V_c = 0.2 m/s; simulated V_c = 0.500 m/s";

/// The first three lines of a command's standard output (and its exit code).
fn head(args: &[&str]) -> (Vec<String>, Option<i32>, String) {
    let o = flinch().args(args).output().unwrap();
    let out = text(&o.stdout);
    (out.lines().take(3).map(str::to_string).collect(), o.status.code(), text(&o.stderr))
}

#[test]
fn every_scene_command_takes_set_and_says_what_it_simulated() {
    let set = ["--set", "motion.speed=0.5"];
    let cases: Vec<Vec<&str>> = vec![
        vec!["run", "body_hand"],
        vec!["check", "body_hand"],
        vec!["hil", "body_hand", "--scan-cycle", "0.016"],
        vec!["design", "body_hand"],
        vec!["sample", "body_hand", "--samples", "3", "--vary", "tool.mass=normal:0.75:0.01"],
    ];
    for mut args in cases {
        args.extend(set);
        let (lines, code, err) = head(&args);
        assert!(matches!(code, Some(0 | 1)), "{args:?}: {err}");
        assert!(lines[0].starts_with("Annex A hand, clamped"), "{args:?}: {lines:?}");
        assert!(lines[1].starts_with("  simulated: V_c = 0.500 m/s, DT = 16.0 ms"), "{args:?}: {lines:?}");
        assert_eq!(lines[2], format!("  {MISMATCH}"), "{args:?}: {lines:?}");
    }
    // run --json: the same in fields.
    let o = flinch().args(["run", "body_hand", "--json", "--set", "motion.speed=0.5"]).output().unwrap();
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["name_mismatches"][0], MISMATCH.trim_start_matches("NAME MISMATCH: "));
    assert!(j["simulated"].as_str().unwrap().starts_with("V_c = 0.500 m/s"));
    // sweep: the headline on standard error, the column per row.
    let o = flinch().args(["sweep", "body_hand", "--set", "motion.speed=0.5", "--vary", "tool.mass=0.7:0.8:2", "--csv", "-"]).output().unwrap();
    assert!(text(&o.stderr).contains(MISMATCH), "{}", text(&o.stderr));
    let mut r = csv::Reader::from_reader(o.stdout.as_slice());
    let col = r.headers().unwrap().iter().position(|h| h == "name_mismatches").expect("a name_mismatches column");
    for row in r.records() {
        assert!(row.unwrap()[col].contains("the name says V_c = 0.2 m/s"));
    }
    // report: the title and the page say it.
    let page = tmp("hand.html");
    let o = flinch().args(["report", "body_hand", "--set", "motion.speed=0.5", "--out"]).arg(&page).output().unwrap();
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", text(&o.stderr));
    let html = std::fs::read_to_string(&page).unwrap();
    let title = html.split("<title>").nth(1).unwrap().split("</title>").next().unwrap();
    assert!(title.contains("simulated: V_c = 0.500 m/s") && title.contains("NAME MISMATCH: name says V_c = 0.2 m/s"), "{title}");
    assert!(html.contains("--set motion.speed=0.5"), "the report lists the overrides");
    // The run's plot title.
    let svg = tmp("hand.svg");
    let o = flinch().args(["run", "body_hand", "--set", "motion.speed=0.5", "--plot"]).arg(&svg).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.contains("simulated: V_c = 0.500 m/s") && s.contains("name says V_c = 0.2 m/s"), "the plot's title");
}

#[test]
fn a_set_is_validated_like_the_file() {
    let (_, code, err) = head(&["run", "body_hand", "--set", "motion.speed=9"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--set motion.speed=9: motion.speed: allowed range [1e-4, 5] m/s"), "{err}");
    let (_, code, err) = head(&["check", "body_hand", "--set", "motion.sped=1"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--set motion.sped=1: motion.sped: unknown key") && err.contains("did you mean `speed`?"), "{err}");
    let (_, code, err) = head(&["run", "body_hand", "--set", "target.region=foot"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--set target.region=foot: target.region: must be one of"), "{err}");
    let (_, code, err) = head(&["run", "body_hand", "--set", "motion.speed"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("KEY=VALUE"), "{err}");
    // A bare word is a string; the name then contradicts the region, and says so.
    let (lines, code, err) = head(&["run", "body_hand", "--set", "target.region=face"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(lines[2], "  NAME MISMATCH: the name says hand and fingers; simulated face");
    // A key both set and swept or sampled is refused.
    for args in [&["sweep", "body_hand", "--set", "motion.speed=0.5", "--vary", "motion.speed=0.1:0.2:2"][..], &["sample", "body_hand", "--samples", "2", "--set", "tool.mass=1", "--vary", "tool.mass=uniform:0.5:1"]] {
        let (_, code, err) = head(args);
        assert_eq!(code, Some(2), "{args:?}");
        assert!(err.contains("also given to --vary"), "{err}");
    }
}

#[test]
fn the_edited_file_is_flagged_too() {
    let shown = flinch().args(["scenes", "show", "body_hand"]).output().unwrap();
    let edited = text(&shown.stdout).replace("speed = 0.2 ", "speed = 0.5 ");
    let p = tmp("hand.toml");
    std::fs::write(&p, edited).unwrap();
    let o = flinch().arg("run").arg(&p).output().unwrap();
    assert!(text(&o.stdout).contains(MISMATCH), "{}", text(&o.stdout));
    let o = flinch().arg("check").arg(&p).output().unwrap();
    assert!(text(&o.stdout).contains(MISMATCH), "{}", text(&o.stdout));
}

#[test]
fn design_headline_follows_its_options() {
    let (lines, _, err) = head(&["design", "tables5-7_bistable", "--speed", "0.5"]);
    assert!(lines[1].starts_with("  simulated: V_c = 0.500 m/s"), "{lines:?} {err}");
    assert_eq!(lines[2], "  NAME MISMATCH: the name says V_c = 0.05 m/s; simulated V_c = 0.500 m/s");
    let (lines, _, _) = head(&["design", "tables5-7_bistable", "--set", "motion.dead_time=0.046"]);
    assert!(lines[1].contains("DT = 46.0 ms"), "{lines:?}");
}

/// `run` at a speed the flange never reaches before contact says so (issue 26 item 3: the old
/// run printed SAFE and "approach 0.1436 m/s" with no note at all).
#[test]
fn run_says_when_the_flange_never_reached_its_speed() {
    let o = flinch().args(["run", "tables5-7_bistable", "--set", "motion.speed=0.3"]).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    // After the name, what was simulated and the name's mismatch.
    assert!(out.lines().nth(3).unwrap().starts_with("  NOT AS COMMANDED: the flange had reached only 0.14"), "{out}");
    let o = flinch().args(["run", "tables5-7_bistable", "--json", "--set", "motion.speed=0.3"]).output().unwrap();
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["as_commanded"], false);
    assert!(j["approach_speed_mps"].as_f64().unwrap() < 0.15);
    // Reached: nothing to say.
    let o = flinch().args(["run", "tables5-7_bistable", "--json", "--set", "motion.speed=0.1"]).output().unwrap();
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["as_commanded"], true);
    assert_eq!(j["not_as_commanded"].as_array().unwrap().len(), 0);
}

/// Issue 26 item 7: input refused before anything runs exits 2 (these exited 3), and a scene for
/// another command gets one line naming it (seven lines of missing keys before).
#[test]
fn refusals_exit_2_everywhere() {
    for args in [
        &["design", "body_hand", "--body-region", "foot"][..],
        &["design", "tables5-7_bistable", "--body-region", "hand"],
        &["design", "tables5-7_bistable", "--stroke", "0.001"],
        &["design", "tables5-7_bistable", "--speed", "9"],
        &["design", "tables5-7_bistable", "--dead-time", "5"],
        &["design", "tables5-7_bistable", "--plot", "x.txt"],
    ] {
        let (_, code, err) = head(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
    }
    for cmd in ["run", "check", "design", "sweep"] {
        let mut args = vec![cmd, "avoid_operator_hand"];
        if cmd == "sweep" {
            args.extend(["--vary", "motion.speed=0.1:0.2:2"]);
        }
        let (_, code, err) = head(&args);
        assert_eq!(code, Some(2), "{cmd}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{cmd}: {err}");
        assert!(err.contains("run it with `flinch avoid avoid_operator_hand`"), "{cmd}: {err}");
    }
}
