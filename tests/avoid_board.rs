//! Issue 29 item 5: the board runs the same monitor as `flinch avoid --mcu`, from one configuration.
//!
//! * The board's shipped constant (`flinch_firmware::avoidance::cell::BOARD_CELL`) is exactly what
//!   `link_config` (the `--mcu` engine's own function) makes of the cell's scene, PFL speeds and
//!   provenance included. `FLINCH_BLESS=1` rewrites the constant in `firmware/src/avoidance/cell.rs`.
//! * The `--mcu` engine is the board's step on the board's cell: it reaches the goal with no step over
//!   the verdict's bounds. (That the board ELF's velocity frames are the host `Link`'s, byte for byte,
//!   on the same frames is the QEMU stage's replay: `cargo xtask board-serial`.)

use flinch_firmware::avoidance::cell::{PflProvenance, BOARD_CELL, BOARD_CELL_SCENE, BOARD_PFL};
use flinch_firmware::avoidance::link::LinkConfig;
use flinch_harness::avoid::path::{link_config, simulate, Engine, Setup};
use flinch_harness::avoid::scene::Avoid;
use flinch_tests::scene_path;

fn board_scene() -> Avoid {
    let name = BOARD_CELL_SCENE.trim_start_matches("scenes/");
    let mut s = Avoid::load(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    flinch_harness::pfl::resolve_pfl(&mut s).unwrap_or_else(|e| panic!("{name}: {e}"));
    s
}

fn provenance(s: &Avoid) -> (String, String, String, String, u32, String, String) {
    let p = s.pfl.as_ref().expect("the board's cell declares [avoid.pfl]");
    let r = p.resolved.as_ref().expect("resolved");
    (p.module.clone(), r.module_sha256.clone(), p.body_regions.join(", "), r.along_region.clone(), r.along_force_limit_n.round() as u32, r.across_region.clone(), r.contact.clone())
}

/// The Rust text of the constants (f64 `{:?}` is the shortest text that reads back exactly).
fn literal(c: &LinkConfig<f64>, p: &(String, String, String, String, u32, String, String)) -> String {
    let g = &c.gains;
    let rep = match g.repulsion {
        flinch_firmware::avoidance::Repulsion::Vortex { sign } => format!("Repulsion::Vortex {{ sign: {sign} }}"),
        flinch_firmware::avoidance::Repulsion::Gradient => "Repulsion::Gradient".to_string(),
    };
    let ssm = match c.ssm {
        None => "None".to_string(),
        Some(s) => format!(
            "Some(SsmParams {{\n        human_speed_mps: {:?},\n        reaction_time_s: {:?},\n        stopping_time_s: {:?},\n        margin_m: {:?},\n        speed_cap_mps: {:?},\n        whole_body_only: {},\n        pfl: {},\n    }})",
            s.human_speed_mps,
            s.reaction_time_s,
            s.stopping_time_s,
            s.margin_m,
            s.speed_cap_mps,
            s.whole_body_only,
            match s.pfl {
                None => "None".to_string(),
                Some(f) => format!("Some(Pfl {{ axis: [{:?}, {:?}], along_mps: {:?}, across_mps: {:?} }})", f.axis[0], f.axis[1], f.along_mps, f.across_mps),
            }
        ),
    };
    let steer = match c.steer {
        None => "None".to_string(),
        Some(s) => format!(
            "Some(Steer {{ barrier_m: {:?}, band_m: {:?}, view_m: [{:?}, {:?}, {:?}, {:?}], edge_margin_m: {:?} }})",
            s.barrier_m, s.band_m, s.view_m[0], s.view_m[1], s.view_m[2], s.view_m[3], s.edge_margin_m
        ),
    };
    let fb = match c.fixture_barrier_m {
        None => "None".to_string(),
        Some(b) => format!("Some({b:?})"),
    };
    format!(
        "// BLESSED-BEGIN (tests/avoid_board.rs writes what is between these lines)\n\
/// The board's cell settings, in `f64` (converted once at start-up).\n\
pub const BOARD_CELL: LinkConfig<f64> = LinkConfig {{\n    \
gains: Gains {{ repulsion: {rep}, k_att: {:?}, k_rep: {:?}, capture_radius_m: {:?}, latch_height_m: {:?}, slow_height_m: {:?}, stop_height_m: {:?}, bounded: {} }},\n    \
watchdog: Watchdog {{ slow_after_ms: {}, stop_after_ms: {} }},\n    \
start_m: [{:?}, {:?}],\n    goal_m: [{:?}, {:?}],\n    speed_cap_mps: {:?},\n    period_ms: {},\n    max_age_ms: {},\n    byte_timeout_ms: {},\n    budget_bytes: {},\n    \
ssm: {ssm},\n    steer: {steer},\n    fixture_barrier_m: {fb},\n}};\n\n\
/// The provenance of [`BOARD_CELL`]'s PFL speeds.\n\
pub const BOARD_PFL: PflProvenance = PflProvenance {{\n    module: {:?},\n    module_sha256: {:?},\n    body_regions: {:?},\n    along_region: {:?},\n    along_force_limit_n: {},\n    across_region: {:?},\n    contact: {:?},\n}};\n\
// BLESSED-END",
        g.k_att, g.k_rep, g.capture_radius_m, g.latch_height_m, g.slow_height_m, g.stop_height_m, g.bounded,
        c.watchdog.slow_after_ms, c.watchdog.stop_after_ms,
        c.start_m[0], c.start_m[1], c.goal_m[0], c.goal_m[1], c.speed_cap_mps, c.period_ms, c.max_age_ms, c.byte_timeout_ms, c.budget_bytes,
        p.0, p.1, p.2, p.3, p.4, p.5, p.6,
    )
}

#[test]
fn the_board_constant_is_what_the_host_makes_of_the_cell_scene() {
    let s = board_scene();
    let want = link_config(&s).unwrap();
    let prov = provenance(&s);
    let have_prov = {
        let PflProvenance { module, module_sha256, body_regions, along_region, along_force_limit_n, across_region, contact } = BOARD_PFL;
        (module.to_string(), module_sha256.to_string(), body_regions.to_string(), along_region.to_string(), along_force_limit_n, across_region.to_string(), contact.to_string())
    };
    if want == BOARD_CELL && prov == have_prov {
        return;
    }
    let text = literal(&want, &prov);
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/src/avoidance/cell.rs");
    if std::env::var_os("FLINCH_BLESS").is_some() {
        let old = std::fs::read_to_string(&file).unwrap();
        let (a, rest) = old.split_once("// BLESSED-BEGIN").unwrap();
        let (_, b) = rest.split_once("// BLESSED-END").unwrap();
        std::fs::write(&file, format!("{a}{text}{b}")).unwrap();
        eprintln!("wrote {}", file.display());
        return;
    }
    panic!("the board's constant differs from what link_config makes of {BOARD_CELL_SCENE} (FLINCH_BLESS=1 writes it):\n{text}\n--- the board has:\n{BOARD_CELL:?}\n{BOARD_PFL:?}");
}

/// The `--mcu` engine (the board's `Link` in its shipped configuration) on the board's cell: it
/// reaches the goal, never over the verdict's SSM bound outside PFL, never inside the operator,
/// no frame refused.
#[test]
fn the_mcu_engine_is_the_board_step() {
    let s = board_scene();
    let setup = Setup::new(&s, None).unwrap();
    let r = simulate(&s, &setup, Engine::Mcu).unwrap();
    assert_eq!(r.ssm_violations, 0, "{:?}", r.status);
    assert!(r.time_to_goal_s.is_some(), "the board's cell reaches its goal under --mcu: {:?}", r.status);
    assert!(r.min_signed_distance_m >= 0.0, "never inside the operator: {}", r.min_signed_distance_m);
    let rx = r.rx.expect("the board engine has a receiver");
    // Every frame applied but the last one still being parsed and those captured while the drive
    // brakes to rest after the end (never sent: the run has ended).
    let slack = 2 + (s.safety.stopping_time_s / s.frame_period_s).ceil() as usize;
    assert!(rx.good as usize + slack >= r.frames && rx.good as usize <= r.frames, "{} of {} frames applied", rx.good, r.frames);
    assert_eq!((rx.bad_crc, rx.stale, rx.backlog, rx.overrun), (0, 0, 0, 0));
}

