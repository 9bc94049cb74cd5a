//! The structure the compiler does not keep by itself (issue 24), checked by `cargo xtask test`
//! (stage "structure") and `cargo xtask structure`:
//!
//! * no import circle between the modules (files) of any crate: the module graph is drawn from the
//!   paths each file names (`use` trees and paths in code, `crate::`, `super::`, `self::` and child
//!   modules; re-exports followed to the module that defines the item), and every strongly connected
//!   component of more than one file is reported with the edges that close it;
//! * no crate depending on one above it: [`LAYERS`] declares the order, and every dependency
//!   (normal, dev, build) between the workspace's crates in each `Cargo.toml` must point down;
//! * no tracked `.rs` file over [`MAX_LINES`] lines (stage "file length").
//!
//! The source reading is in `scan.rs`, the graph in `graph.rs`; this file holds the declared
//! order and the three checks.

mod graph;
mod scan;

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The layers, bottom first: a crate may depend only on crates of a lower layer. Crates of one
/// layer are independent of each other. docs/architecture.md draws this list.
pub const LAYERS: &[&[&str]] = &[
    &["flinch-firmware"],
    &["flinch-hal-sim", "flinch-avoid-cost"],
    &["flinch-solver", "flinch-kinematics", "flinch-output"],
    &["flinch-model"],
    &["flinch-plant"],
    &["flinch-sim"],
    &["flinch-hil"],
    &["flinch-report"],
    &["flinch-studies"],
    &["flinch-avoid"],
    &["flinch-publish"],
    &["flinch-harness"],
    &["flinch-tests", "flinch-python", "xtask"],
];

/// The longest a source file may be, in lines (the brief: "No source file over 800 lines").
pub const MAX_LINES: usize = 800;

fn layer_of(name: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&name))
}

/// Every package of the repository: its name and manifest, found by walking the tree (the
/// workspace, and python/ which is its own workspace).
fn packages(repo: &Path) -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    let mut stack = vec![repo.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            if p.is_dir() {
                if !name.starts_with('.') && name != "target" && name != "node_modules" {
                    stack.push(p);
                }
            } else if name == "Cargo.toml" {
                let Ok(text) = fs::read_to_string(&p) else { continue };
                let Ok(doc) = text.parse::<toml::Table>() else { continue };
                if let Some(n) = doc.get("package").and_then(|p| p.get("name")).and_then(|n| n.as_str()) {
                    out.push((n.to_string(), p));
                }
            }
        }
    }
    out.sort();
    out
}

/// The crate roots of a package: library, binaries, tests, benches and examples.
fn roots(manifest: &Path) -> Vec<PathBuf> {
    let dir = manifest.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for f in ["src/lib.rs", "src/main.rs"] {
        out.push(dir.join(f));
    }
    for sub in ["src/bin", "tests", "benches", "examples"] {
        if let Ok(rd) = fs::read_dir(dir.join(sub)) {
            for e in rd.flatten() {
                let p = e.path();
                if p.extension().is_some_and(|x| x == "rs") {
                    out.push(p);
                } else if p.join("main.rs").exists() {
                    out.push(p.join("main.rs"));
                }
            }
        }
    }
    if let Ok(doc) = fs::read_to_string(manifest).unwrap_or_default().parse::<toml::Table>() {
        let mut explicit = |v: &toml::Value| {
            if let Some(p) = v.get("path").and_then(|p| p.as_str()) {
                out.push(dir.join(p));
            }
        };
        if let Some(l) = doc.get("lib") {
            explicit(l);
        }
        for kind in ["bin", "test", "bench", "example"] {
            for t in doc.get(kind).and_then(|t| t.as_array()).into_iter().flatten() {
                explicit(t);
            }
        }
    }
    out.retain(|p| p.is_file());
    out.sort();
    out.dedup();
    out
}

fn rel(repo: &Path, p: &Path) -> String {
    p.strip_prefix(repo).unwrap_or(p).display().to_string()
}

