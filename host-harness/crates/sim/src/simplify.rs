//! The scene as the simulator models it: [`simplified`] drops what `[solver] simplify` asks to drop
//! (docs/accuracy.md measures the cost of each).

//! A scene run: the plant integrated with its events, and what the summary reports.
//!
//! Events (located, not sampled): 0 tool-target contact onset/separation, 1 front end-stop
//! entry/exit, 2 back end-stop entry/exit, 3 the sensor's threshold, and 4-6 the instants where
//! the contact, the front stop or the back stop stops pushing (or starts again) while still
//! penetrated: its damping term cancels the spring term and the clamp at zero force (no adhesion)
//! takes over. That clamp is a kink in the right-hand side; located as an event, the step ends on
//! it instead of the error control hacking at it with a dozen rejected steps (docs/accuracy.md).
//! Event 7 switches a Coulomb slide (`decoupler.friction.law = "stick-slip"`, `plant::friction`)
//! between sticking and slipping. Breakpoints: end of the
//! acceleration, start and end of braking. Contact dampings chi are fixed at each onset from the
//! approach velocity (eq 7).

use flinch_model::scene::{Decoupler, Scene, TargetKind};

/// The scene as the simulator models it: `scene` without the parts its `[solver]` lets it drop,
/// and the names of those actually dropped (a simplification that changes nothing, such as
/// "rigid-robot" on a scene without `[robot]`, is not listed).
///
/// `fidelity = "fast"` drops nothing on its own: the study (docs/accuracy.md, `flinch bench`) found
/// no simplification safe within the 1 % target on the shipped scenes. A rigid robot moved the peak
/// contact force by 8.7 % even for a light free object (scenes/extremes/tables5-7_bistable_object:
/// the tool bounces on the front stop through the robot's 26 Hz mode) and up to 1990 % for a rigid
/// tool, and was not even faster (the compliant robot softens what the tool sees); dropping friction
/// moved the peak robot force by up to 170 % (friction decides whether a bi-stable module switches,
/// Ch. 3.3) while saving up to 3.3x. So both stay explicit `solver.simplify` options, reported in the
/// summary, for a user who accepts their measured cost.
pub fn simplified(scene: &Scene) -> (Scene, Vec<String>) {
    let mut s = scene.clone();
    let mut done = Vec::new();
    let want = scene.solver.simplify;
    if want.rigid_robot && s.robot.is_some() {
        s.robot = None;
        done.push("rigid-robot".to_string());
    }
    if want.no_friction {
        let mut any = false;
        match &mut s.decoupler {
            Decoupler::Bistable(b) if b.friction.is_some() => {
                b.friction = None;
                any = true;
            }
            Decoupler::Hydraulic(h) if h.dry_friction > 0.0 || h.viscous_friction > 0.0 => {
                h.dry_friction = 0.0;
                h.viscous_friction = 0.0;
                any = true;
            }
            _ => {}
        }
        if let TargetKind::Object { floor_friction, .. } = &mut s.target.kind {
            any |= floor_friction.take().is_some();
        }
        if any {
            done.push("no-friction".to_string());
        }
    }
    (s, done)
}
