//! `cargo xtask`: the project's test driver (std, and `object` to read the firmware ELF).
//!
//! * `cargo xtask test`: every stage below, then one closing line `N passed, N failed, N skipped`.
//!   Each stage prints its wall time as it ends (`xtask: stage NAME took 42.1 s`), the summary
//!   repeats them and gives the total (issue 28). flip-link, the firmware's linker, is installed
//!   with `cargo install flip-link --locked` when it is missing (here and for the commands that
//!   build the firmware), and xtask says so.
//!   1. host tests: the binaries of `cargo test --workspace` at the repo root run side by side,
//!      one per core, slowest first, each binary's output printed whole as it ends (`testpool`),
//!      then the doc tests;
//!   2. firmware build: `cargo build --release --target thumbv7em-none-eabihf` inside `firmware/`
//!      (skipped if that target is not installed), then `cargo clippy -p flinch-firmware --target
//!      thumbv7em-none-eabihf -- -D warnings` (the panic-free lints are only as good as this run);
//!   3. QEMU self-test: the `qemu` binary in `qemu-system-arm -machine mps2-an386` over semihosting,
//!      its output compared with `firmware/qemu/expected.txt` (skipped without `qemu-system-arm`);
//!   4. instruction count: the self-test's `icount:` line, edge-to-stop best (idle) <= 40 and worst
//!      (the edge during the trip tick) <= 60 instructions under `-icount` (issue 10 item 3);
//!   5. size: flash and static RAM of the release `board` ELF, under 64 KiB / 16 KiB (`FLASH_LIMIT`);
//!   6. avoidance step cost: `firmware/avoid-cost` in QEMU, at most 5,000 instructions per step on
//!      a 15 x 15 grid for every number type (issue 4); and the step plus its share of frame handling
//!      (receiver fed one 10 ms step's bytes) at most 5,000 for the shipped grids and frame rates (issue 11).
//!
//!   Board ELF stages (netduinoplus2): "board ELF in QEMU" (boot trace, vectors, a corrupted image,
//!   the first latched fault ending the IWDG feeds), "board ELF edge in QEMU" (the qemu-io bench's
//!   edges, with USART traffic), "board worst case" (the board ELF's own edge-to-stop and
//!   tick-to-output from that run, `worst.rs`), "flash image" (the bytes cargo's runner hands
//!   probe-rs pass the firmware's flash check and boot), "board faults in QEMU" (a panic, a stack
//!   overflow, a flipped configuration bit), "board serial in QEMU".
//!
//!   8. loader fuzz: tests/fuzz.rs for `FLINCH_FUZZ_SECS` seconds (default 60), the cases run
//!      printed (issue 18).
//!   7. no fontconfig: the `flinch` binary built with `PKG_CONFIG_PATH` pointing nowhere and
//!      `FONTCONFIG_FILE` empty draws a PNG and an SVG, and `ldd` lists only the C runtime (issue 16).
//!   9. python: a fresh venv (`python3 -m venv --clear`) with `pytest dask distributed pandas
//!      numpy` (made in the background from the start of the run), `pip install ./python` (maturin
//!      builds the extension), then pytest on
//!      python/tests with the `flinch` binary to compare with (issue 14). A failed install fails.
//!
//!   Exits non-zero if any stage failed; skipped stages do not fail the run, except in CI (`CI` set):
//!   there a missing target, QEMU or tool is a failure, never a quiet pass.
//! * `cargo xtask qemu`: build and run the QEMU self-test, print its output.
//! * `cargo xtask size`: build the board binary and print its flash and RAM use.
//! * `cargo xtask flash [ELF] [probe-rs args]`: patch the start-up flash CRC into the board ELF (built
//!   first without one), check it with the firmware's own routine, then `probe-rs run` it. cargo's
//!   runner (`firmware/scripts/flash-runner`) calls it, so `cargo run --release --bin board` in
//!   firmware/ flashes an image that arms.
//! * `cargo xtask python`: the stage "python" alone (a skip is a failure here).
//! * `cargo xtask host-tests`: the stage "host tests" alone (the test binaries side by side).
//! * `cargo xtask board-serial`: the stage "board serial in QEMU" alone: the `qemu-io` board ELF
//!   on netduinoplus2 (its bench in mode `serial` presses reset and trips the switch), weights
//!   frames over USART1 from a Unix socket, its velocity frames checked against
//!   `firmware/qemu/board-serial.txt` (`ok`/`slowed`/`stopped: stale` after a reset press,
//!   `stopped: latched` while latched).
//! * `cargo xtask board-qemu`: build and run the board ELF on QEMU's netduinoplus2 (the stages
//!   "board ELF in QEMU": boot trace, vectors, a one-byte-corrupted flash image that must stop, the
//!   first latched fault ending the IWDG feeds; "board ELF edge in QEMU": the `qemu-io` build's edges
//!   against `firmware/qemu/board-edge.txt`; "board faults in QEMU": a panic in thread mode and a
//!   stack overflow into the MPU guard, each ending with the outputs low, the latch and no feed).
//!
//! Every build of the firmware patches the board ELF's flash CRC (`flash::patch_flash_crc`).
//!
//! One module per stage group (`qemu`, `board`, `board_serial`, `avoid_budget`, `size`, `host`,
//! `python`), the builds in `firmware`, the ELF's flash image and CRC in `flash`, paths and
//! process helpers in `common`; this file keeps the command line and the stage list.

