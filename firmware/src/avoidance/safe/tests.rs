//! The monitor's tests (`safe.rs`): the protective separation and K, the age and the motion since
//! capture, the length bound, extreme commands, the steering barrier, the directional bound's
//! soundness over random frames, PFL along and across the module's axis.
use super::*;
use crate::avoidance::num::I16F16;

fn params<R: Real>() -> SsmParams<R> {
    SsmParams {
        human_speed_mps: R::from_f64(1.6),
        reaction_time_s: R::from_f64(0.01),
        stopping_time_s: R::from_f64(0.1),
        margin_m: R::from_f64(0.02),
        speed_cap_mps: R::from_f64(0.25),
        whole_body_only: false,
        pfl: None,
    }
}

fn sensed<R: Real>(sep: f64, age: f64) -> Sensed<R> {
    let s = R::from_f64(sep);
    Sensed { separation_m: s, tool_x_m: R::ZERO, tool_y_m: R::ZERO, age_s: R::from_f64(age), nearest_x_m: R::from_f64(sep + 0.05), nearest_y_m: R::ZERO, sectors_m: Sensed::sectors_all(s), fixture_sectors_m: Sensed::no_fixtures() }
}

#[test]
fn limit_follows_the_protective_separation() {
    let c = SafeController::new(params::<f64>());
    // ISO 13855 6.2: K T + C = 2.0 * 0.11 + 0.02 = 0.24 m <= 0.5 m: K = 2.0 m/s; below it, a
    // protective stop.
    assert_eq!(c.approach_speed_mps(), 2.0);
    assert!((c.stop_separation_m() - 0.24).abs() < 1e-12);
    assert_eq!(c.speed_limit(0.235), 0.0);
    // 10 mm above it: v = 0.01 / (0.01 + 0.05) = 0.1667 m/s.
    assert!((c.speed_limit(0.25) - 0.01 / 0.06).abs() < 1e-9);
    assert_eq!(c.speed_limit(5.0), 0.25, "capped");
    // The limit satisfies S_p(v) <= S: check eq 1 directly.
    for s in [0.24, 0.25, 0.27, 0.3] {
        let v = c.speed_limit(s);
        let sp = 2.0 * 0.11 + v * 0.01 + v * 0.1 / 2.0 + 0.02;
        assert!(sp <= s + 1e-12, "S_p {sp} > S {s}");
    }
}

