//! Issue 27: every door of the `flinch` binary, as a user meets it. Inputs: a FIFO, a device or a
//! directory refused by name at once (no hang: each child is killed after 20 s and that fails the
//! test), a `robot.joints` list longer than the chain refused (it panicked). Outputs: never an input
//! of the same command, never a new file in /dev, a failed write leaves the old file. Numbers: the
//! command-line options held to their scene keys' ranges. Terminal text: no control or bidi
//! character reaches it raw.
mod common;
use common::{flinch, repo, text, tmp_in};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `c` with a wall limit; a child still running then is killed and the test fails (a hang).
fn bounded(mut c: Command, what: &str) -> Output {
    let mut child = c.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let t0 = Instant::now();
    loop {
        if let Some(_) = child.try_wait().unwrap() {
            return child.wait_with_output().unwrap();
        }
        if t0.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running after 20 s (a hang)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn dir(name: &str) -> PathBuf {
    let d = tmp_in("io", name);
    for e in std::fs::read_dir(&d).unwrap().flatten() {
        let _ = std::fs::remove_file(e.path());
    }
    d
}

fn mkfifo(p: &Path) {
    let _ = std::fs::remove_file(p);
    assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
}

/// scenes/robot_two_link.toml copied into `d` with its URDF path replaced by `urdf` (and the
/// shipped URDF copied beside it when `urdf` is the default).
fn two_link_in(d: &Path, urdf: &str) -> PathBuf {
    let t = std::fs::read_to_string(repo().join("scenes/robot_two_link.toml")).unwrap();
    std::fs::copy(repo().join("scenes/robots/two_link.urdf"), d.join("two_link.urdf")).unwrap();
    let p = d.join("scene.toml");
    std::fs::write(&p, t.replace("robots/two_link.urdf", urdf)).unwrap();
    p
}

#[test]
fn every_file_input_refuses_a_fifo_a_device_and_a_directory_at_once() {
    let d = dir("inputs");
    let fifo = d.join("fifo");
    mkfifo(&fifo);
    let f = fifo.to_str().unwrap();
    let urdf_fifo = two_link_in(&d, f);
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["run".into(), f.into()], "(a FIFO)"),
        (vec!["run".into(), urdf_fifo.display().to_string()], "(a FIFO)"),
        (vec!["robot".into(), urdf_fifo.display().to_string()], "(a FIFO)"),
        (vec!["run".into(), "table1_rigid_tool".into(), "--measured".into(), f.into()], "(a FIFO)"),
        (vec!["sample".into(), "--merge".into(), f.into()], "(a FIFO)"),
        (vec!["sample".into(), "--merge".into(), "/dev/zero".into()], "(a character device)"),
        (vec!["sample".into(), "--merge".into(), d.display().to_string()], "is a directory"),
        (vec!["avoid".into(), "avoid_operator_hand".into(), "--calibration".into(), f.into()], "(a FIFO)"),
        (vec!["avoid".into(), "avoid_operator_hand".into(), "--calibration".into(), "/dev/urandom".into()], "(a character device)"),
        (vec!["avoid".into(), "avoid_operator_hand".into(), "--depth".into(), f.into()], "(a FIFO)"),
        (vec!["avoid".into(), "avoid_operator_hand".into(), "--depth".into(), "/dev/zero".into(), "--robot-poses".into(), f.into()], "(a character device)"),
    ];
    for (args, want) in cases {
        let mut c = flinch();
        c.args(&args);
        let o = bounded(c, &args.join(" "));
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains(want), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
    // The URDF of /dev/zero read 2.1 GB before; refused at once now.
    let zero = two_link_in(&d, "/dev/zero");
    let mut c = flinch();
    c.args(["check"]).arg(&zero);
    let o = bounded(c, "URDF /dev/zero");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("robot.urdf: cannot read the URDF: /dev/zero: is not a regular file (a character device)"), "{}", text(&o.stderr));
    // A scene over its cap (sparse: 3 GiB said, nothing on disk) is refused before it is read.
    let big = d.join("big.toml");
    std::fs::File::create(&big).unwrap().set_len(3 << 30).unwrap();
    let mut c = flinch();
    c.args(["run"]).arg(&big);
    let o = bounded(c, "3 GiB scene");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("3221225472 bytes; a scene file is at most 1 MiB"), "{}", text(&o.stderr));
    let _ = std::fs::remove_file(&big);
}

