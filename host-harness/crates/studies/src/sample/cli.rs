//! The `flinch sample` command line.

use super::parquet_file::{ParquetRows, ROW_GROUP};
use super::{parse_chunk, Plan, SampleReport, FORMS, STOP};
use flinch_output::output::{self, Failure};
use crate::sweep::{Progress, Template};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// `flinch sample SCENE --samples N --vary KEY=DIST ...`, or `flinch sample --merge A.json B.json`.
#[derive(clap::Args, Debug)]
pub struct SampleArgs {
    /// The scene: a TOML file, `-`, or a shipped scene's name.
    #[arg(required_unless_present = "merge")]
    pub scene: Option<PathBuf>,
    /// N, the number of samples of the whole study (with --chunk, this process runs its share).
    /// Accepts 10000 or 1e4.
    #[arg(long, value_name = "N", value_parser = parse_count, required_unless_present = "merge")]
    pub samples: Option<u64>,
    /// A varied key and its distribution, any number of times: KEY=normal:MEAN:SD[:LO:HI],
    /// KEY=lognormal:MU:SIGMA[:LO:HI] (MU, SIGMA of ln X; median exp(MU)), KEY=uniform:LO:HI,
    /// KEY=triangular:LO:MODE:HI. KEY is a scene key as in `flinch sweep` (motion.dead_time,
    /// decoupler.spring_rate, ...).
    #[arg(long = "vary", value_name = "KEY=DIST")]
    pub vary: Vec<String>,
    /// Seed: the same seed gives the same samples on any number of threads or machines.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run only chunk K of M (sample indices [N(K-1)/M, NK/M)); merge the chunks' --json reports
    /// with --merge.
    #[arg(long, value_name = "K/M")]
    pub chunk: Option<String>,
    /// Draw every key within its accepted range (the validator's, docs/SCENES.md): an exact
    /// truncated distribution; the report says how much probability that cuts. Without it a draw
    /// outside the range is a refused sample, counted and reported.
    #[arg(long)]
    pub truncate: bool,
    /// Write a row per sample here (`-`: standard output), in sample order, as it runs.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the same rows to this Apache Parquet file (the CSV's columns in Parquet types, null
    /// where the CSV has an empty cell), a row group at a time; with --csv too, both are written.
    /// On Ctrl-C or an error the file is still complete: it holds the rows that ran.
    #[arg(long, value_name = "FILE")]
    pub parquet: Option<PathBuf>,
    /// Print the report as JSON (merge it with --merge).
    #[arg(long)]
    pub json: bool,
    /// Merge the --json reports of chunks of one study into its estimate.
    #[arg(long, value_name = "REPORT.json", num_args = 1.., conflicts_with_all = ["scene", "samples", "vary", "chunk", "csv", "parquet", "truncate"])]
    pub merge: Vec<PathBuf>,
    /// With --merge: merge reports that do not cover the whole study (a chunk missing, or one
    /// interrupted); the estimate is then over the samples covered. Without it that is refused.
    #[arg(long, requires = "merge")]
    pub partial: bool,
    /// Threads (default: all cores). The result does not depend on it.
    #[arg(long, value_parser = crate::sweep::cli::jobs, value_name = "N")]
    pub jobs: Option<usize>,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = flinch_model::overrides::Set::parse)]
    pub set: Vec<flinch_model::overrides::Set>,
}

/// A count given as 10000 or 1e4.
pub fn parse_count(s: &str) -> Result<u64, String> {
    if let Ok(n) = s.trim().parse::<u64>() {
        return Ok(n);
    }
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 && x.fract() == 0.0 && x < 1.8e19 => Ok(x as u64),
        _ => Err(format!("{s:?} is not a whole number of samples (10000 or 1e4)")),
    }
}

fn print(args: &SampleArgs, r: &SampleReport) -> Result<(), Failure> {
    if args.json {
        output::print(&flinch_output::to_json(r))
    } else if args.csv.as_deref().is_some_and(output::is_stdout) {
        output::note(r.human().trim_end());
        Ok(())
    } else {
        output::print(&r.human())
    }
}