/// A hand or an arm reaches at K = max(2.0 m/s, v_h) at every distance; only a scene that
/// declares a whole body alone gets ISO 13855:2010 6.2 formula (1)'s 1.6 m/s beyond 0.5 m (and
/// at least 0.5 m there). At least 100 mm either way. The same in the board's number types.
#[test]
fn k_is_two_metres_a_second_for_hands_and_follows_iso_13855_for_whole_bodies() {
    let with = |v_h: f64, t_s: f64, margin: f64, whole: bool| {
        SafeController::new(SsmParams { human_speed_mps: v_h, reaction_time_s: 0.01, stopping_time_s: t_s - 0.01, margin_m: margin, speed_cap_mps: 0.25, whole_body_only: whole, pfl: None })
    };
    let cases = [
        // (v_h, T_r + T_s, margin, whole body) -> (K, stop separation)
        ((1.6, 0.11, 0.02, false), (2.0, 0.24)),
        ((2.5, 0.11, 0.02, false), (2.5, 0.295)),
        // A hand: 2.0 m/s beyond 0.5 m too (the K-falls-to-1.6 finding of issue 29).
        ((1.6, 0.2, 0.15, false), (2.0, 0.55)),
        ((1.6, 0.4, 0.1, false), (2.0, 0.9)),
        ((1.6, 0.11, 0.02, true), (2.0, 0.24)),
        // 2.0 * 0.2 + 0.1 = 0.5: exactly 0.5 m is still the near field.
        ((1.6, 0.2, 0.1, true), (2.0, 0.5)),
        // 2.0 * 0.2 + 0.15 = 0.55 > 0.5: K = 1.6, 1.6 * 0.2 + 0.15 = 0.47, raised to 0.5.
        ((1.6, 0.2, 0.15, true), (1.6, 0.5)),
        // 1.6 * 0.4 + 0.1 = 0.74: beyond 0.5 m either way.
        ((1.6, 0.4, 0.1, true), (1.6, 0.74)),
        // 2.0 * 0.02 + 0 = 0.04: raised to ISO 13855's 100 mm minimum.
        ((1.6, 0.02, 0.0, false), (2.0, 0.1)),
        ((1.6, 0.02, 0.0, true), (2.0, 0.1)),
    ];
    for ((v_h, t, m, whole), (k, stop)) in cases {
        let c = with(v_h, t, m, whole);
        assert!((c.approach_speed_mps() - k).abs() < 1e-12 && (c.stop_separation_m() - stop).abs() < 1e-12, "{v_h} {t} {m} {whole}: K {} S {}", c.approach_speed_mps(), c.stop_separation_m());
        assert_eq!(c.speed_limit(stop - 1e-9), 0.0);
        assert!(c.speed_limit(stop + 0.01) > 0.0);
        let q = |v: f64| I16F16::from_f64(v);
        let f = SafeController::new(SsmParams { human_speed_mps: q(v_h), reaction_time_s: q(0.01), stopping_time_s: q(t - 0.01), margin_m: q(m), speed_cap_mps: q(0.25), whole_body_only: whole, pfl: None });
        assert!((f.approach_speed_mps().to_f64() - k).abs() < 1e-3 && (f.stop_separation_m().to_f64() - stop).abs() < 1e-3, "I16F16 {v_h} {t} {m}");
        let g = SafeController::new(SsmParams { human_speed_mps: v_h as f32, reaction_time_s: 0.01, stopping_time_s: (t - 0.01) as f32, margin_m: m as f32, speed_cap_mps: 0.25, whole_body_only: whole, pfl: None });
        assert!((f64::from(g.approach_speed_mps()) - k).abs() < 1e-5 && (f64::from(g.stop_separation_m()) - stop).abs() < 1e-5, "f32 {v_h} {t} {m}");
    }
    // The age term uses the same K: 0.1 s old eats 0.2 m at 2.0 m/s.
    let c = with(1.6, 0.11, 0.02, false);
    assert_eq!(c.limit(0.1, 0.0, 0.0, 0.0, Some(&sensed(0.43, 0.1))).state, SafeState::ProtectiveStop);
    assert_eq!(c.limit(0.1, 0.0, 0.0, 0.0, Some(&sensed(0.45, 0.1))).state, SafeState::Run);
    // NaN parameters stop.
    let n = with(f64::NAN, 0.11, 0.02, false);
    assert_eq!(n.limit(0.1, 0.0, 0.0, 0.0, Some(&sensed(5.0, 0.0))).state, SafeState::ProtectiveStop);
}

#[test]
fn age_and_motion_since_capture_eat_the_separation() {
    let c = SafeController::new(params::<f64>());
    let fresh = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed(0.5, 0.0)));
    assert_eq!(fresh.state, SafeState::Run);
    // 0.2 s old: a person may have come 0.32 m closer.
    let old = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed(0.5, 0.2)));
    assert_eq!(old.state, SafeState::ProtectiveStop);
    assert_eq!((old.vx, old.vy), (0.0, 0.0));
    // The tool moved 0.31 m since capture.
    let moved = c.limit(0.25, 0.0, 0.31, 0.0, Some(&sensed(0.5, 0.0)));
    assert_eq!(moved.state, SafeState::ProtectiveStop);
    assert_eq!(c.limit(0.1, 0.0, 0.0, 0.0, None).state, SafeState::NoData);
}

