//! The board's step with its monitor ([`super::Link`] on [`crate::avoidance::cell::board_config`]):
//! what the frame's sensed separations and clock echo do to the command.

use super::*;
use crate::avoidance::cell::board_config;
use crate::avoidance::frame::{encode_frame, FrameHeader, MAX_FRAME, NOTHING_MM};

extern crate std;
use std::vec::Vec;

/// A 5 x 5 frame of an empty field (weights 0) over the 1.05 m plane, the tool at `tool` at
/// capture, a person `person_mm` away in sector `k` (nothing elsewhere), echoing `echo_ms` of boot
/// `boot`.
fn frame(seq: u32, tool: [f64; 2], sector: usize, person_mm: u16, echo_ms: u32, boot: u8) -> Vec<u8> {
    let q = |v: f64| (v * 65536.0) as i32;
    let mut person = [NOTHING_MM; 8];
    person[sector] = person_mm;
    let h = FrameHeader {
        session: 1,
        nx: 5,
        ny: 5,
        seq,
        x0_q16: q(0.105),
        y0_q16: q(0.105),
        spacing_q16: q(0.21),
        sigma_q16: q(0.105),
        echo_ms,
        echo_boot: boot,
        tool_q16: [q(tool[0]), q(tool[1])],
        nearest_q16: {
            // On the sector's centre line, at the separation plus the wrist's radius (0.045 m).
            let a = (22.5 + 45.0 * sector as f64).to_radians();
            let r = if person_mm == NOTHING_MM { 10.0 } else { f64::from(person_mm) / 1000.0 + 0.045 };
            [q(tool[0] + r * a.cos()), q(tool[1] + r * a.sin())]
        },
        person_mm: person,
        ..FrameHeader::default()
    };
    let mut out = std::vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[0; 25], &mut out).unwrap();
    out.truncate(n);
    out
}

fn link() -> Link<f32> {
    Link::new(board_config())
}

/// One step at `now` after feeding `f` just before it.
fn step_after(l: &mut Link<f32>, f: &[u8], now: u32) -> Velocity<f32> {
    assert_eq!(l.receiver().push(f, now), f.len());
    l.step(now)
}

#[test]
fn nobody_near_runs_at_the_cap_towards_the_goal() {
    let mut l = link();
    let start = board_config().start_m;
    let v = step_after(&mut l, &frame(1, [start[0] as f64, start[1] as f64], 0, NOTHING_MM, 0, 0), 10);
    assert_eq!((v.status, v.monitor), (Status::Ok, Monitor::Run), "{v:?}");
    assert!((v.vx - 0.25).abs() < 1e-3 && v.vy.abs() < 1e-6, "{v:?}");
}

#[test]
fn a_person_ahead_slows_then_pfl_carries_and_across_it_stops() {
    let start = board_config().start_m;
    let at = [start[0] as f64, start[1] as f64];
    // 0.6 m ahead (sector 0, +x): the SSM bound is above the cap at a fresh frame.
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 0, 600, 5, 0), 10);
    assert_eq!(v.monitor, Monitor::Run, "{v:?}");
    // 0.3 m ahead: the SSM bound (K = 2 m/s, T_r + T_s = 0.12 s, margin 35 mm) is below the cap,
    // but along the module's axis PFL allows 0.287 m/s (at 63/64): the cap passes as PFL.
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 0, 300, 5, 0), 10);
    assert_eq!((v.status, v.monitor), (Status::Slowed, Monitor::Pfl), "{v:?}");
    assert!(v.vx > 0.2 && v.vx <= 0.25 + 1e-6, "{v:?}");
    // The same person, but the frame echoes a clock 150 ms old: the separation less K * age is
    // smaller; still PFL along x (PFL does not depend on the separation).
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 0, 300, 0, 0), 150);
    assert_eq!(v.monitor, Monitor::Pfl, "{v:?}");
    // 0.1 m behind the tool (sector 4, -x), inside the protective separation, and moving away:
    // not limited (ISO/TS 15066 5.5.4.2.3: the speed towards the person). (At 10 mm the 5 ms old
    // frame's person may since be anywhere round the tool: then it is limited, and PFL carries.)
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 4, 100, 5, 0), 10);
    assert_eq!((v.status, v.monitor), (Status::Ok, Monitor::Run), "{v:?}");
}

