//! The shipped scenes, embedded in the binary (`build.rs` collects `scenes/**/*.toml`), and the one
//! way a command reads a scene argument: a file, `-` for standard input, or a shipped scene's name
//! (`tables5-7_bistable`, `figures/fig2_free_tool`), so the examples work from any directory.
//!
//! A path that is not a regular file (a directory, a FIFO, a device) is refused before it is
//! opened: reading a FIFO nobody writes would block forever.

use crate::scene::{self, Scene};
use flinch_output::input::{self, Kind};
use std::path::Path;

include!(concat!(env!("OUT_DIR"), "/scenes.rs"));

/// The names of the shipped scenes, sorted.
pub fn names() -> impl Iterator<Item = &'static str> {
    SCENES.iter().map(|(n, _)| *n)
}

/// A shipped scene's TOML text by name; `scenes/` and `.toml` may be given or not.
pub fn get(name: &str) -> Option<&'static str> {
    let n = name.trim().trim_start_matches("./");
    let n = n.strip_prefix("scenes/").unwrap_or(n);
    let n = n.strip_suffix(".toml").unwrap_or(n);
    SCENES.iter().find(|(k, _)| *k == n).map(|(_, t)| *t)
}

/// Shipped names close to `name` (edit distance on the name and on its last part), best first.
pub fn close_to(name: &str) -> Vec<&'static str> {
    let n = name.rsplit('/').next().unwrap_or(name);
    let n = n.strip_suffix(".toml").unwrap_or(n);
    let mut scored: Vec<(f64, &'static str)> = names()
        .map(|k| (strsim::normalized_levenshtein(n, k.rsplit('/').next().unwrap_or(k)), k))
        .filter(|(s, _)| *s >= 0.6)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    scored.into_iter().take(4).map(|(_, k)| k).collect()
}

/// The first comment block of a shipped scene, joined into one line (what `flinch scenes list`
/// shows beside the name).
pub fn description(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let Some(c) = line.strip_prefix('#') else { break };
        if !out.is_empty() {
            out.push(' ');
        }
        out.push_str(c.trim());
    }
    if out.is_empty() {
        text.lines().find_map(|l| l.trim().strip_prefix("name").and_then(|r| r.trim_start().strip_prefix('=')).map(|v| v.trim().trim_matches('"').to_string())).unwrap_or_default()
    } else {
        out
    }
}

/// A scene argument that cannot be read.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError(pub String);

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Reads a scene argument: `-` (standard input), a regular file (through the one reader,
/// `flinch_output::input`: a FIFO, a device or a directory refused by name before it is opened,
/// at most 1 MiB), or a shipped scene's name when no such file exists. Returns the name to show in
/// messages and the text.
pub fn read(arg: &Path) -> Result<(String, String), InputError> {
    let shown = arg.display().to_string();
    if shown == "-" {
        return input::read_stdin(Kind::Scene).map(|t| ("<stdin>".to_string(), t)).map_err(|e| InputError(e.to_string()));
    }
    match std::fs::symlink_metadata(arg) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => match get(&shown) {
            Some(text) => Ok((format!("{} (shipped)", shown.trim_end_matches(".toml")), text.to_string())),
            None => {
                let near = close_to(&shown);
                let hint = if near.is_empty() { "`flinch scenes list` lists the shipped scenes".to_string() } else { format!("shipped scenes with a close name: {}", near.join(", ")) };
                Err(InputError(format!("{shown}: no such file, and no shipped scene of that name; {hint}")))
            }
        },
        _ => input::read_text(arg, Kind::Scene).map(|t| (shown, t)).map_err(|e| InputError(e.to_string())),
    }
}

/// Reads and validates a scene argument (see [`read`]); the error is the validator's full message.
pub fn load(arg: &Path) -> Result<Scene, String> {
    let (file, text) = read(arg).map_err(|e| e.0)?;
    scene::parse(&text, &file).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_scene_is_embedded_and_found_by_any_spelling() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes");
        let on_disk = std::fs::read_dir(&dir).unwrap().flatten().filter(|e| e.path().extension().is_some_and(|x| x == "toml")).count();
        assert!(on_disk > 10);
        assert!(names().filter(|n| !n.contains('/')).count() == on_disk, "build.rs must embed every scenes/*.toml");
        for spelling in ["tables5-7_bistable", "tables5-7_bistable.toml", "scenes/tables5-7_bistable.toml", "./scenes/tables5-7_bistable.toml"] {
            assert!(get(spelling).is_some(), "{spelling}");
        }
        assert!(get("figures/fig2_free_tool").is_some());
        assert_eq!(close_to("tables5-7_bistabel").first(), Some(&"tables5-7_bistable"));
    }

    #[test]
    fn refuses_what_is_not_a_regular_file() {
        let e = read(Path::new("/")).unwrap_err();
        assert!(e.0.contains("is a directory"), "{e}");
        let e = read(Path::new("/dev/null")).unwrap_err();
        assert!(e.0.contains("not a regular file (a character device)"), "{e}");
        let e = read(Path::new("no_such_scene_here")).unwrap_err();
        assert!(e.0.contains("no such file, and no shipped scene"), "{e}");
    }
}
