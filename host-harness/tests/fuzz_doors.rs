//! Issue 27 item 8: the doors other than the scene loader, fuzzed through the real `flinch` binary
//! for a bounded time: URDF text mutations (through `robot`), measured-CSV mutations (`run
//! --measured`), `sample --merge` report mutations, and command-line option values (every number
//! option with edge values; file options pointed at a FIFO, /dev/zero, a directory).
//!
//! Each case is a child process with a per-case address-space cap (`ulimit -v`, 2 GiB) and a wall
//! limit (20 s, then killed). A case fails on: a panic (exit 101 or "panicked at"), death by a
//! signal (an abort: stack overflow, an allocation past the cap), the wall limit (a hang), or an
//! exit code outside 0-5.
//!
//! `#[ignore]`d: `cargo xtask test` runs it as the stage "doors fuzz" (xtask/src/doors.rs) for
//! `FLINCH_FUZZ_SECS` seconds (default 60). By hand:
//! `FLINCH_FUZZ_SECS=20 cargo test -p flinch-harness --test fuzz_doors -- --ignored --nocapture`.
mod common;
use common::{repo, text, tmp_in};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const EDGES: &[&str] = &["0", "-1", "1e-300", "1e300", "-1e300", "nan", "inf", "-inf", "18446744073709551616", "9e-6", "abc", "", "1e20", "0.5"];
const GARBAGE: &[&str] = &["<", ">", "</robot>", "<robot>", "<!DOCTYPE r [<!ENTITY a \"b\">]>", "\u{0}", "\u{feff}", "\"", ",", "{", "}", "\n\n", "é", "\u{202e}"];
const WALL: Duration = Duration::from_secs(20);
const CAP_KB: u64 = 2 << 20;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

/// One mutation of `t`: a number replaced by an edge value, a line deleted or duplicated, garbage
/// inserted, the text cut short, or (XML) elements nested deeper.
fn mutate(r: &mut Rng, t: &str, xml: bool) -> String {
    let lines: Vec<&str> = t.lines().collect();
    match r.below(if xml { 6 } else { 5 }) {
        0 => {
            // A number replaced.
            let starts: Vec<usize> = t.char_indices().filter(|(i, c)| c.is_ascii_digit() && (*i == 0 || !t.as_bytes()[i - 1].is_ascii_alphanumeric() && t.as_bytes()[i - 1] != b'.')).map(|(i, _)| i).collect();
            if starts.is_empty() {
                return t.to_string();
            }
            let s = *r.pick(&starts);
            let e = s + t[s..].find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+')).unwrap_or(t.len() - s);
            format!("{}{}{}", &t[..s], r.pick(EDGES), &t[e..])
        }
        1 => {
            let k = r.below(lines.len());
            lines.iter().enumerate().filter(|(i, _)| *i != k).map(|(_, l)| *l).collect::<Vec<_>>().join("\n")
        }
        2 => {
            let k = r.below(lines.len());
            let mut v = lines.clone();
            v.insert(k, lines[k]);
            v.join("\n")
        }
        3 => {
            let mut at = r.below(t.len());
            while !t.is_char_boundary(at) {
                at -= 1;
            }
            format!("{}{}{}", &t[..at], r.pick(GARBAGE), &t[at..])
        }
        4 => {
            let mut at = r.below(t.len());
            while !t.is_char_boundary(at) {
                at -= 1;
            }
            t[..at].to_string()
        }
        _ => {
            // Nested deeper: inside the first <link ...>, n levels of <a>.
            let n = [10, 40, 20_000, 200_000][r.below(4)];
            t.replacen("<link name=\"base\"/>", &format!("<link name=\"base\">{}{}</link>", "<a>".repeat(n), "</a>".repeat(n)), 1)
        }
    }
}

struct Case {
    door: &'static str,
    args: Vec<String>,
}

