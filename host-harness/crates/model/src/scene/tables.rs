//! Every table of a scene and its keys ([`key_tables`]): the one source the validator, the docs
//! (docs/SCENES.md's range table, `doc.rs`) and the property tests read; and the top level's own keys.

use super::check::{Bound::*, Key, KeyTable, Ty};
use super::{avoid, controller, decoupler, friction, motion_law, robot, sensor, solver, stopping, target, tool};

/// `name`: echoed in every output.
pub(super) const NAME: Key = Key::of("name", Ty::Text, "a human-readable name, echoed in the summary");

/// `duration`: simulated time.
pub(super) const DURATION: Key = Key::number(
    "duration",
    "s",
    Excl(0.0),
    Incl(60.0),
    "a collision and the stop that follows last under a second (the thesis runs 0.06-0.8 s); 60 s bounds run time and output",
    "simulated time from the start of the motion (t = 0)",
);

/// The top-level keys.
pub(super) const ROOT: &[Key] = &[
    NAME,
    DURATION,
    motion_law::TABLE,
    robot::TABLE,
    tool::TABLE,
    decoupler::TABLE,
    target::TABLE,
    sensor::TABLE,
    solver::TABLE,
    controller::TABLE,
];

/// `KeyTable::when` of the avoidance scene's tables.
pub const AVOID_SCENE: &str = "avoidance scene";

/// Every table of a scene and its keys: the one source the validator, the docs and the property
/// tests read.
pub fn key_tables() -> &'static [KeyTable] {
    const TABLES: &[KeyTable] = &[
        KeyTable { path: "", when: "", keys: ROOT },
        KeyTable { path: "motion", when: "", keys: motion_law::KEYS },
        KeyTable { path: "motion.stopping", when: "", keys: stopping::KEYS },
        KeyTable { path: "robot", when: "", keys: robot::KEYS },
        KeyTable { path: "tool", when: "", keys: tool::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"rigid\"", keys: decoupler::RIGID_KEYS },
        KeyTable { path: "decoupler", when: "kind = \"linear\"", keys: decoupler::linear::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"bistable\"", keys: decoupler::bistable::KEYS },
        KeyTable { path: "decoupler", when: "kind = \"hydraulic\"", keys: decoupler::hydraulic::KEYS },
        KeyTable { path: "decoupler.front_stop", when: "", keys: decoupler::end_stop::FRONT_KEYS },
        KeyTable { path: "decoupler.back_stop", when: "", keys: decoupler::end_stop::BACK_KEYS },
        KeyTable { path: "decoupler.friction", when: "kind = \"bistable\"", keys: friction::KEYS },
        KeyTable { path: "decoupler.rotational", when: "kind = \"bistable\"", keys: decoupler::rotational::KEYS },
        KeyTable { path: "target", when: "kind = \"obstacle\"", keys: target::OBSTACLE_KEYS },
        KeyTable { path: "target", when: "kind = \"object\"", keys: target::OBJECT_KEYS },
        KeyTable { path: "target", when: "kind = \"body_region\"", keys: target::BODY_KEYS },
        KeyTable { path: "sensor", when: "kind = \"travel\"", keys: sensor::TRAVEL_KEYS },
        KeyTable { path: "sensor", when: "kind = \"force\"", keys: sensor::FORCE_KEYS },
        KeyTable { path: "solver", when: "", keys: solver::KEYS },
        KeyTable { path: "controller", when: "", keys: controller::KEYS },
        // Avoidance scenes (`flinch avoid`, docs/avoidance.md): read by `avoid::parse`.
        KeyTable { path: "avoid", when: AVOID_SCENE, keys: avoid::KEYS },
        KeyTable { path: "avoid.safety", when: AVOID_SCENE, keys: avoid::SAFETY_KEYS },
        KeyTable { path: "avoid.camera", when: AVOID_SCENE, keys: avoid::CAMERA_KEYS },
        KeyTable { path: "avoid.fit", when: AVOID_SCENE, keys: avoid::FIT_KEYS },
        KeyTable { path: "avoid.robot", when: AVOID_SCENE, keys: avoid::ROBOT_KEYS },
        KeyTable { path: "avoid.operator", when: AVOID_SCENE, keys: avoid::OPERATOR_KEYS },
        KeyTable { path: "avoid.operator.keyframes[]", when: AVOID_SCENE, keys: avoid::KEYFRAME_KEYS },
        KeyTable { path: "avoid.depth_camera", when: AVOID_SCENE, keys: avoid::DEPTH_CAMERA_KEYS },
        KeyTable { path: "avoid.pfl", when: AVOID_SCENE, keys: avoid::PFL_KEYS },
        KeyTable { path: "avoid.operator.obstacles[]", when: "avoidance scene, kind = \"disc\"", keys: avoid::DISC_KEYS },
        KeyTable { path: "avoid.operator.obstacles[]", when: "avoidance scene, kind = \"box\"", keys: avoid::BOX_KEYS },
        KeyTable { path: "avoid.operator.obstacles[].keyframes[]", when: AVOID_SCENE, keys: avoid::OBSTACLE_KEYFRAME_KEYS },
    ];
    TABLES
}
