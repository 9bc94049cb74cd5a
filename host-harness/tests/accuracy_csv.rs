//! `docs/accuracy/runs.csv` and `summary.csv` are `flinch bench --repeats 7 --out docs/accuracy`'s
//! output (docs/accuracy.md, "Regenerate"): their columns must be the ones the generator writes
//! now (docs/conventions.md: units as suffixes), so a renamed column cannot leave the committed
//! files behind again (runs.csv kept `max_step`, `rejected`, `peak_contact_N` for days), and the
//! per-scene table of docs/accuracy.md must be the file's `default` rows.

use flinch_harness::bench::{RUNS_COLUMNS, SUMMARY_COLUMNS};
use std::path::{Path, PathBuf};

fn docs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs")
}

fn read(name: &str, columns: &[&str]) -> Vec<csv::StringRecord> {
    let path = docs().join("accuracy").join(name);
    let mut r = csv::Reader::from_path(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let head: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    assert_eq!(head, columns, "{}: the header is not the generator's (host-harness/crates/studies/src/bench.rs); regenerate with `flinch bench --repeats 7 --out docs/accuracy`", path.display());
    let rows: Vec<_> = r.records().map(|x| x.unwrap_or_else(|e| panic!("{}: {e}", path.display()))).collect();
    assert!(!rows.is_empty(), "{}: no rows", path.display());
    rows
}

fn col(columns: &[&str], name: &str) -> usize {
    columns.iter().position(|c| *c == name).unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn runs_csv_has_the_generators_columns_and_values() {
    let rows = read("runs.csv", RUNS_COLUMNS);
    let ok = col(RUNS_COLUMNS, "mode_ok");
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), RUNS_COLUMNS.len(), "runs.csv line {}", i + 2);
        assert!(matches!(&r[ok], "0" | "1" | ""), "runs.csv line {}: mode_ok {:?}, the generator writes 0/1", i + 2, &r[ok]);
    }
}

#[test]
fn summary_csv_has_the_generators_columns_and_values() {
    let rows = read("summary.csv", SUMMARY_COLUMNS);
    let within = col(SUMMARY_COLUMNS, "within_1pct");
    for (i, r) in rows.iter().enumerate() {
        assert!(matches!(&r[within], "0" | "1"), "summary.csv line {}: within_1pct {:?}, the generator writes 0/1", i + 2, &r[within]);
    }
}

/// docs/accuracy.md's "Per scene at the defaults" table: steps, rejected steps and RHS evaluations
/// (exact, machine-independent) are runs.csv's `config = default` rows, scene for scene.
#[test]
fn the_per_scene_table_is_runs_csv() {
    let rows = read("runs.csv", RUNS_COLUMNS);
    let [scene, config, steps, rejected, rhs] = ["scene", "config", "steps", "rejected_steps", "rhs_evals"].map(|c| col(RUNS_COLUMNS, c));
    let mut csv_rows: Vec<[String; 4]> = rows.iter().filter(|r| &r[config] == "default").map(|r| [&r[scene], &r[steps], &r[rejected], &r[rhs]].map(str::to_string)).collect();
    let md = std::fs::read_to_string(docs().join("accuracy.md")).unwrap();
    let table = md.split("### Per scene at the defaults").nth(1).expect("docs/accuracy.md: the per-scene section");
    let mut doc_rows: Vec<[String; 4]> = table
        .lines()
        .skip_while(|l| !l.starts_with("| scene"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let c: Vec<&str> = l.split('|').map(str::trim).collect();
            [c[1], c[2], c[3], c[4]].map(str::to_string)
        })
        .collect();
    csv_rows.sort();
    doc_rows.sort();
    assert!(doc_rows.len() >= 20, "{doc_rows:?}");
    assert_eq!(doc_rows, csv_rows, "docs/accuracy.md's per-scene table against docs/accuracy/runs.csv (config = default)");
}