#[test]
fn an_echo_of_another_boot_or_from_the_future_stops() {
    let start = board_config().start_m;
    let at = [start[0] as f64, start[1] as f64];
    // Another boot's clock: the frame's age is unknown.
    let mut l = link();
    l.set_boot(3);
    let v = step_after(&mut l, &frame(1, at, 0, NOTHING_MM, 5, 2), 10);
    assert_eq!((v.status, v.vx, v.vy), (Status::StoppedStale, 0.0, 0.0), "{v:?}");
    // The right boot: runs.
    let mut l = link();
    l.set_boot(3);
    let v = step_after(&mut l, &frame(1, at, 0, NOTHING_MM, 5, 3), 10);
    assert_eq!(v.status, Status::Ok, "{v:?}");
    assert_eq!(v.boot, 3);
    // An echo ahead of this clock (a host that made it up, or a clock that went back): stale.
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 0, NOTHING_MM, 500, 0), 10);
    assert_eq!((v.status, v.vx, v.vy), (Status::StoppedStale, 0.0, 0.0), "{v:?}");
    // An echo older than the watchdog's stop: stale, whatever the arrival.
    let stop = board_config().watchdog.stop_after_ms;
    let mut l = link();
    let v = step_after(&mut l, &frame(1, at, 0, NOTHING_MM, 1000, 0), 1000 + stop);
    assert_eq!(v.status, Status::StoppedStale, "{v:?}");
}

#[test]
fn a_person_touching_across_the_axis_stops_a_move_towards_them() {
    // The goal straight +y of the start: the command goes +y, across the module's axis, where PFL
    // allows only the rigid tool's 0.063 m/s; a person 5 mm away in +y (sector 1 and 2).
    let mut cfg = board_config();
    cfg.goal_m = [cfg.start_m[0], cfg.start_m[1] + 0.4];
    let at = [cfg.start_m[0] as f64, cfg.start_m[1] as f64];
    let q = |v: f64| (v * 65536.0) as i32;
    let mut person = [NOTHING_MM; 8];
    person[1] = 5;
    person[2] = 5;
    let h = FrameHeader { session: 1, nx: 5, ny: 5, seq: 1, x0_q16: q(0.105), y0_q16: q(0.105), spacing_q16: q(0.21), sigma_q16: q(0.105), echo_ms: 5, tool_q16: [q(at[0]), q(at[1])], nearest_q16: [q(at[0]), q(at[1] + 0.05)], person_mm: person, ..FrameHeader::default() };
    let mut out = std::vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[0; 25], &mut out).unwrap();
    let mut l = Link::new(cfg);
    let v = step_after(&mut l, &out[..n], 10);
    // Towards the person (+y, across the module's axis) at most the rigid tool's PFL speed, or
    // stopped, or turned away by the steering: never faster towards them.
    assert!(v.vy <= 0.0633, "{v:?}");
    assert!(matches!(v.monitor, Monitor::Pfl | Monitor::ProtectiveStop | Monitor::Slow), "{v:?}");
    // And the velocity frame says what happened.
    let d = decode_velocity(&encode_velocity(&v)).unwrap();
    assert_eq!((d.status, d.monitor), (v.status, v.monitor));
}

#[test]
fn latched_is_before_the_monitor_and_stale_before_any_frame() {
    let mut l = link();
    let v = l.step_with(10, true);
    assert_eq!((v.status, v.monitor, v.limit_mps), (Status::StoppedLatched, Monitor::NotRun, 0.0));
    let v = l.step(20);
    assert_eq!((v.status, v.monitor), (Status::StoppedStale, Monitor::NotRun));
}

