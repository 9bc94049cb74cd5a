//! `flinch`: run a scene, run it with the firmware in the loop, check a stroke budget, sweep, size
//! a module, compare with measurements.
//!
//! Conventions (docs/conventions.md): results on standard output, messages on standard error, `-`
//! is standard output for every file option (and standard input for a scene), exit codes 0 ran
//! (favourable verdict), 1 ran (unfavourable verdict), 2 bad input, 3 runtime failure, 130
//! interrupted, 141 the reader of standard output went away.

use clap::{Parser, Subcommand};
use flinch_harness::report::output::{self, Failure};
use flinch_harness::report::{self, measured, stream, trace::HilSignals, trace::Trace};
use flinch_harness::{check, hil, overrides, scene, shipped};
use overrides::Set;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const AFTER_HELP: &str = "A SCENE is a TOML file, `-` for standard input, or the name of a shipped scene \
(`flinch scenes list`). The scene contract (every key, unit and range) is docs/SCENES.md, the model \
docs/MODEL.md, the output convention and exit codes docs/conventions.md, the JSON Schemas docs/schema/.\n\
Exit codes: 0 ran (favourable verdict), 1 ran (unfavourable verdict of check, design, avoid (unsafe), or a hil fault \
ending in go; run exits 0 on a NOT SAFE summary: read `safe`), 2 bad input, 3 runtime failure, \
4 avoid stopped safely before the goal, 5 avoid on recorded frames (--depth): unverified, \
130 interrupted (Ctrl-C), 141 standard output closed by its reader.";

#[derive(Parser)]
#[command(name = "flinch", version, about = "Collision management for robot end-effectors: simulate, check, and run the firmware in the loop", after_help = AFTER_HELP)]
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
    /// Monte Carlo over a scene's keys drawn from distributions (all cores, deterministic for a
    /// seed, in chunks that merge): each failure's probability with a 95 % interval (docs/sample.md).
    Sample(flinch_harness::sample::cli::SampleArgs),
    /// Your robot from its URDF: m_r, k_r, c_r reduced from joint space (thesis eq 10-16), and
    /// against one joint (--sweep-joint, like Fig. 12).
    Robot(flinch_harness::kinematics::cli::RobotArgs),
    /// Size a module: the stroke a robot needs, the largest safe speed for a stroke, the working mode.
    Design(flinch_harness::design::DesignArgs),
    /// Regenerate docs/validation.md and its pictures: the thesis's figures against ours.
    Validate(flinch_harness::validate::ValidateArgs),
    /// One printable, self-contained HTML page: inputs and their sources, the verdicts, the safe
    /// speed, the time history, the design curve (and a sweep), the tool version and the scene's SHA-256.
    Report(flinch_harness::report::html::ReportArgs),
    /// The shipped scenes, built into this binary: list them, or print one to start your own.
    Scenes {
        #[command(subcommand)]
        what: ScenesCmd,
    },
}

#[derive(Subcommand)]
enum ScenesCmd {
    /// Every shipped scene, with its first comment line.
    List,
    /// Print a shipped scene's TOML (e.g. `flinch scenes show tables5-7_bistable > my.toml`).
    Show {
        /// The scene's name, as `flinch scenes list` prints it.
        name: String,
    },
}

#[derive(clap::Args)]
struct Output {
    /// Print the JSON summary instead of the human one (schema: docs/schema/).
    #[arg(long)]
    json: bool,
    /// Write the time history to this CSV file (`-`: standard output); rows stream as they are made.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Draw velocities, forces, travel (and gas pressure, firmware signals) against time to this .svg or .png file.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// The scene: a TOML file, `-`, or a shipped scene's name (docs/SCENES.md).
    scene: PathBuf,
    #[command(flatten)]
    out: Output,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = Set::parse)]
    set: Vec<Set>,
    /// Compare with measured traces: a CSV with `t_s` and any of v_t_mps, v_r_mps, v_p_mps, v_c_mps,
    /// f_contact_n, f_robot_n, travel_m, s_m. Reports RMS and peak errors and the time shift, and
    /// draws the measured traces on --plot.
    #[arg(long, value_name = "FILE.csv")]
    measured: Option<PathBuf>,
}

