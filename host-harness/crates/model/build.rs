//! Embeds every shipped scene (`scenes/**/*.toml`) in the binary, so `flinch scenes list`,
//! `flinch scenes show NAME` and `flinch run NAME` work from any directory. A new scene file is
//! picked up by the next build without editing a list: cargo reruns this script when a file in
//! `scenes/` (or a folder's listing) changes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) {
    println!("cargo:rerun-if-changed={}", dir.display());
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_string();
        if p.is_dir() {
            collect(&p, &format!("{prefix}{name}/"), out);
        } else if let Some(stem) = name.strip_suffix(".toml") {
            println!("cargo:rerun-if-changed={}", p.display());
            out.push((format!("{prefix}{stem}"), p));
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it")).join("../../..").join("scenes");
    let mut scenes = Vec::new();
    collect(&root, "", &mut scenes);
    let mut src = String::from("/// Every shipped scene: (name, TOML text), sorted by name.\npub const SCENES: &[(&str, &str)] = &[\n");
    for (name, path) in &scenes {
        let abs = path.canonicalize().unwrap_or_else(|_| path.clone());
        let _ = writeln!(src, "    ({name:?}, include_str!({:?})),", abs.display().to_string());
    }
    src.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it")).join("scenes.rs");
    std::fs::write(&out, src).expect("OUT_DIR is writable");
}