#[test]
fn joints_longer_than_the_chain_are_refused_not_a_panic() {
    let d = dir("joints");
    let p = two_link_in(&d, "two_link.urdf");
    let t = std::fs::read_to_string(&p).unwrap().replace("joints = { shoulder = 0.3, elbow = 1.2 }", "joints = [0.3, 1.2, 0.5]");
    std::fs::write(&p, t).unwrap();
    for cmd in ["run", "check", "robot"] {
        let mut c = flinch();
        c.arg(cmd).arg(&p);
        let o = bounded(c, cmd);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", text(&o.stderr));
        assert!(text(&o.stderr).contains("robot.joints: has 3 values; the chain \"base\" -> \"tip\" has 2 moving joints"), "{cmd}: {}", text(&o.stderr));
    }
}

#[test]
fn an_output_never_replaces_an_input_of_the_same_command() {
    let d = dir("outputs");
    let scene = d.join("own.toml");
    let original = std::fs::read_to_string(repo().join("scenes/tables5-7_bistable.toml")).unwrap();
    std::fs::write(&scene, &original).unwrap();
    std::fs::hard_link(&scene, d.join("hard.toml")).unwrap();
    std::os::unix::fs::symlink(&scene, d.join("sym.csv")).unwrap();
    for (opt, target) in [("--csv", scene.clone()), ("--csv", d.join("hard.toml")), ("--csv", d.join("sym.csv")), ("--plot", d.join("sym.csv").with_extension("svg"))] {
        if opt == "--plot" {
            std::os::unix::fs::symlink(&scene, &target).unwrap();
        }
        let mut c = flinch();
        c.args(["run"]).arg(&scene).arg(opt).arg(&target);
        let o = bounded(c, "run --csv own");
        assert_eq!(o.status.code(), Some(2), "{opt} {}: {}", target.display(), text(&o.stderr));
        assert!(text(&o.stderr).contains("is a file this command reads"), "{}", text(&o.stderr));
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), original, "the scene was overwritten");
    }
    // No new file in /dev; /dev/null keeps working, another device is refused.
    let dev = Path::new("/dev/flinch-io-test.svg");
    let _ = std::fs::remove_file(dev);
    let mut c = flinch();
    c.args(["run", "tables5-7_bistable", "--plot"]).arg(dev);
    let o = bounded(c, "--plot /dev/x.svg");
    let created = dev.exists();
    let _ = std::fs::remove_file(dev);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(!created, "a file was created in /dev");
    assert!(text(&o.stderr).contains("a kernel file system"), "{}", text(&o.stderr));
    let mut c = flinch();
    c.args(["run", "tables5-7_bistable", "--csv", "/dev/null"]);
    assert_eq!(bounded(c, "--csv /dev/null").status.code(), Some(0));
    let mut c = flinch();
    c.args(["run", "tables5-7_bistable", "--csv", "/dev/urandom"]);
    let o = bounded(c, "--csv /dev/urandom");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("is a device"), "{}", text(&o.stderr));
}

#[test]
fn a_failed_write_leaves_the_old_file_and_no_temporary_file() {
    let d = dir("failed");
    let out = d.join("out.csv");
    std::fs::write(&out, "the old file\n").unwrap();
    // The file-size limit makes the write fail (EFBIG) part way; SIGXFSZ ignored so it is an error.
    let cmd = format!("trap '' XFSZ; ulimit -f 64; exec '{}' run tables5-7_bistable --csv '{}'", env!("CARGO_BIN_EXE_flinch"), out.display());
    let mut c = Command::new("sh");
    c.args(["-c", &cmd]).current_dir(repo());
    let o = bounded(c, "ulimit -f");
    assert_eq!(o.status.code(), Some(3), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "the old file\n");
    let left: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().map(|e| e.file_name()).collect();
    assert_eq!(left.len(), 1, "{left:?}");
    // And a run that ends well replaces it.
    let mut c = flinch();
    c.args(["run", "tables5-7_bistable", "--csv"]).arg(&out);
    assert_eq!(bounded(c, "run --csv").status.code(), Some(0));
    assert!(std::fs::read_to_string(&out).unwrap().starts_with("t_s,"));
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
}

