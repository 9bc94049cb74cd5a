//! `flinch sample --parquet`: the Parquet file read back with the parquet crate's own reader holds
//! the CSV's rows value for value (nulls where the CSV has empty cells, refused samples, a body
//! region's `body_limits_pass`), in row groups of at most the writer's group size, the same with
//! or without a CSV beside it, and chunks whose files concatenate into the whole run's rows.
//! The command line's endings (Ctrl-C, a write error) are in host-harness/tests/sample_cli.rs.

use flinch_harness::sample::parquet_file::{ParquetRows, ROW_GROUP};
use flinch_harness::sample::{self, Plan, SampleReport};
use flinch_harness::sweep::{Progress, Template};
use flinch_tests::scene_path;
use parquet::basic::{Repetition, Type as Physical};
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

fn plan(scene: &str, keys: &[&str], seed: u64, n: u64, chunk: Option<(u64, u64)>) -> Plan {
    let path = scene_path(scene);
    let text = std::fs::read_to_string(&path).unwrap();
    let t = Template::from_text(&text, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
    let keys: Vec<String> = keys.iter().map(|s| s.to_string()).collect();
    Plan::new(t, &text, &keys, seed, n, chunk, false).unwrap_or_else(|e| panic!("{e}"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flinch-sample-parquet-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Runs `p` writing the CSV (if `csv`) and a Parquet file at `path` with row groups of `group`
/// rows; the CSV text, the report, and the row groups' sizes the writer reports.
fn run(p: &Plan, csv: bool, path: &Path, group: usize) -> (String, SampleReport, Vec<usize>) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let f: Box<dyn std::io::Write + Send> = Box::new(std::io::BufWriter::new(std::fs::File::create(path).unwrap()));
    let mut pq = ParquetRows::new(p, f, group).unwrap();
    let mut text = Vec::new();
    let r = p.run_to(Progress::Hidden, csv.then_some(&mut text as &mut dyn std::io::Write), Some(&mut pq), &AtomicBool::new(false), Some(&pool)).unwrap();
    let rows = pq.finish().unwrap();
    assert_eq!(rows, r.drawn);
    (String::from_utf8(text).unwrap(), r, pq.groups().to_vec())
}

/// The file's rows as the parquet crate reads them (column name, value), and its row groups' sizes.
fn read(path: &Path) -> (Vec<Vec<(String, Field)>>, Vec<i64>) {
    let r = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let groups = r.metadata().row_groups().iter().map(|g| g.num_rows()).collect();
    let rows = r.get_row_iter(None).unwrap().map(|row| row.unwrap().get_column_iter().map(|(n, f)| (n.clone(), f.clone())).collect()).collect();
    (rows, groups)
}

fn csv_rows(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header = r.headers().unwrap().iter().map(String::from).collect();
    (header, r.records().map(|x| x.unwrap().iter().map(String::from).collect()).collect())
}

/// One cell of the CSV against the Parquet value of the same row and column: integers and
/// doubles to the bit (the CSV writes Rust's shortest round-trip form), 0/1 against false/true,
/// an empty cell against null.
fn same(col: &str, cell: &str, v: &Field) -> bool {
    match v {
        Field::Null => cell.is_empty(),
        Field::Long(x) => cell.parse::<i64>().ok() == Some(*x),
        Field::Int(x) => cell.parse::<i32>().ok() == Some(*x),
        Field::Double(x) => cell.parse::<f64>().is_ok_and(|c| c.to_bits() == x.to_bits()),
        Field::Bool(b) => cell == if *b { "1" } else { "0" },
        Field::Str(s) => !s.is_empty() && s == cell,
        other => panic!("column {col}: unexpected Parquet value {other:?}"),
    }
}

/// Every row and every value of `csv` in `rows`, in order; the count of nulls seen per column.
fn assert_same(csv: &str, rows: &[Vec<(String, Field)>]) -> std::collections::BTreeMap<String, usize> {
    let (header, records) = csv_rows(csv);
    assert_eq!(records.len(), rows.len(), "rows in the CSV and in the Parquet file");
    let mut nulls = std::collections::BTreeMap::new();
    for (i, (rec, row)) in records.iter().zip(rows).enumerate() {
        let names: Vec<&str> = row.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, header.iter().map(String::as_str).collect::<Vec<_>>(), "row {i}: the columns");
        for ((name, v), cell) in row.iter().zip(rec) {
            assert!(same(name, cell, v), "row {i}, column {name}: CSV {cell:?}, Parquet {v:?}");
            *nulls.entry(name.clone()).or_insert(0) += usize::from(matches!(v, Field::Null));
        }
    }
    nulls
}

/// A body-region scene whose speed is drawn wide: some draws are refused (negative speeds, and
/// speeds too slow to reach the hand), so the file has nulls in every result column, and the
/// `body_limits_pass` column has both values.
const BODY: &str = "body_hand.toml";
const BODY_KEYS: [&str; 2] = ["motion.speed=normal:0.3:0.2", "decoupler.spring_rate=normal:400:40"];

#[test]
fn the_parquet_file_holds_the_csv_rows_value_for_value() {
    let n = 700;
    let p = plan(BODY, &BODY_KEYS, 2, n, None);
    let path = tmp("both.parquet");
    let (csv, r, groups) = run(&p, true, &path, 256);
    assert!(r.refused > 10 && r.ran > 100, "the study must have refused samples and runs: {} refused, {} ran", r.refused, r.ran);
    let (rows, file_groups) = read(&path);
    let nulls = assert_same(&csv, &rows);
    // Refused samples: null in every result column, a reason; samples that ran: a null reason.
    for c in ["stroke_exhausted", "mode", "peak_contact_force_n", "peak_robot_force_n", "safe", "body_limits_pass"] {
        assert!(nulls[c] as u64 >= r.refused, "{c}: {} nulls, {} refused", nulls[c], r.refused);
    }
    // (an inconclusive sample, one that ran but ended before the robot stopped, has its reason)
    assert_eq!(nulls["reason"] as u64, r.ran - r.inconclusive);
    assert_eq!(nulls["status"] + nulls["sample"] + nulls["motion.speed_mps"], 0);
    let pass: Vec<&Field> = rows.iter().map(|row| &row.iter().find(|(n, _)| n == "body_limits_pass").unwrap().1).collect();
    assert!(pass.contains(&&Field::Bool(true)) && pass.contains(&&Field::Bool(false)), "body_limits_pass takes both values");
    // Row groups of at most 256 rows, as many as needed: the writer holds one group at a time.
    assert_eq!(groups, vec![256, 256, 188]);
    assert_eq!(file_groups, vec![256, 256, 188]);

    // The schema: Parquet types, nullable exactly where the CSV can have an empty cell.
    let f = SerializedFileReader::new(std::fs::File::open(&path).unwrap()).unwrap();
    let schema = f.metadata().file_metadata().schema_descr();
    let types: Vec<(String, Physical, Repetition)> = schema.columns().iter().map(|c| (c.name().to_string(), c.physical_type(), c.self_type().get_basic_info().repetition())).collect();
    use Physical::*;
    use Repetition as R;
    let want = [
        ("sample", INT64, R::REQUIRED),
        ("motion.speed_mps", DOUBLE, R::REQUIRED),
        ("decoupler.spring_rate_n_per_m", DOUBLE, R::REQUIRED),
        ("stroke_exhausted", BOOLEAN, R::OPTIONAL),
        ("mode", INT32, R::OPTIONAL),
        ("peak_contact_force_n", DOUBLE, R::OPTIONAL),
        ("peak_robot_force_n", DOUBLE, R::OPTIONAL),
        ("stroke_left_min_m", DOUBLE, R::OPTIONAL),
        ("safe", BOOLEAN, R::OPTIONAL),
        ("body_limits_pass", BOOLEAN, R::OPTIONAL),
        ("status", BYTE_ARRAY, R::REQUIRED),
        ("reason", BYTE_ARRAY, R::OPTIONAL),
    ];
    assert_eq!(types, want.map(|(n, t, r)| (n.to_string(), t, r)).to_vec());
    // The study is in the file's metadata.
    let kv: Vec<(String, String)> = f.metadata().file_metadata().key_value_metadata().unwrap().iter().map(|k| (k.key.clone(), k.value.clone().unwrap_or_default())).collect();
    for (k, v) in [("flinch.seed", "2"), ("flinch.samples", "700"), ("flinch.range", "0..700"), ("flinch.scene_fnv1a64", r.scene_fnv1a64.as_str())] {
        assert!(kv.contains(&(k.to_string(), v.to_string())), "{k} = {v} missing in {kv:?}");
    }

    // Without the CSV beside it: the same file, byte for byte.
    let alone = tmp("alone.parquet");
    let (none, r2, _) = run(&p, false, &alone, 256);
    assert!(none.is_empty());
    assert_eq!(r2, r);
    assert_eq!(std::fs::read(&alone).unwrap(), std::fs::read(&path).unwrap(), "the Parquet file depends on --csv");
}

#[test]
fn a_scene_without_a_body_region_has_no_body_column_and_chunks_concatenate() {
    // Tables 5-7 with its four toleranced keys (a study with failures, all samples run), in the
    // command line's row groups; then in two chunks, whose files' rows follow each other into the
    // whole run's.
    let keys = ["motion.dead_time=uniform:0.016:0.040", "decoupler.spring_rate=normal:200:10", "decoupler.height=triangular:0.029:0.03:0.031", "motion.speed=uniform:0.2:0.3"];
    let n = 301;
    let whole = plan("tables5-7_bistable_v025.toml", &keys, 4, n, None);
    let path = tmp("whole.parquet");
    let (csv, r, groups) = run(&whole, true, &path, ROW_GROUP);
    assert!(r.estimates[0].failures > 0 && r.estimates[0].failures < r.estimates[0].runs, "{:?}", r.estimates[0]);
    assert_eq!(groups, vec![301]);
    let (rows, _) = read(&path);
    assert_same(&csv, &rows);
    assert!(rows[0].iter().all(|(n, _)| n != "body_limits_pass"));

    let mut joined = Vec::new();
    for k in 1..=2 {
        let c = tmp(&format!("chunk{k}.parquet"));
        run(&plan("tables5-7_bistable_v025.toml", &keys, 4, n, Some((k, 2))), false, &c, ROW_GROUP);
        joined.extend(read(&c).0);
    }
    assert_eq!(joined, rows, "the chunks' rows, one file after the other, are the whole run's");
}

#[test]
fn a_file_finished_early_holds_the_rows_before_it() {
    // The command line finishes the file on Ctrl-C and on a write error: the footer after the rows
    // pushed so far, a last group shorter than the others. Simulated here by pushing part of a run.
    let p = plan(BODY, &BODY_KEYS, 2, 100, None);
    let path = tmp("early.parquet");
    let f: Box<dyn std::io::Write + Send> = Box::new(std::fs::File::create(&path).unwrap());
    let mut pq = ParquetRows::new(&p, f, 16).unwrap();
    for i in 0..37 {
        pq.push(&p.run_one(i)).unwrap();
        assert!(pq.buffered() < pq.group_rows(), "the writer holds less than a group after a push");
    }
    assert_eq!(pq.finish().unwrap(), 37);
    let (rows, groups) = read(&path);
    assert_eq!(groups, vec![16, 16, 5]);
    let idx: Vec<&Field> = rows.iter().map(|r| &r[0].1).collect();
    assert_eq!(idx, (0..37).map(Field::Long).collect::<Vec<_>>().iter().collect::<Vec<_>>());
    assert!(pq.push(&p.run_one(37)).is_err(), "a finished file takes no more rows");

    // Dropped without finishing (a panic unwinding past it): still a valid file.
    let path = tmp("dropped.parquet");
    {
        let f: Box<dyn std::io::Write + Send> = Box::new(std::fs::File::create(&path).unwrap());
        let mut pq = ParquetRows::new(&p, f, 16).unwrap();
        for i in 0..20 {
            pq.push(&p.run_one(i)).unwrap();
        }
    }
    assert_eq!(read(&path).1, vec![16, 4]);
    // No rows at all (Ctrl-C before the first block ended): a valid empty file with the schema.
    let path = tmp("empty.parquet");
    let f: Box<dyn std::io::Write + Send> = Box::new(std::fs::File::create(&path).unwrap());
    let mut pq = ParquetRows::new(&p, f, 16).unwrap();
    assert_eq!(pq.finish().unwrap(), 0);
    let (rows, groups) = read(&path);
    assert!(rows.is_empty() && groups.is_empty());
}

#[test]
fn the_command_lines_row_group_is_whole_blocks() {
    assert_eq!(ROW_GROUP % sample::BLOCK, 0);
}

/// Samples that end before the robot stops (`inconclusive`, review of issue 14): the Parquet file
/// has the CSV's cells for them too, the stroke, the mode and the body limits null (unknown), the
/// status `inconclusive` with its reason.
#[test]
fn inconclusive_samples_are_the_csvs_in_the_parquet_file() {
    let p = plan("tables5-7_bistable.toml", &["motion.dead_time=uniform:0.2:0.7"], 1, 60, None);
    let path = tmp("inconclusive.parquet");
    let (csv, r, _) = run(&p, true, &path, 256);
    assert!(r.inconclusive > 10 && r.inconclusive < 60, "the study must mix inconclusive and concluded samples: {} inconclusive", r.inconclusive);
    let (rows, _) = read(&path);
    let nulls = assert_same(&csv, &rows);
    // Unknown (null) only where the run did not conclude (and had not yet exhausted the stroke).
    assert!(nulls["stroke_exhausted"] as u64 <= r.inconclusive && nulls["stroke_exhausted"] > 0, "{} nulls, {} inconclusive", nulls["stroke_exhausted"], r.inconclusive);
    let statuses: Vec<String> = rows.iter().map(|row| format!("{}", row.iter().find(|(n, _)| n == "status").unwrap().1)).collect();
    assert_eq!(statuses.iter().filter(|s| s.contains("inconclusive")).count() as u64, r.inconclusive);
}
