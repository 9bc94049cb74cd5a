//! The `flinch` command line as a user meets it: exit codes, `-` for standard output, no panic
//! when standard output cannot be written, a FIFO or directory refused as a scene, shipped scenes
//! from any directory, bounded memory on long runs, a clean Ctrl-C, and `--measured`.

mod common;
use std::io::Read;
use common::{bytes_written, flinch, peak_rss_kb, repo, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    common::tmp_in("cli", name)
}

fn no_panic(o: &Output) {
    let e = text(&o.stderr);
    assert!(!e.contains("panicked"), "{e}");
}

/// A shipped scene with `duration` and `output_interval` replaced, written to `dir`.
fn long_scene(dir: &Path, duration: f64, interval: f64) -> PathBuf {
    let t = std::fs::read_to_string(repo().join("scenes/tables5-7_bistable.toml")).unwrap();
    let t = t.replace("duration = 0.6 ", &format!("duration = {duration} "));
    let t = format!("{t}\n[solver]\noutput_interval = {interval}\n");
    let p = dir.join("long.toml");
    std::fs::write(&p, t).unwrap();
    p
}

#[test]
fn a_full_stdout_is_exit_3_not_a_panic() {
    for args in [&["run", "tables5-7_bistable", "--json"][..], &["check", "tables5-7_bistable"], &["scenes", "list"], &["run", "tables5-7_bistable", "--csv", "-"]] {
        let o = flinch().args(args).stdout(std::fs::File::create("/dev/full").unwrap()).output().unwrap();
        no_panic(&o);
        assert_eq!(o.status.code(), Some(3), "{args:?}: {}", text(&o.stderr));
        assert!(text(&o.stderr).contains("could not write"), "{}", text(&o.stderr));
    }
}

#[test]
fn a_closed_pipe_ends_quietly_with_141() {
    // `design` prints with the standard macros (the print guard), `run` through the output module.
    //
    // The reader is closed right after the spawn, but the other tests of this file spawn children on
    // other threads: a fork taken in that instant holds a copy of the read end until it execs, and a
    // short output (`scenes list` is about 3 kB) then fits the pipe and the child exits 0. That race
    // is the test's, not the program's: an exit 0 is retried, and the test fails if it never sees
    // 141. Any other code, or a panic, fails at once.
    for args in [&["run", "tables5-7_bistable", "--csv", "-"][..], &["design", "tables5-7_bistable", "--json"], &["scenes", "list"]] {
        let mut codes = Vec::new();
        for _ in 0..8 {
            let mut child = flinch().args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
            drop(child.stdout.take());
            let mut err = String::new();
            child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
            let status = child.wait().unwrap();
            assert!(!err.contains("panicked"), "{args:?}: {err}");
            codes.push(status.code());
            match status.code() {
                Some(141) => break,
                Some(0) => continue,
                other => panic!("{args:?}: exit {other:?}: {err}"),
            }
        }
        assert_eq!(codes.last(), Some(&Some(141)), "{args:?}: exits {codes:?}");
    }
}