#[test]
fn the_length_bound_is_above_the_length_and_scaled_commands_end_near_the_limit() {
    let c = SafeController::new(params::<f64>());
    let q = SafeController::new(params::<I16F16>());
    let far = sensed::<f64>(10.0, 0.0);
    for k in 0..360 {
        let a = (k as f64).to_radians();
        for len in [0.01, 0.2, 0.3, 1.0, 50.0] {
            let (vx, vy) = (len * a.cos(), len * a.sin());
            let b = c.norm_bound(vx, vy);
            assert!(b >= len * (1.0 - 1e-12) && b <= len * 1.1181, "{a} {len}: {b}");
            let out = c.limit(vx, vy, 0.0, 0.0, Some(&far));
            let sp = out.vx.hypot(out.vy);
            if len <= 0.25 / 1.1181 {
                assert_eq!((out.vx, out.vy), (vx, vy), "passed unchanged");
            } else if len > 0.25 {
                assert!(sp <= 0.25 + 1e-12 && sp >= 0.25 / 1.1181, "{a} {len}: {sp}");
            } else {
                assert!(sp <= 0.25 + 1e-12);
            }
            let (qx, qy) = (I16F16::from_f64(vx), I16F16::from_f64(vy));
            let o = q.limit(qx, qy, I16F16::ZERO, I16F16::ZERO, Some(&sensed(10.0, 0.0)));
            assert!(o.vx.to_f64().hypot(o.vy.to_f64()) <= 0.2502, "I16F16 {a} {len}");
        }
    }
    // Motion since capture is over-estimated, never under: the separation left is smaller.
    let moved = c.limit(0.0, 0.0, 0.03, 0.04, Some(&sensed(0.5, 0.0)));
    assert!(moved.separation_m <= 0.5 - 0.05 + 1e-12 && moved.separation_m >= 0.5 - 0.05 * 1.1181);
}

#[test]
fn extreme_and_non_finite_commands_are_capped_or_stopped() {
    let c = SafeController::new(params::<f64>());
    let far = sensed::<f64>(10.0, 0.0);
    for (vx, vy) in [(3000.0, -4000.0), (1e300, 1e300), (-0.3, 0.0)] {
        let out = c.limit(vx, vy, 0.0, 0.0, Some(&far));
        let sp = (out.vx * out.vx + out.vy * out.vy).sqrt();
        assert!(sp <= 0.25 + 1e-12, "{vx} {vy} -> {sp}");
        assert_eq!(out.state, SafeState::Slow);
    }
    let nan = c.limit(f64::NAN, 0.0, 0.0, 0.0, Some(&far));
    assert_eq!((nan.vx, nan.vy, nan.state), (0.0, 0.0, SafeState::ProtectiveStop));
    let nan_sep = c.limit(0.1, 0.0, 0.0, 0.0, Some(&sensed(f64::NAN, 0.0)));
    assert_eq!(nan_sep.state, SafeState::ProtectiveStop);

    // The target's number type: saturated components still end at the cap.
    let q = SafeController::new(params::<I16F16>());
    let big = I16F16::from_f64(30000.0);
    let out = q.limit(big, big, I16F16::ZERO, I16F16::ZERO, Some(&sensed(10.0, 0.0)));
    let sp = (out.vx.to_f64().powi(2) + out.vy.to_f64().powi(2)).sqrt();
    assert!(sp <= 0.2501, "{sp}");
    // Scaled to the bound max + min / 2 = 1.5 m for a diagonal of true length sqrt 2 m.
    assert!(sp > 0.25 * 2f64.sqrt() / 1.5 - 1e-3, "{sp}");
}

fn steered(barrier: f64) -> SafeController<f64> {
    SafeController::new(params::<f64>()).with_steer(Steer { barrier_m: barrier, band_m: 0.05, view_m: [0.0, 0.0, 2.0, 2.0], edge_margin_m: 0.045 })
}

fn at(sep: f64, nearest: [f64; 2]) -> Sensed<f64> {
    Sensed { separation_m: sep, tool_x_m: 1.0, tool_y_m: 1.0, age_s: 0.0, nearest_x_m: nearest[0], nearest_y_m: nearest[1], sectors_m: [sep; SECTORS], fixture_sectors_m: Sensed::no_fixtures() }
}

/// Head-on in the band: the approach is cut to the barrier's rate (its length bound allows at
/// most 11.8 % more), the cut turned along the boundary (never a faster command), its side
/// latched; below the barrier it backs off and turns; far away nothing changes.
#[test]
fn the_barrier_cuts_the_approach_and_turns_it() {
    let mut c = steered(0.4);
    let rate = 0.25 / 0.05;
    let near = at(0.42, [1.5, 1.0]);
    let (vx, vy) = c.steer(0.25, 0.0, 1.0, 1.0, Some(&near));
    assert!(vx <= rate * 0.02 * 1.1181 + 1e-12 && vx >= 0.0, "{vx}");
    assert!(vy.abs() > 0.1, "turned along the boundary: {vy}");
    assert!(vx.hypot(vy) <= 0.25 + 1e-12);
    let side = vy.signum();
    // The command now leans the other way: the side stays while in the band.
    let (_, vy2) = c.steer(0.25, -0.05 * side, 1.0, 1.0, Some(&near));
    assert_eq!(vy2.signum(), side);
    // Below the barrier: backs off, and still turns; out of the band the latch is released.
    let (bx, by) = c.steer(0.25, 0.0, 1.0, 1.0, Some(&at(0.35, [1.5, 1.0])));
    assert!(bx < 0.0 && by.signum() == side, "{bx} {by}");
    assert_eq!(c.steer(0.25, 0.1, 1.0, 1.0, Some(&at(1.0, [2.5, 1.0]))), (0.25, 0.1));
    assert_eq!(c.side, 0);
    // Moving away from the obstacle is never cut.
    assert_eq!(c.steer(-0.25, 0.0, 1.0, 1.0, Some(&near)), (-0.25, 0.0));
}