#[derive(clap::Args)]
struct HilArgs {
    /// The scene; its [controller] table, if any, gives the defaults below.
    scene: PathBuf,
    /// The robot controller's scan cycle, s (e.g. 0.016 Viper, 0.07 experiments, 0.0001 EtherCAT).
    #[arg(long, value_name = "S", value_parser = opt_scan_cycle)]
    scan_cycle: Option<f64>,
    /// Phase of the controller's first sample, as a fraction of the scan cycle in [0, 1).
    #[arg(long, value_name = "FRACTION", value_parser = opt_phase)]
    phase: Option<f64>,
    /// The worst phase instead: the sample before the stop output just missed it, so the stop is
    /// seen a whole scan cycle later (the worst case of the dead time).
    #[arg(long, conflicts_with = "phase")]
    worst_phase: bool,
    /// The firmware's tick period, s (whole microseconds).
    #[arg(long, value_name = "S", value_parser = opt_tick)]
    tick: Option<f64>,
    /// The robot's reaction after a scan sample sees the stop (brake engage, drive delay), s;
    /// default [controller] reaction_time, else motion.dead_time - scan cycle.
    #[arg(long, value_name = "S")]
    reaction_time: Option<f64>,
    /// Faults to inject, NAME@SECONDS, comma-separated: stuck-rest, stuck-trip, cut-wire,
    /// stuck-rest-b, welded-output, edm-wire-cut, clock-stall, reset; output faults stuck-stop-pin,
    /// frozen-port-k1, frozen-port-k2, frozen-port-escalation, welded-k2, welded-k1-k2. Exit 1 if
    /// one ends in "go".
    #[arg(long, value_name = "NAME@S,...")]
    fault: Option<String>,
    /// Channels of the travel switch: 1, or 2 (antivalent pair, cross-monitored, 20 ms discrepancy).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=2))]
    channels: u8,
    /// The firmware's glitch filter: none (the edge stops at once), consecutive:N (N tick samples
    /// tripped), min-duration:S (tripped for S seconds).
    #[arg(long, value_name = "FILTER", default_value = "none")]
    filter: String,
    /// How a trip is cleared: input (a reset press, none during the run: latched), or auto:S (back
    /// on the front stop for S seconds).
    #[arg(long, value_name = "POLICY", default_value = "input")]
    reset_policy: String,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = Set::parse)]
    set: Vec<Set>,
    #[command(flatten)]
    out: Output,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// The scene.
    scene: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = Set::parse)]
    set: Vec<Set>,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scenes: files or shipped scenes' names (default: every shipped scene, top level and
    /// extremes/, except avoid_*; built into the binary).
    scenes: Vec<PathBuf>,
    /// Read the default scenes from this directory (and its extremes/) instead.
    #[arg(long, value_name = "DIR")]
    scenes_dir: Option<PathBuf>,
    /// Output directory for runs.csv, summary.csv, pareto.svg and fixed_point.csv.
    #[arg(long, value_name = "DIR", default_value = "target/bench")]
    out: PathBuf,
    /// Timed repetitions of every configuration (the median is reported), 1 to 1000.
    #[arg(long, default_value_t = 5, value_parser = opt_repeats)]
    repeats: usize,
    /// A shorter sweep.
    #[arg(long)]
    quick: bool,
}

/// Reads a scene argument with its `--set` overrides, validated together.
fn load(scene: &Path, sets: &[Set]) -> Result<scene::Scene, Failure> {
    overrides::load(scene, sets).map(|l| l.scene).map_err(Failure::bad_input)
}

