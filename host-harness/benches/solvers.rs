//! Our Dormand-Prince 5(4) (`solver::dopri5` driven by `solver::driver`) against the DOPRI5 of the
//! `differential-equations` crate (0.7, crates.io), on the same right-hand side at the same
//! tolerances (the defaults: rtol 1e-6, atol 1e-9, largest step 10 ms), per run and per RHS
//! evaluation (criterion's throughput line, "elem/s", counts RHS evaluations).
//!
//! The right-hand side is the plant's (`sim::Simulation`, the one every run integrates) over a
//! window without switching events, since the crate's `Event` watches one function and cannot
//! carry ours (tests/reference.rs): Tables 5-7 bi-stable from rest to t = 0.2 s, before the tool
//! touches the target (0.23 s): the flange accelerates to 0.05 m/s until 0.05 s (the motion law's
//! breakpoint, where both solvers stop and restart) and cruises; the robot's lightly damped 26 Hz
//! mode rings and the tool sits on its stiff front stop (1e6 N/m). `scripts/lsoda_tables5-7.py`
//! integrates the same equations over the same window with SciPy's LSODA. Neither side records
//! output: the crate is given a `Solout` that keeps only the last state, ours a driver with no events. Both
//! use Hairer's RMS error norm and start from their own initial-step estimate.
//!
//! Run: `cargo bench -p flinch-harness --bench solvers`

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use differential_equations::prelude::*;
use flinch_harness::plant::{State, N};
use flinch_harness::scene::{self, Scene};
use flinch_harness::sim::Simulation;
use flinch_harness::solver::dopri5::Dopri5;
use flinch_harness::solver::driver::{Crossing, Driver, Hybrid, Settings};
use flinch_harness::solver::System;
use std::cell::Cell;
use std::path::PathBuf;

const RTOL: f64 = 1e-6;
const ATOL: f64 = 1e-9;
const H_MAX: f64 = 1e-2;
/// End of the flange's acceleration (0.05 m/s at 1 m/s^2), s.
const T_BREAK: f64 = 0.05;
/// End of the window, s.
const T_END: f64 = 0.2;

fn scene(name: &str) -> Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
    scene::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

/// The plant's right-hand side with a counter, and no events.
struct Rhs {
    sim: Simulation,
    evals: Cell<u64>,
}

impl System<N> for Rhs {
    fn rhs(&self, t: f64, y: &State, dy: &mut State) {
        self.evals.set(self.evals.get() + 1);
        self.sim.rhs(t, y, dy);
    }
}

impl Hybrid<N, 0> for Rhs {
    fn events(&self, _: f64, _: &State) -> [f64; 0] {
        []
    }
    fn watching(&self, _: usize) -> Option<Crossing> {
        None
    }
    fn on_event(&mut self, _: usize, _: f64, _: &mut State) {}
    fn next_breakpoint(&self, t: f64) -> Option<f64> {
        (t < T_BREAK).then_some(T_BREAK)
    }
    fn on_step(&mut self, _: f64, _: f64, _: &State, _: &dyn Fn(f64) -> State) {}
}

impl ODE<f64, [f64; N]> for Rhs {
    fn diff(&self, t: f64, y: &[f64; N], dydt: &mut [f64; N]) {
        self.rhs(t, y, dydt);
    }
}

/// Keeps the last step's end only (a copy of 7 numbers a step, as our driver's).
struct Last<'a>(&'a mut (f64, State));

impl Solout<f64, [f64; N]> for Last<'_> {
    fn solout<I>(&mut self, t: f64, _: f64, y: &[f64; N], _: &[f64; N], _: &mut I, _: &mut Solution<f64, [f64; N]>) -> ControlFlag<f64, [f64; N]>
    where
        I: Interpolation<f64, [f64; N]> + ?Sized,
    {
        *self.0 = (t, *y);
        ControlFlag::Continue
    }
}

fn problem(name: &str) -> (Rhs, State) {
    let s = scene(name);
    let sim = Simulation::new(&s, false, false);
    let y0 = sim.plant.initial_state(s.motion.start_at_speed, s.motion.speed);
    (Rhs { sim, evals: Cell::new(0) }, y0)
}

fn ours(p: &mut Rhs, y0: State, t1: f64) -> (State, u64) {
    let mut d = Driver::<N, 0>::new(p, 0.0, y0, Settings { max_step: H_MAX, ..Default::default() });
    let mut st = Dopri5::<N>::new(RTOL, ATOL);
    d.advance_to(p, &mut st, t1).unwrap();
    (d.y, d.stats.steps)
}

fn theirs(p: &Rhs, y0: State, t1: f64) -> (State, usize) {
    let (mut y, mut steps) = (y0, 0);
    for (a, b) in [(0.0, T_BREAK), (T_BREAK, t1)] {
        let method = ExplicitRungeKutta::dopri5().rtol(RTOL).atol(ATOL).h_max(H_MAX).max_steps(10_000_000);
        let mut last = (a, y);
        let sol = IVP::ode(p, a, b, y).solout(Last(&mut last)).method(method).solve().unwrap();
        assert!((last.0 - b).abs() < 1e-12, "ended at {}, not {b}", last.0);
        y = last.1;
        steps += sol.steps.accepted;
    }
    (y, steps)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("dopri5");
    for (name, t1) in [("tables5-7_bistable.toml", T_END)] {
        let (mut p, y0) = problem(name);
        p.evals.set(0);
        let (ya, steps_a) = ours(&mut p, y0, t1);
        let evals_a = p.evals.get();
        p.evals.set(0);
        let (yb, steps_b) = theirs(&p, y0, t1);
        let evals_b = p.evals.get();
        let diff = (0..N).map(|i| (ya[i] - yb[i]).abs()).fold(0.0, f64::max);
        eprintln!("{name} [0, {t1}] s: ours {steps_a} steps, {evals_a} RHS evaluations; differential-equations DOPRI5 {steps_b} steps, {evals_b} RHS evaluations; largest difference of the end states {diff:.1e}; ours x_r {:.12e} m, v_r {:.12e} m/s, x_t {:.12e} m, v_t {:.12e} m/s", ya[0], ya[1], ya[2], ya[3]);
        g.throughput(Throughput::Elements(evals_a));
        g.bench_function(format!("ours/{name}"), |b| b.iter(|| ours(&mut p, black_box(y0), t1)));
        g.throughput(Throughput::Elements(evals_b as u64));
        g.bench_function(format!("differential-equations/{name}"), |b| b.iter(|| theirs(&p, black_box(y0), t1)));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
