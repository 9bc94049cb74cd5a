//! The stages that run on the host: the workspace tests, the loader fuzz, the plots without fontconfig.

use crate::common::{cargo, host_flinch, repo_root, run_captured};
use crate::testpool::{self, TestBinary};
use crate::Outcome;
use std::env;
use std::fs;
use std::process::Command;
use std::time::{Duration, Instant};

/// `cargo test --workspace`: its binaries built by `cargo test --workspace --no-run`, run side by
/// side ([`testpool`]: one per core, the slowest first, every one to its end), then its doc tests
/// (`cargo test --workspace --doc`). The same tests as `cargo test --workspace`, in less wall time.
/// Also returns the binaries built (empty if the build failed): the fuzz stages run two of them.
pub fn host_tests() -> (Outcome, Vec<TestBinary>) {
    let bins = match testpool::build() {
        Ok(b) => b,
        Err(e) => return (Outcome::Fail(e), Vec::new()),
    };
    let jobs = std::thread::available_parallelism().map_or(2, |n| n.get());
    let n = bins.len();
    let failed = match testpool::run(bins.clone(), jobs) {
        Ok(f) => f,
        Err(e) => return (Outcome::Fail(e), bins),
    };
    let doc = cargo().args(["test", "--workspace", "--doc"]).current_dir(repo_root()).status();
    let doc = match doc {
        Ok(s) if s.success() => None,
        Ok(s) => Some(format!("cargo test --workspace --doc exited with {s}")),
        Err(e) => Some(format!("could not run cargo: {e}")),
    };
    let outcome = if failed.is_empty() && doc.is_none() {
        Outcome::Pass(format!("cargo test --workspace: {n} test binaries ({jobs} at a time) and the doc tests"))
    } else {
        Outcome::Fail(failed.into_iter().chain(doc).collect::<Vec<_>>().join("; "))
    };
    (outcome, bins)
}

/// `FLINCH_FUZZ_SECS` (default 60): how long each fuzz stage runs.
pub fn fuzz_secs() -> u64 {
    env::var("FLINCH_FUZZ_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(60)
}

/// Runs the ignored (time-bounded) tests of the host tests' binary `name`, as
/// `cargo test --test NAME -- --ignored --nocapture` would run them, without cargo: the binary is
/// the host tests' own, so nothing is built again. (`cargo test -p flinch-tests --test fuzz`
/// resolved the features for that one package, unlike `--workspace`, and rebuilt about 75 s of
/// the workspace before fuzzing: /work/ci/run8.log, issue 28.) `summary` starts the line the test
/// prints; the outcome quotes it. Killed after twice `FLINCH_FUZZ_SECS` plus a minute.
pub fn run_ignored(bins: &[TestBinary], name: &str, what: &str, summary: &str) -> Outcome {
    let Some(bin) = bins.iter().find(|b| b.name == name && b.kind == "test") else {
        return Outcome::Fail(format!("no `{name}` test binary: the host tests' build (cargo test --workspace --no-run) did not make it"));
    };
    let secs = fuzz_secs();
    let mut cmd = Command::new(&bin.path);
    cmd.args(["--ignored", "--nocapture"]).current_dir(&bin.dir).env("CARGO_MANIFEST_DIR", &bin.dir).env("FLINCH_FUZZ_SECS", secs.to_string());
    println!("xtask: {what}: {} --ignored --nocapture (FLINCH_FUZZ_SECS={secs})", bin.path.display());
    match run_captured(cmd, what, Duration::from_secs(2 * secs + 60)) {
        Ok((out, status)) => {
            let line = out.lines().find(|l| l.starts_with(summary)).unwrap_or("no summary line").to_string();
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

/// The loader fuzzed for a bounded time (tests/fuzz.rs, issue 18): `FLINCH_FUZZ_SECS` seconds
/// (default 60) of mutated and random scenes; prints the cases run. The host tests' `fuzz` binary
/// ([`run_ignored`]).
pub fn loader_fuzz(bins: &[TestBinary]) -> Outcome {
    run_ignored(bins, "fuzz", "the loader fuzz", "fuzz: ")
}

/// The plots need no system font and the binary no font library: build `flinch` with pkg-config
/// pointing nowhere (a `-sys` crate that needs libfontconfig1-dev fails to build), draw a PNG and
/// an SVG with fontconfig disabled (`FONTCONFIG_FILE` empty), and check that `ldd` lists only the
/// C runtime. The build is the host tests' own (`cargo test --workspace --no-run`, a no-op after
/// them unless a build script reads the pkg-config variables, which is what this must catch), so
/// it adds seconds, not a second build of the harness in the dev profile (issue 28).
pub fn no_fontconfig() -> Result<String, String> {
    let start = Instant::now();
    let nowhere = repo_root().join("target").join("no-pkg-config");
    let env = [("PKG_CONFIG_PATH", nowhere.as_os_str()), ("PKG_CONFIG_LIBDIR", nowhere.as_os_str()), ("FONTCONFIG_FILE", "".as_ref()), ("FONTCONFIG_PATH", nowhere.as_os_str())];
    let bin = host_flinch(&env).map_err(|e| format!("without pkg-config: {e}"))?;
    let out = env::temp_dir().join(format!("flinch-no-fontconfig-{}", std::process::id()));
    fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    for ext in ["png", "svg"] {
        let plot = out.join(format!("x.{ext}"));
        let o = Command::new(&bin).args(["run", "tables5-7_bistable", "--plot"]).arg(&plot).envs(env).current_dir(&out).output().map_err(|e| format!("could not run {}: {e}", bin.display()))?;
        if !o.status.success() {
            return Err(format!("flinch run --plot x.{ext} failed: {}", String::from_utf8_lossy(&o.stderr)));
        }
        let bytes = fs::read(&plot).map_err(|e| format!("{}: {e}", plot.display()))?;
        if bytes.len() < 20_000 {
            return Err(format!("{}: only {} bytes: the plot is broken", plot.display(), bytes.len()));
        }
        if ext == "svg" && !String::from_utf8_lossy(&bytes).contains("peak contact force") {
            return Err(format!("{}: the SVG has no text", plot.display()));
        }
    }
    let _ = fs::remove_dir_all(&out);
    let ldd = Command::new("ldd").arg(&bin).output().map_err(|e| format!("could not run ldd: {e}"))?;
    let listing = String::from_utf8_lossy(&ldd.stdout).to_string();
    const C_RUNTIME: [&str; 8] = ["linux-vdso", "libc.so", "libm.so", "libgcc_s.so", "ld-linux", "libpthread.so", "libdl.so", "librt.so"];
    let extra: Vec<&str> = listing.lines().map(str::trim).filter(|l| !l.is_empty() && !C_RUNTIME.iter().any(|c| l.contains(c))).collect();
    if !extra.is_empty() {
        return Err(format!("ldd {} lists more than the C runtime: {}", bin.display(), extra.join("; ")));
    }
    Ok(format!("built without pkg-config, PNG and SVG drawn without fontconfig, ldd lists only the C runtime ({} libraries), {:.1} s", listing.lines().count(), start.elapsed().as_secs_f64()))
}