/// Refuses option combinations that would write two things to standard output.
fn check_outputs(out: &Output, extra: Option<&Path>) -> Result<(), Failure> {
    if let Some(p) = &out.plot {
        report::figure::check_extension(p).map_err(|e| Failure::bad_input(format!("--plot {e}")))?;
    }
    if out.csv.as_deref().is_some_and(output::is_stdout) && out.json {
        return Err(Failure::bad_input("--json and --csv - both write to standard output; give --csv a file name"));
    }
    if let Some(m) = extra {
        if output::is_stdout(m) {
            return Err(Failure::bad_input("--measured -: standard input is not supported for the measured file; give a file name"));
        }
    }
    Ok(())
}

/// After the inputs are read: refuses outputs that would replace one of them, or land on a device
/// or in a kernel folder, before anything runs (the careful writer, flinch_output::writer).
fn check_targets(out: &Output) -> Result<(), Failure> {
    if let Some(p) = &out.csv {
        output::check_target("--csv", p)?;
    }
    if let Some(p) = &out.plot {
        output::check_target("--plot", p)?;
    }
    Ok(())
}

/// Prints a summary where it belongs: standard output, or standard error when the CSV has it.
fn print_result(out: &Output, text: &str) -> Result<(), Failure> {
    if out.csv.as_deref().is_some_and(output::is_stdout) {
        output::note(text.trim_end());
        Ok(())
    } else {
        output::print(text)
    }
}

fn wrote(path: &Path, what: &str) {
    if !output::is_stdout(path) {
        output::note(&format!("wrote {} ({what})", path.display()));
    }
}

fn run(args: &RunArgs) -> Result<bool, Failure> {
    check_outputs(&args.out, args.measured.as_deref())?;
    let sc = load(&args.scene, &args.set)?;
    let meas = match &args.measured {
        Some(p) => Some(measured::Measured::load(p).map_err(Failure::bad_input)?),
        None => None,
    };
    check_targets(&args.out)?;
    let resampler = meas.as_ref().map(|m| measured::Resampler::new(m, Trace::new(&sc)));
    let r = stream::run(&sc, args.out.csv.as_deref(), args.out.plot.is_some(), resampler).map_err(|f| Failure { message: format!("{}: {}", args.scene.display(), f.message), ..f })?;
    if let Some(p) = &args.out.csv {
        wrote(p, &format!("{} rows", r.rows));
    }
    let comparisons = match (&meas, &r.resampled) {
        (Some(m), Some(rs)) => Some(rs.compare(m)),
        _ => None,
    };
    if let Some(p) = &args.out.plot {
        let overlay = meas.as_ref().map(measured::overlay).unwrap_or_default();
        report::plot::draw(p, &sc, &r.summary, &r.plotted, &Trace::new(&sc), &overlay).map_err(Failure::runtime)?;
        wrote(p, "plot");
    }
    let text = if args.out.json {
        report::to_json(&report::RunJson { schema_version: report::SCHEMA_VERSION, summary: &r.summary, measured: comparisons.as_deref() })
    } else {
        let mut t = report::human(&r.summary);
        if let (Some(m), Some(c)) = (&meas, &comparisons) {
            t.push_str(&report::human_measured(&m.file, c));
        }
        t
    };
    print_result(&args.out, &text)?;
    Ok(true)
}

/// The controller: the scene's `[controller]` (validated by the loader, which names file, line and
/// key) with the options on top (named as options).
fn controller(args: &HilArgs, sc: &scene::Scene, file: &Path) -> Result<scene::Controller, String> {
    let base = sc.controller;
    let scan_cycle = args.scan_cycle.or(base.map(|c| c.scan_cycle)).ok_or_else(|| format!("{}: [controller] scan_cycle is missing: add a [controller] table or pass --scan-cycle", file.display()))?;
    let phase = args.phase.or(base.map(|c| c.phase)).unwrap_or(0.0);
    let firmware_tick = args.tick.or(base.map(|c| c.firmware_tick)).unwrap_or(1e-4);
    // --scan-cycle, --phase and --tick were held to their scene keys' ranges by clap (opt_*).
    if let Some(r) = args.reaction_time.filter(|r| !(0.0..=1.0).contains(r)) {
        return Err(format!("--reaction-time: must be in [0, 1] s (a robot's reaction to a stop it has read), got {r}"));
    }
    let mut c = base.unwrap_or(scene::Controller::new(scan_cycle, phase, firmware_tick));
    c.reaction_time = args.reaction_time.or(c.reaction_time);
    c.scan_cycle = scan_cycle;
    c.phase = phase;
    c.firmware_tick = firmware_tick;
    Ok(c)
}

