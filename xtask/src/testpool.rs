//! The stage "host tests" run as a pool: `cargo test --workspace --no-run` builds every test
//! binary (the same binaries `cargo test --workspace` builds), then they run side by side, as many
//! at once as the machine has cores, the slowest first, each as cargo would run it (its package
//! folder as the working directory, its default test threads), then the doc tests.
//!
//! Why (issue 28 item 5): `cargo test` runs its binaries one after the other, and a binary holds
//! the machine until its longest test ends: `box` and `avoid_recorded` ran at about one core of two
//! for minutes (docs/performance.md section 4). In the pool another binary uses that core. Each
//! binary's output is kept in `target/xtask-tests/<binary>.log` and printed whole when it ends, so
//! outputs never interleave; every binary runs to its end (cargo stops at the first failing one).

use crate::common::{cargo, repo_root, seconds, target_dir};
use std::collections::VecDeque;
use std::fs::{self, File};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// One test executable of `cargo test --workspace --no-run`.
#[derive(Debug, Clone, PartialEq)]
pub struct TestBinary {
    /// The target's name (`box`, `flinch_harness`) and kind (`lib`, `bin`, `test`).
    pub name: String,
    pub kind: String,
    pub path: PathBuf,
    /// The package's folder: cargo runs a test binary there.
    pub dir: PathBuf,
}

impl TestBinary {
    fn label(&self) -> String {
        format!("{} ({})", self.name, self.kind)
    }
}

/// CPU seconds per binary measured in docs/performance.md section 4 (`python/bench/test_times.py`,
/// load 7-11): the order the pool starts them in, slowest first, so no long binary starts last.
/// A binary not listed counts as 1 s; the order only changes the wall time, never what runs.
const MEASURED_CPU_S: &[(&str, f64)] = &[
    ("avoid_adversarial", 233.0),
    ("avoid_recorded", 136.0),
    ("box", 124.0),
    ("validation", 57.0),
    ("flinch_harness", 37.0),
    ("body", 22.0),
    ("sample", 18.0),
    ("cli", 14.0),
    ("sample_cli", 12.0),
    ("hil_cli", 10.5),
    ("readme", 8.3),
    ("report", 5.3),
    ("sample_parquet", 3.0),
    ("stability", 2.7),
    ("reference", 2.4),
    ("thesis", 2.0),
];

fn weight(b: &TestBinary) -> f64 {
    MEASURED_CPU_S.iter().find(|(n, _)| *n == b.name).map_or(1.0, |(_, s)| *s)
}

/// The string value of `"key":"..."` at or after `from` in one JSON line (cargo escapes only `"`
/// and `\` in paths here).
fn string_field(l: &str, key: &str, from: usize) -> Option<String> {
    let pat = format!("\"{key}\":\"");
    let start = l[from..].find(&pat)? + from + pat.len();
    let mut out = String::new();
    let mut chars = l[start..].chars();
    while let Some(c) = chars.next() {
        match c {
            '"' => return Some(out),
            '\\' => out.push(chars.next()?),
            c => out.push(c),
        }
    }
    None
}

/// The test executables in cargo's JSON messages: compiler artifacts built with the test harness
/// (`"profile":{..."test":true}`) that have an executable, in cargo's order, each once.
pub fn test_binaries(json: &str) -> Vec<TestBinary> {
    let mut out: Vec<TestBinary> = Vec::new();
    for l in json.lines().filter(|l| l.contains("\"reason\":\"compiler-artifact\"")) {
        let Some(p) = l.find("\"profile\":{") else { continue };
        let profile = &l[p..p + l[p..].find('}').unwrap_or(0)];
        if !profile.contains("\"test\":true") {
            continue;
        }
        let (Some(path), Some(manifest), Some(t)) = (string_field(l, "executable", 0), string_field(l, "manifest_path", 0), l.find("\"target\":{")) else {
            continue;
        };
        let kind = l[t..].find("\"kind\":[\"").map(|k| l[t + k + 9..].split('"').next().unwrap_or("").to_string()).unwrap_or_default();
        let name = string_field(l, "name", t).unwrap_or_default();
        let dir = PathBuf::from(manifest).parent().map(PathBuf::from).unwrap_or_else(repo_root);
        let b = TestBinary { name, kind, path: PathBuf::from(path), dir };
        if !out.contains(&b) {
            out.push(b);
        }
    }
    out
}

