//! Random variants of the scenes: never inside the operator, always safe and honestly reported.

use super::*;
use flinch_harness::avoid::path::{simulate, Engine, Setup, Status};
use flinch_harness::avoid::scene::Avoid;
use flinch_tests::scene_path;

/// Randomised variants of the shipped scene (seeded, reproducible): the hand reaches from a random
/// point of the near edge to a random point, at up to 1.6 m/s; with the monitor on, zero
/// penetrations and the SSM bound holds at every step.
#[test]
fn random_variants_never_penetrate() {
    let base = Avoid::load(&scene_path("avoid_under_tool.toml")).unwrap();
    let setup = Setup::new(&base, None).unwrap();
    let mut seed: u64 = 0x5EED_F11C;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..12 {
        let mut s = base.clone();
        let ex = 0.1 + 0.85 * next();
        s.operator.entry_m = [ex, 0.0];
        let (hx, hy) = (0.1 + 0.85 * next(), 0.2 + 0.75 * next());
        let t0 = 2.0 * next();
        let dist = ((hx - ex).powi(2) + (hy - 0.05).powi(2)).sqrt();
        let speed = 0.2 + 1.4 * next();
        s.operator.keyframes[0].t_s = t0;
        s.operator.keyframes[0].hand_m = [ex, 0.05];
        s.operator.keyframes[1].t_s = t0 + dist / speed;
        s.operator.keyframes[1].hand_m = [hx, hy];
        s.camera.seed = k;
        s.max_time_s = 6.0;
        let r = simulate(&s, &setup, Engine::Reference).unwrap();
        safe(&format!("variant {k} (hand to [{hx:.2}, {hy:.2}] at {speed:.2} m/s from t = {t0:.2} s)"), &s, &r);
    }
}

/// Item 4: variants nobody tuned for, seeded and reproducible (`FLINCH_AVOID_VARIANTS` sets how
/// many; 200 by default). The operator anywhere along the near edge, hand 30-80 mm, forearm
/// 40-100 mm wide, 50-250 mm high, still or moving at up to `v_h` (1.6 m/s); start and goal
/// anywhere at least 0.3 m apart; grid 15 x 15 or 30 x 30; latency 0 to 0.2 s. Our law (not
/// `--thesis`) every time: a run reported reached kept the clearance and the SSM bound; any run that
/// went inside is a collision and `flinch avoid` would exit 1; and, stronger, every run is safe
/// (`safe`: never over the SSM bound at the true separation, never moving in contact). A hand whose
/// key frames run into the tool held in a protective stop is a `collision` (ISO/TS 15066 5.5.4
/// allows contact with a stopped robot; the report still says so), with the tool at rest.
#[test]
fn random_variants_are_safe_and_honest() {
    let base = Avoid::load(&scene_path("avoid_fast_hand.toml")).unwrap();
    let n: usize = std::env::var("FLINCH_AVOID_VARIANTS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let mut seed: u64 = 0x0A70_1D09;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let setups: Vec<(usize, Setup)> = [15, 30]
        .into_iter()
        .map(|g| {
            let mut s = base.clone();
            s.fit.grid = g;
            (g, Setup::new(&s, None).unwrap())
        })
        .collect();
    let mut tally = std::collections::BTreeMap::new();
    let mut reached_near = f64::INFINITY;
    let t_start = std::time::Instant::now();
    for k in 0..n {
        let mut s = base.clone();
        let mut pt = || [0.1 + 0.85 * next(), 0.1 + 0.85 * next()];
        let (start, goal) = loop {
            let (a, b) = (pt(), pt());
            if (a[0] - b[0]).hypot(a[1] - b[1]) > 0.3 {
                break (a, b);
            }
        };
        s.start_m = start;
        s.goal_m = goal;
        let ex = 0.05 + 0.95 * next();
        s.operator.entry_m = [ex, 0.0];
        s.operator.hand_radius_m = 0.03 + 0.05 * next();
        s.operator.forearm_width_m = 0.04 + 0.06 * next();
        s.operator.hand_height_m = 0.05 + 0.2 * next();
        s.operator.forearm_height_m = 0.05 + 0.2 * next();
        // The hand starts within 0.4 m of its edge (farther, its forearm leaves most starts or
        // goals inside S_p: `no_room` at once) and then reaches anywhere.
        let h0 = [ex, 0.02 + 0.38 * next()];
        let h1 = [0.05 + 0.9 * next(), 0.05 + 0.9 * next()];
        let t0 = 1.5 * next();
        let speed = 1.6 * next();
        let still = next() < 0.3;
        s.operator.keyframes.truncate(1);
        s.operator.keyframes[0].t_s = t0;
        s.operator.keyframes[0].hand_m = h0;
        if !still {
            let mut kf = s.operator.keyframes[0].clone();
            kf.t_s = t0 + (h1[0] - h0[0]).hypot(h1[1] - h0[1]) / speed.max(0.05);
            kf.hand_m = h1;
            s.operator.keyframes.push(kf);
        }
        let grid = if next() < 0.5 { 15 } else { 30 };
        s.fit.grid = grid;
        s.latency_s = 0.2 * next();
        s.camera.seed = k as u64;
        s.max_time_s = 5.0;
        let setup = &setups.iter().find(|(g, _)| *g == grid).unwrap().1;
        let r = simulate(&s, setup, Engine::Reference).unwrap();
        let name = format!(
            "variant {k}: start {start:.2?} goal {goal:.2?}, hand {h0:.2?} -> {h1:.2?} at {speed:.2} m/s from {t0:.2} s (still {still}), grid {grid}, latency {:.3} s",
            s.latency_s
        );
        // The brief's assertions first (they name the defect), then everything `safe` checks.
        if r.status == Status::Reached {
            assert!(r.min_signed_distance_m >= s.clearance_m && r.ssm_violations == 0, "{name}: reached unsafely");
        }
        if r.min_signed_distance_m < 0.0 {
            assert!(matches!(r.status, Status::Collision(_)) && !r.status.ok(), "{name}: inside but {:?}", r.status);
        }
        safe(&name, &s, &r);
        if r.status == Status::Reached { reached_near = reached_near.min(r.min_signed_distance_m); }
        *tally.entry(format!("{} {}", r.status.name(), r.status.reason().map_or("", |x| x.name()))).or_insert(0) += 1;
    }
    println!("{n} variants: {tally:?}; closest reached run {reached_near} m; {:.1} s", t_start.elapsed().as_secs_f64());
}