/// Runs `flinch sample`: exit 0 when it ran (the estimates are the answer, not a verdict), 2 for
/// bad input or when every sample was refused, 3 when the solver failed at any sample (after
/// writing everything), 130 on Ctrl-C (the CSV and the report cover the samples that ran).
pub fn run(args: &SampleArgs) -> Result<bool, Failure> {
    if !args.merge.is_empty() {
        let mut reports = Vec::new();
        let names: Vec<String> = args.merge.iter().map(|p| p.display().to_string()).collect();
        for p in &args.merge {
            let text = flinch_output::input::read_text(p, flinch_output::input::Kind::MergeReport).map_err(|e| Failure::bad_input(format!("--merge {e}")))?;
            let r: SampleReport = serde_json::from_str(&text).map_err(|e| Failure::bad_input(format!("--merge {}: not a `flinch sample --json` report: {e}", p.display())))?;
            reports.push(r);
        }
        let m = super::merge_checked(&reports, &names).map_err(|e| Failure::bad_input(e.0))?;
        if !m.complete {
            let missing = m.missing().iter().map(|r| format!("{}..{}", r[0], r[1])).collect::<Vec<_>>().join(", ");
            if !args.partial {
                return Err(Failure::bad_input(format!(
                    "--merge: the reports cover {} of the {} samples: samples {missing} are missing (a chunk not given, or one interrupted); give every chunk's report, or --partial to merge these anyway (the estimate is then over the samples covered)",
                    m.drawn, m.samples
                )));
            }
            output::note(&format!("note: the merged reports cover {} of the {} samples (--partial; missing {missing})", m.drawn, m.samples));
        }
        print(args, &m)?;
        return if m.solver_failed > 0 { Err(Failure::runtime(format!("the solver failed at {} of {} samples", m.solver_failed, m.drawn))) } else { Ok(true) };
    }
    let (Some(scene), Some(samples)) = (&args.scene, args.samples) else {
        return Err(Failure::bad_input("give a SCENE and --samples N (or --merge REPORT.json ...)"));
    };
    if args.json && args.csv.as_deref().is_some_and(output::is_stdout) {
        return Err(Failure::bad_input("--json and --csv - both write to standard output; give --csv a file name"));
    }
    if args.vary.is_empty() {
        return Err(Failure::bad_input(format!("nothing to vary: give --vary KEY=DIST at least once; DIST is one of {FORMS}")));
    }
    if let Some(p) = &args.parquet {
        if output::is_stdout(p) {
            return Err(Failure::bad_input("--parquet -: a Parquet file is binary and written with its footer last; give --parquet a file name"));
        }
        if args.csv.as_deref() == Some(p.as_path()) {
            return Err(Failure::bad_input(format!("--csv and --parquet both name {}: give them different files", p.display())));
        }
    }
    let chunk = args.chunk.as_deref().map(parse_chunk).transpose().map_err(|e| Failure::bad_input(e.0))?;
    if args.jobs == Some(0) {
        return Err(Failure::bad_input("--jobs must be at least 1"));
    }
    let varied: Vec<&str> = args.vary.iter().map(|v| v.split_once('=').map_or(v.as_str(), |(k, _)| k).trim()).collect();
    flinch_model::overrides::refuse_overlap(&args.set, &varied, "--vary").map_err(Failure::bad_input)?;
    let loaded = flinch_model::overrides::load(scene, &args.set).map_err(Failure::bad_input)?;
    let (file, text) = (loaded.file, loaded.text);
    let template = Template::from_text(&text, &file).map_err(|e| Failure::bad_input(e.0))?;
    let plan = Plan::new(template, &text, &args.vary, args.seed, samples, chunk, args.truncate).map_err(|e| Failure::bad_input(e.0))?;
    for v in &plan.vary {
        if v.outside > 0.0 && v.outside * (plan.range.1 - plan.range.0) as f64 >= 0.5 {
            output::note(&format!(
                "note: {} ~ {} puts {:.3} % of its draws outside the accepted range {}: those samples are refused and counted (--truncate draws within it)",
                v.spec.key,
                v.spec.dist.spec(),
                v.outside * 100.0,
                v.info.as_ref().map_or(String::new(), |i| i.range.clone())
            ));
        }
    }
    for v in &plan.vary {
        // A lognormal's MU is of ln X: lognormal:0.05:0.01 is a median of 1.05, not 0.05.
        let (Some(file), median) = (plan.template.value(&v.spec.key), v.spec.dist.median()) else { continue };
        let lognormal = matches!(v.spec.dist, super::Dist::LogNormal { .. });
        if lognormal && file != 0.0 && median.is_finite() && (median / file > 10.0 || median / file < 0.1) {
            output::note(&format!(
                "note: {} ~ {} has median exp(MU) = {:.4e}, {:.3}x the scene's value {} (lognormal's MU and SIGMA are of ln X: for a median of {} give MU = ln({}) = {:.4e})",
                v.spec.key,
                v.spec.dist.spec(),
                median,
                median / file,
                super::num(file),
                super::num(file),
                super::num(file),
                file.ln()
            ));
        }
    }
    let _ = ctrlc::set_handler(|| {
        if !STOP.swap(true, Ordering::SeqCst) {
            eprintln!("\ninterrupted: finishing the samples under way, then writing the rows and the report of the samples before them");
        }
    });
    if args.parquet.is_some() && plan.range.1 > i64::MAX as u64 {
        return Err(Failure::bad_input(format!("--parquet: sample indices above {} do not fit Parquet's INT64 column `sample`", i64::MAX)));
    }
    let mut out = match &args.csv {
        Some(p) => Some(output::create(p)?),
        None => None,
    };
    let parquet_path = args.parquet.clone().unwrap_or_default();
    let mut pq = match &args.parquet {
        Some(p) => {
            let f = output::create_file(p)?.ok_or_else(|| Failure::bad_input("--parquet -: give --parquet a file name"))?;
            let w: Box<dyn std::io::Write + Send> = Box::new(std::io::BufWriter::with_capacity(1 << 16, f));
            Some(ParquetRows::new(&plan, w, ROW_GROUP).map_err(|e| output::write_error(p, &e))?)
        }
        None => None,
    };
    let t0 = Instant::now();
    let pool = match args.jobs {
        None => None,
        Some(j) => Some(rayon::ThreadPoolBuilder::new().num_threads(j).build().map_err(|e| Failure::runtime(format!("--jobs {j}: {e}")))?),
    };
    let ran = plan.run_to(Progress::Auto, out.as_mut().map(|w| w.as_mut() as &mut dyn std::io::Write), pq.as_mut(), &STOP, pool.as_ref());
    // The Parquet footer is written on every ending: the rows so far are a valid file.
    let finished = pq.as_mut().map(ParquetRows::finish).transpose();
    let csv_path = args.csv.clone().unwrap_or_default();
    // A write error on one output ends the command (exit 3 naming that output), but the other
    // output holds a complete prefix of the samples, as on Ctrl-C: it is kept (the failed one's
    // temporary file is removed when its writer is dropped), so hours of samples are not lost
    // because the other file's disk filled (docs/conventions.md "Outputs").
    let written = match ran {
        Err(e) => Err(output::write_error(if pq.as_ref().is_some_and(ParquetRows::failed) { &parquet_path } else { &csv_path }, &e)),
        Ok(report) => match finished {
            Err(e) => Err(output::write_error(&parquet_path, &e)),
            Ok(_) => match out.as_mut().map(|w| w.flush()).transpose() {
                Err(e) => Err(output::write_error(&csv_path, &e)),
                Ok(_) => Ok(report),
            },
        },
    };
    let report = match written {
        Ok(report) => report,
        Err(failure) => {
            drop(out);
            drop(pq);
            output::settle(true);
            return Err(failure);
        }
    };
    let wall = t0.elapsed().as_secs_f64();
    output::note(&format!(
        "{} samples in {:.2} s ({} threads, {:.0} samples/s){}{}",
        report.drawn,
        wall,
        args.jobs.unwrap_or_else(rayon::current_num_threads),
        report.drawn as f64 / wall.max(1e-9),
        args.csv.as_ref().filter(|p| !output::is_stdout(p)).map_or(String::new(), |p| format!("; csv {}", p.display())),
        match (&args.parquet, &pq) {
            (Some(p), Some(w)) => format!("; parquet {} ({} row groups)", p.display(), w.groups().len()),
            _ => String::new(),
        }
    ));
    print(args, &report)?;
    if STOP.load(Ordering::SeqCst) {
        let covered = match (args.csv.is_some(), args.parquet.is_some()) {
            (true, true) => "the report, the CSV and the Parquet file cover",
            (true, false) => "the report and the CSV cover",
            (false, true) => "the report and the Parquet file cover",
            (false, false) => "the report covers",
        };
        return Err(Failure::interrupted(format!("interrupted after {} samples: {covered} samples {}..{}", report.drawn, plan.range.0, plan.range.0 + report.drawn)));
    }
    if report.ran == 0 && report.refused > 0 {
        return Err(Failure::bad_input(format!("the validator refused all {} samples; the first: {}", report.refused, report.refusals.first().map_or("", |g| g.first_reason.as_str()))));
    }
    if report.solver_failed > 0 {
        return Err(Failure::runtime(format!("the solver failed at {} of {} samples (status and reason columns)", report.solver_failed, report.drawn)));
    }
    Ok(true)
}
