//! Instructions per avoidance step on an emulated Cortex-M4 (QEMU `mps2-an386`).
//!
//! QEMU has no cycle model and DWT's cycle counter reads 0. With `-icount shift=6` each instruction
//! takes 64 ns of virtual time and SysTick, clocked at the AN386's 25 MHz, counts every 40 ns, so
//! `counts * 40 / 64` is an instruction count (an instruction-count proxy, not cycles: no wait states,
//! no pipeline, FPU instructions count as one). The empty measurement (two SysTick reads) is
//! subtracted.
//!
//! One step = `avoidance::sample` (field height and gradient over the truncated window) plus
//! `Controller::command` (attraction, vortex, speed scaling, watchdog factor) plus
//! `SafeController::steer` (the barrier on the sensed separation and the view's edges) and
//! `SafeController::limit` (speed and separation monitoring: separation less the tool's motion since
//! capture and the frame's age, speed limit, clamp) at one tool position. The separations are chosen
//! so that every branch is taken: run, slow (a scaled command) and protective stop (counted in the
//! output).
//! Measured at 16 positions across a hill, for each number type and Gaussian, on a 15 x 15 grid
//! (the thesis's) and a 30 x 30 one, both with the widened sigma' = 1.5 sigma of Fig. 90 (the
//! largest window: 7 x 7 centres at 15 x 15). Prints max and mean, then exits through semihosting.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::ptr::read_volatile;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use flinch_firmware::avoidance::{
    frame, FrameHeader, Receiver,
    num::{I16F16, I20F12, I8F24},
    sample, Controller, Gains, Gauss, GaussLibm, GaussLut, GaussMicromath, Grid, Real, Repulsion, Pfl, SafeController, SafeState, Sensed,
    SsmParams, Steer, Watchdog, SECTORS,
};

const SYST_CVR: u32 = 0xE000_E018;

#[inline(always)]
fn now_ticks() -> u32 {
    // SAFETY: SysTick's current-value register is always readable; reading has no side effect.
    unsafe { read_volatile(SYST_CVR as *const u32) }
}

/// SysTick counts down, 24 bits.
fn counts(t0: u32, t1: u32) -> u32 {
    t0.wrapping_sub(t1) & 0x00FF_FFFF
}

/// A hill of weights (0.2 m peak) around the middle of an `n x n` grid over 1.05 m, evaluated at
/// sigma' = `sigma_over_s` x spacing.
fn grid<R: Real>(g: &mut Grid<R>, n: usize, sigma_over_s: f64) {
    let s = 1.05 / n as f64;
    let _ = g.set_geometry(n, n, R::from_f64(s / 2.0), R::from_f64(s / 2.0), R::from_f64(s), R::from_f64(sigma_over_s * s));
    let c = n as f64 / 2.0;
    for j in 0..n {
        for i in 0..n {
            let d2 = (i as f64 - c) * (i as f64 - c) + (j as f64 - c) * (j as f64 - c);
            let w = if d2 < (n * n) as f64 / 30.0 { 0.2 - 0.01 * d2 / (n as f64 / 15.0) } else { 0.0 };
            if let Some(slot) = g.weights.get_mut(j * n + i) {
                *slot = R::from_f64(if w > 0.0 { w } else { 0.0 });
            }
        }
    }
}