#[test]
fn a_fifo_or_a_directory_as_the_scene_is_refused_at_once() {
    let d = tmp("fifo");
    let fifo = d.join("scene.toml");
    let _ = std::fs::remove_file(&fifo);
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let mut child = flinch().args(["run"]).arg(&fifo).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            panic!("flinch run FIFO blocked");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    assert_eq!(status.code(), Some(2), "{err}");
    assert!(err.contains("not a regular file"), "{err}");
    let o = flinch().args(["run"]).arg(&d).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("is a directory"), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn exit_codes_say_what_happened() {
    // 2: bad input (unknown scene, with suggestions; an unknown option).
    let o = flinch().args(["run", "tables5-7_bistabel"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("tables5-7_bistable"), "{}", text(&o.stderr));
    assert_eq!(flinch().args(["run", "--no-such-option"]).output().unwrap().status.code(), Some(2));
    // 2: two results on standard output.
    let o = flinch().args(["run", "tables5-7_bistable", "--json", "--csv", "-"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    // 1: an unfavourable verdict (the hydraulic's 23 mm stroke cannot absorb 33 mm).
    let o = flinch().args(["check", "table14_hydraulic_surface"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    // 2: check and design on a scene without a stroke or a travel switch (a rigid tool, a force
    // sensor): the wrong input for the command, said as such.
    for cmd in ["check", "design"] {
        let o = flinch().args([cmd, "tables5-7_rigid"]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", text(&o.stderr));
        assert!(text(&o.stderr).contains(".kind: flinch"), "{}", text(&o.stderr));
    }
    // 0.
    assert_eq!(flinch().args(["check", "tables5-7_bistable"]).output().unwrap().status.code(), Some(0));
}

#[test]
fn dash_is_stdout_and_messages_go_to_stderr() {
    let o = flinch().args(["run", "tables5-7_bistable", "--csv", "-"]).output().unwrap();
    assert!(o.status.success());
    let out = text(&o.stdout);
    assert!(out.starts_with("t_s,v_c_mps,v_r_mps,v_t_mps,v_p_mps,s_m,travel_m,f_contact_n,f_robot_n,"), "{}", &out[..200]);
    assert_eq!(out.lines().count(), 6002, "header and 6001 rows");
    assert!(!std::path::Path::new(&repo().join("-")).exists(), "no file named -");
    // The human summary went to standard error, not into the CSV.
    assert!(text(&o.stderr).contains("peak contact force 43.86 N"), "{}", text(&o.stderr));
    let o = flinch().args(["run", "tables5-7_bistable", "--json"]).output().unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["schema_version"], 1);
    assert!(v["peak_contact_force"].as_f64().unwrap() > 40.0);
    assert!(o.stderr.is_empty(), "{}", text(&o.stderr));
}

#[test]
fn shipped_scenes_run_from_any_directory() {
    let d = tmp("anywhere");
    let o = flinch().current_dir(&d).args(["run", "tables5-7_bistable"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("peak contact force 43.86 N"));
    let list = text(&flinch().current_dir(&d).args(["scenes", "list"]).output().unwrap().stdout);
    assert!(list.lines().any(|l| l.starts_with("tables5-7_bistable ")), "{list}");
    assert!(list.lines().any(|l| l.starts_with("figures/fig2_free_tool ")), "{list}");
    let shown = flinch().current_dir(&d).args(["scenes", "show", "tables5-7_bistable"]).output().unwrap().stdout;
    assert_eq!(text(&shown), std::fs::read_to_string(repo().join("scenes/tables5-7_bistable.toml")).unwrap());
    // A shown scene read back from standard input.
    let mut child = flinch().current_dir(&d).args(["run", "-", "--json"]).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    std::io::Write::write_all(&mut child.stdin.take().unwrap(), &shown).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_long_run_streams_its_csv_and_decimates_its_plot_in_bounded_memory() {
    let d = tmp("long");
    // 20 s at 10 us: two million rows (the old code held them all: 176 MB of samples).
    let scene = long_scene(&d, 20.0, 1e-5);
    let mut c = flinch();
    c.args(["run"]).arg(&scene).args(["--csv"]).arg(d.join("h.csv")).args(["--plot"]).arg(d.join("h.png"));
    let (kb, o) = peak_rss_kb(c, Duration::from_secs(120));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rows = std::io::BufRead::lines(std::io::BufReader::new(std::fs::File::open(d.join("h.csv")).unwrap())).count();
    assert_eq!(rows, 2_000_002, "header and every row");
    assert!(kb < 80_000, "peak resident set {kb} kB");
    assert!(std::fs::metadata(d.join("h.png")).unwrap().len() > 20_000);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ctrl_c_stops_a_long_run_with_complete_rows() {
    let d = tmp("sigint");
    let scene = long_scene(&d, 60.0, 1e-5);
    let csv = d.join("h.csv");
    let mut child = flinch().args(["run"]).arg(&scene).args(["--csv"]).arg(&csv).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    // Wait for rows to appear, then interrupt.
    let start = Instant::now();
    while bytes_written(&csv) < 200_000 && start.elapsed() < Duration::from_secs(30) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted at t ="), "{err}");
    let body = std::fs::read_to_string(&csv).unwrap();
    assert!(body.ends_with('\n'), "the last row is complete");
    let cols = body.lines().next().unwrap().split(',').count();
    assert!(body.lines().all(|l| l.split(',').count() == cols));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn measured_traces_give_errors_and_the_time_shift() {
    let o = flinch().args(["run", "tables5-7_bistable", "--json", "--measured", "docs/measured/tables5-7_bistable_synthetic.csv"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let m = v["measured"].as_array().unwrap();
    let vt = m.iter().find(|c| c["column"] == "v_t_mps").unwrap();
    // The file is the run shifted by +3 ms with 2 mm/s of noise: both come back.
    let shift = vt["time_shift_s"].as_f64().unwrap();
    assert!((shift - 0.003).abs() < 0.0006, "{shift}");
    let after = vt["rms_error_shifted"].as_f64().unwrap();
    assert!(after < 0.0025 && after > 0.0015, "{after}");
    assert!(vt["rms_error"].as_f64().unwrap() > 2.0 * after, "unshifted, the error is larger");
    // A bad file is bad input naming the line.
    let d = tmp("measured");
    std::fs::write(d.join("m.csv"), "t_s,v_t_mps\n0,0\n0.1,oops\n").unwrap();
    let o = flinch().args(["run", "tables5-7_bistable", "--measured"]).arg(d.join("m.csv")).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("m.csv:3: v_t_mps"), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&d);
}

/// Column `name` of a CSV's rows, parsed as f64 (empty cells as NaN).
fn csv_column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let i = lines.next().unwrap().split(',').position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    lines.map(|l| l.split(',').nth(i).unwrap().parse().unwrap_or(f64::NAN)).collect()
}

#[test]
fn hil_stop_output_is_go_after_arming_and_drops_at_the_detection() {
    // The firmware logs its boot "Reset" before t = 0 (during the self-test); after arming the
    // output is go, and it drops at the firmware's detection, latched to the end.
    let d = tmp("hil-stop");
    let csv = d.join("hil.csv");
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--phase", "0.3", "--json", "--csv"]).arg(&csv).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fw = &v["firmware"];
    assert!(fw["event_log"][0]["at_s"].as_f64().unwrap() < 0.0, "the boot event is logged before t = 0: {fw}");
    let detect = fw["firmware_detect_s"].as_f64().unwrap();
    let seen = fw["stop_seen_s"].as_f64().unwrap();
    let c = std::fs::read_to_string(&csv).unwrap();
    let (t, stop, sampled) = (csv_column(&c, "t_s"), csv_column(&c, "stop_requested"), csv_column(&c, "stop_seen_by_controller"));
    let before = t.iter().zip(&stop).filter(|(&t, _)| t < detect).collect::<Vec<_>>();
    let after = t.iter().zip(&stop).filter(|(&t, _)| t >= detect).collect::<Vec<_>>();
    assert!(before.len() > 1000 && after.len() > 100, "{} rows before, {} after", before.len(), after.len());
    assert!(before.iter().all(|(_, &s)| s == 0.0), "go (0) from t = 0 until the detection at {detect} s");
    assert!(after.iter().all(|(_, &s)| s == 1.0), "stop (1) from the detection at {detect} s on, latched");
    assert!(t.iter().zip(&sampled).all(|(&t, &s)| (s == 1.0) == (t >= seen)), "the controller sees it from {seen} s");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn every_json_output_carries_its_schema_version() {
    let runs: [&[&str]; 5] = [
        &["run", "tables5-7_bistable", "--json"],
        &["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--json"],
        &["check", "tables5-7_bistable", "--json"],
        &["design", "tables5-7_bistable", "--json"],
        &["avoid", "scenes/avoid_wall.toml", "--json"],
    ];
    for args in runs {
        let o = flinch().args(args).output().unwrap();
        no_panic(&o);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {}", text(&o.stdout)));
        // check is at 2: its lengths were renamed to carry their unit (docs/schema/check.json).
        let want = if args[0] == "check" { 2 } else { 1 };
        assert_eq!(v["schema_version"], want, "{args:?}: {}", text(&o.stdout));
        // Every numeric field of the document carries its unit: no bare length left in check/design.
        for bare in ["\"margin\"", "\"stroke\"", "\"stopping_distance\"", "\"speed\"", "\"dead_time\""] {
            assert!(!text(&o.stdout).contains(bare), "{args:?}: {bare} without a unit");
        }
        // Written first, so a reader can branch on it before the rest.
        assert!(text(&o.stdout).trim_start().starts_with("{\n  \"schema_version\""), "{args:?}");
    }
}

#[test]
fn avoid_and_bench_take_shipped_names_from_any_directory() {
    let d = tmp("names");
    let o = flinch().current_dir(&d).args(["avoid", "avoid_wall", "--json"]).output().unwrap();
    // The wall has no way round: a safe stop before the goal, exit 4 (docs/conventions.md).
    assert_eq!(o.status.code(), Some(4), "{}", text(&o.stderr));
    assert!(text(&o.stderr).is_empty(), "an answer, not an error: {}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["min_signed_distance_m"].is_number());
    let o = flinch().current_dir(&d).args(["avoid", "avoid_wal"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("avoid_wall"), "a close name is suggested: {}", text(&o.stderr));
    let o = flinch().current_dir(&d).args(["bench", "tables5-7_bistable", "--quick", "--repeats", "1", "--out", "b"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(d.join("b/runs.csv").is_file() && d.join("b/fixed_point.csv").is_file());
    // Bad input is exit 2, before anything runs.
    for args in [&["bench", "no_such_scene"][..], &["bench", "--repeats", "0"], &["bench", "--scenes-dir", "/no/such/dir"]] {
        let o = flinch().current_dir(&d).args(args).output().unwrap();
        no_panic(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn messages_go_to_stderr_and_csv_names_carry_their_unit() {
    let d = tmp("messages");
    let runs: [&[&str]; 4] = [
        &["design", "tables5-7_bistable", "--plot", "d.svg"],
        &["avoid", "avoid_wall", "--plot", "a.svg", "--csv", "a.csv"],
        &["robot", "robot_viper_standin", "--sweep-joint", "joint3", "--points", "5", "--plot", "r.svg", "--csv", "r.csv"],
        &["bench", "tables5-7_bistable", "--quick", "--repeats", "1", "--out", "b"],
    ];
    for args in runs {
        let o = flinch().current_dir(&d).args(args).output().unwrap();
        no_panic(&o);
        // `avoid avoid_wall` stops safely before the wall: exit 4.
        assert!(o.status.code().is_some_and(|c| c <= 1 || (args[0] == "avoid" && c == 4)), "{args:?}: {}", text(&o.stderr));
        let out = text(&o.stdout);
        assert!(!out.contains("wrote") && !out.contains("plot:") && !out.contains("d.svg") && !out.contains("a.svg"), "{args:?}: a message on stdout: {out}");
        assert!(text(&o.stderr).contains("wrote"), "{args:?}: {}", text(&o.stderr));
    }
    let header = |f: &str| std::fs::read_to_string(d.join(f)).unwrap().lines().next().unwrap().to_string();
    assert_eq!(header("r.csv"), "joint3_rad,mass_kg,stiffness_n_per_m,damping_ns_per_m,mobility,status,reason");
    let runs_csv = header("b/runs.csv");
    for want in ["max_step_s", "peak_contact_force_n", "peak_robot_force_n", "object_final_velocity_mps", "status", "reason"] {
        assert!(runs_csv.split(',').any(|c| c == want), "runs.csv lacks {want}: {runs_csv}");
    }
    assert!(!runs_csv.contains("_N,") && !runs_csv.contains("peak_contact_N"), "{runs_csv}");
    // Booleans are 0/1, and the labels with spaces and '=' are quoted by the csv crate, not mangled.
    let summary = std::fs::read_to_string(d.join("b/summary.csv")).unwrap();
    let mut rd = summary.lines();
    let cols: Vec<&str> = rd.next().unwrap().split(',').collect();
    let within = cols.iter().position(|c| *c == "within_1pct").unwrap();
    for l in rd {
        let last = l.rsplit(',').next().unwrap();
        assert!(last == "0" || last == "1", "within_1pct is 0/1: {l} ({within})");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn run_exits_0_on_a_not_safe_summary_as_the_conventions_say() {
    let o = flinch().args(["run", "table14_hydraulic_surface", "--json"]).output().unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["safe"], false, "the scene is the NOT SAFE example");
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(flinch().args(["check", "table14_hydraulic_surface"]).output().unwrap().status.code(), Some(1));
    let conv = std::fs::read_to_string(repo().join("docs/conventions.md")).unwrap();
    assert!(conv.contains("a `flinch run` whose summary says NOT SAFE (`\"safe\": false`) exits 0"), "docs/conventions.md must state it");
    // The contract lives in the repo: no source points at ../shared/.
    for f in ["host-harness/crates/model/src/scene/model.rs", "host-harness/src/main.rs", "README.md"] {
        let t = std::fs::read_to_string(repo().join(f)).unwrap();
        assert!(!t.contains("shared/SCENES.md") && !t.contains("shared/MODEL.md"), "{f} points outside the repo");
    }
}