/// The view's edges: the speed towards an edge is at most `rate` times the room left inside
/// `edge_margin_m`, and outside it the command points back in.
#[test]
fn the_view_edges_are_a_barrier() {
    let mut c = steered(0.4);
    let far = at(5.0, [9.0, 9.0]);
    let (vx, vy) = c.steer(0.25, 0.25, 2.0 - 0.045 - 0.01, 1.0, Some(&far));
    assert!((vx - 0.25 / 0.05 * 0.01).abs() < 1e-12 && vy == 0.25, "{vx} {vy}");
    let (ox, _) = c.steer(0.25, 0.0, 2.01, 1.0, Some(&far));
    assert!(ox < 0.0);
    let (lx, ly) = c.steer(-0.3, -0.3, 0.02, 0.02, None);
    assert!(lx > 0.0 && ly > 0.0, "{lx} {ly}");
}

/// Whatever comes in (extreme, non-finite), steering then the limit ends at or below the cap
/// and never moves towards an obstacle faster than the barrier allows, in I16F16 too.
#[test]
fn steered_commands_stay_bounded() {
    let q = |v: f64| I16F16::from_f64(v);
    let mut c = SafeController::new(params::<I16F16>()).with_steer(Steer { barrier_m: q(0.4), band_m: q(0.05), view_m: [q(0.0), q(0.0), q(2.0), q(2.0)], edge_margin_m: q(0.045) });
    let s = Sensed { separation_m: q(0.43), tool_x_m: q(1.0), tool_y_m: q(1.0), age_s: q(0.0), nearest_x_m: q(1.4), nearest_y_m: q(1.3), sectors_m: [q(0.43); SECTORS], fixture_sectors_m: Sensed::no_fixtures() };
    for (vx, vy) in [(30000.0, 30000.0), (-30000.0, 5.0), (0.3, 0.2), (0.0, 0.0)] {
        let (sx, sy) = c.steer(q(vx), q(vy), q(1.0), q(1.0), Some(&s));
        let out = c.limit(sx, sy, q(1.0), q(1.0), Some(&s));
        let (ox, oy) = (out.vx.to_f64(), out.vy.to_f64());
        assert!(ox.hypot(oy) <= 0.2502, "{vx} {vy}: {ox} {oy}");
    }
    let mut f = steered(0.4);
    let (nx, ny) = f.steer(f64::NAN, 0.0, 1.0, 1.0, Some(&at(0.42, [1.5, 1.0])));
    let out = f.limit(nx, ny, 1.0, 1.0, Some(&at(0.42, [1.5, 1.0])));
    assert_eq!((out.vx, out.vy), (0.0, 0.0));
}
fn sectors(list: &[(usize, f64)]) -> [f64; SECTORS] {
    let mut s = [10.0; SECTORS];
    for &(k, d) in list {
        s[k] = d;
    }
    s
}

fn dir(sep: [f64; SECTORS]) -> Sensed<f64> {
    let min = sep.iter().copied().fold(f64::INFINITY, f64::min);
    Sensed { separation_m: min, tool_x_m: 0.0, tool_y_m: 0.0, age_s: 0.0, nearest_x_m: 1.0, nearest_y_m: 0.0, sectors_m: sep, fixture_sectors_m: Sensed::no_fixtures() }
}

