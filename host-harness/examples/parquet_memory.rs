//! The memory of `flinch sample --parquet`'s writer alone, at any N without running N samples:
//! synthetic rows (the Tables 5-7 study's draws, made-up results, one sample in 50 refused with a
//! reason) pushed into [`ParquetRows`] writing to nowhere, the peak resident memory printed as it
//! goes. docs/sample.md quotes it:
//!
//! ```sh
//! cargo run --release -p flinch-harness --example parquet_memory -- 1e7 32768
//! ```
//!
//! Arguments: N, rows per row group (the command line's is `sample::parquet_file::ROW_GROUP`).

use flinch_harness::sample::parquet_file::ParquetRows;
use flinch_harness::sample::{Brief, Outcome, Plan, Row};
use flinch_harness::sweep::Template;

fn peak() -> String {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status.lines().find(|l| l.starts_with("VmHWM")).map_or("VmHWM unknown".into(), |l| l.split_whitespace().collect::<Vec<_>>().join(" "))
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (Some(n), Some(g)) = (a.get(1).and_then(|s| s.parse::<f64>().ok()), a.get(2).and_then(|s| s.parse::<usize>().ok())) else {
        eprintln!("usage: parquet_memory N ROWS_PER_GROUP");
        std::process::exit(2);
    };
    let n = n as u64;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/tables5-7_bistable_v025.toml");
    let text = std::fs::read_to_string(path).expect("the shipped scene");
    let t = Template::from_text(&text, path).expect("a valid scene");
    let keys: Vec<String> = ["motion.dead_time=uniform:0.016:0.032", "decoupler.spring_rate=normal:200:10", "decoupler.height=triangular:0.029:0.03:0.031", "motion.speed=lognormal:-1.3:0.05"].map(String::from).to_vec();
    let p = Plan::new(t, &text, &keys, 1, n, None, false).expect("a valid study");
    let mut w = ParquetRows::new(&p, Box::new(std::io::sink()), g).expect("a writer");
    println!("start: {}", peak());
    for i in 0..n {
        let v = p.draw(i);
        let outcome = if i % 50 == 0 {
            Outcome::Refused { keys: vec!["motion.speed".into()], reason: format!("motion.speed = {}: the scene validator refuses it", v[3]) }
        } else {
            Outcome::Ran(Brief { stroke_exhausted: i % 7 == 0, mode: Some((i % 3) as u8 + 1), peak_contact_force_n: v[1] * 1.1, peak_robot_force_n: v[1], stroke_left_min_m: Some(v[2]), safe: i % 7 != 0, body_limits_pass: None, failed: vec![false; 4], not_concluded: None, warnings: Vec::new() })
        };
        w.push(&Row { index: i, values: v, outcome }).expect("push");
        if n >= 4 && i > 0 && i % (n / 4) == 0 {
            println!("{i} rows: {}", peak());
        }
    }
    w.finish().expect("finish");
    println!("{n} rows in {} row groups: {}", w.groups().len(), peak());
}
