//! Issue 18 item 5: the loader (impact and avoidance scenes, one machinery) fuzzed for a bounded time. Random mutations of the shipped scenes'
//! TOML text (a number replaced by an edge value: 0, 1e-9, 1e9, 1e308, -1, nan, inf, 5e-324, the
//! largest integer, a string; a line deleted or duplicated; garbage inserted) and random TOML made
//! of the scene keys. For every case: the loader never panics; every scene it refuses is refused
//! with the file named; every scene it accepts runs to its end without a panic or a solver error,
//! with finite figures, within the stated wall time.
//!
//! `#[ignore]`d: `cargo xtask test` runs it as its own stage, for `FLINCH_FUZZ_SECS` seconds
//! (default 60), and prints the number of cases run. By hand:
//! `FLINCH_FUZZ_SECS=20 cargo test -p flinch-tests --test fuzz -- --ignored --nocapture`.
use flinch_harness::avoid::path::{simulate, Engine, Setup};
use flinch_harness::scene::{self, estimated_steps};
use flinch_harness::sim;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Instant;

/// Wall-time bound of one accepted impact run: 2 s plus 5 us per estimated step in the optimised
/// test profile (tests/box.rs states the same), 100 us in an unoptimised build.
fn impact_bound_s(steps: f64) -> f64 {
    2.0 + steps * if cfg!(debug_assertions) { 100e-6 } else { 5e-6 }
}
/// Wall-time bound of one accepted avoidance run (setup, calibration when asked, simulation): the
/// loader's work caps allow about 8 s of calibration in release (docs/avoidance.md).
const AVOID_BOUND_S: f64 = 30.0;

const EDGES: &[&str] = &["0", "1e-9", "1e9", "1e308", "-1", "nan", "inf", "-inf", "5e-324", "9223372036854775807", "\"x\"", "[1, 2, 3]", "0.5"];
const GARBAGE: &[&str] = &["=", "[", "]]", "\"", "{", "\u{0}", "\u{feff}", "x = ", "[avoid]\n", "[motion]\n", "\n\n", "#", "é", "= = ="];

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// Byte ranges of the numbers in `text` (outside comments, roughly: a token after `=` or in `[ ]`).
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start_ok = i == 0 || matches!(b[i - 1], b' ' | b'=' | b'[' | b',');
        if start_ok && (b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit())) {
            let s = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || matches!(b[i], b'.' | b'-' | b'+' | b'_')) {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

fn mutate(rng: &mut Rng, text: &str) -> String {
    let mut t = text.to_string();
    for _ in 0..1 + rng.below(3) {
        match rng.below(6) {
            0..=2 => {
                let nums = numbers(&t);
                if !nums.is_empty() {
                    let (a, b) = *rng.pick(&nums);
                    let e = EDGES[rng.below(EDGES.len())];
                    t.replace_range(a..b, e);
                }
            }
            3 => {
                let lines: Vec<&str> = t.lines().collect();
                let k = rng.below(lines.len());
                t = lines.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, l)| *l).collect::<Vec<_>>().join("\n");
            }
            4 => {
                let lines: Vec<&str> = t.lines().collect();
                let k = rng.below(lines.len());
                let mut v: Vec<&str> = lines.clone();
                v.insert(k, lines[k]);
                t = v.join("\n");
            }
            _ => {
                let mut at = rng.below(t.len() + 1);
                while !t.is_char_boundary(at) {
                    at -= 1;
                }
                let g = GARBAGE[rng.below(GARBAGE.len())];
                t.insert_str(at, g);
            }
        }
    }
    t
}

/// Random TOML built from the scene's own table and key names.
fn random_toml(rng: &mut Rng) -> String {
    let mut out = String::new();
    let tables = scene::key_tables();
    for _ in 0..1 + rng.below(6) {
        let t = rng.pick(tables);
        if !t.path.is_empty() && !t.path.contains('[') {
            out.push_str(&format!("[{}]\n", t.path));
        }
        for _ in 0..rng.below(6) {
            let k = rng.pick(t.keys);
            out.push_str(&format!("{} = {}\n", k.name, EDGES[rng.below(EDGES.len())]));
        }
    }
    out
}

#[derive(Default)]
struct Tally {
    cases: u64,
    accepted: u64,
    refused: u64,
}