#[test]
fn sectors_cover_the_plane_counter_clockwise() {
    for k in 0..360 {
        let a = (k as f64 + 0.5).to_radians();
        assert_eq!(sector_of(a.cos(), a.sin()), (k / 45) as usize, "{k} deg");
        let q = |v: f64| I16F16::from_f64(v);
        assert_eq!(sector_of(q(a.cos()), q(a.sin())), (k / 45) as usize, "I16F16 {k} deg");
    }
}

/// ISO/TS 15066 5.5.4.2.3: `v_r` is the speed towards the person. A person 0.25 m behind the
/// tool (10 mm above the stop separation): moving away passes at the cap, towards it is cut to
/// the bound, across it is cut less than head-on.
#[test]
fn moving_away_from_a_person_is_not_limited() {
    let c = SafeController::new(params::<f64>());
    let behind = dir(sectors(&[(3, 0.25), (4, 0.25)]));
    let away = c.limit(0.25, 0.0, 0.0, 0.0, Some(&behind));
    assert_eq!((away.vx, away.vy, away.state), (0.25, 0.0, SafeState::Run));
    let towards = c.limit(-0.25, 0.0, 0.0, 0.0, Some(&behind));
    assert_eq!(towards.state, SafeState::Slow);
    assert!(towards.vx.hypot(towards.vy) <= c.speed_limit(0.25) + 1e-12);
    let across = c.limit(0.0, 0.25, 0.0, 0.0, Some(&behind));
    let sp = across.vx.hypot(across.vy);
    assert!(sp > towards.vx.hypot(towards.vy) && sp < 0.25, "{sp}");
}

/// The fixed-point types bound the whole speed by the nearest sector (no division a sector):
/// moving away from a close person is cut as moving towards it (never less safe).
#[test]
fn fixed_point_bounds_the_whole_speed_by_the_nearest_sector() {
    let q = |v: f64| I16F16::from_f64(v);
    let c = SafeController::new(params::<I16F16>());
    let mut sec = [q(10.0); SECTORS];
    sec[3] = q(0.25);
    sec[4] = q(0.25);
    let behind = Sensed { separation_m: q(0.25), tool_x_m: q(0.0), tool_y_m: q(0.0), age_s: q(0.0), nearest_x_m: q(-0.3), nearest_y_m: q(0.0), sectors_m: sec, fixture_sectors_m: Sensed::no_fixtures() };
    let away = c.limit(q(0.2), q(0.0), q(0.0), q(0.0), Some(&behind));
    assert_eq!(away.state, SafeState::Slow);
    assert!(away.vx.to_f64() <= c.speed_limit(q(0.25)).to_f64() + 1e-4, "{}", away.vx.to_f64());
}

/// The nearest point is not the only one: a person 0.245 m behind and another 0.25 m ahead.
/// Moving away from the nearer one must still respect the farther one in front.
#[test]
fn a_second_person_ahead_still_limits() {
    let c = SafeController::new(params::<f64>());
    let both = dir(sectors(&[(3, 0.245), (0, 0.25), (7, 0.25)]));
    let out = c.limit(0.25, 0.0, 0.0, 0.0, Some(&both));
    assert!(out.vx <= c.speed_limit(0.25) + 1e-12 && c.speed_limit(0.25) < 0.2, "{}", out.vx);
    assert_eq!(out.state, SafeState::Slow);
}

/// The bound holds for every point the frame could have shown, wherever it moved since capture
/// (at most `K age`) and wherever the tool moved: `S_p(v . n) <= s` for the point's true
/// direction `n` and separation `s` now, over 200,000 random frames, points and commands.
#[test]
fn the_directional_bound_holds_for_every_point_a_frame_could_hold() {
    let c = SafeController::new(params::<f64>());
    let w = 0.045;
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let (k, per) = (c.approach_speed_mps(), 0.01 + 0.1 / 2.0);
    for _ in 0..200_000 {
        // One point, sensed at capture in its sector, the others far.
        let a = rnd() * core::f64::consts::TAU;
        let d = w + 0.05 + rnd() * 0.6;
        let q = [d * a.cos(), d * a.sin()];
        let mut sep = [10.0; SECTORS];
        sep[sector_of(q[0], q[1])] = d - w;
        let age = rnd() * 0.25;
        let sensed = Sensed { separation_m: d - w, tool_x_m: 0.0, tool_y_m: 0.0, age_s: age, nearest_x_m: q[0], nearest_y_m: q[1], sectors_m: sep, fixture_sectors_m: Sensed::no_fixtures() };
        // The tool moved since capture, the point moved up to K age.
        let (tb, tm) = (rnd() * core::f64::consts::TAU, rnd() * 0.01);
        let p = [tm * tb.cos(), tm * tb.sin()];
        let (eb, em) = (rnd() * core::f64::consts::TAU, rnd() * k * age);
        let qn = [q[0] + em * eb.cos(), q[1] + em * eb.sin()];
        let (vb, vm) = (rnd() * core::f64::consts::TAU, rnd() * 0.4);
        let out = c.limit(vm * vb.cos(), vm * vb.sin(), p[0], p[1], Some(&sensed));
        let (rx, ry) = (qn[0] - p[0], qn[1] - p[1]);
        let dist = rx.hypot(ry);
        let u = ((out.vx * rx + out.vy * ry) / dist).max(0.0);
        let s_now = dist - w;
        let sp = k * (0.01 + 0.1) + 0.02 + u * per;
        assert!(u == 0.0 || sp <= s_now + 1e-9, "point {q:?} -> {qn:?}, tool {p:?}, age {age}: u {u} needs {sp} > {s_now}");
    }
}