/// The crates of the firmware (issue 25): checked in a stage of their own, so that the host's
/// stage says only what the host's crates do.
pub const FIRMWARE_CRATES: [&str; 2] = ["flinch-firmware", "flinch-hal-sim"];

/// Import circles that existed when the check was introduced, outside the host harness (the
/// firmware's board support and avoidance modules, hal-sim, xtask), each a set of files sorted by
/// path. They are reported on every run, a new circle fails, and an entry whose circle is gone
/// fails until it is removed here: the list only shrinks, to empty (issue 24).
pub const KNOWN_CIRCLES: &[&[&str]] = &[];

/// No import circle in any crate of the repository whose package name passes `which`: Ok with
/// what was checked, Err naming every circle with its edges (one line per pair of files: the
/// first place the path is written, and how many more there are).
pub fn import_cycles(repo: &Path, which: impl Fn(&str) -> bool) -> Result<String, String> {
    let mut problems = Vec::new();
    let (mut crates, mut files) = (0, 0);
    let mut scanned = std::collections::BTreeSet::new();
    let mut known_seen = Vec::new();
    for (name, manifest) in packages(repo).into_iter().filter(|(n, _)| which(n)) {
        for root in roots(&manifest) {
            let cs = scan::read_crate(&root);
            crates += 1;
            files += cs.modules.values().map(|m| &m.file).collect::<std::collections::BTreeSet<_>>().len();
            scanned.extend(cs.modules.values().map(|m| rel(repo, &m.file)));
            for e in &cs.errors {
                problems.push(format!("{name} ({}): {e}", rel(repo, &root)));
            }
            for cycle in graph::cycles(&cs) {
                let mut set: Vec<String> = cycle.files.iter().map(|f| rel(repo, f)).collect();
                set.sort();
                if let Some(k) = KNOWN_CIRCLES.iter().position(|k| k.iter().copied().eq(set.iter().map(String::as_str))) {
                    known_seen.push(k);
                    continue;
                }
                let mut msg = format!("{name} ({}): import circle of {} files:", rel(repo, &root), cycle.files.len());
                for f in &cycle.files {
                    msg.push_str(&format!("\n    {}", rel(repo, f)));
                }
                msg.push_str("\n  its edges (file:line: the path as written -> the file that defines it):");
                let mut i = 0;
                while i < cycle.edges.len() {
                    let e = &cycle.edges[i];
                    let same = cycle.edges[i..].iter().take_while(|x| x.from == e.from && x.to == e.to).count();
                    let more = if same > 1 { format!(" (and {} more)", same - 1) } else { String::new() };
                    msg.push_str(&format!("\n    {}:{}: {} -> {}{more}", rel(repo, &e.from), e.line, e.written, rel(repo, &e.to)));
                    i += same;
                }
                problems.push(msg);
            }
        }
    }
    let mut known = Vec::new();
    for (k, circle) in KNOWN_CIRCLES.iter().enumerate() {
        if !circle.first().is_some_and(|f| scanned.contains(*f)) {
            continue; // a crate this call does not check
        }
        if known_seen.contains(&k) {
            known.push(circle.join(" <-> "));
        } else {
            problems.push(format!(
                "the known circle {} is gone: remove it from KNOWN_CIRCLES in xtask/src/structure/mod.rs",
                circle.join(" <-> ")
            ));
        }
    }
    if problems.is_empty() {
        let mut m = format!("no import circle in {crates} crate roots ({files} files)");
        if !known.is_empty() {
            m = format!(
                "no new import circle in {crates} crate roots ({files} files); {} KNOWN circle(s) still to remove (KNOWN_CIRCLES): {}",
                known.len(),
                known.join("; ")
            );
        }
        Ok(m)
    } else {
        Err(problems.join("\n"))
    }
}