/// Runs one case under the caps; `Err` says what went wrong.
fn run(c: &Case) -> Result<i32, String> {
    let bin = env!("CARGO_BIN_EXE_flinch");
    let quoted: Vec<String> = c.args.iter().map(|a| format!("'{}'", a.replace('\'', "'\\''"))).collect();
    let mut child = Command::new("sh")
        .args(["-c", &format!("ulimit -v {CAP_KB}; exec '{bin}' {}", quoted.join(" "))])
        .current_dir(repo())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if t0.elapsed() > WALL {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("still running after {} s (a hang)", WALL.as_secs()));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    let err = text(err.as_bytes());
    match status.code() {
        Some(101) => Err(format!("panicked: {err}")),
        _ if err.contains("panicked at") => Err(format!("panicked: {err}")),
        Some(c @ 0..=5) => Ok(c),
        Some(c) => Err(format!("exit {c}: {err}")),
        None => Err(format!("killed by a signal ({status:?}): {err}")),
    }
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
#[ignore]
fn doors_fuzz() {
    let secs: u64 = std::env::var("FLINCH_FUZZ_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(60);
    let seed: u64 = std::env::var("FLINCH_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x5eed_d00e);
    let d = tmp_in("doors", "fuzz");
    let urdf = std::fs::read_to_string(repo().join("scenes/robots/two_link.urdf")).unwrap();
    let scene = std::fs::read_to_string(repo().join("scenes/robot_two_link.toml")).unwrap().replace("robots/two_link.urdf", "m.urdf");
    let scene_path = write(&d, "scene.toml", &scene);
    // The bases: a measured CSV (a run's own, 200 rows) and a real chunk report.
    let csv = d.join("base.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_flinch")).current_dir(repo()).args(["run", "table1_rigid_tool", "--csv"]).arg(&csv).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let base_csv: String = std::fs::read_to_string(&csv).unwrap().lines().take(200).collect::<Vec<_>>().join("\n");
    let o = Command::new(env!("CARGO_BIN_EXE_flinch")).current_dir(repo()).args(["sample", "table1_rigid_tool", "--vary", "tool.mass=uniform:0.3:0.5", "--samples", "8", "--chunk", "1/2", "--json"]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let base_report = text(&o.stdout);
    let fifo = d.join("fifo");
    let _ = std::fs::remove_file(&fifo);
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let specials = [fifo.display().to_string(), "/dev/zero".into(), d.display().to_string()];
    let s = |x: &str| x.to_string();
    let numbers: &[(&[&str], &str)] = &[
        (&["hil", "tables5-7_bistable", "--scan-cycle"], ""),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--phase"], ""),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--tick"], ""),
        (&["hil", "tables5-7_bistable", "--scan-cycle", "0.016", "--fault"], "stuck-rest@"),
        (&["design", "tables5-7_bistable", "--speed"], ""),
        (&["design", "tables5-7_bistable", "--dead-time"], ""),
        (&["sweep", "table1_rigid_tool", "--vary"], "tool.mass=0.2:"),
        (&["sweep", "table1_rigid_tool", "--vary", "tool.mass=0.2:1:3", "--jobs"], ""),
        (&["sample", "table1_rigid_tool", "--vary", "tool.mass=uniform:0.3:0.5", "--samples"], ""),
        (&["sample", "table1_rigid_tool", "--vary", "tool.mass=uniform:0.3:0.5", "--samples", "4", "--jobs"], ""),
    ];
    let files: &[&[&str]] = &[&["run", "table1_rigid_tool", "--measured"], &["sample", "--merge"], &["avoid", "avoid_operator_hand", "--calibration"], &["run"]];
    let mut r = Rng(seed | 1);
    let t0 = Instant::now();
    let mut per_door: Vec<(&str, usize)> = vec![("urdf", 0), ("measured csv", 0), ("merge report", 0), ("cli number", 0), ("file option", 0)];
    let mut failures = Vec::new();
    let mut n = 0;
    while t0.elapsed().as_secs() < secs {
        let which = r.below(per_door.len());
        let case = match which {
            0 => {
                write(&d, "m.urdf", &mutate(&mut r, &urdf, true));
                Case { door: "urdf", args: vec![s("robot"), scene_path.display().to_string()] }
            }
            1 => {
                let p = write(&d, "m.csv", &mutate(&mut r, &base_csv, false));
                Case { door: "measured csv", args: vec![s("run"), s("table1_rigid_tool"), s("--measured"), p.display().to_string()] }
            }
            2 => {
                let p = write(&d, "m.json", &mutate(&mut r, &base_report, false));
                Case { door: "merge report", args: vec![s("sample"), s("--merge"), p.display().to_string(), s("--partial")] }
            }
            3 => {
                let (pre, prefix) = r.pick(numbers);
                let v = r.pick(EDGES);
                let mut args: Vec<String> = pre.iter().map(|x| x.to_string()).collect();
                // design with an accepted value runs a whole search (minutes): edge values only.
                if args[0] == "design" && *v == "0.5" {
                    continue;
                }
                args.push(if prefix.ends_with(':') { format!("{prefix}{v}:3") } else { format!("{prefix}{v}") });
                Case { door: "cli number", args }
            }
            _ => {
                let pre = r.pick(files);
                let mut args: Vec<String> = pre.iter().map(|x| x.to_string()).collect();
                args.push(r.pick(&specials).clone());
                Case { door: "file option", args }
            }
        };
        per_door[which].1 += 1;
        n += 1;
        if let Err(e) = run(&case) {
            let kept = d.join(format!("failure-{n}"));
            let _ = std::fs::create_dir_all(&kept);
            for f in ["m.urdf", "m.csv", "m.json"] {
                let _ = std::fs::copy(d.join(f), kept.join(f));
            }
            failures.push(format!("{} {:?}: {e} (inputs kept in {})", case.door, case.args, kept.display()));
            if failures.len() >= 5 {
                break;
            }
        }
    }
    let doors: Vec<String> = per_door.iter().map(|(k, v)| format!("{k} {v}")).collect();
    println!("fuzz doors: {n} cases in {:.0} s (seed {seed}): {}", t0.elapsed().as_secs_f64(), doors.join(", "));
    assert!(failures.is_empty(), "{} failing cases:\n{}", failures.len(), failures.join("\n"));
}