fn with_pfl() -> SafeController<f64> {
    SafeController::new(SsmParams { pfl: Some(Pfl { axis: [1.0, 0.0], along_mps: 0.29, across_mps: 0.063 }), ..params::<f64>() })
}

/// PFL (ISO/TS 15066 5.5.5): in contact (separation 0 ahead), a command along the module's axis
/// within its speed passes; across it the rigid speed applies; a diagonal keeps both components
/// within theirs; without PFL the same command stops.
#[test]
fn pfl_lets_the_module_touch_along_its_axis_only() {
    let c = with_pfl();
    let contact = dir(sectors(&[(0, 0.0), (7, 0.0), (1, 0.0), (2, 0.0)]));
    let along = c.limit(0.25, 0.0, 0.0, 0.0, Some(&contact));
    assert_eq!((along.vx, along.vy, along.state), (0.25, 0.0, SafeState::Pfl));
    let quick = SafeController::new(SsmParams { speed_cap_mps: 0.5, pfl: Some(Pfl { axis: [1.0, 0.0], along_mps: 0.29, across_mps: 0.063 }), ..params::<f64>() });
    let fast = quick.limit(0.4, 0.0, 0.0, 0.0, Some(&contact));
    assert!(fast.vx <= 0.29 * 63.0 / 64.0 + 1e-12 && fast.vx > 0.28, "{}", fast.vx);
    let across = c.limit(0.0, 0.25, 0.0, 0.0, Some(&contact));
    assert!(across.vy <= 0.063 * 63.0 / 64.0 + 1e-12 && across.vy > 0.06, "{}", across.vy);
    let diag = c.limit(0.2, 0.2, 0.0, 0.0, Some(&contact));
    assert!(diag.vx <= 0.29 && diag.vy <= 0.063 * 63.0 / 64.0 + 1e-12, "{diag:?}");
    let none = SafeController::new(params::<f64>()).limit(0.25, 0.0, 0.0, 0.0, Some(&contact));
    assert_eq!((none.vx, none.vy, none.state), (0.0, 0.0, SafeState::ProtectiveStop));
    // A rotated axis, in the board's number type too.
    let a = [0.6, 0.8];
    let r = SafeController::new(SsmParams { pfl: Some(Pfl { axis: a, along_mps: 0.29, across_mps: 0.063 }), ..params::<f64>() });
    let o = r.limit(0.12, 0.16, 0.0, 0.0, Some(&contact));
    assert!((o.vx - 0.12).abs() < 1e-12 && (o.vy - 0.16).abs() < 1e-12, "along the rotated axis: {o:?}");
    // The board's f32: the across component cut to the rigid speed, the along one kept.
    let g = SafeController::new(SsmParams { pfl: Some(Pfl { axis: [0.6f32, 0.8], along_mps: 0.29, across_mps: 0.063 }), ..params::<f32>() });
    let gc = Sensed { separation_m: 0.0f32, tool_x_m: 0.0, tool_y_m: 0.0, age_s: 0.0, nearest_x_m: 0.1, nearest_y_m: 0.0, sectors_m: [0.0; SECTORS], fixture_sectors_m: Sensed::no_fixtures() };
    let o = g.limit(0.2, -0.15, 0.0, 0.0, Some(&gc));
    let (ox, oy) = (f64::from(o.vx), f64::from(o.vy));
    assert!((ox * 0.8 - oy * 0.6).abs() <= 0.063 && (ox * 0.6 + oy * 0.8).abs() <= 0.29 && ox > 0.0, "f32 across: {ox} {oy}");
    // Fixed point applies no PFL (the step budget): in contact it stops.
    let q = |v: f64| I16F16::from_f64(v);
    let f = SafeController::new(SsmParams { pfl: Some(Pfl { axis: [q(0.6), q(0.8)], along_mps: q(0.29), across_mps: q(0.063) }), ..params::<I16F16>() });
    let qc = Sensed { separation_m: q(0.0), tool_x_m: q(0.0), tool_y_m: q(0.0), age_s: q(0.0), nearest_x_m: q(0.1), nearest_y_m: q(0.0), sectors_m: [q(0.0); SECTORS], fixture_sectors_m: Sensed::no_fixtures() };
    let o = f.limit(q(0.12), q(0.16), q(0.0), q(0.0), Some(&qc));
    assert_eq!((o.vx.to_f64(), o.vy.to_f64(), o.state), (0.0, 0.0, SafeState::ProtectiveStop));
}