/// Every dependency between the repository's own crates points down [`LAYERS`], and every
/// `flinch-*` crate is in it.
pub fn layer_order(repo: &Path) -> Result<String, String> {
    let pkgs = packages(repo);
    let ours: BTreeMap<&str, &PathBuf> = pkgs.iter().map(|(n, p)| (n.as_str(), p)).collect();
    let mut problems = Vec::new();
    let mut edges = 0;
    for (name, manifest) in &pkgs {
        let Some(level) = layer_of(name) else {
            problems.push(format!("{}: crate {name} is not in xtask/src/structure/mod.rs LAYERS: give it a layer (and a paragraph in docs/architecture.md)", rel(repo, manifest)));
            continue;
        };
        let doc: toml::Table = fs::read_to_string(manifest).unwrap_or_default().parse().map_err(|e| format!("{}: {e}", rel(repo, manifest)))?;
        let mut tables: Vec<(&str, &toml::Table)> = Vec::new();
        for kind in ["dependencies", "dev-dependencies", "build-dependencies"] {
            if let Some(t) = doc.get(kind).and_then(|t| t.as_table()) {
                tables.push((kind, t));
            }
        }
        if let Some(targets) = doc.get("target").and_then(|t| t.as_table()) {
            for (_, t) in targets {
                for kind in ["dependencies", "dev-dependencies", "build-dependencies"] {
                    if let Some(t) = t.get(kind).and_then(|t| t.as_table()) {
                        tables.push((kind, t));
                    }
                }
            }
        }
        for (kind, t) in tables {
            for (key, spec) in t {
                let dep = spec.get("package").and_then(|p| p.as_str()).unwrap_or(key);
                if !ours.contains_key(dep) {
                    continue;
                }
                edges += 1;
                match layer_of(dep) {
                    Some(l) if l < level => {}
                    Some(l) => problems.push(format!(
                        "{}: [{kind}] {name} (layer {level}: {}) depends on {dep} (layer {l}: {}), which is {}: a crate may depend only on a lower layer (xtask/src/structure/mod.rs LAYERS, docs/architecture.md)",
                        rel(repo, manifest),
                        LAYERS[level].join(", "),
                        LAYERS[l].join(", "),
                        if l == level { "in the same layer" } else { "above it" }
                    )),
                    None => {}
                }
            }
        }
    }
    if problems.is_empty() {
        Ok(format!("{} crates in {} layers, {edges} dependencies between them, all pointing down", pkgs.len(), LAYERS.len()))
    } else {
        Err(problems.join("\n"))
    }
}