/// Builds the host tests (`cargo test --workspace --no-run`, diagnostics shown as cargo shows
/// them) and returns their executables.
pub fn build() -> Result<Vec<TestBinary>, String> {
    let out = cargo()
        .args(["test", "--workspace", "--no-run", "--message-format=json-render-diagnostics"])
        .current_dir(repo_root())
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!("cargo test --workspace --no-run exited with {}", out.status));
    }
    let bins = test_binaries(&String::from_utf8_lossy(&out.stdout));
    if bins.is_empty() {
        return Err("cargo test --workspace --no-run listed no test binary".into());
    }
    Ok(bins)
}

struct Running {
    bin: TestBinary,
    child: Child,
    log: PathBuf,
    start: Instant,
}

/// Runs `bins` with at most `jobs` at once, the slowest (by [`MEASURED_CPU_S`]) first. Prints each
/// binary's output whole when it ends. Returns the labels of the binaries that failed.
pub fn run(mut bins: Vec<TestBinary>, jobs: usize) -> Result<Vec<String>, String> {
    bins.sort_by(|a, b| weight(b).total_cmp(&weight(a)));
    let logs = target_dir().join("xtask-tests");
    fs::create_dir_all(&logs).map_err(|e| format!("{}: {e}", logs.display()))?;
    let deps = target_dir().join("debug").join("deps");
    let mut queue: VecDeque<TestBinary> = bins.into();
    let mut running: Vec<Running> = Vec::new();
    let mut failed = Vec::new();
    while !queue.is_empty() || !running.is_empty() {
        while running.len() < jobs.max(1) {
            let Some(bin) = queue.pop_front() else { break };
            let log = logs.join(format!("{}-{}.log", bin.name, bin.kind));
            let file = File::create(&log).map_err(|e| format!("{}: {e}", log.display()))?;
            let err = file.try_clone().map_err(|e| format!("{}: {e}", log.display()))?;
            let mut cmd = Command::new(&bin.path);
            cmd.current_dir(&bin.dir)
                .env("CARGO_MANIFEST_DIR", &bin.dir)
                .env("LD_LIBRARY_PATH", std::env::join_paths([deps.clone()]).unwrap_or_default())
                .stdin(Stdio::null())
                .stdout(file)
                .stderr(err);
            let child = cmd.spawn().map_err(|e| format!("could not start {}: {e}", bin.path.display()))?;
            running.push(Running { bin, child, log, start: Instant::now() });
        }
        let mut i = 0;
        let mut ended = false;
        while i < running.len() {
            match running[i].child.try_wait() {
                Ok(Some(status)) => {
                    let r = running.swap_remove(i);
                    let text = fs::read_to_string(&r.log).unwrap_or_else(|e| format!("(could not read {}: {e})", r.log.display()));
                    println!("     Running {} ({})", r.bin.label(), r.bin.path.display());
                    print!("{text}");
                    println!("xtask: {} {} in {}", r.bin.label(), if status.success() { "passed" } else { "FAILED" }, seconds(r.start.elapsed()));
                    if !status.success() {
                        failed.push(format!("{} (exit {status}, log {})", r.bin.label(), r.log.display()));
                    }
                    ended = true;
                }
                Ok(None) => i += 1,
                Err(e) => return Err(format!("waiting for {}: {e}", running[i].bin.label())),
            }
        }
        if !ended {
            sleep(Duration::from_millis(50));
        }
    }
    Ok(failed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_test_executables_once_each_with_their_package_folder() {
        let json = concat!(
            "{\"reason\":\"compiler-artifact\",\"package_id\":\"path+file:///r/tests#flinch-tests@0.1.0\",\"manifest_path\":\"/r/tests/Cargo.toml\",\"target\":{\"kind\":[\"test\"],\"crate_types\":[\"bin\"],\"name\":\"box\",\"src_path\":\"/r/tests/box.rs\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":true},\"features\":[],\"filenames\":[\"/r/target/debug/deps/box-1\"],\"executable\":\"/r/target/debug/deps/box-1\",\"fresh\":true}\n",
            // the flinch binary itself (not a test harness) and a library without an executable
            "{\"reason\":\"compiler-artifact\",\"manifest_path\":\"/r/host-harness/Cargo.toml\",\"target\":{\"kind\":[\"bin\"],\"name\":\"flinch\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":false},\"executable\":\"/r/target/debug/flinch\"}\n",
            "{\"reason\":\"compiler-artifact\",\"manifest_path\":\"/r/host-harness/Cargo.toml\",\"target\":{\"kind\":[\"lib\"],\"name\":\"flinch_harness\",\"test\":true},\"profile\":{\"test\":false},\"executable\":null}\n",
            "{\"reason\":\"compiler-artifact\",\"manifest_path\":\"/r/host-harness/Cargo.toml\",\"target\":{\"kind\":[\"lib\"],\"name\":\"flinch_harness\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":true},\"executable\":\"/r/target/debug/deps/flinch_harness-2\"}\n",
            "{\"reason\":\"compiler-artifact\",\"manifest_path\":\"/r/tests/Cargo.toml\",\"target\":{\"kind\":[\"test\"],\"name\":\"box\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":true},\"executable\":\"/r/target/debug/deps/box-1\"}\n",
            "{\"reason\":\"build-finished\",\"success\":true}\n",
        );
        let bins = test_binaries(json);
        assert_eq!(bins.len(), 2, "{bins:?}");
        assert_eq!((bins[0].name.as_str(), bins[0].kind.as_str()), ("box", "test"));
        assert_eq!(bins[0].dir, PathBuf::from("/r/tests"));
        assert_eq!(bins[0].path, PathBuf::from("/r/target/debug/deps/box-1"));
        assert_eq!((bins[1].name.as_str(), bins[1].kind.as_str()), ("flinch_harness", "lib"));
        assert!(test_binaries("{\"reason\":\"build-finished\",\"success\":true}").is_empty());
    }

    #[test]
    fn runs_every_binary_and_names_the_failures() {
        let dir = std::env::temp_dir().join(format!("xtask-testpool-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let script = |name: &str, body: &str| {
            use std::os::unix::fs::PermissionsExt;
            let p = dir.join(name);
            fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
            fs::set_permissions(&p, fs::Permissions::from_mode(0o755)).unwrap();
            TestBinary { name: format!("pool-{name}"), kind: "test".into(), path: p, dir: dir.clone() }
        };
        // The failing one first in the queue: a failure must not stop the others.
        let bins = vec![
            script("fails", "echo failing >&2; exit 3"),
            script("slow", "sleep 0.3; pwd > slow.out"),
            script("quick", "echo ok > quick.out"),
        ];
        let failed = run(bins, 2).unwrap();
        assert_eq!(failed.len(), 1, "{failed:?}");
        assert!(failed[0].starts_with("pool-fails (test)"), "{failed:?}");
        assert_eq!(fs::read_to_string(dir.join("quick.out")).unwrap().trim(), "ok");
        // run in the package folder, as cargo runs a test binary
        assert_eq!(fs::read_to_string(dir.join("slow.out")).unwrap().trim(), dir.to_str().unwrap());
        let log = fs::read_to_string(target_dir().join("xtask-tests").join("pool-fails-test.log")).unwrap();
        assert!(log.contains("failing"), "stderr not in the log: {log}");
        let _ = fs::remove_dir_all(&dir);
    }
}