fn measure<R: Real, G: Gauss<R>>(name: &str, n: usize, sigma_over_s: f64, gauss: &G, overhead: u32) -> u32 {
    let mut g = Grid::<R>::empty();
    grid(&mut g, n, sigma_over_s);
    let mut ctl = Controller::new(Gains {
        repulsion: Repulsion::Vortex { sign: 0 },
        k_att: R::from_f64(0.25),
        k_rep: R::from_f64(5.0),
        capture_radius_m: R::from_f64(0.03),
        latch_height_m: R::from_f64(0.02),
        slow_height_m: R::from_f64(0.05),
        stop_height_m: R::from_f64(0.3),
        // Ours: the vortex bounded (k_rep high enough that the bound applies) and the radial
        // barrier on f* (the hill is above slow_height_m at these positions).
        bounded: true,
    });
    let wd = Watchdog { slow_after_ms: 100, stop_after_ms: 330 };
    let mut safe = SafeController::new(SsmParams {
        human_speed_mps: R::from_f64(1.6),
        reaction_time_s: R::from_f64(0.02),
        stopping_time_s: R::from_f64(0.1),
        margin_m: R::from_f64(0.035),
        speed_cap_mps: R::from_f64(0.25),
        whole_body_only: false,
        // The PFL regime's scale is computed at every step with a command: its cost counted.
        pfl: Some(Pfl { axis: [R::ONE, R::ZERO], along_mps: R::from_f64(0.29), across_mps: R::from_f64(0.063) }),
    })
    .with_steer(Steer {
        // The barrier at 0.45 m with a 0.05 m band: every separation below 0.5 m is steered.
        barrier_m: R::from_f64(0.45),
        band_m: R::from_f64(0.05),
        view_m: [R::ZERO, R::ZERO, R::from_f64(1.05), R::from_f64(1.05)],
        edge_margin_m: R::from_f64(0.045),
    });
    let kick = R::from_f64(0.3);
    let (mut max, mut sum) = (0u32, 0u32);
    let mut states = [0u32; 3];
    let mut check = R::ZERO;
    let mut parts = [0u32; 4];
    for k in 0..16 {
        let x = R::from_f64(0.30 + 0.028 * k as f64);
        let y = R::from_f64(0.40 + 0.011 * k as f64);
        let (gx, gy) = (R::from_f64(0.95), R::from_f64(0.5));
        // 0.30 to 0.60 m at capture, 0.1 s old, the tool 10 mm on: stop, slow and run.
        let sensed = Sensed {
            separation_m: R::from_f64(0.30 + 0.02 * k as f64),
            tool_x_m: x.sub(R::from_f64(0.01)),
            tool_y_m: y,
            age_s: R::from_f64(0.1),
            // Nearest point straight ahead of the command (head-on: the costliest turn).
            nearest_x_m: x.add(R::from_f64(0.345 + 0.02 * k as f64)),
            nearest_y_m: y,
            // Every sector as near as the nearest: each one's bound is computed (the costliest).
            sectors_m: [R::from_f64(0.30 + 0.02 * k as f64); SECTORS],
            // Every fixture sector near too: each one's bound is computed (the costliest).
            fixture_sectors_m: [R::from_f64(0.05 + 0.01 * k as f64); SECTORS],
        };
        let t0 = now_ticks();
        let f = sample(black_box(&g), gauss, black_box(x), black_box(y));
        let ta = now_ticks();
        let factor = wd.factor::<R>(black_box(Some(40)));
        let c = ctl.command(x, y, gx, gy, &f, factor);
        let tb = now_ticks();
        // On top of the hill the field's command is zero: a 0.3 m/s kick keeps a command for the
        // monitor to scale at every position (its costliest branch).
        let (vx, vy) = safe.steer(c.vx.add(black_box(kick)), c.vy, x, y, black_box(Some(&sensed)));
        let tc = now_ticks();
        let out = safe.limit(vx, vy, x, y, black_box(Some(&sensed)));
        let t1 = now_ticks();
        black_box(out);
        if let Some(n) = states.get_mut(match out.state {
            SafeState::Run => 0,
            SafeState::Slow => 1,
            _ => 2,
        }) {
            *n += 1;
        }
        check = check.add(out.vx.abs()).add(out.vy.abs());
        // Three more SysTick reads inside the step: their cost is subtracted too.
        let ins = (counts(t0, t1).saturating_sub(4 * overhead)) * 40 / 64;
        for (slot, (a, b)) in parts.iter_mut().zip([(t0, ta), (ta, tb), (tb, tc), (tc, t1)]) {
            *slot = (*slot).max(counts(a, b).saturating_sub(overhead) * 40 / 64);
        }
        max = max.max(ins);
        sum += ins;
    }
    hprintln!(
        "avoid_cost grid={}x{} sigma'={}s variant={} max={} mean={} (instructions) monitor run/slow/stop={}/{}/{} parts field/command/steer/limit max={}/{}/{}/{} check={}",
        n,
        n,
        sigma_over_s,
        name,
        max,
        sum / 16,
        states[0],
        states[1],
        states[2],
        parts[0],
        parts[1],
        parts[2],
        parts[3],
        check.to_f64()
    );
    max
}