fn impact(t: &mut Tally, text: &str, path: &str) -> Result<(), String> {
    let sc = match scene::parse(text, path) {
        Ok(sc) => sc,
        Err(e) => {
            t.refused += 1;
            let shown = e.to_string();
            return if shown.lines().all(|l| l.starts_with(path)) { Ok(()) } else { Err(format!("a refusal without the file: {shown}")) };
        }
    };
    t.accepted += 1;
    let bound = impact_bound_s(estimated_steps(&sc));
    let t0 = Instant::now();
    let (s, _) = sim::run(&sc, false).map_err(|e| format!("accepted, then the solver failed: {e}"))?;
    let wall = t0.elapsed().as_secs_f64();
    if !(s.peak_contact_force.is_finite() && s.peak_robot_force.is_finite() && s.max_travel.is_finite()) {
        return Err(format!("non-finite figures: {s:?}"));
    }
    if wall > bound {
        return Err(format!("ran {wall:.1} s, over the bound {bound:.1} s"));
    }
    Ok(())
}

fn avoid(t: &mut Tally, text: &str, path: &str, thesis: bool) -> Result<(), String> {
    // The loader `flinch avoid` uses (`Avoid::load` reads the file, then this).
    let mut sc = match scene::avoid::parse(text, path) {
        Ok(sc) => sc,
        Err(e) => {
            t.refused += 1;
            let shown = e.to_string();
            return if shown.lines().all(|l| l.starts_with(path)) { Ok(()) } else { Err(format!("a refusal without the file: {shown}")) };
        }
    };
    t.accepted += 1;
    if thesis {
        sc.thesis_mode();
    }
    // As `flinch avoid` does: `[avoid.pfl]`'s speeds computed from the module scene (once per
    // module and regions in a process: not in the per-case bound below).
    flinch_harness::pfl::resolve_pfl(&mut sc).map_err(|e| format!("accepted, then the PFL speeds failed: {e}"))?;
    let t0 = Instant::now();
    let setup = Setup::new(&sc, None).map_err(|e| format!("accepted, then setup failed: {e}"))?;
    // A simulation error (e.g. a run that leaves the view is a status, not an error) is reported.
    simulate(&sc, &setup, Engine::Reference).map_err(|e| format!("accepted, then the run failed: {e}"))?;
    let wall = t0.elapsed().as_secs_f64();
    if wall > AVOID_BOUND_S {
        return Err(format!("ran {wall:.1} s, over the bound {AVOID_BOUND_S} s"));
    }
    Ok(())
}

#[test]
#[ignore = "a time-bounded fuzz stage: cargo xtask test runs it (FLINCH_FUZZ_SECS, default 60)"]
fn fuzz_the_loaders() {
    let secs: f64 = std::env::var("FLINCH_FUZZ_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let seed: u64 = std::env::var("FLINCH_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x466c_696e_6368_0018);
    let mut scenes: Vec<(String, String)> = std::fs::read_dir(flinch_tests::scene_path(""))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| (p.display().to_string(), std::fs::read_to_string(&p).unwrap()))
        .collect();
    scenes.sort();
    let mut rng = Rng(seed | 1);
    let mut tally = Tally::default();
    let start = Instant::now();
    let mut failures = Vec::new();
    while start.elapsed().as_secs_f64() < secs {
        tally.cases += 1;
        let (path, text) = rng.pick(&scenes).clone();
        let is_avoid = path.contains("avoid_");
        let case = if rng.below(8) == 0 { random_toml(&mut rng) } else { mutate(&mut rng, &text) };
        let thesis = rng.below(4) == 0;
        let r = catch_unwind(AssertUnwindSafe(|| {
            let mut t = Tally::default();
            let r = if is_avoid { avoid(&mut t, &case, &path, thesis) } else { impact(&mut t, &case, &path) };
            (t, r)
        }));
        match r {
            Ok((t, Ok(()))) => {
                tally.accepted += t.accepted;
                tally.refused += t.refused;
            }
            Ok((_, Err(e))) => failures.push(format!("{path} (thesis {thesis}): {e}\n--- scene ---\n{case}")),
            Err(_) => failures.push(format!("{path} (thesis {thesis}): PANIC\n--- scene ---\n{case}")),
        }
        if failures.len() >= 5 {
            break;
        }
    }
    println!(
        "fuzz: {} cases in {:.1} s (seed {seed:#x}): {} accepted and run, {} refused, {} failed",
        tally.cases,
        start.elapsed().as_secs_f64(),
        tally.accepted,
        tally.refused,
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
