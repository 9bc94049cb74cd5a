//! Firmware in the loop against a plain run (issue 12 item 3: `hil` at most 2x `run`): every shipped
//! scene `flinch hil` accepts, with a controller whose scan cycle is the scene's dead time and whose
//! samples fall on the switch instant (so hil brakes where run does, `tests/hil.rs`). Medians per
//! run from criterion, and their ratio, printed at the end; docs/accuracy.md "Firmware in the loop"
//! quotes them.
//!
//! Run: `cargo bench -p flinch-harness --bench hil`

use criterion::{black_box, Criterion};
use flinch_harness::scene::{self, Controller};
use flinch_harness::{hil, sim};
use std::path::PathBuf;
use std::time::Duration;

fn scenes() -> Vec<(String, scene::Scene, Controller)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut paths: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    paths.sort();
    let mut out = Vec::new();
    for p in paths {
        let Ok(sc) = scene::load(&p) else { continue };
        if hil::refusal(&sc).is_some() || sc.motion.dead_time <= 0.0 {
            continue;
        }
        let Ok((plain, _)) = sim::run(&sc, false) else { continue };
        let Some(t_sw) = plain.t_detect else { continue };
        let ctl = Controller::new(sc.motion.dead_time, (t_sw / sc.motion.dead_time).fract(), 1e-4);
        out.push((p.file_stem().unwrap().to_string_lossy().into_owned(), sc, ctl));
    }
    out
}

fn main() {
    let mut c = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(30).configure_from_args();
    let mut rows = Vec::new();
    for (name, sc, ctl) in scenes() {
        let (plain, _) = sim::run(&sc, false).unwrap();
        let (h, _) = hil::run(&sc, &ctl, false).unwrap();
        let mut med = [0.0f64; 2];
        for (i, what) in ["run", "hil"].into_iter().enumerate() {
            let id = format!("hil/{name}/{what}");
            let mut times = Vec::new();
            c.bench_function(&id, |b| {
                b.iter_custom(|iters| {
                    let start = std::time::Instant::now();
                    for _ in 0..iters {
                        if i == 0 {
                            black_box(sim::run(black_box(&sc), false).unwrap());
                        } else {
                            black_box(hil::run(black_box(&sc), &ctl, false).unwrap());
                        }
                    }
                    let el = start.elapsed();
                    times.push(el.as_secs_f64() / iters as f64);
                    el
                })
            });
            times.sort_by(f64::total_cmp);
            med[i] = times[times.len() / 2];
        }
        rows.push((name, med, plain.rhs_evals, h.summary.rhs_evals, h.firmware.category0));
    }
    println!("\n| scene | run median, ms | hil median, ms | hil / run | RHS run | RHS hil | category 0 |");
    println!("|---|---:|---:|---:|---:|---:|---|");
    for (name, m, r, h, c0) in rows {
        println!("| {name} | {:.3} | {:.3} | {:.2} | {r} | {h} | {} |", m[0] * 1e3, m[1] * 1e3, m[1] / m[0], if c0 { "yes" } else { "no" });
    }
}