/// Frame handling: one 30 Hz stream of `n x n` frames fed to the receiver `bytes_per_step` at a
/// time, one call a 10 ms control step (what arrives on the line in one step at 30 frames a second),
/// three frames; the largest cost of one step's call, and the mean per frame byte. Then the same
/// frame handed over whole in one call (the worst single call if a whole frame is waiting).
fn measure_rx<R: Real>(name: &str, n: usize, rate_hz: usize, overhead: u32) -> u32 {
    let mut rx = Receiver::<R>::new(100, 50);
    let mut out = [0u8; frame::MAX_FRAME];
    let len = frame::frame_len(n, n).unwrap_or(0);
    // `rate_hz` frames a second, 10 ms steps: what the line brings in one step.
    let per_step = (len * rate_hz).div_ceil(100);
    let mut w = [0i32; flinch_firmware::avoidance::MAX_CENTRES];
    for (k, v) in w.iter_mut().enumerate() {
        *v = ((k as i32).wrapping_mul(2_654_435) % 40_000).wrapping_sub(20_000);
    }
    let (mut max, mut total, mut now) = (0u32, 0u32, 0u32);
    for seq in 1..=3u32 {
        let h = FrameHeader { session: 0, nx: n as u8, ny: n as u8, seq, age_ms: 5, x0_q16: 1 << 14, y0_q16: 1 << 14, spacing_q16: 1 << 15, sigma_q16: 1 << 14, ..FrameHeader::default() };
        let Some(l) = frame::encode_frame(&h, w.get(..n * n).unwrap_or(&[]), &mut out) else { return u32::MAX };
        for chunk in out.get(..l).unwrap_or(&[]).chunks(per_step.max(1)) {
            let t0 = now_ticks();
            rx.feed(black_box(chunk), now);
            let t1 = now_ticks();
            let ins = counts(t0, t1).saturating_sub(overhead) * 40 / 64;
            max = max.max(ins);
            total = total.saturating_add(ins);
            now = now.wrapping_add(10);
        }
    }
    let h = FrameHeader { session: 0, nx: n as u8, ny: n as u8, seq: 4, age_ms: 5, x0_q16: 1 << 14, y0_q16: 1 << 14, spacing_q16: 1 << 15, sigma_q16: 1 << 14, ..FrameHeader::default() };
    let l = frame::encode_frame(&h, w.get(..n * n).unwrap_or(&[]), &mut out).unwrap_or(0);
    let t0 = now_ticks();
    rx.feed(black_box(out.get(..l).unwrap_or(&[])), now);
    let t1 = now_ticks();
    let whole = counts(t0, t1).saturating_sub(overhead) * 40 / 64;
    hprintln!(
        "avoid_rx grid={}x{} rate_hz={} variant={} frame_bytes={} bytes_per_step={} max={} per_byte={} whole_frame={} (instructions) good={}",
        n,
        n,
        rate_hz,
        name,
        len,
        per_step,
        max,
        total / (3 * len as u32).max(1),
        whole,
        rx.stats.good
    );
    if rx.stats.good == 4 {
        max
    } else {
        u32::MAX
    }
}