mod avoid_budget;
mod board;
mod board_serial;
mod common;
mod doors;
mod firmware;
mod flash;
mod flash_run;
mod host;
mod python;
mod qemu;
mod size;
mod structure;
mod testpool;
mod worst;

use avoid_budget::{check_avoid_board, check_avoid_budget, check_avoid_cost, run_avoid_cost};
use board::{check_board_corrupt, check_board_edge, check_board_faults, check_board_log, check_board_vectors, run_board_edge, run_board_qemu};
use board_serial::board_serial;
use common::{elf_path, ensure_flip_link, seconds, which, Outcome, Timed, TARGET};
use firmware::{build_board_qemu_io, build_firmware, firmware_clippy, target_installed};
use host::{host_tests, loader_fuzz, no_fontconfig};
use python::python_stage;
use qemu::{check_icount, check_qemu_output, check_stack, run_qemu, ICOUNT_BEST_LIMIT, ICOUNT_WORST_LIMIT, STACK_LIMIT};
use size::{check_size, elf_size, FLASH_LIMIT, RAM_LIMIT};
use std::env;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    if matches!(args.first().map(String::as_str), Some("test" | "qemu" | "size" | "board-qemu" | "board-serial")) {
        ensure_flip_link();
    }
    match args.first().map(String::as_str) {
        Some("test") => test(),
        Some("qemu") => single(|| {
            build_firmware()?;
            let out = run_qemu()?;
            print!("{}", out.stdout);
            check_qemu_output(&out).and_then(|_| check_icount(&out.stdout)).and_then(|_| check_stack(&out.stdout).map(|_| ()))
        }),
        Some("board-serial") => single(|| {
            build_board_qemu_io()?;
            board_serial().map(|m| println!("{m}"))
        }),
        Some("board-qemu") => single(|| {
            build_firmware()?;
            let log = run_board_qemu()?;
            println!("{}", check_board_log(&log)?);
            println!("{}", check_board_vectors(&elf_path("board"))?);
            println!("{}", check_board_corrupt()?);
            build_board_qemu_io()?;
            let (out, log) = run_board_edge()?;
            print!("{out}");
            println!("{}", check_board_edge(&out, &log)?);
            println!("{}", worst::check_board_worst(&out)?);
            println!("{}", check_board_faults()?);
            Ok(())
        }),
        Some("host-tests") => single(|| match host_tests().0 {
            Outcome::Pass(m) => {
                println!("{m}");
                Ok(())
            }
            Outcome::Fail(m) | Outcome::Skip(m) => Err(m),
        }),
        Some("python") => single(|| match python_stage(python::prepare()) {
            Outcome::Pass(m) => {
                println!("{m}");
                Ok(())
            }
            Outcome::Fail(m) | Outcome::Skip(m) => Err(m),
        }),
        Some("structure") => single(|| {
            let root = common::repo_root();
            let mut failed = Vec::new();
            for r in [structure::import_cycles(&root, |_| true), structure::layer_order(&root), structure::file_lengths(&root)] {
                match r {
                    Ok(m) => println!("{m}"),
                    Err(e) => failed.push(e),
                }
            }
            if failed.is_empty() { Ok(()) } else { Err(failed.join("\n")) }
        }),
        Some("flash") => single(|| flash_run::flash(&args[1..])),
        Some("flash-image") => single(|| {
            build_firmware()?;
            flash_run::check_flash_image().map(|m| println!("{m}"))
        }),
        Some("size") => single(|| {
            build_firmware()?;
            let s = elf_size(&elf_path("board"))?;
            println!("board (STM32F407VGTx): flash {} B, static RAM {} B", s.flash, s.ram);
            check_size(&s)
        }),
        _ => {
            eprintln!("usage: cargo xtask <test|host-tests|qemu|size|board-qemu|board-serial|flash [ELF]|python|structure>");
            ExitCode::from(2)
        }
    }
}

