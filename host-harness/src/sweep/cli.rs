//! The `flinch sweep` command line.

use super::{check_metric, plot, Axis, Progress, Sweep, SweepError, Template};
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
    /// Write the CSV here (one row per point, every summary field).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Draw the plot here (.svg or .png): lines for one axis, a heat map for two.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// The summary field a heat map shows.
    #[arg(long, default_value = "peak_robot_force")]
    pub metric: String,
    /// Threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
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

/// Runs `flinch sweep`.
pub fn run(args: &SweepArgs) -> Result<(), String> {
    let axes = axes(&args.vary, &args.log).map_err(|e| e.to_string())?;
    check_metric(&args.metric).map_err(|e| e.to_string())?;
    let (csv, svg) = match &args.out {
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            (Some(args.csv.clone().unwrap_or_else(|| dir.join("sweep.csv"))), Some(args.plot.clone().unwrap_or_else(|| dir.join("sweep.svg"))))
        }
        None => (args.csv.clone(), args.plot.clone()),
    };
    if let Some(p) = &svg {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if ext != "svg" && ext != "png" {
            return Err(format!("--plot {}: the plot file must end in .svg or .png", p.display()));
        }
    }
    let template = Template::load(&args.scene).map_err(|e| e.to_string())?;
    let sweep = Sweep::new(&template, axes).map_err(|e| e.to_string())?;
    // A tool that meets the target while the flange is still accelerating never sees V_c: say so,
    // since a speed sweep of such a scene saturates at sqrt(2 a_c gap).
    let early = (0..sweep.len())
        .filter(|&k| {
            let s = sweep.scene(k);
            !s.motion.start_at_speed && s.target.gap < s.motion.speed * s.motion.speed / (2.0 * s.motion.accel)
        })
        .count();
    if early > 0 {
        eprintln!("note: at {early} of {} points the tool meets the target before the flange reaches motion.speed (gap < V_c^2 / 2 a_c): the impact speed there is sqrt(2 a_c gap), not V_c; raise target.gap or set motion.start_at_speed = true", sweep.len());
    }
    let t0 = Instant::now();
    let result = sweep.run_with_jobs(Progress::Auto, args.jobs).map_err(|e| e.to_string())?;
    let wall = t0.elapsed().as_secs_f64();
    match &csv {
        Some(path) => std::fs::write(path, result.csv()).map_err(|e| format!("{}: {e}", path.display()))?,
        None if svg.is_none() => print!("{}", result.csv()),
        None => {}
    }
    if let Some(path) = &svg {
        plot::draw(path, &result, &args.metric)?;
    }
    let exhausted = result.metric("stroke_exhausted").iter().filter(|&&e| e == 1.0).count();
    let modes: Vec<String> = (1..=3u8)
        .map(|m| (m, result.points.iter().filter(|p| p.outcome.as_ref().is_ok_and(|s| s.mode == Some(m))).count()))
        .filter(|&(_, n)| n > 0)
        .map(|(m, n)| format!("mode {m}: {n}"))
        .collect();
    eprintln!(
        "{}: {} points in {:.2} s ({} threads){}{}{}{}",
        template.base.name,
        result.points.len(),
        wall,
        args.jobs.unwrap_or_else(rayon::current_num_threads),
        if modes.is_empty() { String::new() } else { format!("; {}", modes.join(", ")) },
        if exhausted > 0 { format!("; stroke exhausted at {exhausted}") } else { String::new() },
        if result.failures() > 0 { format!("; SOLVER FAILED at {} (see the error column)", result.failures()) } else { String::new() },
        [csv.as_ref().map(|p| format!("; csv {}", p.display())), svg.as_ref().map(|p| format!("; plot {}", p.display()))].into_iter().flatten().collect::<String>(),
    );
    if result.failures() > 0 {
        return Err(format!("the solver failed at {} of {} points", result.failures(), result.points.len()));
    }
    Ok(())
}
