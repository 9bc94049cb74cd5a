//! The stage "doors fuzz" (issue 27 item 8): the doors other than the scene loader fuzzed through
//! the `flinch` binary for a bounded time (host-harness/tests/fuzz_doors.rs: URDF, measured CSV,
//! merge-report mutations, command-line option values, file options pointed at special files; each
//! case under a 2 GiB address-space cap and a 20 s wall limit). `FLINCH_FUZZ_SECS` seconds (default
//! 60), as the loader fuzz. Owned by the io helper; registered with one line in main.rs.

use crate::common::{cargo, repo_root, run_captured};
use crate::Outcome;
use std::env;
use std::time::Duration;

pub fn doors_fuzz() -> Outcome {
    let secs: u64 = env::var("FLINCH_FUZZ_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(60);
    let mut cmd = cargo();
    cmd.args(["test", "-p", "flinch-harness", "--test", "fuzz_doors", "--", "--ignored", "--nocapture"])
        .env("FLINCH_FUZZ_SECS", secs.to_string())
        .current_dir(repo_root());
    match run_captured(cmd, "the doors fuzz", Duration::from_secs(2 * secs + 600)) {
        Ok((out, status)) => {
            let line = out.lines().find(|l| l.starts_with("fuzz doors: ")).unwrap_or("no summary line").to_string();
            print!("{out}");
            if status.success() {
                Outcome::Pass(line)
            } else {
                Outcome::Fail(format!("{line} (exit {status})"))
            }
        }
        Err(e) => Outcome::Fail(e),
    }
}