/// PFL speeds that are not positive numbers are no PFL at all (never a free pass).
#[test]
fn a_broken_pfl_configuration_is_none() {
    let contact = dir([0.0; SECTORS]);
    for (a, b, axis) in [(f64::NAN, 0.063, [1.0, 0.0]), (0.29, f64::NAN, [1.0, 0.0]), (0.29, -1.0, [1.0, 0.0]), (0.29, 0.063, [f64::NAN, 0.0]), (0.0, 0.0, [1.0, 0.0]), (0.29, 0.063, [0.1, 0.0]), (0.29, 0.063, [1.0, 1.0])] {
        let c = SafeController::new(SsmParams { pfl: Some(Pfl { axis, along_mps: a, across_mps: b }), ..params::<f64>() });
        let o = c.limit(0.1, 0.0, 0.0, 0.0, Some(&contact));
        assert_eq!((o.vx, o.vy, o.state), (0.0, 0.0, SafeState::ProtectiveStop), "{a} {b} {axis:?}");
    }
}

fn with_fixture<R: Real>(person_m: f64, fixtures: &[(usize, f64)], age: f64) -> Sensed<R> {
    let mut s = sensed::<R>(person_m, age);
    for &(k, d) in fixtures {
        s.fixture_sectors_m[k] = R::from_f64(d);
    }
    s
}

/// A fixture is bounded by the robot's own stop only (issue 29 item 2): `v (T_r + T_s / 2) +
/// margin <= s`, no `K (T_r + T_s)` and no `K age`. At 0.1 m ahead a person would stop the tool
/// (`S_p(0)` = 0.24 m); a fixture there lets it run at the cap; at 30 mm it slows to (0.03 -
/// 0.02) / 0.06 m/s, whatever the frame's age; moving away is not limited. `separation_m` stays
/// the person's.
#[test]
fn a_fixture_is_bounded_without_a_human_approach() {
    let c = SafeController::new(params::<f64>());
    let ahead = [(0, 0.1), (7, 0.1)];
    let out = c.limit(0.25, 0.0, 0.0, 0.0, Some(&with_fixture::<f64>(5.0, &ahead, 0.0)));
    assert_eq!((out.vx, out.state), (0.25, SafeState::Run));
    assert!((out.separation_m - 5.0).abs() < 1e-12, "the person's separation: {}", out.separation_m);
    // The same pixel as a person: a protective stop.
    let person = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed::<f64>(0.1, 0.0)));
    assert_eq!(person.state, SafeState::ProtectiveStop);
    for age in [0.0, 0.1, 0.3] {
        let near = with_fixture::<f64>(5.0, &[(0, 0.03), (7, 0.03)], age);
        let out = c.limit(0.25, 0.0, 0.0, 0.0, Some(&near));
        let l = (0.03 - 0.02) / 0.06;
        assert!(out.vx <= l + 1e-12 && out.vx > 0.9 * l, "age {age}: {} against {l}", out.vx);
        assert_eq!(out.state, SafeState::Slow);
        let away = c.limit(-0.25, 0.0, 0.0, 0.0, Some(&near));
        assert_eq!(away.vx, -0.25, "moving away from the fixture");
    }
    // The tool's own motion since capture still counts: 10 mm on, 20 mm are left: (0.02 - 0.02).
    let near = with_fixture::<f64>(5.0, &[(0, 0.03), (7, 0.03)], 0.0);
    let moved = c.limit(0.25, 0.0, 0.01, 0.0, Some(&near));
    assert_eq!(moved.state, SafeState::ProtectiveStop);
    // In fixed point (the whole speed by the nearest, no extra division): within the same bound.
    let q = SafeController::new(params::<I16F16>());
    let out = q.limit(I16F16::from_f64(0.25), I16F16::ZERO, I16F16::ZERO, I16F16::ZERO, Some(&with_fixture::<I16F16>(5.0, &[(0, 0.03), (7, 0.03)], 0.1)));
    assert!(out.vx.to_f64() <= (0.03 - 0.02) / 0.06 + 1e-4 && out.vx.to_f64() > 0.1, "{}", out.vx.to_f64());
    let out = q.limit(I16F16::from_f64(0.25), I16F16::ZERO, I16F16::ZERO, I16F16::ZERO, Some(&with_fixture::<I16F16>(5.0, &[(0, 0.1), (7, 0.1)], 0.1)));
    assert_eq!(out.state, SafeState::Run);
}