/// A fixture 5 mm ahead (and nothing else) is not driven into at the cap.
#[test]
fn a_fixture_ahead_bounds_the_command() {
    let start = board_config().start_m;
    let at = [start[0] as f64, start[1] as f64];
    let mut f = frame(1, at, 0, NOTHING_MM, 5, 0);
    // Rewrite the frame with the fixture separations set (sectors 0 and 7, 5 mm).
    let mut h = crate::avoidance::frame::decode_header(&f).unwrap();
    h.fixture_mm[0] = 5;
    h.fixture_mm[7] = 5;
    let mut out = std::vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[0; 25], &mut out).unwrap();
    f = out[..n].to_vec();
    let mut l = link();
    let v = step_after(&mut l, &f, 10);
    assert_ne!(v.monitor, Monitor::Run, "{v:?}");
    // Towards it (+x): not at all with PFL off (5 mm is inside the robot's own stop and the margin).
    let mut cfg = board_config();
    if let Some(p) = cfg.ssm.as_mut() {
        p.pfl = None;
    }
    let mut l = Link::new(cfg);
    let v = step_after(&mut l, &f, 10);
    assert!(v.vx <= 0.0 + 1e-6, "into a fixture 5 mm ahead: {v:?}");
}

/// The tool's motion since capture comes from the board's own path, not from the frame's tool
/// position: a frame whose tool at capture is 4 mm off the board's dead reckoning gives the same
/// command, and an older echo (the tool moved at the cap meanwhile) a lower one.
#[test]
fn the_motion_since_capture_is_the_boards_own_path() {
    let mut cfg = board_config();
    if let Some(p) = cfg.ssm.as_mut() {
        p.pfl = None;
    }
    cfg.steer = None;
    let start = [cfg.start_m[0] as f64, cfg.start_m[1] as f64];
    // Drive 10 steps at the cap with nobody near, then a person 0.45 m ahead, echoing the clock of
    // 100 ms ago (the tool has moved 25 mm since), the frame's tool at the start (stale) or 4 mm off.
    let run = |tool: [f64; 2], echo_back: u32| {
        let mut l = Link::new(cfg);
        let _ = step_after(&mut l, &frame(1, start, 0, NOTHING_MM, 0, 0), 0);
        for k in 1..10u32 {
            let _ = l.step(10 * k);
        }
        step_after(&mut l, &frame(2, tool, 0, 450, 100 - echo_back, 0), 100)
    };
    let a = run(start, 0);
    let b = run([start[0] + 0.004, start[1]], 0);
    assert_eq!((a.vx, a.vy, a.monitor), (b.vx, b.vy, b.monitor), "the frame's tool position must not move the bound");
    let c = run(start, 100);
    assert!(c.vx < a.vx, "an echo 100 ms older (the tool 25 mm further) must lower the bound: {a:?} {c:?}");
}

/// A host whose echo claims the frame is fresher than it arrived: the receiver's lower bound wins.
#[test]
fn the_age_is_never_below_the_arrival_bound() {
    let start = board_config().start_m;
    let at = [start[0] as f64, start[1] as f64];
    let mut h = crate::avoidance::frame::decode_header(&frame(1, at, 0, NOTHING_MM, 1000, 0)).unwrap();
    // Sent just after the watchdog's slowing age by its own account, but echoing the clock of its
    // arrival.
    let slow = board_config().watchdog.slow_after_ms;
    h.age_ms = u16::try_from(slow + 10).unwrap();
    let mut out = std::vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[0; 25], &mut out).unwrap();
    // A receiver that still takes it (its own refusal of frames too old on arrival is another check).
    let mut cfg = board_config();
    cfg.max_age_ms = 2000;
    let mut l = Link::new(cfg);
    let v = step_after(&mut l, &out[..n], 1000);
    // Older than the watchdog's slowing age: slowed, not ok at the cap.
    assert_eq!(v.status, Status::Slowed, "{v:?}");
}

/// A host that forgets its sensing (the header's defaults) stops a monitored board; it does not
/// clear it.
#[test]
fn a_frame_without_sensing_stops() {
    let q = |v: f64| (v * 65536.0) as i32;
    let h = FrameHeader { session: 1, nx: 5, ny: 5, seq: 1, x0_q16: q(0.105), y0_q16: q(0.105), spacing_q16: q(0.21), sigma_q16: q(0.105), echo_ms: 5, ..FrameHeader::default() };
    let mut out = std::vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[0; 25], &mut out).unwrap();
    let mut cfg = board_config();
    if let Some(p) = cfg.ssm.as_mut() {
        p.pfl = None;
    }
    let mut l = Link::new(cfg);
    let v = step_after(&mut l, &out[..n], 10);
    assert_eq!((v.status, v.vx, v.vy), (Status::StoppedProtective, 0.0, 0.0), "{v:?}");
}
