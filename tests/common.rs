//! Shared helpers for the integration suite.
use std::path::PathBuf;

/// Absolute path of a file in the workspace's `scenes/` folder.
pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("scenes").join(name)
}