fn hil_cmd(args: &HilArgs) -> Result<bool, Failure> {
    use flinch_harness::sim::Sample;
    check_outputs(&args.out, None)?;
    let sc = load(&args.scene, &args.set)?;
    let at_file = |e: String| format!("{}: {e}", args.scene.display());
    if let Some(why) = hil::refusal(&sc) {
        return Err(Failure::bad_input(at_file(why)));
    }
    let ctl = controller(args, &sc, &args.scene).map_err(Failure::bad_input)?;
    let faults = hil::parse_faults(args.fault.as_deref().unwrap_or("")).map_err(Failure::bad_input)?;
    // A fault after the run's end would silently never be injected: refused (issue 27).
    if let Some(f) = faults.iter().find(|f| f.at_s >= sc.duration_s) {
        return Err(Failure::bad_input(format!("--fault: {:?} at {} s is not before the end of the run (duration = {} s); a fault must fall within [0, duration)", f.kind, f.at_s, sc.duration_s)));
    }
    check_targets(&args.out)?;
    if args.channels == 1 && faults.iter().any(|f| f.kind == hil::FaultKind::StuckRestB) {
        return Err(Failure::bad_input("--fault stuck-rest-b: needs --channels 2 (this run has one channel)"));
    }
    let filter = hil::parse_filter(&args.filter).map_err(Failure::bad_input)?;
    let reset = hil::parse_reset_policy(&args.reset_policy).map_err(Failure::bad_input)?;
    let opts = hil::HilOptions { faults, two_channels: args.channels == 2, filter, reset, worst_phase: args.worst_phase };
    // Outputs stream (bounded memory whatever the duration); a long run shows its progress on a
    // terminal and stops cleanly on Ctrl-C, the CSV flagged partial.
    let long = sc.duration_s > 5.0 || stream::expected_rows(&sc) > 1_000_000;
    let streaming = args.out.csv.is_some() || args.out.plot.is_some() || (long && std::io::IsTerminal::is_terminal(&std::io::stderr()));
    let (rep, plotted, rows) = if streaming {
        let trace = Trace::new(&sc).with_hil(HilSignals::before_run(&sc, ctl.scan_cycle, ctl.phase));
        let mut st = stream::Streamer::open(&sc, args.out.csv.as_deref(), args.out.plot.is_some(), None, trace)?;
        let mut shown = (0usize, None::<f64>);
        let mut sink = |s: &Sample, sig: &hil::RowSignals<'_>| {
            if (sig.stop_output.len(), sig.stop_seen) != shown {
                shown = (sig.stop_output.len(), sig.stop_seen);
                if let Some(h) = st.trace_mut().and_then(|t| t.hil.as_mut()) {
                    h.stop_output = sig.stop_output.to_vec();
                    h.stop_seen_s = sig.stop_seen;
                }
            }
            st.take(s);
        };
        let r = hil::run_recording(&sc, &ctl, &opts, hil::Record::Stream(&mut sink));
        let (plotted, rows, _) = st.close()?;
        (r.map_err(|e| Failure::runtime(at_file(e)))?.0, plotted, rows)
    } else {
        (hil::run_with(&sc, &ctl, false, &opts).map_err(|e| Failure::runtime(at_file(e)))?.0, Vec::new(), 0)
    };
    let safe = rep.firmware.faults.iter().all(|f| !f.ended_in_go);
    if let Some(p) = &args.out.csv {
        wrote(p, &format!("{rows} rows"));
    }
    if let Some(p) = &args.out.plot {
        let trace = Trace::new(&sc).with_hil(HilSignals::new(&sc, &rep));
        report::plot::draw(p, &sc, &rep.summary, &plotted, &trace, &Vec::new()).map_err(Failure::runtime)?;
        wrote(p, "plot");
    }
    let text = if args.out.json {
        report::to_json(&report::HilJson { schema_version: report::SCHEMA_VERSION, report: &rep })
    } else {
        let mut t = report::human(&rep.summary);
        t.push_str(&hil::human(&rep.firmware));
        t
    };
    print_result(&args.out, &text)?;
    Ok(safe)
}

