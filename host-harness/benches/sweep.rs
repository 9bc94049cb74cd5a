//! The issue-6 target: a 50 x 50 sweep (V_c x DT) of the Tables 5-7 bi-stable scene in under 5 s
//! on two cores, everything included: editing and re-validating the 2,500 scene texts, then
//! simulating them on a rayon pool of two threads. Prints the points' total steps and RHS
//! evaluations beside the timing so a change in cost can be told from a change in work.
//!
//! Run: `cargo bench -p flinch-harness --bench sweep` (criterion's median is the figure to quote;
//! the machine is shared, so note its load).

use criterion::{criterion_group, criterion_main, Criterion};
use flinch_harness::sweep::{Axis, Progress, Sweep, Template};
use std::path::PathBuf;
use std::time::Duration;

fn axes() -> Vec<Axis> {
    // 0.02 m/s is about the slowest at which the flange closes the scene's 10 mm gap in 0.6 s (the
    // validator refuses slower); DT from 0 to 100 ms (Viper 16 ms, the experiments' 70 ms).
    vec![Axis::parse("motion.speed=0.02:0.3:50", false).expect("axis"), Axis::parse("motion.dead_time=0:0.1:50", false).expect("axis")]
}

fn bench(c: &mut Criterion) {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/tables5-7_bistable.toml");
    let t = Template::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
    let r = pool.install(|| Sweep::new(&t, axes()).unwrap_or_else(|e| panic!("{e}")).run(Progress::Hidden));
    let steps: f64 = r.metric("steps").iter().sum();
    let rhs: f64 = r.metric("rhs_evals").iter().sum();
    eprintln!("50 x 50 sweep: {} points, {} solver failures, {steps} steps, {rhs} RHS evaluations in all", r.points.len(), r.failures());
    let mut g = c.benchmark_group("sweep");
    g.sample_size(10).measurement_time(Duration::from_secs(40)).warm_up_time(Duration::from_secs(1));
    g.bench_function("tables5-7_bistable 50x50 speed x dead_time, 2 threads", |b| {
        b.iter(|| pool.install(|| Sweep::new(&t, axes()).unwrap_or_else(|e| panic!("{e}")).run(Progress::Hidden)))
    });
    g.bench_function("build and validate the 2500 scenes only, 2 threads", |b| b.iter(|| pool.install(|| Sweep::new(&t, axes()).unwrap_or_else(|e| panic!("{e}")).len())));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
