//! The `flinch sweep` command line.

use super::{check_metric, metric, plot, stream, Axis, Point, Progress, RowWriter, SweepError, SweepResult, Template};
use flinch_output::output::{self, Failure};
use std::path::PathBuf;
use std::time::Instant;

/// `flinch sweep SCENE --vary KEY=START:STOP:N [--vary ...]`.
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// The scene file to sweep.
    pub scene: PathBuf,
    /// A swept key: KEY=START:STOP:N (linear) or KEY=log:START:STOP:N (geometric); once or twice.
    /// Any numeric scene key, e.g. motion.speed, motion.dead_time, tool.mass, decoupler.spring_rate,
    /// target.stiffness, decoupler.front_stop.stiffness.
    #[arg(long = "vary", value_name = "KEY=START:STOP:N", required = true)]
    pub vary: Vec<String>,
    /// Make this key's axis geometric (same as a log: prefix).
    #[arg(long = "log", value_name = "KEY")]
    pub log: Vec<String>,
    /// Write sweep.csv and sweep.svg into this folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write the CSV here (`-`: standard output; one row per point: every summary field, status, reason).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Draw the plot here (.svg or .png): lines for one axis, a heat map for two.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// The summary field a heat map shows.
    #[arg(long, default_value = "peak_robot_force")]
    pub metric: String,
    /// Colour the heat map on a logarithmic scale (a metric spanning decades: 3 N and 40 N apart).
    #[arg(long)]
    pub log_color: bool,
    /// Refuse the whole sweep if the validator refuses any point (default: such points become rows
    /// with status "refused" and the reason, drawn as grey crosses).
    #[arg(long)]
    pub strict: bool,
    /// Threads (default: all cores), 1 to 1024.
    #[arg(long, value_name = "N", value_parser = jobs)]
    pub jobs: Option<usize>,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = flinch_model::overrides::Set::parse)]
    pub set: Vec<flinch_model::overrides::Set>,
}

/// `--jobs`: 1 to 1024 threads (each holds a scene and a solver; 100,000 threads took 42 s to make
/// before a 3-point sweep ran).
pub fn jobs(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n @ 1..=1024) => Ok(n),
        _ => Err(format!("allowed range [1, 1024] threads, got {text}")),
    }
}

/// Parses the axes, honouring `--log KEY`; refuses a `--log` key that is not swept.
pub fn axes(vary: &[String], log: &[String]) -> Result<Vec<Axis>, SweepError> {
    let parsed: Vec<Axis> = vary
        .iter()
        .map(|spec| {
            let key = spec.split_once('=').map_or(spec.as_str(), |(k, _)| k).trim();
            Axis::parse(spec, log.iter().any(|l| l.trim() == key))
        })
        .collect::<Result<_, _>>()?;
    for l in log {
        if !parsed.iter().any(|a| a.key == l.trim()) {
            return Err(SweepError(format!("--log {l}: not one of the swept keys ({})", parsed.iter().map(|a| a.key.as_str()).collect::<Vec<_>>().join(", "))));
        }
    }
    Ok(parsed)
}

