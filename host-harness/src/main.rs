//! `flinch`: run a scene, run it with the firmware in the loop, check a stroke budget, avoid.

use clap::{Parser, Subcommand};
use flinch_harness::{report, scene, sim};
use std::path::PathBuf;
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
}

#[derive(clap::Args)]
struct RunArgs {
    /// The scene file (TOML, SI units; see shared/SCENES.md).
    scene: PathBuf,
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

fn run(args: &RunArgs) -> Result<(), String> {
    let scene = scene::load(&args.scene).map_err(|e| e.to_string())?;
    let record = args.csv.is_some() || args.plot.is_some();
    let (summary, history) = sim::run(&scene, record).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    if let Some(path) = &args.csv {
        let mut f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        report::csv::write(&mut f, &history).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let object = matches!(scene.target.kind, scene::TargetKind::Object { .. });
        report::plot::draw(path, &summary, &history, object, scene.robot.is_none())?;
    }
    if args.json {
        println!("{}", report::json(&summary));
    } else {
        print!("{}", report::human(&summary));
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