fn single(f: impl FnOnce() -> Result<(), String>) -> ExitCode {
    match f() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The stage "structure": no import circle in any crate, no crate depending on one above it
/// (`structure.rs`, docs/architecture.md).
fn structure_stage() -> Outcome {
    let root = common::repo_root();
    match (structure::import_cycles(&root, |c| !structure::FIRMWARE_CRATES.contains(&c)), structure::layer_order(&root)) {
        (Ok(a), Ok(b)) => Outcome::Pass(format!("{a}; {b}")),
        (a, b) => Outcome::Fail([a.err(), b.err()].into_iter().flatten().collect::<Vec<_>>().join("\n")),
    }
}

/// The stage "structure (firmware, hal-sim)": the same import check on the firmware's crates.
fn firmware_structure_stage() -> Outcome {
    match structure::import_cycles(&common::repo_root(), |c| structure::FIRMWARE_CRATES.contains(&c)) {
        Ok(m) => Outcome::Pass(m),
        Err(e) => Outcome::Fail(e),
    }
}

fn test() -> ExitCode {
    let mut results = Timed::new();
    // The Python stage's venv and test dependencies, fetched while the host tests build and run.
    let venv = python::prepare();

    // Cheap, and a circle or an upward dependency is better named before the long stages run.
    results.push(("structure", structure_stage()));
    results.push(("structure (firmware, hal-sim)", firmware_structure_stage()));
    results.push(("file length", match structure::file_lengths(&common::repo_root()) {
        Ok(m) => Outcome::Pass(m),
        Err(e) => Outcome::Fail(e),
    }));
    let (host, bins) = host_tests();
    results.push(("host tests", host));
    // The two fuzz stages are single-threaded and bounded in time, not in cases: side by side,
    // each has a core of its own for its whole FLINCH_FUZZ_SECS, and the pair takes the wall time
    // of one (issue 28). The doors fuzz's time is then the wait after the loader fuzz ended.
    let (loader, doors) = std::thread::scope(|s| {
        let doors = s.spawn(|| doors::doors_fuzz(&bins));
        let loader = loader_fuzz(&bins);
        (loader, doors.join().unwrap_or_else(|_| Outcome::Fail("the doors fuzz thread panicked".into())))
    });
    results.push(("loader fuzz", loader));
    results.push(("doors fuzz", doors));

    let have_target = target_installed();
    let built = if have_target {
        match build_firmware() {
            Ok(()) => Outcome::Pass(format!("board and qemu ELFs for {TARGET}")),
            Err(e) => Outcome::Fail(e),
        }
    } else {
        println!("SKIPPED on-target part: target {TARGET} not installed (rustup target add {TARGET})");
        Outcome::Skip(format!("target {TARGET} not installed (rustup target add {TARGET})"))
    };
    let built_ok = matches!(built, Outcome::Pass(_));
    results.push(("firmware build", built));
    results.push((
        "firmware clippy",
        if have_target { firmware_clippy() } else { Outcome::Skip(format!("target {TARGET} not installed")) },
    ));

    if !built_ok {
        let why = "no firmware build".to_string();
        results.push(("qemu self-test", Outcome::Skip(why.clone())));
        results.push(("instruction count", Outcome::Skip(why.clone())));
        results.push(("size", Outcome::Skip(why.clone())));
        results.push(("avoidance step cost", Outcome::Skip(why)));
    } else {
        if which("qemu-system-arm").is_none() {
            println!("SKIPPED on-target part: qemu-system-arm not found");
            let why = "qemu-system-arm not found".to_string();
            results.push(("qemu self-test", Outcome::Skip(why.clone())));
            results.push(("instruction count", Outcome::Skip(why)));
        } else {
            match run_qemu() {
                Ok(out) => {
                    print!("{}", out.stdout);
                    results.push((
                        "qemu self-test",
                        match check_qemu_output(&out) {
                            Ok(()) => Outcome::Pass("output matches firmware/qemu/expected.txt".into()),
                            Err(e) => Outcome::Fail(e),
                        },
                    ));
                    results.push((
                        "stack",
                        match check_stack(&out.stdout) {
                            Ok(n) => Outcome::Pass(format!("{n} B <= {STACK_LIMIT} B (painted, qemu self-test)")),
                            Err(e) => Outcome::Fail(e),
                        },
                    ));
                    results.push((
                        "instruction count",
                        match check_icount(&out.stdout) {
                            Ok((b, w)) => Outcome::Pass(format!(
                                "edge-to-stop best {b} <= {ICOUNT_BEST_LIMIT}, worst (edge during the trip tick) {w} <= {ICOUNT_WORST_LIMIT} instructions (-icount)"
                            )),
                            Err(e) => Outcome::Fail(e),
                        },
                    ));
                }
                Err(e) => {
                    results.push(("qemu self-test", Outcome::Fail(e)));
                    results.push(("instruction count", Outcome::Skip("no qemu output".into())));
                }
            }
        }
        results.push((
            "board ELF in QEMU",
            if which("qemu-system-arm").is_none() {
                Outcome::Skip("qemu-system-arm not found".into())
            } else {
                match run_board_qemu()
                    .and_then(|log| check_board_log(&log))
                    .and_then(|m| check_board_vectors(&elf_path("board")).map(|v| format!("{m}; {v}")))
                    .and_then(|m| check_board_corrupt().map(|c| format!("{m}; {c}")))
                {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                }
            },
        ));
        let edge_run = if which("qemu-system-arm").is_none() {
            Err("qemu-system-arm not found".to_string())
        } else {
            build_board_qemu_io().and_then(|()| run_board_edge())
        };
        results.push((
            "board ELF edge in QEMU",
            match &edge_run {
                Ok((out, log)) => {
                    print!("{out}");
                    match check_board_edge(out, log) {
                        Ok(m) => Outcome::Pass(m),
                        Err(e) => Outcome::Fail(e),
                    }
                }
                Err(e) if e.contains("not found") => Outcome::Skip(e.clone()),
                Err(e) => Outcome::Fail(e.clone()),
            },
        ));
        results.push((
            "board worst case",
            match &edge_run {
                Ok((out, _)) => match worst::check_board_worst(out) {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                },
                Err(e) if e.contains("not found") => Outcome::Skip(e.clone()),
                Err(_) => Outcome::Fail("no board edge run".into()),
            },
        ));
        results.push((
            "flash image",
            if which("qemu-system-arm").is_none() {
                Outcome::Skip("qemu-system-arm not found".into())
            } else {
                match flash_run::check_flash_image() {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                }
            },
        ));
        results.push((
            "board faults in QEMU",
            if which("qemu-system-arm").is_none() {
                Outcome::Skip("qemu-system-arm not found".into())
            } else {
                match check_board_faults() {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                }
            },
        ));
        results.push((
            "board serial in QEMU",
            if which("qemu-system-arm").is_none() {
                Outcome::Skip("qemu-system-arm not found".into())
            } else {
                match build_board_qemu_io().and_then(|()| board_serial()) {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                }
            },
        ));
        results.push((
            "size",
            match elf_size(&elf_path("board")).and_then(|s| check_size(&s).map(|_| s)) {
                Ok(s) => Outcome::Pass(format!(
                    "board flash {} B <= {} B, static RAM {} B <= {} B",
                    s.flash, FLASH_LIMIT, s.ram, RAM_LIMIT
                )),
                Err(e) => Outcome::Fail(e),
            },
        ));
        results.push((
            "avoidance step cost",
            if which("qemu-system-arm").is_none() {
                Outcome::Skip("qemu-system-arm not found".into())
            } else {
                match run_avoid_cost().and_then(|out| {
                    let step = check_avoid_cost(&out)?;
                    let budget = check_avoid_budget(&out)?;
                    let board = check_avoid_board(&out)?;
                    Ok(format!("{step}; {budget}; {board}"))
                }) {
                    Ok(m) => Outcome::Pass(m),
                    Err(e) => Outcome::Fail(e),
                }
            },
        ));
    }

    results.push(("no fontconfig", match no_fontconfig() {
        Ok(m) => Outcome::Pass(m),
        Err(e) => Outcome::Fail(e),
    }));

    results.push(("python", python_stage(venv)));

    // In CI nothing is skipped quietly: a missing target or tool fails the run.
    if env::var_os("CI").is_some_and(|v| !v.is_empty() && v != "false" && v != "0") {
        for (_, outcome, _) in results.list.iter_mut() {
            if let Outcome::Skip(m) = outcome {
                *outcome = Outcome::Fail(format!("skipped in CI: {m}"));
            }
        }
    }

    println!();
    let (mut passed, mut failed, mut skipped) = (0, 0, 0);
    for (stage, outcome, took) in &results.list {
        let took = seconds(*took);
        match outcome {
            Outcome::Pass(m) => {
                passed += 1;
                println!("xtask: PASS {stage} ({took}): {m}");
            }
            Outcome::Fail(m) => {
                failed += 1;
                println!("xtask: FAIL {stage} ({took}): {m}");
            }
            Outcome::Skip(m) => {
                skipped += 1;
                println!("xtask: SKIP {stage} ({took}): {m}");
            }
        }
    }
    println!("xtask: total {}", seconds(results.total()));
    println!("{passed} passed, {failed} failed, {skipped} skipped");
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}


#[cfg(test)]
mod tests {
    use crate::common::repo_root;
    use std::env;
    use std::fs;
    use std::process::{Command, Stdio};

    /// Run `.ci/run` with fake `rustup` (exiting `rustup_status`) and `cargo` (recording its
    /// arguments and `CI`) first on PATH; returns the script's exit status and what cargo recorded.
    fn ci_run_with(rustup_status: i32) -> (bool, String) {
        let dir = env::temp_dir().join(format!("flinch-ci-run-{}-{rustup_status}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let record = dir.join("cargo.log");
        let write_exe = |name: &str, body: String| {
            use std::os::unix::fs::PermissionsExt;
            let p = dir.join(name);
            fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
            fs::set_permissions(&p, fs::Permissions::from_mode(0o755)).unwrap();
        };
        write_exe("rustup", format!("exit {rustup_status}"));
        write_exe("cargo", format!("echo \"CI=${{CI:-}} $*\" >> '{}'", record.display()));
        // Also a qemu-system-arm, so the script never tries apt-get.
        write_exe("qemu-system-arm", "exit 0".into());
        let path = format!("{}:/usr/bin:/bin", dir.display());
        let status = Command::new("bash")
            .arg(repo_root().join(".ci/run"))
            .env_clear()
            .env("PATH", path)
            .env("HOME", &dir)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .unwrap();
        let log = fs::read_to_string(&record).unwrap_or_default();
        let _ = fs::remove_dir_all(&dir);
        (status.success(), log)
    }

    #[test]
    fn ci_run_fails_without_the_target_and_runs_xtask_in_ci_mode() {
        let (ok, log) = ci_run_with(1);
        assert!(!ok, ".ci/run went on after rustup target add failed");
        assert!(!log.contains("xtask"), "xtask ran without the target: {log}");
        let (ok, log) = ci_run_with(0);
        assert!(ok, ".ci/run failed with every tool present: {log}");
        let xtask = log.lines().find(|l| l.contains("xtask test")).unwrap_or_else(|| panic!("no cargo xtask test: {log}"));
        assert!(xtask.starts_with("CI=1 "), "xtask not in CI mode (skips would pass): {xtask}");
        let flip = log.lines().position(|l| l.contains("install flip-link --locked"));
        let run = log.lines().position(|l| l.contains("xtask test"));
        assert!(flip.is_some() && flip < run, "flip-link (the firmware's linker) not installed before xtask: {log}");
    }
}