/// Runs `flinch sweep`: exit 0 when every point ran, 3 when the solver failed at any, 2 for a
/// sweep that cannot be built (or, with `--strict`, a refused point).
pub fn run(args: &SweepArgs) -> Result<bool, Failure> {
    let axes = axes(&args.vary, &args.log).map_err(|e| Failure::bad_input(e.to_string()))?;
    check_metric(&args.metric).map_err(|e| Failure::bad_input(e.to_string()))?;
    let (csv, svg) = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|e| Failure::runtime(format!("{}: {e}", dir.display())))?;
            (Some(args.csv.clone().unwrap_or_else(|| dir.join("sweep.csv"))), Some(args.plot.clone().unwrap_or_else(|| dir.join("sweep.svg"))))
        }
        None => (args.csv.clone(), args.plot.clone()),
    };
    if let Some(p) = &svg {
        flinch_output::figure::check_extension(p).map_err(|e| Failure::bad_input(format!("--plot {e}")))?;
    }
    let varied: Vec<&str> = axes.iter().map(|a| a.key.as_str()).collect();
    flinch_model::overrides::refuse_overlap(&args.set, &varied, "--vary").map_err(Failure::bad_input)?;
    let template = Template::load_with(&args.scene, &args.set).map_err(|e| Failure::bad_input(e.to_string()))?;
    output::note(flinch_model::headline::headline(&template.base).lines().trim_end());
    // Before any point runs: an output that would replace the scene, or land on a device, is refused.
    for (opt, p) in [("--csv", &csv), ("--plot", &svg)] {
        if let Some(p) = p {
            output::check_target(opt, p)?;
        }
    }
    let csv_out = match (&csv, &svg) {
        (Some(p), _) => Some(p.clone()),
        (None, None) => Some(PathBuf::from("-")),
        (None, Some(_)) => None,
    };
    let pool = match args.jobs {
        None => None,
        Some(j) => Some(rayon::ThreadPoolBuilder::new().num_threads(j).build().map_err(|e| Failure::runtime(format!("--jobs {j}: {e}")))?),
    };
    // Streamed (issue 27): each row is written as soon as the points before it are, in grid order;
    // nothing grows with the number of points but the plot's points (kept only with --plot).
    let mut writer = match &csv_out {
        Some(p) => Some(RowWriter::new(output::create(p)?, &axes)),
        None => None,
    };
    let _ = ctrlc::set_handler(|| {
        if !stream::STOP.swap(true, std::sync::atomic::Ordering::SeqCst) {
            eprintln!("\ninterrupted: finishing the points under way, then keeping the rows before them");
        }
    });
    let mut kept: Vec<Point> = Vec::new();
    let (mut exhausted, mut not_safe, mut modes_n) = (0usize, 0usize, [0usize; 3]);
    let t0 = Instant::now();
    let streamed = stream::stream(&template, axes.clone(), args.strict, Progress::Auto, pool.as_ref(), &mut |p: Point| {
        if let Ok(s) = &p.outcome {
            exhausted += usize::from(s.stroke_exhausted);
            not_safe += usize::from(metric(s, "safe") == Some(0.0));
            if let Some(m @ 1..=3) = s.mode {
                modes_n[usize::from(m) - 1] += 1;
            }
        }
        if svg.is_some() {
            kept.push(p.clone());
        }
        match writer.as_mut() {
            Some(w) => w.push(p),
            None => Ok(()),
        }
    })
    .map_err(|e| Failure::bad_input(e.to_string()))?;
    let csv_path = csv_out.clone().unwrap_or_default();
    let st = streamed.map_err(|e| output::write_error(&csv_path, &e))?;
    if let Some(w) = writer.as_mut() {
        w.finish().map_err(|e| output::write_error(&csv_path, &e))?;
    }
    let wall = t0.elapsed().as_secs_f64();
    if st.interrupted {
        let kept_in = csv_out.as_ref().filter(|p| !output::is_stdout(p)).map_or_else(String::new, |p| format!(": {} holds points 1..{} in grid order", p.display(), st.done));
        return Err(Failure::interrupted(format!("interrupted after {} of {} points{kept_in}; no plot drawn", st.done, st.total)));
    }
    if st.refused == st.total {
        return Err(Failure::bad_input(format!("the validator refuses all {} points; the first: {}", st.total, st.first_refusal.unwrap_or_default())));
    }
    // A tool that meets the target while the flange is still accelerating never sees V_c: say so,
    // since a speed sweep of such a scene saturates at sqrt(2 a_c gap).
    if st.early > 0 {
        output::note(&format!("note: at {} of {} points the tool meets the target before the flange reaches motion.speed (gap < V_c^2 / 2 a_c): the impact speed there is sqrt(2 a_c gap), not V_c; raise target.gap or set motion.start_at_speed = true", st.early, st.total));
    }
    if let Some(path) = &svg {
        let result = SweepResult { axes: axes.clone(), values: axes.iter().map(Axis::values).collect(), points: kept, scene_name: template.base.name.clone() };
        plot::draw_with(path, &result, &args.metric, args.log_color).map_err(Failure::runtime)?;
    }
    let modes: Vec<String> = modes_n.iter().enumerate().filter(|(_, &n)| n > 0).map(|(m, n)| format!("mode {}: {n}", m + 1)).collect();
    output::note(&format!(
        "{}: {} points in {:.2} s ({} threads){}{}{}{}{}{}",
        template.base.name,
        st.total,
        wall,
        args.jobs.unwrap_or_else(rayon::current_num_threads),
        if modes.is_empty() { String::new() } else { format!("; {}", modes.join(", ")) },
        if exhausted > 0 { format!("; stroke exhausted at {exhausted}") } else { String::new() },
        if not_safe > 0 { format!("; NOT SAFE at {not_safe} (docs/verdicts.md)") } else { String::new() },
        if st.refused > 0 { format!("; REFUSED by the validator at {} (status and reason columns; --strict refuses the sweep)", st.refused) } else { String::new() },
        if st.failed > 0 { format!("; SOLVER FAILED at {} (status and reason columns)", st.failed) } else { String::new() },
        [csv_out.as_ref().filter(|p| !output::is_stdout(p)).map(|p| format!("; csv {}", p.display())), svg.as_ref().map(|p| format!("; plot {}", p.display()))].into_iter().flatten().collect::<String>(),
    ));
    if st.failed > 0 {
        return Err(Failure::runtime(format!("the solver failed at {} of {} points", st.failed, st.total)));
    }
    Ok(true)
}