/// Every tracked `.rs` file is at most [`MAX_LINES`] lines.
pub fn file_lengths(repo: &Path) -> Result<String, String> {
    let out = Command::new("git").args(["ls-files", "*.rs"]).current_dir(repo).output().map_err(|e| format!("could not run git ls-files: {e}"))?;
    if !out.status.success() {
        return Err(format!("git ls-files failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    let mut long = Vec::new();
    let listing = String::from_utf8_lossy(&out.stdout).to_string();
    let mut n = 0;
    for f in listing.lines() {
        let Ok(text) = fs::read_to_string(repo.join(f)) else { continue };
        n += 1;
        let lines = text.lines().count();
        if lines > MAX_LINES {
            long.push((lines, f.to_string()));
        }
    }
    long.sort_by(|a, b| b.cmp(a));
    if long.is_empty() {
        Ok(format!("{n} tracked .rs files, none over {MAX_LINES} lines"))
    } else {
        let list: Vec<String> = long.iter().map(|(l, f)| format!("{f}: {l} lines")).collect();
        Err(format!("{} of {n} tracked .rs files are over {MAX_LINES} lines (split each by concern, its first comment saying what it owns):\n    {}", long.len(), list.join("\n    ")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, files: &[(&str, &str)]) {
        for (p, text) in files {
            let f = dir.join(p);
            fs::create_dir_all(f.parent().unwrap()).unwrap();
            fs::write(f, text).unwrap();
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("xtask-structure-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_circle_through_a_re_export_is_named_with_its_edges() {
        let d = scratch("circle");
        write(&d, &[
            ("Cargo.toml", "[package]\nname = \"flinch-model\"\n"),
            ("src/lib.rs", "pub mod scene;\npub mod plant;\n"),
            ("src/scene/mod.rs", "mod model;\npub use model::*;\n"),
            ("src/scene/model.rs", "pub struct ContactDamping;\npub fn f() { crate::plant::contact::chi(); }\n"),
            ("src/plant/mod.rs", "pub mod contact;\n"),
            ("src/plant/contact.rs", "use crate::scene::ContactDamping;\npub fn chi() {}\n"),
        ]);
        let e = import_cycles(&d, |_| true).unwrap_err();
        assert!(e.contains("import circle of 2 files"), "{e}");
        assert!(e.contains("src/plant/contact.rs:1: crate::scene::ContactDamping -> src/scene/model.rs"), "{e}");
        assert!(e.contains("src/scene/model.rs:2: crate::plant::contact::chi -> src/plant/contact.rs"), "{e}");
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn a_parent_that_re_exports_a_child_which_reaches_back_is_a_circle_and_a_clean_tree_is_not() {
        let d = scratch("parent");
        write(&d, &[
            ("Cargo.toml", "[package]\nname = \"flinch-model\"\n"),
            ("src/lib.rs", "pub mod sim;\n#[cfg(test)]\nmod tests { use super::*; }\n"),
            ("src/sim/mod.rs", "mod summary;\npub use summary::Summary;\npub const N: usize = 3;\n"),
            ("src/sim/summary.rs", "pub struct Summary([f64; super::N]);\n"),
        ]);
        let e = import_cycles(&d, |_| true).unwrap_err();
        assert!(e.contains("src/sim/summary.rs:1: super::N -> src/sim/mod.rs"), "{e}");
        write(&d, &[("src/sim/mod.rs", "mod summary;\nmod size;\npub use summary::Summary;\n"), ("src/sim/size.rs", "pub const N: usize = 3;\n"), ("src/sim/summary.rs", "use super::size::N;\npub struct Summary([f64; N]);\n")]);
        assert!(import_cycles(&d, |_| true).is_ok(), "{:?}", import_cycles(&d, |_| true));
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn an_upward_or_sideways_dependency_is_refused_with_both_layers() {
        let d = scratch("layers");
        write(&d, &[
            ("plant/Cargo.toml", "[package]\nname = \"flinch-plant\"\n[dependencies]\nflinch-model = { path = \"../model\" }\n[dev-dependencies]\nflinch-sim = { path = \"../sim\" }\n"),
            ("model/Cargo.toml", "[package]\nname = \"flinch-model\"\n"),
            ("sim/Cargo.toml", "[package]\nname = \"flinch-sim\"\n[dependencies]\nflinch-plant = { path = \"../plant\" }\n"),
            ("kin/Cargo.toml", "[package]\nname = \"flinch-kinematics\"\n[dependencies]\nflinch-output = { path = \"../out\" }\n"),
            ("out/Cargo.toml", "[package]\nname = \"flinch-output\"\n"),
            ("new/Cargo.toml", "[package]\nname = \"flinch-new\"\n"),
        ]);
        let e = layer_order(&d).unwrap_err();
        assert!(e.contains("[dev-dependencies] flinch-plant (layer 4: flinch-plant) depends on flinch-sim (layer 5: flinch-sim), which is above it"), "{e}");
        assert!(e.contains("flinch-kinematics") && e.contains("in the same layer"), "{e}");
        assert!(e.contains("crate flinch-new is not in"), "{e}");
        assert!(!e.contains("flinch-sim (layer 5: flinch-sim) depends"), "{e}");
        let _ = fs::remove_dir_all(&d);
    }
}
