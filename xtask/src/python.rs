//! The Python package's stage: a fresh venv, `pip install ./python`, pytest.

use crate::common::{host_flinch, repo_root, run_captured, target_dir, which};
use crate::Outcome;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The Python package (issue 14): a fresh venv in the target folder, `pip install ./python` with
/// the test dependencies (maturin builds the extension, in `target/python`), then pytest on
/// python/tests with FLINCH_BIN set to the host tests' `flinch` binary (the tests compare with it;
/// [`host_flinch`]: no second build). Skipped without python3 (a failure in CI); any other problem
/// fails.
pub fn python_stage() -> Outcome {
    let Some(python) = which("python3") else {
        return Outcome::Skip("python3 not found (the Python package needs CPython >= 3.9 with venv and pip)".into());
    };
    match python_tests(&python) {
        Ok(m) => Outcome::Pass(m),
        Err(e) => Outcome::Fail(e),
    }
}

fn python_tests(python: &Path) -> Result<String, String> {
    let start = Instant::now();
    let root = repo_root();
    let venv = target_dir().join("python-venv");
    let run = |mut cmd: Command, what: &str| -> Result<(), String> {
        let status = cmd.current_dir(&root).stdin(Stdio::null()).status().map_err(|e| format!("could not run {what}: {e}"))?;
        if status.success() {
            Ok(())
        } else {
            Err(format!("{what} exited with {status}"))
        }
    };
    let mut venv_cmd = Command::new(python);
    venv_cmd.args(["-m", "venv", "--clear"]).arg(&venv);
    run(venv_cmd, "python3 -m venv")?;
    let py = venv.join("bin").join("python");
    let mut pip = Command::new(&py);
    pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "./python", "pytest", "dask", "distributed", "pandas", "numpy"])
        .env("CARGO_TARGET_DIR", target_dir().join("python"));
    run(pip, "pip install ./python pytest dask distributed pandas numpy")?;
    let installed = start.elapsed().as_secs_f64();
    let bin = host_flinch(&[])?;
    let mut pytest = Command::new(&py);
    pytest.args(["-m", "pytest", "python/tests", "-p", "no:cacheprovider", "-p", "no:logging", "-q"]).env("FLINCH_BIN", &bin).current_dir(&root);
    let (out, status) = run_captured(pytest, "pytest", Duration::from_secs(1200))?;
    print!("{out}");
    let verdict = check_pytest(&out, status.code())?;
    Ok(format!("{verdict}; venv and pip install {installed:.0} s, total {:.0} s", start.elapsed().as_secs_f64()))
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
