//! What every stage uses: the repo and target folders, cargo, running a command with a time limit.

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