/// The board's own step (`avoidance::Link<BoardReal>` with `link::board_config`, the settings
/// `src/bin/support/board_avoid.rs` runs):
/// one 10 ms step's bytes pushed into the receiver, then `Link::step` (receiver serviced, field,
/// command, cap, status) and `encode_velocity` (the frame sent back), measured together; three
/// frames' worth of steps at `rate_hz` frames a second, then 40 steps with the line silent. Prints
/// the largest step.
fn measure_board(n: usize, sigma_over_s: f64, rate_hz: usize, overhead: u32) -> u32 {
    use flinch_firmware::avoidance::cell::board_config;
    use flinch_firmware::avoidance::link::{encode_velocity, Link};
    let mut link = Link::new(board_config());
    let mut out = [0u8; frame::MAX_FRAME];
    let len = frame::frame_len(n, n).unwrap_or(0);
    let per_step = (len * rate_hz).div_ceil(100);
    let s = 1.05 / n as f64;
    let q = |v: f64| (v * 65536.0) as i32;
    // A low hill (0.04 m peak weights) so that the step runs its full command path, not a stop.
    let mut w = [0i32; flinch_firmware::avoidance::MAX_CENTRES];
    let c = n as f64 / 2.0;
    for j in 0..n {
        for i in 0..n {
            let d2 = (i as f64 - c) * (i as f64 - c) + (j as f64 - c) * (j as f64 - c);
            if let Some(slot) = w.get_mut(j * n + i) {
                *slot = if d2 < (n * n) as f64 / 30.0 { q(0.04) } else { 0 };
            }
        }
    }
    let (mut max, mut now, mut steps) = (0u32, 0u32, 0u32);
    let mut states = [0u32; 6];
    for seq in 1..=3u32 {
        // The monitor's paths: a person 0.30 m away in every sector (every sector's bound and the
        // PFL speeds computed).
        let start = board_config().start_m;
        let h = FrameHeader {
            session: 0,
            nx: n as u8,
            ny: n as u8,
            seq,
            age_ms: 5,
            x0_q16: q(s / 2.0),
            y0_q16: q(s / 2.0),
            spacing_q16: q(s),
            sigma_q16: q(sigma_over_s * s),
            // Echoes 0, 100 and 150 ms old: with the tool's motion and K * age the sectors' bounds
            // take each path (moving away, a division a sector, and every direction possible).
            echo_ms: now.wrapping_sub([0, 100, 150][(seq as usize - 1) % 3]),
            tool_q16: [q(f64::from(start[0])), q(f64::from(start[1]))],
            nearest_q16: [q(f64::from(start[0]) + 0.345), q(f64::from(start[1]))],
            person_mm: [300; 8],
            // And a fixture 0.10 m away in every sector: each fixture bound computed too.
            fixture_mm: [100; 8],
            ..FrameHeader::default()
        };
        let Some(l) = frame::encode_frame(&h, w.get(..n * n).unwrap_or(&[]), &mut out) else { return u32::MAX };
        let chunks = out.get(..l).unwrap_or(&[]).chunks(per_step.max(1));
        for chunk in chunks.chain(core::iter::repeat_n(&[][..], 40 * (seq == 3) as usize)) {
            let t0 = now_ticks();
            link.receiver().push(chunk, now);
            // The board's call (`board_avoid.rs`): unlatched, the whole step runs.
            let v = link.step_with(black_box(now), black_box(false));
            let f = encode_velocity(&v);
            let t1 = now_ticks();
            black_box(f);
            if let Some(k) = states.get_mut(v.status as usize) {
                *k += 1;
            }
            max = max.max(counts(t0, t1).saturating_sub(overhead) * 40 / 64);
            now = now.wrapping_add(10);
            steps += 1;
        }
    }
    hprintln!(
        "avoid_board grid={}x{} sigma'={}s rate_hz={} variant=BoardReal max={} steps={} ok/slowed/stale/no_path/latched/protective={}/{}/{}/{}/{}/{} (instructions per 10 ms step: bytes in, Link::step with the monitor (a person 0.3 m and a fixture 0.1 m away in every sector), encode_velocity; limit 5000)",
        n, n, sigma_over_s, rate_hz, max, steps, states[0], states[1], states[2], states[3], states[4], states[5]
    );
    max
}

/// Exit QEMU through semihosting (and spin if not under a debugger).
fn exit(code: debug::ExitStatus) -> ! {
    debug::exit(code);
    loop {
        cortex_m::asm::nop();
    }
}

/// The steering barrier's obstacle part (the same arithmetic as `SafeController::steer`, side
/// fixed) written with nalgebra's `Vector2<f32>`, and again with plain `f32`s, to compare the cost.
#[inline(never)]
fn steer_nalgebra(v: nalgebra::Vector2<f32>, p: nalgebra::Vector2<f32>, at: nalgebra::Vector2<f32>, near: nalgebra::Vector2<f32>, sep: f32) -> nalgebra::Vector2<f32> {
    let moved = (p - at).norm();
    let free = sep - moved - 0.45;
    if free >= 0.05 {
        return v;
    }
    let n = near - p;
    let n2 = n.norm_squared();
    let a = free * 5.0;
    let vn = v.dot(&n);
    let over = vn - a * n.norm();
    if over > 0.0 && n2 > 0.0 {
        let e = over / n2;
        let t = if vn > 0.0 { e } else { 0.0 };
        v - n * e + nalgebra::Vector2::new(-n.y, n.x) * t
    } else {
        v
    }
}

#[inline(never)]
fn steer_plain(v: [f32; 2], p: [f32; 2], at: [f32; 2], near: [f32; 2], sep: f32) -> [f32; 2] {
    let (dx, dy) = (p[0] - at[0], p[1] - at[1]);
    let moved = libm::sqrtf(dx * dx + dy * dy);
    let free = sep - moved - 0.45;
    if free >= 0.05 {
        return v;
    }
    let (nx, ny) = (near[0] - p[0], near[1] - p[1]);
    let n2 = nx * nx + ny * ny;
    let a = free * 5.0;
    let vn = v[0] * nx + v[1] * ny;
    let over = vn - a * libm::sqrtf(n2);
    if over > 0.0 && n2 > 0.0 {
        let e = over / n2;
        let t = if vn > 0.0 { e } else { 0.0 };
        [v[0] - e * nx - t * ny, v[1] - e * ny + t * nx]
    } else {
        v
    }
}