fn check_cmd(args: &CheckArgs) -> Result<bool, Failure> {
    let sc = load(&args.scene, &args.set)?;
    let c = check::check(&sc).map_err(|e| {
        let m = format!("{}: {e}", args.scene.display());
        if refuses_the_scene_kind(&e) { Failure::bad_input(m) } else { Failure::runtime(m) }
    })?;
    let text = if args.json {
        report::to_json(&report::Versioned::at(report::CHECK_SCHEMA_VERSION, &c))
    } else {
        check::human(&c)
    };
    output::print(&text)?;
    Ok(c.safe)
}

fn scenes_cmd(what: &ScenesCmd) -> Result<bool, Failure> {
    match what {
        ScenesCmd::List => {
            let width = shipped::names().map(str::len).max().unwrap_or(0);
            let mut t = String::new();
            for (name, text) in shipped::SCENES {
                let mut d = shipped::description(text);
                if d.chars().count() > 100 {
                    d = d.chars().take(97).collect::<String>() + "...";
                }
                t.push_str(&format!("{name:width$}  {d}\n"));
            }
            output::print(&t)?;
        }
        ScenesCmd::Show { name } => match shipped::get(name) {
            Some(text) => output::print(text)?,
            None => {
                let near = shipped::close_to(name);
                return Err(Failure::bad_input(format!("{name}: no shipped scene of that name; {}", if near.is_empty() { "`flinch scenes list` lists them".to_string() } else { format!("close: {}", near.join(", ")) })));
            }
        },
    }
    Ok(true)
}

fn bench_cmd(a: &BenchArgs) -> Result<bool, Failure> {
    use flinch_harness::bench;
    let o = bench::Options { scenes: a.scenes.clone(), scenes_dir: a.scenes_dir.clone(), out: a.out.clone(), repeats: a.repeats, quick: a.quick };
    if a.repeats == 0 {
        return Err(Failure::bad_input("--repeats: at least 1 timed repetition, got 0"));
    }
    let scenes = bench::load_scenes(&o).map_err(Failure::bad_input)?;
    bench::run(&o, &scenes).map(|_| true).map_err(Failure::runtime)
}

/// A module outside this file returns its errors as text: a scene it cannot read is bad input,
/// anything after that a runtime failure.
fn classify(scene_ok: Result<(), String>, r: Result<bool, String>) -> Result<bool, Failure> {
    scene_ok.map_err(Failure::bad_input)?;
    r.map_err(|e| if refuses_the_scene_kind(&e) { Failure::bad_input(e) } else { Failure::runtime(e) })
}

/// `avoid`'s input files that are not regular files (a FIFO, a device) or over their caps are bad
/// input (exit 2), said before anything runs; what is wrong inside them is found while reading.
fn avoid_inputs(a: &flinch_harness::avoid::AvoidArgs) -> Result<(), Failure> {
    use flinch_harness::report::input::{check, Kind};
    let bad = |opt: &str, e: flinch_harness::report::input::InputError| Failure::bad_input(format!("{opt} {e}"));
    if let Some(p) = &a.calibration {
        check(p, Kind::Calibration).map_err(|e| bad("--calibration", e))?;
    }
    if let Some(p) = a.depth.as_ref().filter(|p| !p.is_dir()) {
        check(p, Kind::DepthFrame).map_err(|e| bad("--depth", e))?;
    }
    if let Some(p) = &a.robot_poses {
        check(p, Kind::Poses).map_err(|e| bad("--robot-poses", e))?;
    }
    Ok(())
}

