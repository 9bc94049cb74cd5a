//! Shared helpers for the integration suite.
use std::path::PathBuf;

/// Absolute path of a file in the workspace's `scenes/` folder.
pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("scenes").join(name)
}

/// Shared set-up of the avoidance tests (`tests/avoid_*.rs`).
pub mod avoid {
    use std::path::PathBuf;

    use flinch_harness::avoid::path::{simulate, Engine, PathResult, Setup};
    use flinch_harness::avoid::scene::Avoid;
    use flinch_harness::avoid::AvoidArgs;

    /// Every shipped avoidance scene (`scenes/avoid_*.toml`), by file name, sorted.
    pub fn scene_names() -> Vec<String> {
        let scenes = super::scene_path("");
        let mut names: Vec<String> = std::fs::read_dir(&scenes)
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| n.starts_with("avoid_") && n.ends_with(".toml"))
            .collect();
        names.sort();
        names
    }

    /// `flinch avoid SCENE --json` as the CLI parses it, nothing else asked for; set the fields a
    /// test needs on the result.
    pub fn args(scene: PathBuf) -> AvoidArgs {
        AvoidArgs {
            scene,
            plot: None,
            json: true,
            mcu: false,
            calibration: None,
            save_calibration: None,
            compare: false,
            csv: None,
            thesis: false,
            save_depth: None,
            depth: None,
            robot_poses: None,
        }
    }

    /// The scene's run with the `f64` reference engine on the synthetic camera.
    pub fn run_reference(mut scene: Avoid) -> (Avoid, PathResult) {
        // `[avoid.pfl]`: the module's speeds computed as `flinch avoid` does before a run.
        flinch_harness::pfl::resolve_pfl(&mut scene).unwrap();
        let setup = Setup::new(&scene, None).unwrap();
        let res = simulate(&scene, &setup, Engine::Reference).unwrap();
        (scene, res)
    }
}