fn measure_vec(overhead: u32) {
    let (mut na_max, mut pl_max, mut diff) = (0u32, 0u32, 0.0f32);
    for k in 0..16 {
        let x = 0.30 + 0.028 * k as f32;
        let sep = 0.30 + 0.02 * k as f32;
        let t0 = now_ticks();
        let a = steer_nalgebra(black_box(nalgebra::Vector2::new(0.3, 0.05)), black_box(nalgebra::Vector2::new(x, 0.5)), nalgebra::Vector2::new(x - 0.01, 0.5), nalgebra::Vector2::new(x + sep + 0.045, 0.52), black_box(sep));
        let t1 = now_ticks();
        let b = steer_plain(black_box([0.3, 0.05]), black_box([x, 0.5]), [x - 0.01, 0.5], [x + sep + 0.045, 0.52], black_box(sep));
        let t2 = now_ticks();
        black_box((a, b));
        diff = diff.max((a.x - b[0]).abs()).max((a.y - b[1]).abs());
        na_max = na_max.max(counts(t0, t1).saturating_sub(overhead) * 40 / 64);
        pl_max = pl_max.max(counts(t1, t2).saturating_sub(overhead) * 40 / 64);
    }
    hprintln!("avoid_vec steer f32: nalgebra Vector2 max={} plain f32 max={} (instructions) largest difference {}", na_max, pl_max, diff);
}

#[entry]
fn main() -> ! {
    let mut cp = match cortex_m::Peripherals::take() {
        Some(p) => p,
        None => exit(debug::EXIT_FAILURE),
    };
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00FF_FFFF);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();

    // The cost of the measurement itself: two back-to-back SysTick reads.
    let mut overhead = u32::MAX;
    for _ in 0..8 {
        let t0 = now_ticks();
        let t1 = now_ticks();
        overhead = overhead.min(counts(t0, t1));
    }
    hprintln!("avoid_cost: empty measurement {} counts subtracted; SysTick 25 MHz, -icount shift=6", overhead);

    for n in [15usize, 30] {
        measure::<I16F16, _>("I16F16-lut", n, 0.75, &GaussLut::<I16F16>::new(), overhead);
        measure::<I20F12, _>("I20F12-lut", n, 0.75, &GaussLut::<I20F12>::new(), overhead);
        measure::<I8F24, _>("I8F24-lut", n, 0.75, &GaussLut::<I8F24>::new(), overhead);
        measure::<f32, _>("f32-lut", n, 0.75, &GaussLut::<f32>::new(), overhead);
        measure::<f32, _>("f32-micromath", n, 0.75, &GaussMicromath, overhead);
        measure::<f32, _>("f32-libm", n, 0.75, &GaussLibm, overhead);
    }
    // The step plus its share of frame handling, per 10 ms step. The grids and rates: the shipped
    // demo (5 x 5, sigma' = 2 sigma = the spacing, the widest window the firmware takes: 9 x 9
    // centres; 30 frames a second), the thesis's 15 x 15 (sigma' = 1.5 sigma) at 30 and 10 frames a
    // second, and 30 x 30 at 30.
    for (n, sig, rate) in [(5usize, 1.0, 30usize), (15, 0.75, 30), (15, 0.75, 10), (30, 0.75, 30)] {
        let steps = [
            ("I16F16-lut", measure::<I16F16, _>("I16F16-lut", n, sig, &GaussLut::<I16F16>::new(), overhead), measure_rx::<I16F16>("I16F16", n, rate, overhead)),
            ("f32-lut", measure::<f32, _>("f32-lut", n, sig, &GaussLut::<f32>::new(), overhead), measure_rx::<f32>("f32", n, rate, overhead)),
        ];
        for (name, step, rx) in steps {
            hprintln!(
                "avoid_budget grid={}x{} sigma'={}s rate_hz={} variant={} step_max={} rx_max={} total={} (instructions per 10 ms step; limit 5000)",
                n, n, sig, rate, name, step, rx, step.saturating_add(rx)
            );
        }
    }
    measure_vec(overhead);
    for (n, sig, rate) in [(5usize, 1.0, 30usize), (15, 0.75, 10)] {
        measure_board(n, sig, rate, overhead);
    }
    exit(debug::EXIT_SUCCESS)
}

#[exception]
unsafe fn HardFault(_ef: &ExceptionFrame) -> ! {
    hprintln!("FAIL hard fault");
    exit(debug::EXIT_FAILURE)
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    hprintln!("FAIL panic");
    exit(debug::EXIT_FAILURE)
}

// ---- Vector table: AN386's 32 interrupt lines, none used -------------------------------------
#[derive(Copy, Clone)]
#[repr(C)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}
extern "C" {
    fn DefaultHandler();
}
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
pub static __INTERRUPTS: [Vector; 32] = [Vector { handler: DefaultHandler }; 32];
