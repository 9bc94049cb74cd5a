//! docs/validation.md is generated (`flinch validate --out docs/`): recompute every number in it
//! from the simulator and fail if the committed document differs, so it cannot drift from the code.

use flinch_harness::validate::{markdown, plots, tables, Verdict};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn validation_doc_is_up_to_date() {
    let sections = tables(&root().join("scenes")).unwrap_or_else(|e| panic!("{e}"));
    let fresh = markdown(&sections);
    let path = root().join("docs/validation.md");
    let committed = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}; run `flinch validate --out docs/`", path.display()));
    if fresh != committed {
        let first = fresh.lines().zip(committed.lines()).enumerate().find(|(_, (a, b))| a != b);
        match first {
            Some((i, (a, b))) => panic!("docs/validation.md is out of date (run `flinch validate --out docs/` and commit); first difference at line {}:\n  now:       {a}\n  committed: {b}", i + 1),
            None => panic!("docs/validation.md is out of date: {} lines now, {} committed; run `flinch validate --out docs/`", fresh.lines().count(), committed.lines().count()),
        }
    }
    for p in plots(&sections) {
        assert!(root().join("docs").join(&p).is_file(), "docs/{p} is referenced but missing; run `flinch validate --out docs/`");
    }
}

#[test]
fn every_difference_is_explained() {
    let sections = tables(&root().join("scenes")).unwrap_or_else(|e| panic!("{e}"));
    for s in &sections {
        assert!(!s.rows.is_empty() && !s.commands.is_empty() && !s.plots.is_empty(), "{}", s.title);
        if s.rows.iter().any(|r| r.verdict == Verdict::Differs) {
            assert!(!s.notes.is_empty(), "{}: a row differs and no note says why", s.title);
        }
    }
}
