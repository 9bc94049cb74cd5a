//! `flinch`: run a scene, run it with the firmware in the loop, check a stroke budget.

use clap::{Parser, Subcommand};
use flinch_harness::{check, hil, report, scene, sim};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "flinch", version, about = "Collision management for robot end-effectors: simulate, check, and run the firmware in the loop")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and print its summary.
    Run(RunArgs),
    /// Simulate a scene with the firmware in the loop and a scan-cycle robot controller.
    Hil(HilArgs),
    /// Check that the decoupler's stroke absorbs the stopping distance, and confirm by simulation.
    Check(CheckArgs),
    /// Speed against accuracy: every scene over methods and tolerances against the reference, the
    /// firmware's fixed point against f64; CSV tables and a Pareto plot (docs/accuracy.md).
    Bench(BenchArgs),
    /// Collision avoidance (Ch. 5): fit the depth image, run the potential field, report the path.
    Avoid(flinch_harness::avoid::AvoidArgs),
    /// Run a scene over a grid of one or two of its keys (all cores): CSV and a line chart or heat map.
    Sweep(flinch_harness::sweep::cli::SweepArgs),
    /// Size a module: the stroke a robot needs, the largest safe speed for a stroke, the working mode.
    Design(flinch_harness::design::DesignArgs),
    /// Regenerate docs/validation.md and its pictures: the thesis's figures against ours.
    Validate(flinch_harness::validate::ValidateArgs),
}

#[derive(clap::Args)]
struct Output {
    /// Print the JSON summary instead of the human one.
    #[arg(long)]
    json: bool,
    /// Write the time history to this CSV file.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Draw velocities and forces against time to this .svg or .png file.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// The scene file (TOML, SI units; see shared/SCENES.md).
    scene: PathBuf,
    #[command(flatten)]
    out: Output,
}

