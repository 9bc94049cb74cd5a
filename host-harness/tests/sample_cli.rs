//! `flinch sample` as a user meets it: exit codes, `--csv -` with the report on standard error,
//! chunks run as separate processes and merged from their JSON files, and a clean Ctrl-C and write
//! error (the CSV ends on a whole row, the Parquet file has its footer).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

fn flinch(args: &[&str], dir: &Path) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_flinch")).args(args).current_dir(dir).output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!e.contains("panicked"), "{args:?}: {e}");
    o
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flinch-sample-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const KEYS: [&str; 4] = ["--vary", "motion.dead_time=uniform:0.016:0.032", "--vary", "motion.speed=normal:0.27:0.01"];

#[test]
fn chunks_run_as_processes_merge_into_the_whole_run() {
    let d = tmp("merge");
    let run = |extra: &[&str], out: &str| {
        let mut a = vec!["sample", "tables5-7_bistable_v025", "--samples", "90", "--seed", "9", "--json"];
        a.extend_from_slice(&KEYS);
        a.extend_from_slice(extra);
        let o = flinch(&a, &d);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::write(d.join(out), &o.stdout).unwrap();
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let whole = run(&[], "whole.json");
    run(&["--chunk", "1/3"], "c1.json");
    run(&["--chunk", "2/3"], "c2.json");
    run(&["--chunk", "3/3"], "c3.json");
    let m = flinch(&["sample", "--merge", "c3.json", "c1.json", "c2.json", "--json"], &d);
    assert_eq!(m.status.code(), Some(0));
    assert_eq!(String::from_utf8_lossy(&m.stdout), whole, "merged chunks differ from the whole run");
    let v: serde_json::Value = serde_json::from_str(&whole).unwrap();
    assert_eq!(v["schema_version"], 1);
    assert_eq!(v["complete"], true);
    // A chunk twice is refused (exit 2), naming the files.
    let o = flinch(&["sample", "--merge", "c1.json", "c1.json"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("overlap"));
    // Two chunks of three: refused, naming the missing samples; merged with --partial, with a note.
    let o = flinch(&["sample", "--merge", "c1.json", "c3.json"], &d);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("cover 60 of the 90 samples: samples 30..60 are missing") && e.contains("--partial"), "{e}");
    assert!(o.stdout.is_empty());
    let o = flinch(&["sample", "--merge", "c1.json", "c3.json", "--partial"], &d);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cover 60 of the 90 samples (--partial; missing 30..60)"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("60 of 90 samples (ranges 0..30, 60..90)"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn exit_codes_and_standard_output() {
    let d = tmp("exit");
    // --csv -: rows on standard output, the report on standard error.
    let mut a = vec!["sample", "tables5-7_bistable", "--samples", "5", "--csv", "-"];
    a.extend_from_slice(&KEYS[..2]);
    let o = flinch(&a, &d);
    assert_eq!(o.status.code(), Some(0));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.lines().count(), 6, "{out}");
    assert!(out.starts_with("sample,motion.dead_time_s,stroke_exhausted,"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("probability (95 % interval"));
    // Bad input: exit 2 with the reason.
    for (args, says) in [
        (vec!["sample", "tables5-7_bistable", "--samples", "5"], "nothing to vary"),
        (vec!["sample", "tables5-7_bistable", "--samples", "5", "--vary", "motion.sped=uniform:0:1"], "close matches: motion.speed"),
        (vec!["sample", "tables5-7_bistable", "--samples", "5", "--vary", "motion.speed=gauss:1:1"], "unknown distribution"),
        (vec!["sample", "tables5-7_bistable", "--samples", "5", "--vary", "target.restitution=uniform:1.1:1.2"], "every sample would be refused"),
        (vec!["sample", "tables5-7_bistable", "--samples", "5", "--chunk", "0/2", "--vary", "motion.speed=uniform:0.04:0.06"], "--chunk"),
        (vec!["sample", "tables5-7_bistable", "--samples", "5", "--json", "--csv", "-", "--vary", "motion.speed=uniform:0.04:0.06"], "both write to standard output"),
        (vec!["sample", "no_such_scene", "--samples", "5", "--vary", "motion.speed=uniform:0.04:0.06"], "no_such_scene"),
    ] {
        let o = flinch(&args, &d);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.contains(says), "{args:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ctrl_c_stops_with_complete_rows_and_a_report_of_what_ran() {
    let d = tmp("ctrlc");
    let csv = d.join("rows.csv");
    let pq = d.join("rows.parquet");
    let mut a: Vec<String> = ["sample", "tables5-7_bistable", "--samples", "1e7", "--json", "--csv"].map(String::from).to_vec();
    a.push(csv.display().to_string());
    a.push("--parquet".into());
    a.push(pq.display().to_string());
    a.extend(KEYS[..2].iter().map(|s| s.to_string()));
    let child = Command::new(env!("CARGO_BIN_EXE_flinch")).args(&a).current_dir(&d).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{e}");
    assert!(e.contains("interrupted after"), "{e}");
    assert!(e.contains("interrupted: finishing the samples under way"), "the note on the first Ctrl-C: {e}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let drawn = v["drawn"].as_u64().unwrap();
    assert!(drawn > 0 && drawn < 10_000_000 && v["complete"] == false, "{drawn}");
    // Its report is a part of the study: --merge refuses it alone, naming the samples missing.
    std::fs::write(d.join("cut.json"), &o.stdout).unwrap();
    let m = flinch(&["sample", "--merge", "cut.json"], &d);
    assert_eq!(m.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&m.stderr).contains(&format!("samples {drawn}..10000000 are missing")), "{}", String::from_utf8_lossy(&m.stderr));
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(rows.lines().count() as u64, drawn + 1, "the CSV holds exactly the samples the report counts");
    assert!(rows.ends_with('\n'));
    // The Parquet file is complete (its footer written on Ctrl-C) and holds the same samples.
    let (n, groups) = parquet_rows(&pq);
    assert_eq!(n, (0..drawn as i64).collect::<Vec<_>>(), "the Parquet file holds exactly the samples the report counts");
    assert!(groups.iter().all(|&g| g as usize <= flinch_harness::sample::parquet_file::ROW_GROUP), "{groups:?}");
    assert!(e.contains("the report, the CSV and the Parquet file cover samples 0.."), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// The `sample` column of a Parquet file and its row groups' sizes, by the parquet crate's reader
/// (an error if the file is not a complete Parquet file).
fn parquet_rows(path: &Path) -> (Vec<i64>, Vec<i64>) {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let r = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let groups = r.metadata().row_groups().iter().map(|g| g.num_rows()).collect();
    let idx = r
        .get_row_iter(None)
        .unwrap()
        .map(|row| match row.unwrap().get_column_iter().next().unwrap().1 {
            parquet::record::Field::Long(i) => *i,
            f => panic!("sample column: {f:?}"),
        })
        .collect();
    (idx, groups)
}

#[test]
fn a_write_error_leaves_a_complete_parquet_file_and_names_the_file() {
    let d = tmp("full");
    let pq = d.join("rows.parquet");
    // The CSV's device is full (its first 64 KiB buffer fails, after some hundreds of rows): exit 3
    // naming it, and the Parquet file beside it complete with the rows before the error.
    let mut a: Vec<String> = ["sample", "tables5-7_bistable", "--samples", "3000", "--csv", "/dev/full", "--parquet"].map(String::from).to_vec();
    a.push(pq.display().to_string());
    a.extend(KEYS[..2].iter().map(|s| s.to_string()));
    let o = flinch(&a.iter().map(String::as_str).collect::<Vec<_>>(), &d);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(e.contains("/dev/full: could not write"), "{e}");
    let (idx, _) = parquet_rows(&pq);
    assert!(!idx.is_empty() && idx.len() < 3000, "{} rows", idx.len());
    assert_eq!(idx, (0..idx.len() as i64).collect::<Vec<_>>());
    // The Parquet file's device is full: exit 3 naming it, not the CSV.
    let csv = d.join("rows.csv");
    let mut a: Vec<String> = ["sample", "tables5-7_bistable", "--samples", "3000", "--parquet", "/dev/full", "--csv"].map(String::from).to_vec();
    a.push(csv.display().to_string());
    a.extend(KEYS[..2].iter().map(|s| s.to_string()));
    let o = flinch(&a.iter().map(String::as_str).collect::<Vec<_>>(), &d);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{e}");
    assert!(e.contains("/dev/full: could not write") && !e.contains("rows.csv"), "{e}");
    // Refused before anything runs: standard output, the same file twice.
    for (extra, says) in [(vec!["--parquet", "-"], "give --parquet a file name"), (vec!["--parquet", "x.out", "--csv", "x.out"], "both name x.out")] {
        let mut a = vec!["sample", "tables5-7_bistable", "--samples", "5"];
        a.extend_from_slice(&extra);
        a.extend_from_slice(&KEYS[..2]);
        let o = flinch(&a, &d);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {e}");
        assert!(e.contains(says), "{extra:?}: {e}");
    }
    assert!(!d.join("x.out").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `flinch sample --csv - | head` and `flinch sweep ... | head`: the reader goes away; exit 141,
/// quiet (docs/conventions.md). A CSV writer's error once hid the broken pipe's kind: exit 3,
/// "Broken pipe (os error 32)".
#[test]
fn a_reader_that_goes_away_ends_quietly_with_141() {
    use std::io::{BufRead, BufReader};
    let d = tmp("pipe");
    for args in [
        vec!["sample", "tables5-7_bistable", "--samples", "1e5", "--csv", "-", "--vary", "motion.dead_time=uniform:0.016:0.032"],
        vec!["sweep", "tables5-7_bistable", "--vary", "motion.speed=0.01:0.3:3000"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_flinch")).args(&args).current_dir(&d).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        assert!(line.contains("motion."), "{args:?}: {line}");
        drop(out);
        let o = child.wait_with_output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(141), "{args:?}: {e}");
        assert!(!e.contains("Broken pipe") && !e.contains("error"), "{args:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The merge guard covers the files a scene refers to (its URDF edited between chunks) and the
/// version of flinch that ran each chunk.
#[test]
fn chunks_of_a_scene_whose_urdf_changed_do_not_merge() {
    let d = tmp("urdf");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    std::fs::create_dir_all(d.join("robots")).unwrap();
    std::fs::copy(root.join("robot_two_link.toml"), d.join("scene.toml")).unwrap();
    let urdf = std::fs::read_to_string(root.join("robots/two_link.urdf")).unwrap();
    std::fs::write(d.join("robots/two_link.urdf"), &urdf).unwrap();
    let chunk = |k: &str, out: &str| {
        let o = flinch(&["sample", "scene.toml", "--samples", "6", "--json", "--chunk", k, "--vary", "motion.dead_time=uniform:0.016:0.032"], &d);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::write(d.join(out), &o.stdout).unwrap();
    };
    chunk("1/2", "c1.json");
    chunk("2/2", "c2.json");
    let o = flinch(&["sample", "--merge", "c1.json", "c2.json"], &d);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    // The URDF edited (a comment is enough: the text is hashed), then the second chunk again.
    std::fs::write(d.join("robots/two_link.urdf"), urdf.replacen("<robot", "<!-- edited -->\n<robot", 1)).unwrap();
    chunk("2/2", "c2.json");
    let o = flinch(&["sample", "--merge", "c1.json", "c2.json"], &d);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("referenced files"), "{e}");
    // Another version of flinch: refused, naming it.
    let c1 = std::fs::read_to_string(d.join("c1.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&c1).unwrap();
    assert_eq!(v["flinch_version"], env!("CARGO_PKG_VERSION"));
    std::fs::write(d.join("old.json"), c1.replace(&format!("\"flinch_version\": \"{}\"", env!("CARGO_PKG_VERSION")), "\"flinch_version\": \"0.0.1\"")).unwrap();
    let o = flinch(&["sample", "--merge", "c1.json", "old.json"], &d);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("flinch version"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A lognormal's MU is of ln X: `lognormal:0.05:0.01` on motion.speed is a median of 1.05 m/s, 21x
/// the scene's 0.05 m/s. The note says so before the run, the summary shows the median.
#[test]
fn a_lognormal_far_from_the_scene_s_value_is_noted() {
    let d = tmp("lognormal");
    let o = flinch(&["sample", "tables5-7_bistable", "--samples", "2", "--vary", "motion.speed=lognormal:0.05:0.01"], &d);
    let (out, e) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(e.contains("median exp(MU) = 1.0513e0, 21.025x the scene's value 0.05"), "{e}");
    assert!(out.contains("motion.speed ~ lognormal:0.05:0.01 (median 1.0512710963760241 m/s)"), "{out}");
    // Close to the scene's value: no note.
    let o = flinch(&["sample", "tables5-7_bistable", "--samples", "2", "--vary", "motion.speed=lognormal:-3:0.01"], &d);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("median exp(MU)"));
    let _ = std::fs::remove_dir_all(&d);
}
