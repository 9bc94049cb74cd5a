//! Helpers the command-line tests share (`cli.rs`, `hil_cli.rs`): the binary, the repository, a
//! scratch directory, and the peak memory of a child.
#![allow(dead_code)]

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The `flinch` binary, run from the repository root.
pub fn flinch() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flinch"));
    c.current_dir(repo());
    c
}

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A scratch directory `flinch-<what>-<pid>-<name>` under the system's temporary directory.
pub fn tmp_in(what: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flinch-{what}-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Bytes as text (lossy).
pub fn text(o: &[u8]) -> String {
    String::from_utf8_lossy(o).into_owned()
}

/// Largest resident set of a child while it runs, kB (polled from /proc), and its output
/// (standard output discarded; standard error read as it comes, so a full pipe cannot stall it).
/// Fails after `limit`.
pub fn peak_rss_kb(mut cmd: Command, limit: Duration) -> (u64, Output) {
    let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let pid = child.id();
    let mut peak = 0;
    let start = Instant::now();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        err.read_to_end(&mut s).unwrap();
        s
    });
    loop {
        if let Ok(s) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
            if let Some(kb) = s.lines().find_map(|l| l.strip_prefix("VmHWM:")).and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok()) {
                peak = peak.max(kb);
            }
        }
        if let Some(status) = child.try_wait().unwrap() {
            return (peak, Output { status, stdout: Vec::new(), stderr: reader.join().unwrap() });
        }
        assert!(start.elapsed() < limit, "too slow");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Bytes written so far to the output `target`: the careful writer writes a regular file to a
/// temporary `.NAME.flinch-PID-N.EXT` beside it and renames it into place when the command ends
/// (docs/conventions.md "Outputs"), so a test that waits for rows watches both.
pub fn bytes_written(target: &std::path::Path) -> u64 {
    let dir = target.parent().unwrap_or(std::path::Path::new("."));
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.rsplit_once('.').map_or(name.as_str(), |(s, _)| s).to_string();
    let temp_prefix = format!(".{stem}.flinch-");
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| {
                    let n = e.file_name().to_string_lossy().into_owned();
                    n == name || n.starts_with(&temp_prefix)
                })
                .filter_map(|e| e.metadata().ok().map(|m| m.len()))
                .max()
                .unwrap_or(0)
        })
        .unwrap_or(0)
}