/// `check` and `design` need a module with a stroke and a travel switch: a scene without them
/// (a rigid tool, a linear spring, a force sensor) is the wrong input for the command (exit 2),
/// not a failure while running it.
fn refuses_the_scene_kind(e: &str) -> bool {
    e.contains("decoupler.kind: flinch ") || e.contains("sensor.kind: flinch ")
}

fn main() -> ExitCode {
    output::install_print_guard();
    output::defer_to_settle();
    report::font::ensure();
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run(a),
        Command::Hil(a) => hil_cmd(a),
        Command::Check(a) => check_cmd(a),
        Command::Scenes { what } => scenes_cmd(what),
        Command::Sweep(a) => flinch_harness::sweep::cli::run(a),
        Command::Sample(a) => flinch_harness::sample::cli::run(a),
        Command::Bench(a) => bench_cmd(a),
        Command::Avoid(a) => avoid_inputs(a)
            .and_then(|_| flinch_harness::avoid::scene::Avoid::load(&a.scene).map_err(Failure::bad_input))
            // `[avoid.pfl]`: the module's PFL speeds computed from its scene before the run.
            .and_then(|mut sc| flinch_harness::pfl::resolve_pfl(&mut sc).map(|_| sc).map_err(Failure::bad_input))
            .and_then(|sc| match flinch_harness::avoid::run_scene(a, sc) {
            Ok(v) => match v.code() {
                0 => Ok(true),
                1 => Ok(false),
                // 4 (stopped safely) and 5 (unverified): an answer, not an error; no message.
                code => Err(Failure { code, message: String::new() }),
            },
            Err(e) => Err(Failure::runtime(e)),
        }),
        Command::Robot(a) => flinch_harness::kinematics::cli::run(a),
        // Everything refused before a run is bad input (exit 2); after that, a runtime failure.
        Command::Design(a) => classify(flinch_harness::design::refusal_of(a).map_or(Ok(()), Err), flinch_harness::design::run(a)),
        Command::Validate(a) => flinch_harness::validate::run(a).map(|_| true).map_err(Failure::runtime),
        Command::Report(a) => report::html::run(a),
    };
    // The outputs written through temporary files are renamed into place, or removed when the
    // command failed (exit 2 or 3), so the old files stay as they were (crate output::writer).
    output::settle(result.as_ref().map_or_else(|f| output::keeps(f.code), |_| true));
    match result {
        Ok(true) => ExitCode::SUCCESS,
        // An unfavourable verdict is an answer, not an error: exit 1 so scripts can branch.
        Ok(false) => ExitCode::from(output::EXIT_VERDICT),
        Err(f) => {
            if !f.message.is_empty() {
                output::note(&format!("error: {}", f.message));
            }
            ExitCode::from(f.code)
        }
    }
}

/// `hil --scan-cycle`: held to `controller.scan_cycle`'s range (scene::option_number).
fn opt_scan_cycle(text: &str) -> Result<f64, String> {
    scene::option_number("controller.scan_cycle", &scene::CONTROLLER_SCAN_CYCLE, text)
}

/// `hil --phase`: held to `controller.phase`'s range (scene::option_number).
fn opt_phase(text: &str) -> Result<f64, String> {
    scene::option_number("controller.phase", &scene::CONTROLLER_PHASE, text)
}

/// `hil --tick`: held to `controller.firmware_tick`'s range (scene::option_number).
fn opt_tick(text: &str) -> Result<f64, String> {
    scene::option_number("controller.firmware_tick", &scene::CONTROLLER_FIRMWARE_TICK, text)
}

/// `bench --repeats`: 1 to 1000 (a billion ran forever; issue 27).
fn opt_repeats(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n @ 1..=1000) => Ok(n),
        _ => Err(format!("allowed range [1, 1000] timed repetitions, got {text}")),
    }
}