#[test]
fn every_number_option_is_held_to_its_key_s_range() {
    let cases: &[(&[&str], &str)] = &[
        (&["hil", "tables5-7_bistable", "--scan-cycle", "9e-6"], "controller.scan_cycle: allowed range [1e-5, 0.1] s"),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "1e-12"], "controller.scan_cycle: allowed range"),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.5"], "controller.scan_cycle: allowed range"),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--phase", "1"], "controller.phase: allowed range"),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--tick", "0.1"], "controller.firmware_tick: allowed range"),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--fault", "stuck-rest@1e300"], "is not before the end of the run"),
        (&["design", "tables5-7_bistable", "--speed", "100"], "motion.speed: allowed range"),
        (&["design", "tables5-7_bistable", "--speed", "nan"], "motion.speed: allowed range"),
        (&["design", "tables5-7_bistable", "--dead-time", "1e6"], "motion.dead_time: allowed range"),
        (&["sweep", "table1_rigid_tool", "--vary", "tool.mass=0.2:1:3", "--jobs", "100000"], "allowed range [1, 1024] threads"),
        (&["sample", "table1_rigid_tool", "--vary", "tool.mass=uniform:0.3:0.5", "--samples", "10", "--jobs", "100000"], "allowed range [1, 1024] threads"),
        (&["bench", "--repeats", "1000000000"], "allowed range [1, 1000] timed repetitions"),
    ];
    for (args, want) in cases {
        let mut c = flinch();
        c.args(*args);
        let t0 = Instant::now();
        let o = bounded(c, &args.join(" "));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        assert!(text(&o.stderr).contains(want), "{args:?}: {}", text(&o.stderr));
        assert!(t0.elapsed() < Duration::from_secs(10), "{args:?}: refused only after {:?}", t0.elapsed());
    }
}

#[test]
fn terminal_text_escapes_control_and_bidi_characters() {
    let d = dir("terminal");
    let p = d.join("ctl.toml");
    let t = std::fs::read_to_string(repo().join("scenes/tables5-7_bistable.toml")).unwrap();
    let name_line = t.lines().find(|l| l.starts_with("name")).unwrap().to_string();
    let evil = r#"name = "evil \u001b[31mRED\u001b[0m \u202eSAFE\u202c \u0007 bell \u009b2J""#;
    std::fs::write(&p, t.replace(&name_line, evil)).unwrap();
    let bad = d.join("bad.toml");
    std::fs::write(&bad, format!("{}\n\"\\u001b[2J\\u202e\" = 1\n", t.replace(&name_line, evil))).unwrap();
    for (args, scene) in [(vec!["run"], &p), (vec!["check"], &p), (vec!["run"], &bad)] {
        let mut c = flinch();
        c.args(&args).arg(scene);
        let o = bounded(c, "evil name");
        for s in [text(&o.stdout), text(&o.stderr)] {
            let raw: Vec<char> = s.chars().filter(|&c| (c < ' ' && c != '\n' && c != '\t') || ('\u{7f}'..='\u{9f}').contains(&c) || ('\u{202a}'..='\u{202e}').contains(&c)).collect();
            assert!(raw.is_empty(), "{args:?}: raw {raw:?} in {s}");
        }
        assert!(text(&o.stdout).contains("\\u202eSAFE") || text(&o.stderr).contains("\\u202e"), "{args:?}: {}", text(&o.stdout));
    }
    // JSON parses back to the exact name.
    let mut c = flinch();
    c.args(["run", "--json"]).arg(&p);
    let o = bounded(c, "run --json");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["scene"].as_str().unwrap(), "evil \u{1b}[31mRED\u{1b}[0m \u{202e}SAFE\u{202c} \u{7} bell \u{9b}2J");
    assert!(!text(&o.stdout).contains('\u{202e}'));
}

#[test]
fn an_interrupted_sweep_keeps_its_rows_in_grid_order_and_exits_130() {
    let d = dir("sweep_int");
    let out = d.join("s.csv");
    // 1e5 points take about a minute: interrupted after 3 s, the rows so far are kept.
    let mut child = flinch()
        .args(["sweep", "table1_rigid_tool", "--vary", "tool.mass=0.2:1:100000", "--jobs", "2", "--csv"])
        .arg(&out)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(3));
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let t0 = Instant::now();
    let o = loop {
        if child.try_wait().unwrap().is_some() {
            break child.wait_with_output().unwrap();
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "did not stop after Ctrl-C");
        std::thread::sleep(Duration::from_millis(20));
    };
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("interrupted after ") && e.contains("in grid order"), "{e}");
    let csv = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert!(!rows.is_empty() && rows.len() < 100_000, "{} rows", rows.len());
    assert!(csv.lines().next().unwrap().starts_with("tool.mass,"));
    // A complete prefix of the grid, in order, each row complete.
    let cols = csv.lines().next().unwrap().split(',').count();
    for (k, r) in rows.iter().enumerate() {
        let x: f64 = r.split(',').next().unwrap().parse().unwrap();
        assert!((x - (0.2 + 0.8 * k as f64 / 99_999.0)).abs() < 1e-9, "row {k}: {x}");
        assert!(r.split(',').count() >= cols - 1, "row {k} cut short: {r}");
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "a temporary file was left");
}
