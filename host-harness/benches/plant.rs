//! The plant's speed: the Tables 5-7 bi-stable scene (0.6 s simulated) at default accuracy, and
//! its rigid twin. Target: at least 1,000 times faster than real time on one core, i.e. under
//! 600 us a run. Prints steps and RHS evaluations beside the timings. The whole trade study over
//! every scene and method is `flinch bench` (docs/accuracy.md); this is the quick check.
//!
//! Run: `cargo bench -p flinch-harness --bench plant`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use flinch_harness::{scene, sim};
use std::path::PathBuf;

fn scene(name: &str) -> scene::Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
    scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("plant");
    for name in ["tables5-7_bistable.toml", "tables5-7_rigid.toml"] {
        let s = scene(name);
        let (summary, _) = sim::run(&s, false).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("{name}: {} s simulated, {} steps, {} rejected, {} RHS evaluations, {} events", s.duration_s, summary.steps, summary.rejected_steps, summary.rhs_evals, summary.events);
        g.bench_function(name, |b| b.iter(|| sim::run(black_box(&s), false)));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