#[derive(clap::Args)]
struct HilArgs {
    /// The scene file; its [controller] table, if any, gives the defaults below.
    scene: PathBuf,
    /// The robot controller's scan cycle, s (e.g. 0.016 Viper, 0.07 experiments, 0.0001 EtherCAT).
    #[arg(long, value_name = "S")]
    scan_cycle: Option<f64>,
    /// Phase of the controller's first sample, as a fraction of the scan cycle in [0, 1).
    #[arg(long, value_name = "FRACTION")]
    phase: Option<f64>,
    /// The firmware's tick period, s.
    #[arg(long, value_name = "S")]
    tick: Option<f64>,
    /// Lockstep interval between plant and firmware, s.
    #[arg(long, value_name = "S", default_value_t = hil::DEFAULT_STEP)]
    step: f64,
    #[command(flatten)]
    out: Output,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// The scene file.
    scene: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scene files (default: every scenes/*.toml except avoid_*).
    scenes: Vec<PathBuf>,
    /// Directory the shipped scenes are read from when none is given.
    #[arg(long, value_name = "DIR", default_value = "scenes")]
    scenes_dir: PathBuf,
    /// Output directory for runs.csv, summary.csv, pareto.svg and fixed_point.csv.
    #[arg(long, value_name = "DIR", default_value = "target/bench")]
    out: PathBuf,
    /// Timed repetitions of every configuration (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// A shorter sweep.
    #[arg(long)]
    quick: bool,
}

fn write_outputs(out: &Output, sc: &scene::Scene, summary: &sim::Summary, history: &[sim::Sample]) -> Result<(), String> {
    if let Some(path) = &out.csv {
        let mut f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        report::csv::write(&mut f, history).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &out.plot {
        let object = matches!(sc.target.kind, scene::TargetKind::Object { .. });
        report::plot::draw(path, summary, history, object, sc.robot.is_none())?;
    }
    Ok(())
}

fn run(args: &RunArgs) -> Result<(), String> {
    let sc = scene::load(&args.scene).map_err(|e| e.to_string())?;
    let record = args.out.csv.is_some() || args.out.plot.is_some();
    let (summary, history) = sim::run(&sc, record).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    write_outputs(&args.out, &sc, &summary, &history)?;
    if args.out.json {
        println!("{}", report::json(&summary));
    } else {
        print!("{}", report::human(&summary));
    }
    Ok(())
}

fn controller(args: &HilArgs, sc: &scene::Scene, file: &Path) -> Result<scene::Controller, String> {
    let base = sc.controller;
    let scan_cycle = args.scan_cycle.or(base.map(|c| c.scan_cycle)).ok_or_else(|| format!("{}: [controller] scan_cycle is missing: add a [controller] table or pass --scan-cycle", file.display()))?;
    let phase = args.phase.or(base.map(|c| c.phase)).unwrap_or(0.0);
    let firmware_tick = args.tick.or(base.map(|c| c.firmware_tick)).unwrap_or(1e-4);
    if !(scan_cycle > 0.0 && scan_cycle.is_finite()) {
        return Err(format!("--scan-cycle: must be > 0 s, got {scan_cycle}"));
    }
    if !(0.0..1.0).contains(&phase) {
        return Err(format!("--phase: must be in [0, 1), got {phase}"));
    }
    if !(firmware_tick >= 1e-6 && firmware_tick <= 0.1) {
        return Err(format!("--tick: must be in [1e-6, 0.1] s, got {firmware_tick}"));
    }
    if !(args.step >= 1e-7 && args.step <= firmware_tick) {
        return Err(format!("--step: must be in [1e-7 s, the firmware tick {firmware_tick} s], got {}", args.step));
    }
    Ok(scene::Controller { scan_cycle, phase, firmware_tick })
}

fn hil_cmd(args: &HilArgs) -> Result<(), String> {
    let sc = scene::load(&args.scene).map_err(|e| e.to_string())?;
    let ctl = controller(args, &sc, &args.scene)?;
    let record = args.out.csv.is_some() || args.out.plot.is_some();
    let (rep, history) = hil::run(&sc, &ctl, args.step, record).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    write_outputs(&args.out, &sc, &rep.summary, &history)?;
    if args.out.json {
        println!("{}", serde_json::to_string_pretty(&rep).map_err(|e| e.to_string())?);
    } else {
        print!("{}", report::human(&rep.summary));
        let f = &rep.firmware;
        let ms = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{:.3} ms", v * 1e3));
        println!("  firmware in the loop: scan cycle {:.3} ms, phase {:.2}, tick {:.3} ms", f.scan_cycle * 1e3, f.phase, f.firmware_tick * 1e3);
        println!("    switch {}   firmware timestamp {}   latency {}   controller saw the stop {}", ms(f.switch_time), ms(f.firmware_detect), ms(f.firmware_latency), ms(f.stop_seen));
        println!("    observed dead time {}{}   event log: {} entr{}", ms(f.observed_dead_time), if f.category0 { "   CATEGORY 0 requested (stroke budget exceeded)" } else { "" }, f.event_log.len(), if f.event_log.len() == 1 { "y" } else { "ies" });
    }
    Ok(())
}

fn check_cmd(args: &CheckArgs) -> Result<bool, String> {
    let sc = scene::load(&args.scene).map_err(|e| e.to_string())?;
    let c = check::check(&sc).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c).map_err(|e| e.to_string())?);
    } else {
        println!("{}", sc.name);
        println!("  stopping distance after detection v DT + v^2/2d = {:.2} mm", c.stopping_distance * 1e3);
        println!("  stroke C = {:.2} mm, switch travel {:.2} mm, left at detection {:.2} mm", c.stroke * 1e3, c.switch_travel * 1e3, c.remaining * 1e3);
        println!("  budget: {} (margin {:+.2} mm)", if c.fits { "FITS" } else { "DOES NOT FIT: escalate to a category-0 stop" }, c.margin * 1e3);
        println!("  simulation: max travel {:.2} mm, flange reached the target: {}", c.simulated.max_travel * 1e3, if c.simulated.stroke_exhausted { "YES" } else { "no" });
    }
    Ok(c.fits)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run(a).map(|_| true),
        Command::Hil(a) => hil_cmd(a).map(|_| true),
        Command::Check(a) => check_cmd(a),
        Command::Bench(a) => flinch_harness::bench::run(&flinch_harness::bench::Options { scenes: a.scenes.clone(), scenes_dir: a.scenes_dir.clone(), out: a.out.clone(), repeats: a.repeats, quick: a.quick }).map(|_| true),
        Command::Avoid(a) => flinch_harness::avoid::run(a).map(|_| true),
        Command::Sweep(a) => flinch_harness::sweep::cli::run(a).map(|_| true),
        Command::Design(a) => flinch_harness::design::run(a),
        Command::Validate(a) => flinch_harness::validate::run(a).map(|_| true),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        // A budget that does not fit is an answer, not an error: exit 1 so scripts can branch.
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
