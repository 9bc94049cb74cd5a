//! Avoidance benchmarks (Ch. 5 timings): the weights of a 210 x 210 image and the pseudo-inverse,
//! 15 x 15 and 30 x 30 grids, separable (`W = Gy+ F Gx+^T`) against the literal dense `lambda = G+ f`.
//! Thesis (MATLAB): pseudo-inverse 0.268 s / 3.44 s, weights 1.8 ms / 10.3 ms.
//!
//! `cargo bench -p flinch-harness --bench avoid` (add a filter, e.g. `-- weights`, to run a subset).
//! The dense 30 x 30 pseudo-inverse (an SVD of a 44,100 x 900 matrix) is not benchmarked: see
//! docs/avoidance.md; its weights product is, with `G+` assembled from the separable factors.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use flinch_harness::avoid::depth::{Camera, OperatorShape, RobotShape, Rng};
use flinch_harness::avoid::{calib, depth, rbf};

const PX: usize = 210;

fn image() -> depth::HeightMap {
    let cam = Camera { width_px: PX, height_px: PX, m_per_px: 0.005, camera_height_m: 1.2, noise_mm: 3.0, null_fraction: 0.01 };
    let robot = RobotShape { base_m: [0.55, 1.3], wrist_radius_m: 0.045, wrist_height_m: 0.3, link_width_m: 0.07, link_height_m: 0.4 };
    let op = OperatorShape { entry_m: [0.5, 0.0], hand_radius_m: 0.05, hand_height_m: 0.2, forearm_width_m: 0.07, forearm_height_m: 0.15, obstacles: Vec::new() };
    let img = depth::render(&cam, Some((&robot, [0.3, 0.5])), Some((&op, [0.5, 0.42])), &mut Rng::new(1));
    calib::preprocess(&img, &cam, 0.065, None)
}

fn grid(n: usize) -> rbf::RbfGrid {
    rbf::RbfGrid::new(PX, PX, n, 0.005, 1.0).expect("grid")
}

fn weights(c: &mut Criterion) {
    let map = image();
    let mut g = c.benchmark_group("weights_210px");
    for n in [15, 30] {
        let sep = rbf::Fitter::new(grid(n)).expect("fitter");
        g.bench_function(format!("separable_{n}x{n}"), |b| b.iter(|| sep.weights(black_box(&map))));
        let dense = rbf::DenseFitter::from_separable(&sep);
        g.sample_size(20);
        g.bench_function(format!("dense_{n}x{n}"), |b| b.iter(|| dense.weights(black_box(&map))));
    }
    g.finish();
}

fn pinv(c: &mut Criterion) {
    let mut g = c.benchmark_group("pinv_210px");
    for n in [15, 30] {
        g.bench_function(format!("separable_{n}x{n}"), |b| b.iter(|| rbf::Fitter::new(black_box(grid(n))).expect("fitter")));
    }
    g.sample_size(10);
    g.bench_function("dense_15x15", |b| b.iter(|| rbf::DenseFitter::new(black_box(&grid(15))).expect("dense")));
    g.finish();
}

fn frame(c: &mut Criterion) {
    // One camera frame as `flinch avoid` processes it: fill, raise, weights, filter (render excluded).
    let cam = Camera { width_px: PX, height_px: PX, m_per_px: 0.005, camera_height_m: 1.2, noise_mm: 3.0, null_fraction: 0.01 };
    let op = OperatorShape { entry_m: [0.5, 0.0], hand_radius_m: 0.05, hand_height_m: 0.2, forearm_width_m: 0.07, forearm_height_m: 0.15, obstacles: Vec::new() };
    let img = depth::render(&cam, None, Some((&op, [0.5, 0.42])), &mut Rng::new(2));
    let sep = rbf::Fitter::new(grid(15)).expect("fitter");
    c.bench_function("frame_210px_15x15_preprocess_fit_filter", |b| {
        b.iter(|| {
            let map = calib::preprocess(black_box(&img), &cam, 0.065, None);
            let mut w = sep.weights(&map);
            rbf::filter_weights(&mut w);
            w
        })
    });
}

criterion_group!(benches, weights, pinv, frame);
criterion_main!(benches);
