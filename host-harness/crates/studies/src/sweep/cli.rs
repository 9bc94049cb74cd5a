//! The `flinch sweep` command line.

use super::{check_metric, plot, Axis, Progress, Sweep, SweepError, Template};
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
    /// Threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = flinch_model::overrides::Set::parse)]
    pub set: Vec<flinch_model::overrides::Set>,
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
    let built = if args.strict { Sweep::new(&template, axes) } else { Sweep::keep_going(&template, axes) };
    let sweep = built.map_err(|e| Failure::bad_input(e.to_string()))?;
    if sweep.refused_count() == sweep.len() {
        let first = (0..sweep.len()).find_map(|k| sweep.refusal(k)).unwrap_or_default();
        return Err(Failure::bad_input(format!("the validator refuses all {} points; the first: {first}", sweep.len())));
    }
    // A tool that meets the target while the flange is still accelerating never sees V_c: say so,
    // since a speed sweep of such a scene saturates at sqrt(2 a_c gap).
    let early = (0..sweep.len())
        .filter(|&k| sweep.refusal(k).is_none())
        .filter(|&k| {
            let s = sweep.scene(k);
            !s.motion.start_at_speed && s.target.gap < s.motion.speed * s.motion.speed / (2.0 * s.motion.accel)
        })
        .count();
    if early > 0 {
        output::note(&format!("note: at {early} of {} points the tool meets the target before the flange reaches motion.speed (gap < V_c^2 / 2 a_c): the impact speed there is sqrt(2 a_c gap), not V_c; raise target.gap or set motion.start_at_speed = true", sweep.len()));
    }
    let t0 = Instant::now();
    let result = sweep.run_with_jobs(Progress::Auto, args.jobs).map_err(|e| Failure::bad_input(e.to_string()))?;
    let wall = t0.elapsed().as_secs_f64();
    let csv_out = match (&csv, &svg) {
        (Some(p), _) => Some(p.clone()),
        (None, None) => Some(PathBuf::from("-")),
        (None, Some(_)) => None,
    };
    if let Some(path) = &csv_out {
        let mut w = output::create(path)?;
        result.write_csv(&mut w).and_then(|_| w.flush()).map_err(|e| output::write_error(path, &e))?;
    }
    if let Some(path) = &svg {
        plot::draw_with(path, &result, &args.metric, args.log_color).map_err(Failure::runtime)?;
    }
    let exhausted = result.metric("stroke_exhausted").iter().filter(|&&e| e == 1.0).count();
    let not_safe = result.metric("safe").iter().filter(|&&e| e == 0.0).count();
    let modes: Vec<String> = (1..=3u8)
        .map(|m| (m, result.points.iter().filter(|p| p.outcome.as_ref().is_ok_and(|s| s.mode == Some(m))).count()))
        .filter(|&(_, n)| n > 0)
        .map(|(m, n)| format!("mode {m}: {n}"))
        .collect();
    output::note(&format!(
        "{}: {} points in {:.2} s ({} threads){}{}{}{}{}{}",
        template.base.name,
        result.points.len(),
        wall,
        args.jobs.unwrap_or_else(rayon::current_num_threads),
        if modes.is_empty() { String::new() } else { format!("; {}", modes.join(", ")) },
        if exhausted > 0 { format!("; stroke exhausted at {exhausted}") } else { String::new() },
        if not_safe > 0 { format!("; NOT SAFE at {not_safe} (docs/verdicts.md)") } else { String::new() },
        if result.refused() > 0 { format!("; REFUSED by the validator at {} (status and reason columns; --strict refuses the sweep)", result.refused()) } else { String::new() },
        if result.failures() > 0 { format!("; SOLVER FAILED at {} (status and reason columns)", result.failures()) } else { String::new() },
        [csv_out.as_ref().filter(|p| !output::is_stdout(p)).map(|p| format!("; csv {}", p.display())), svg.as_ref().map(|p| format!("; plot {}", p.display()))].into_iter().flatten().collect::<String>(),
    ));
    if result.failures() > 0 {
        return Err(Failure::runtime(format!("the solver failed at {} of {} points", result.failures(), result.points.len())));
    }
    Ok(true)
}