/// PFL permits contact with a person, never with a fixture: the fixture's bound caps the PFL
/// speeds too.
#[test]
fn pfl_does_not_carry_the_tool_into_a_fixture() {
    let c = with_pfl();
    let near = with_fixture::<f64>(5.0, &[(0, 0.025), (7, 0.025)], 0.0);
    let out = c.limit(0.25, 0.0, 0.0, 0.0, Some(&near));
    let l = (0.025 - 0.02) / 0.06;
    assert!(out.vx <= l + 1e-12, "{} over the fixture's {l}", out.vx);
    assert_eq!(out.state, SafeState::Slow);
    // A person as near: PFL carries it at the module's speed.
    let person = c.limit(0.25, 0.0, 0.0, 0.0, Some(&sensed::<f64>(0.025, 0.0)));
    assert_eq!(person.state, SafeState::Pfl);
}

/// The fixture bound holds for every fixture point a frame could show, wherever the tool moved
/// since capture: `v . n (T_r + T_s / 2) + margin <= s` for the point's direction `n` and
/// separation `s` now, over 200,000 random frames (a fixture does not move: no `K age`), with a
/// person far; and where a person is in the frame too, that one's bound still holds.
#[test]
fn the_fixture_bound_holds_for_every_point_a_frame_could_hold() {
    let c = SafeController::new(params::<f64>());
    let w = 0.045;
    let mut seed: u64 = 0x2545_F491_4F6C_DD1D;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let per = 0.01 + 0.1 / 2.0;
    for _ in 0..200_000 {
        let a = rnd() * core::f64::consts::TAU;
        let d = w + rnd() * 0.3;
        let q = [d * a.cos(), d * a.sin()];
        let mut fix = [10.0; SECTORS];
        fix[sector_of(q[0], q[1])] = d - w;
        let sensed = Sensed { separation_m: 10.0, tool_x_m: 0.0, tool_y_m: 0.0, age_s: rnd() * 0.25, nearest_x_m: q[0], nearest_y_m: q[1], sectors_m: [10.0; SECTORS], fixture_sectors_m: fix };
        let (tb, tm) = (rnd() * core::f64::consts::TAU, rnd() * 0.01);
        let p = [tm * tb.cos(), tm * tb.sin()];
        let (vb, vm) = (rnd() * core::f64::consts::TAU, rnd() * 0.4);
        for c in [c, with_pfl()] {
            let out = c.limit(vm * vb.cos(), vm * vb.sin(), p[0], p[1], Some(&sensed));
            let (rx, ry) = (q[0] - p[0], q[1] - p[1]);
            let dist = rx.hypot(ry);
            let u = ((out.vx * rx + out.vy * ry) / dist).max(0.0);
            let sp = 0.02 + u * per;
            assert!(u == 0.0 || sp <= dist - w + 1e-9, "fixture {q:?}, tool {p:?}: u {u} needs {sp} > {}", dist - w);
        }
    }
}
