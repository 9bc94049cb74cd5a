//! What every stage uses: the repo and target folders, cargo, running a command with a time limit,
//! the host tests' `flinch` binary, the stages' wall times, and flip-link installed when missing.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// What a stage of `cargo xtask test` came to.
pub enum Outcome {
    Pass(String),
    Fail(String),
    Skip(String),
}

pub const TARGET: &str = "thumbv7em-none-eabihf";
pub const QEMU_TIMEOUT: Duration = Duration::from_secs(120);

pub fn repo_root() -> PathBuf {
    // xtask/ sits in the repo root.
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(Path::to_path_buf).unwrap_or(manifest)
}

pub fn cargo() -> Command {
    Command::new(env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

pub fn target_dir() -> PathBuf {
    match env::var_os("CARGO_TARGET_DIR") {
        Some(d) => {
            let d = PathBuf::from(d);
            if d.is_absolute() {
                d
            } else {
                repo_root().join("firmware").join(d)
            }
        }
        None => repo_root().join("target"),
    }
}

pub fn elf_path(bin: &str) -> PathBuf {
    target_dir().join(TARGET).join("release").join(bin)
}

pub fn which(name: &str) -> Option<PathBuf> {
    env::var_os("PATH").and_then(|p| env::split_paths(&p).map(|d| d.join(name)).find(|f| f.is_file()))
}

/// Runs `cmd` with stdout captured (stderr passed through), killing it after `limit`.
pub fn run_captured(mut cmd: Command, what: &str, limit: Duration) -> Result<(String, std::process::ExitStatus), String> {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| format!("could not start {what}: {e}"))?;
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!("{what} did not exit within {} s", limit.as_secs()));
            }
            Ok(None) => sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("waiting for {what}: {e}")),
        }
    };
    let mut stdout = String::new();
    if let Some(mut out) = child.stdout.take() {
        use std::io::Read;
        out.read_to_string(&mut stdout).map_err(|e| format!("reading {what} output: {e}"))?;
    }
    Ok((stdout, status))
}

/// A checked-in expected file without its `#` comments and blank lines.
pub fn read_expected(rel: &str) -> Result<Vec<String>, String> {
    let path = repo_root().join(rel);
    let text = fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    Ok(text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()).map(String::from).collect())
}

/// The stages' outcomes with the wall time each took. A stage's time is what passed since the
/// previous one was recorded (the stage list computes each outcome just before recording it), and
/// is printed as it is recorded, so a long run shows where it is; checks that share one run (the
/// QEMU self-test's output, its stack and instruction count) show the run on the first and about
/// 0 s on the others.
pub struct Timed<T> {
    pub list: Vec<(&'static str, T, Duration)>,
    start: Instant,
    last: Instant,
}

impl<T> Default for Timed<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> Timed<T> {
    pub fn new() -> Self {
        let now = Instant::now();
        Self { list: Vec::new(), start: now, last: now }
    }

    pub fn push(&mut self, (stage, outcome): (&'static str, T)) {
        let now = Instant::now();
        let took = now - self.last;
        self.last = now;
        println!("xtask: stage {stage} took {}", seconds(took));
        self.list.push((stage, outcome, took));
    }

    /// Since `new`.
    pub fn total(&self) -> Duration {
        self.start.elapsed()
    }
}

/// A duration as people read it: `42.1 s`, `12 min 3 s`.
pub fn seconds(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 60.0 {
        format!("{s:.1} s")
    } else {
        format!("{} min {:.0} s", (s / 60.0).floor(), s % 60.0)
    }
}

/// flip-link, the firmware's linker (firmware/.cargo/config.toml), installed when it is missing:
/// `cargo install flip-link --locked` (the thumbv7em target comes with rust-toolchain.toml). Says
/// what it did; a failed install is printed and the firmware build then fails with the linker's
/// own error (or is skipped without the target).
pub fn ensure_flip_link() {
    if which("flip-link").is_some() {
        return;
    }
    println!("xtask: flip-link (the firmware's linker) is not installed: running `cargo install flip-link --locked`");
    let start = Instant::now();
    match cargo().args(["install", "flip-link", "--locked"]).stdin(Stdio::null()).status() {
        Ok(s) if s.success() => println!("xtask: installed flip-link in {}", seconds(start.elapsed())),
        Ok(s) => println!("xtask: `cargo install flip-link --locked` exited with {s}: the firmware cannot be linked"),
        Err(e) => println!("xtask: could not run `cargo install flip-link --locked`: {e}: the firmware cannot be linked"),
    }
}

/// The `flinch` binary of the host tests' build (`cargo test --workspace`, test profile: the one
/// the integration tests run), built if needed: `cargo test --workspace --no-run` with `envs`,
/// a no-op after the host tests unless a build script reads one of `envs`. The stages that need a
/// `flinch` (no fontconfig, python) used to build a second one in the dev profile.
pub fn host_flinch(envs: &[(&str, &std::ffi::OsStr)]) -> Result<PathBuf, String> {
    let out = cargo()
        .args(["test", "--workspace", "--no-run", "--message-format=json"])
        .envs(envs.iter().copied())
        .current_dir(repo_root())
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!("cargo test --workspace --no-run exited with {}", out.status));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    flinch_executable(&text).ok_or_else(|| "cargo test --workspace --no-run built no `flinch` binary".to_string())
}

/// The message's `"profile":{...}` says `"test":false` (the target object has a `test` key too).
fn profile_is_not_test(l: &str) -> bool {
    l.find("\"profile\":{").and_then(|i| l[i..].find('}').map(|j| &l[i..i + j])).is_some_and(|p| p.contains("\"test\":false"))
}

/// The `flinch` binary (not its unit-test harness) in cargo's JSON messages.
fn flinch_executable(json: &str) -> Option<PathBuf> {
    json.lines()
        .filter(|l| l.contains("\"reason\":\"compiler-artifact\"") && l.contains("\"kind\":[\"bin\"]") && l.contains("\"name\":\"flinch\"") && profile_is_not_test(l))
        .find_map(|l| {
            let rest = &l[l.find("\"executable\":\"")? + 14..];
            Some(PathBuf::from(rest[..rest.find('"')?].replace("\\\\", "\\")))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_flinch_binary_not_its_test_harness() {
        let json = concat!(
            "{\"reason\":\"compiler-artifact\",\"target\":{\"kind\":[\"bin\"],\"name\":\"flinch\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":true},\"executable\":\"/t/debug/deps/flinch-08e1\"}\n",
            "{\"reason\":\"compiler-artifact\",\"target\":{\"kind\":[\"lib\"],\"name\":\"flinch_harness\"},\"profile\":{\"test\":false},\"executable\":null}\n",
            "{\"reason\":\"compiler-artifact\",\"target\":{\"kind\":[\"bin\"],\"name\":\"flinch\",\"test\":true},\"profile\":{\"opt_level\":\"2\",\"test\":false},\"executable\":\"/t/debug/flinch\"}\n",
            "{\"reason\":\"build-finished\",\"success\":true}\n",
        );
        assert_eq!(flinch_executable(json), Some(PathBuf::from("/t/debug/flinch")));
        assert_eq!(flinch_executable("{\"reason\":\"build-finished\",\"success\":true}"), None);
    }

    #[test]
    fn durations_read_as_people_read_them() {
        assert_eq!(seconds(Duration::from_millis(42_149)), "42.1 s");
        assert_eq!(seconds(Duration::from_secs(723)), "12 min 3 s");
    }
}
