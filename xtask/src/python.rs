//! The Python package's stage: a fresh venv, `pip install ./python`, pytest.

use crate::common::{host_flinch, repo_root, run_captured, target_dir, which};
use crate::Outcome;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The test dependencies of the Python package, installed into the venv before it.
const TEST_DEPS: [&str; 5] = ["pytest", "dask", "distributed", "pandas", "numpy"];

/// The venv made, the test dependencies and then `./python` installed in the background while the
/// host tests build and run ([`prepare`]): downloading and unpacking NumPy, pandas and Dask is
/// mostly waiting on the network and the disk, and the extension's build (maturin, release with thin
/// LTO in `target/python`) runs at `nice -n 10`, so it takes the cores the host tests' build and
/// run leave idle (a crate alone on the critical path, a binary's last long test, the single-threaded
/// fuzz and QEMU stages) instead of adding its own minutes after every other stage (issue 28).
/// Its result: what it printed, the seconds of the venv part and of `pip install ./python`, or why
/// it failed.
pub struct Prepared(std::thread::JoinHandle<Result<(String, f64, f64), String>>);

/// Starts the venv (`python3 -m venv --clear target/python-venv`), `pip install` of the test
/// dependencies and then `pip install ./python` on a thread; None without python3 (the stage then
/// skips). Its output is kept and printed by the stage.
pub fn prepare() -> Option<Prepared> {
    let python = which("python3")?;
    Some(Prepared(std::thread::spawn(move || {
        let start = Instant::now();
        let venv = target_dir().join("python-venv");
        let mut log = String::new();
        let mut run = |mut cmd: Command, what: &str| -> Result<(), String> {
            let o = cmd.current_dir(repo_root()).stdin(Stdio::null()).output().map_err(|e| format!("could not run {what}: {e}"))?;
            log.push_str(&String::from_utf8_lossy(&o.stdout));
            log.push_str(&String::from_utf8_lossy(&o.stderr));
            if o.status.success() {
                Ok(())
            } else {
                Err(format!("{what} exited with {}: {log}", o.status))
            }
        };
        let mut venv_cmd = Command::new(&python);
        venv_cmd.args(["-m", "venv", "--clear"]).arg(&venv);
        run(venv_cmd, "python3 -m venv")?;
        let py = venv.join("bin").join("python");
        let mut pip = Command::new(&py);
        pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check"]).args(TEST_DEPS);
        run(pip, "pip install pytest dask distributed pandas numpy")?;
        let venv_s = start.elapsed().as_secs_f64();
        // Low priority where `nice` exists: the extension's build fills idle cores, the tests go first.
        let mut ext = match which("nice") {
            Some(nice) => {
                let mut c = Command::new(nice);
                c.args(["-n", "10"]).arg(&py);
                c
            }
            None => Command::new(&py),
        };
        ext.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "./python"])
            .args(TEST_DEPS)
            .env("CARGO_TARGET_DIR", target_dir().join("python"));
        run(ext, "pip install ./python pytest dask distributed pandas numpy")?;
        Ok((log, venv_s, start.elapsed().as_secs_f64() - venv_s))
    })))
}

/// The Python package (issue 14): a fresh venv in the target folder with the test dependencies and
/// `pip install ./python` (maturin builds the extension, in `target/python`) from [`prepare`],
/// started in the background by `cargo xtask test`, then pytest on python/tests with FLINCH_BIN set to the host
/// tests' `flinch` binary (the tests compare with it; [`host_flinch`]: no second build). Skipped
/// without python3 (a failure in CI); any other problem fails.
pub fn python_stage(prepared: Option<Prepared>) -> Outcome {
    let Some(prepared) = prepared else {
        return Outcome::Skip("python3 not found (the Python package needs CPython >= 3.9 with venv and pip)".into());
    };
    match python_tests(prepared) {
        Ok(m) => Outcome::Pass(m),
        Err(e) => Outcome::Fail(e),
    }
}

fn python_tests(prepared: Prepared) -> Result<String, String> {
    let start = Instant::now();
    let root = repo_root();
    let (log, venv_s, install_s) = prepared.0.join().map_err(|_| "the venv thread panicked".to_string())??;
    print!("{log}");
    let waited = start.elapsed().as_secs_f64();
    let py = target_dir().join("python-venv").join("bin").join("python");
    let bin = host_flinch(&[])?;
    let mut pytest = Command::new(&py);
    pytest.args(["-m", "pytest", "python/tests", "-p", "no:cacheprovider", "-p", "no:logging", "-q"]).env("FLINCH_BIN", &bin).current_dir(&root);
    let (out, status) = run_captured(pytest, "pytest", Duration::from_secs(1200))?;
    print!("{out}");
    let verdict = check_pytest(&out, status.code())?;
    Ok(format!(
        "{verdict}; in the background: venv and test dependencies {venv_s:.0} s, then pip install ./python {install_s:.0} s (at nice 10), waited for {waited:.0} s here; stage {:.0} s",
        start.elapsed().as_secs_f64()
    ))
}

/// pytest's closing line: Ok with it when pytest exited 0 having passed at least one test and
/// skipped none (a skip hides a comparison the tests should make).
fn check_pytest(out: &str, code: Option<i32>) -> Result<String, String> {
    let last = out.lines().rev().map(str::trim).find(|l| !l.is_empty()).unwrap_or("").trim_matches('=').trim().to_string();
    match code {
        Some(0) => {}
        Some(5) => return Err(format!("pytest collected no tests: {last}")),
        c => return Err(format!("pytest exited with {c:?}: {last}")),
    }
    // "24 passed, 2 skipped, 1 warning in 3.1s": the number before each word.
    let count = |word: &str| {
        last.split(", ")
            .find_map(|p| {
                let t: Vec<&str> = p.split_whitespace().collect();
                (t.len() >= 2 && t[1] == word).then(|| t[0].parse::<u32>().ok()).flatten()
            })
            .unwrap_or(0)
    };
    if count("passed") == 0 {
        return Err(format!("pytest passed no test: {last}"));
    }
    if count("skipped") > 0 {
        return Err(format!("pytest skipped tests: {last}"));
    }
    Ok(format!("pytest: {last}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pytest_must_pass_tests_and_skip_none() {
        assert_eq!(check_pytest("....\n24 passed, 1 warning in 30.12s\n", Some(0)), Ok("pytest: 24 passed, 1 warning in 30.12s".into()));
        assert!(check_pytest("===== 24 passed in 3s =====\n", Some(0)).is_ok());
        assert!(check_pytest("19 passed, 5 skipped, 1 warning in 11.66s\n", Some(0)).unwrap_err().contains("skipped"));
        assert!(check_pytest("no tests ran in 0.01s\n", Some(5)).unwrap_err().contains("no tests"));
        assert!(check_pytest("1 failed, 23 passed in 9s\n", Some(1)).is_err());
        assert!(check_pytest("0 passed\n", Some(0)).is_err());
        assert!(check_pytest("", None).is_err());
    }
}
