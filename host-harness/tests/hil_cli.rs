//! `flinch hil` as a user meets it: a long run streams its CSV in bounded memory and stops cleanly
//! on Ctrl-C with the file flagged partial; `[controller]` values are refused with file, line and
//! key; a module hil cannot run is refused (exit 2) for its real reason.

mod common;
use std::io::Read;
use common::{bytes_written, flinch, peak_rss_kb, repo, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    common::tmp_in("hil-cli", name)
}

/// Tables 5-7 with `extra` appended and `duration` replaced, written to `dir`.
fn scene(dir: &Path, duration: f64, extra: &str) -> PathBuf {
    let t = std::fs::read_to_string(repo().join("scenes/tables5-7_bistable.toml")).unwrap();
    let t = t.replace("duration = 0.6 ", &format!("duration = {duration} "));
    let p = dir.join("s.toml");
    std::fs::write(&p, format!("{t}\n{extra}")).unwrap();
    p
}

#[test]
fn a_long_hil_run_streams_its_csv_and_decimates_its_plot_in_bounded_memory() {
    let d = tmp("long");
    // 20 s at 10 us: two million rows; the old hil kept every sample (and the whole history)
    // until the end.
    let sc = scene(&d, 20.0, "[solver]\noutput_interval = 1e-5\n");
    let mut c = flinch();
    c.args(["hil"]).arg(&sc).args(["--scan-cycle", "0.016", "--csv"]).arg(d.join("h.csv")).args(["--plot"]).arg(d.join("h.png"));
    let (kb, o) = peak_rss_kb(c, Duration::from_secs(300));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.contains("will receive about 2000001 rows"), "says up front what it will write: {err}");
    let f = std::io::BufReader::new(std::fs::File::open(d.join("h.csv")).unwrap());
    let mut n = 0;
    let mut last = String::new();
    let mut header = String::new();
    for l in std::io::BufRead::lines(f) {
        let l = l.unwrap();
        if n == 0 {
            header = l.clone();
        }
        n += 1;
        last = l;
    }
    assert_eq!(n, 2_000_002, "header and every row");
    assert!(header.ends_with("switch_tripped,stop_requested,stop_seen_by_controller"), "{header}");
    assert!(last.ends_with(",1,1"), "the stop, latched, seen by the controller at the end: {last}");
    assert!(kb < 80_000, "peak resident set {kb} kB");
    assert!(std::fs::metadata(d.join("h.png")).unwrap().len() > 20_000);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ctrl_c_stops_a_long_hil_run_with_complete_rows_and_says_the_file_is_partial() {
    let d = tmp("sigint");
    let sc = scene(&d, 60.0, "[solver]\noutput_interval = 1e-5\n");
    let csv = d.join("h.csv");
    let mut child = flinch().args(["hil"]).arg(&sc).args(["--scan-cycle", "0.016", "--csv"]).arg(&csv).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while bytes_written(&csv) < 200_000 && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted at t =") && err.contains("is partial"), "{err}");
    let body = std::fs::read_to_string(&csv).unwrap();
    assert!(body.ends_with('\n'), "the last row is complete");
    let cols = body.lines().next().unwrap().split(',').count();
    assert!(body.lines().all(|l| l.split(',').count() == cols));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn controller_values_are_refused_with_file_line_and_key() {
    let d = tmp("ctl");
    // Not a whole number of microseconds: the firmware's clock cannot tick at it.
    let sc = scene(&d, 0.6, "[controller]\nscan_cycle = 0.016\nphase = 0.0\nfirmware_tick = 1.5e-6\n");
    let o = flinch().args(["hil"]).arg(&sc).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let e = text(&o.stderr);
    let line = std::fs::read_to_string(&sc).unwrap().lines().position(|l| l.starts_with("firmware_tick")).unwrap() + 1;
    assert!(e.contains(&format!("s.toml:{line}: controller.firmware_tick: a whole number of microseconds")), "{e}");
    assert!(!e.contains("--step") && !e.contains("--tick"), "a scene value is not an option: {e}");
    // A 2 us tick is fine (it used to be refused as a --step error: the old lockstep's default
    // 10 us step was longer than the tick).
    let sc = scene(&d, 0.6, "[controller]\nscan_cycle = 0.016\nphase = 0.0\nfirmware_tick = 2e-6\n");
    let o = flinch().args(["hil"]).arg(&sc).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    // Out of range in the scene: the loader's own message.
    let sc = scene(&d, 0.6, "[controller]\nscan_cycle = 0.016\nphase = 0.0\nfirmware_tick = 1e-4\nbrake_decel = 0\n");
    let o = flinch().args(["hil"]).arg(&sc).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("controller.brake_decel: allowed range"), "{}", text(&o.stderr));
    // An option is named as an option.
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--tick", "1.5e-6"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("'--tick <S>': controller.firmware_tick: a whole number of microseconds"), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_module_hil_cannot_run_and_bad_flags_are_exit_2_with_the_reason() {
    let d = tmp("refuse");
    let t = std::fs::read_to_string(repo().join("scenes/table2_linear.toml")).unwrap();
    let t = t.replace("kind = \"force\"", "kind = \"travel\"").replace("threshold = 1.0 ", "threshold = 0.005 ");
    let p = d.join("lin.toml");
    std::fs::write(&p, t).unwrap();
    let o = flinch().args(["hil"]).arg(&p).args(["--scan-cycle", "0.016"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("decoupler.kind: flinch hil cannot run a \"linear\" spring-damper: it has no end-stops"), "{}", text(&o.stderr));
    for (flag, value, says) in [("--filter", "median", "consecutive:N"), ("--reset-policy", "button", "auto:SECONDS"), ("--filter", "consecutive:0", "1 to 255")] {
        let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", flag, value]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        assert!(text(&o.stderr).contains(says), "{flag} {value}: {}", text(&o.stderr));
    }
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--filter", "consecutive:2", "--reset-policy", "auto:0.05", "--json"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["firmware"]["filter"], "consecutive:2");
    assert_eq!(v["firmware"]["reset_policy"], "auto:0.05");
    // The board ELF's worst case (hal-sim/src/latency.rs), not a figure written here.
    assert_eq!(v["firmware"]["edge_to_stop_latency_s"], flinch_harness::hil::latency::edge_to_stop_s());
    assert_eq!(v["firmware"]["tick_to_output_latency_s"], flinch_harness::hil::latency::tick_to_output_s());
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue 26 item 2 at the command line: `--reaction-time` moves braking by that much after the
/// sample that saw the stop, the text says how the dead time was formed, and a reaction outside
/// [0, 1] s is refused as an option (exit 2).
#[test]
fn the_reaction_time_moves_braking_and_the_text_says_how_the_dead_time_was_formed() {
    let run = |extra: &[&str]| {
        let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--json"]).args(extra).output().unwrap();
        assert!(o.status.success(), "{}", text(&o.stderr));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    let (a, b) = (run(&[]), run(&["--reaction-time", "0.03"]));
    let brake = |v: &serde_json::Value| v["t_brake"].as_f64().unwrap();
    assert!((brake(&b) - brake(&a) - 0.03).abs() < 1e-9, "{} vs {}", brake(&b), brake(&a));
    assert_eq!(b["firmware"]["dead_time_model"]["reaction_time_source"], "controller.reaction_time");
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--reaction-time", "0.03"]).output().unwrap();
    let out = text(&o.stdout);
    assert!(out.contains("robot reaction 30.000 ms (controller.reaction_time)") && out.contains("scan wait"), "{out}");
    assert!(out.contains("differs from motion.dead_time"), "DT = 16 ms is the scan alone: {out}");
    for bad in ["--reaction-time=-0.01", "--reaction-time=1.5"] {
        let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", bad]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(text(&o.stderr).contains("--reaction-time: must be in [0, 1] s"), "{bad}: {}", text(&o.stderr));
    }
}

/// `--worst-phase` waits the whole scan, says so, and cannot be combined with `--phase`.
#[test]
fn the_worst_phase_flag_waits_the_whole_scan_and_refuses_a_phase_beside_it() {
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--worst-phase", "--json"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let d = &v["firmware"]["dead_time_model"];
    assert_eq!(d["worst_phase"], true);
    assert!((d["scan_wait_s"].as_f64().unwrap() - 0.016).abs() < 1e-9, "{d}");
    let o = flinch().args(["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--worst-phase", "--phase", "0.3"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
}
