//! `flinch robot SCENE`: the robot of a scene's `[robot] urdf = ...` reduced to m_r, k_r, c_r, how
//! each joint contributes, and (`--sweep-joint J`) the three against one joint, like the thesis's
//! Fig. 12 (m_r, c_r, k_r along the approach).
use flinch_kinematics::{Reduced, MIN_MOBILITY};
use flinch_output::figure::{self, Mark, Panel, Series, Style, XAxis, PALETTE};
use flinch_output::output::{self, Failure};
use flinch_model::scene::{self, UrdfRobot};
use flinch_model::shipped;
use std::fmt::Write as _;
use std::path::PathBuf;

/// `flinch robot SCENE [--sweep-joint J [--from A --to B --points N] [--plot F] [--csv F]]`.
#[derive(clap::Args, Debug)]
pub struct RobotArgs {
    /// The scene; its [robot] must be given by a URDF (urdf = ...).
    pub scene: PathBuf,
    /// Vary this joint (its URDF name, or its number from the base, 1 = first) over --from..--to,
    /// the others held at the scene's configuration.
    #[arg(long, value_name = "JOINT")]
    pub sweep_joint: Option<String>,
    /// Start of the swept joint's range, rad or m (default: its URDF lower limit, else -pi or -1 m).
    #[arg(long, value_name = "Q", allow_hyphen_values = true)]
    pub from: Option<f64>,
    /// End of the range (default: the URDF upper limit, else pi or 1 m).
    #[arg(long, value_name = "Q", allow_hyphen_values = true)]
    pub to: Option<f64>,
    /// Points in the range.
    #[arg(long, default_value_t = 181)]
    pub points: usize,
    /// Draw m_r, k_r, c_r against the joint (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Write the sweep as CSV (`-`: standard output): q, mass_kg, stiffness_n_per_m, damping_ns_per_m,
    /// mobility, status, reason.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
}

fn unit(robot: &UrdfRobot, i: usize) -> &'static str {
    match robot.chain.joint_kinds[i] {
        flinch_kinematics::JointKind::Revolute => "rad",
        flinch_kinematics::JointKind::Prismatic => "m",
    }
}

/// The human report of one reduction.
pub fn describe(name: &str, robot: &UrdfRobot, r: &Reduced) -> String {
    let c = &robot.chain;
    let mut t = String::new();
    let _ = writeln!(t, "{name}");
    let _ = writeln!(t, "  robot: {} from \"{}\" to \"{}\": {} moving joints, {:.3} kg of links moving", robot.urdf, c.base_link, c.tip_link, c.dof(), r.moving_mass_kg);
    let _ = writeln!(t, "  flange at [{:.4}, {:.4}, {:.4}] m, approach u = [{:.4}, {:.4}, {:.4}] (base frame)", r.tip_m[0], r.tip_m[1], r.tip_m[2], r.direction[0], r.direction[1], r.direction[2]);
    let w = c.joint_names.iter().map(String::len).max().unwrap_or(5).max(5);
    let _ = writeln!(t, "  {:<w$}  {:>14}  {:>18}  {:>20}  {:>15}  {:>10}", "joint", "q", "K_q", "D_q", "J^T u", "compliance");
    for (i, s) in r.joints.iter().enumerate() {
        let u = unit(robot, i);
        let (ku, du, lu) = if u == "rad" { ("N m/rad", "N m s/rad", "m/rad") } else { ("N/m", "N s/m", "m/m") };
        let q = format!("{:.4} {u}", robot.joints[i]);
        let k = format!("{:.4e} {ku}", robot.joint_stiffness[i]);
        let d = format!("{:.4} {du}", robot.joint_damping[i]);
        let l = format!("{:.5} {lu}", s.lever);
        let _ = writeln!(t, "  {:<w$}  {q:>14}  {k:>18}  {d:>20}  {l:>15}  {:>8.1} %", s.name, 100.0 * s.compliance_share);
    }
    let _ = writeln!(t, "  m_r = {:.4} kg: operational-space mass along u, 1/(u^T J M_q^-1 J^T u) (thesis eq 12, flange free across u)", r.mass_kg);
    let _ = writeln!(t, "  k_r = {:.4e} N/m: 1/(u^T J K_q^-1 J^T u), the Cartesian compliance along u (eq 14)", r.stiffness_npm);
    let _ = writeln!(t, "  c_r = {:.4} N s/m: the joint dampers on the deflection K_q^-1 J^T u (eq 13)", r.damping_nspm);
    let _ = writeln!(t, "  mobility |J^T u|/|J| = {:.4} (a configuration below {MIN_MOBILITY:.0e} is refused as singular)", r.mobility);
    match r.held {
        Some((m, k, d)) => {
            let _ = writeln!(t, "  thesis eq 12-14 element along u (flange held in the other 5 directions): m = {m:.4} kg, k = {k:.4e} N/m, c = {d:.4} N s/m");
        }
        None => {
            let _ = writeln!(t, "  thesis eq 12-14 element along u: not defined (needs six joints and an invertible 6x6 J)");
        }
    }
    t
}

/// Runs `flinch robot`.
pub fn run(a: &RobotArgs) -> Result<bool, Failure> {
    if let Some(p) = &a.plot {
        figure::check_extension(p).map_err(|e| Failure::bad_input(format!("--plot {e}")))?;
        if a.sweep_joint.is_none() {
            return Err(Failure::bad_input("--plot draws a sweep: give --sweep-joint JOINT"));
        }
    }
    if a.csv.is_some() && a.sweep_joint.is_none() {
        return Err(Failure::bad_input("--csv writes a sweep: give --sweep-joint JOINT"));
    }
    let (file, text) = shipped::read(&a.scene).map_err(|e| Failure::bad_input(e.0))?;
    // The whole scene must be valid, as for `run`.
    let sc = scene::parse(&text, &file).map_err(|e| Failure::bad_input(e.to_string()))?;
    let robot = scene::urdf_robot(&text, &file).map_err(|e| Failure::bad_input(e.to_string()))?.ok_or_else(|| {
        Failure::bad_input(format!("{file}: [robot] is not given by a URDF (urdf = \"...\"): nothing to reduce; docs/robot.md says how to give one"))
    })?;
    let r = robot.reduce().map_err(|e| Failure::bad_input(e.to_string()))?;
    let mut text = describe(&sc.name, &robot, &r);

    if let Some(j) = &a.sweep_joint {
        let n = robot.chain.dof();
        let i = match j.parse::<usize>() {
            Ok(k) if (1..=n).contains(&k) => k - 1,
            Ok(k) => return Err(Failure::bad_input(format!("--sweep-joint {k}: the chain has joints 1 to {n} ({})", robot.chain.joint_names.join(", ")))),
            Err(_) => robot.chain.joint_names.iter().position(|x| x == j).ok_or_else(|| {
                Failure::bad_input(format!("--sweep-joint {j}: not a moving joint of the chain; joints: {}", robot.chain.joint_names.join(", ")))
            })?,
        };
        let u = unit(&robot, i);
        let (dlo, dhi) = robot.chain.joint_limits[i].unwrap_or(if u == "rad" { (-std::f64::consts::PI, std::f64::consts::PI) } else { (-1.0, 1.0) });
        let (lo, hi) = (a.from.unwrap_or(dlo), a.to.unwrap_or(dhi));
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(Failure::bad_input(format!("--from {lo} --to {hi}: must be finite with from < to")));
        }
        if !(2..=100_000).contains(&a.points) {
            return Err(Failure::bad_input(format!("--points {}: allowed 2 to 100000", a.points)));
        }
        let name = robot.chain.joint_names[i].clone();
        let mut rows: Vec<(f64, Result<Reduced, String>)> = Vec::with_capacity(a.points);
        for k in 0..a.points {
            let q = lo + (hi - lo) * k as f64 / (a.points - 1) as f64;
            let mut qs = robot.joints.clone();
            qs[i] = q;
            rows.push((q, robot.reduce_at(&qs).map_err(|e| e.what).and_then(within_plant_range)));
        }
        let refused = rows.iter().filter(|r| r.1.is_err()).count();
        let ok: Vec<&Reduced> = rows.iter().filter_map(|r| r.1.as_ref().ok()).collect();
        let span = |f: fn(&Reduced) -> f64| ok.iter().map(|r| f(r)).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        let (m0, m1) = span(|r| r.mass_kg);
        let (k0, k1) = span(|r| r.stiffness_npm);
        let (c0, c1) = span(|r| r.damping_nspm);
        let _ = writeln!(text, "  sweep of {name} over [{lo:.4}, {hi:.4}] {u}, {} points, the other joints as above:", a.points);
        if ok.is_empty() {
            let _ = writeln!(text, "    every point refused");
        } else {
            let _ = writeln!(text, "    m_r {m0:.4} to {m1:.4} kg, k_r {k0:.4e} to {k1:.4e} N/m, c_r {c0:.4} to {c1:.4} N s/m");
        }
        if refused > 0 {
            let first = rows.iter().find(|r| r.1.is_err()).map(|r| r.0).unwrap_or(f64::NAN);
            let _ = writeln!(text, "    {refused} point(s) refused, as singular or outside the plant's ranges (the first at {name} = {first:.4} {u}); they are left out of the plot and marked in the CSV with the reason");
        }
        if let Some(p) = &a.csv {
            // Names by docs/conventions.md (unit suffixes), quoting by the csv crate.
            let mut w = csv::Writer::from_writer(output::create(p)?);
            let io = |e: csv::Error| match e.into_kind() {
                csv::ErrorKind::Io(e) => output::write_error(p, &e),
                k => Failure::runtime(format!("{}: {k:?}", p.display())),
            };
            w.write_record([format!("{name}_{u}").as_str(), "mass_kg", "stiffness_n_per_m", "damping_ns_per_m", "mobility", "status", "reason"]).map_err(io)?;
            for (q, r) in &rows {
                let rec: Vec<String> = match r {
                    Ok(r) => vec![q.to_string(), r.mass_kg.to_string(), r.stiffness_npm.to_string(), r.damping_nspm.to_string(), r.mobility.to_string(), "ok".into(), String::new()],
                    Err(e) => vec![q.to_string(), String::new(), String::new(), String::new(), String::new(), "refused".into(), e.clone()],
                };
                w.write_record(&rec).map_err(io)?;
            }
            w.flush().map_err(|e| output::write_error(p, &e))?;
            if !output::is_stdout(p) {
                output::note(&format!("wrote {} ({} rows)", p.display(), rows.len()));
            }
        }
        if let Some(p) = &a.plot {
            let series = |f: fn(&Reduced) -> f64, color| Series {
                name: String::new(),
                points: rows.iter().map(|(q, r)| (*q, r.as_ref().map_or(f64::NAN, f))).collect(),
                color,
                style: Style::Line,
            };
            let mark = || vec![Mark { x: robot.joints[i], label: format!("the scene: {name} = {:.3} {u}", robot.joints[i]), color: PALETTE[6] }];
            let panel = |caption: &str, y: &str, s: Series| Panel { caption: caption.into(), y_label: y.into(), series: vec![s], marks: mark(), y_log: true, weight: 1.0, ..Default::default() };
            let panels = [
                panel("m_r, operational-space mass along the approach", "m_r (kg)", series(|r| r.mass_kg, PALETTE[0])),
                panel("k_r, stiffness along the approach", "k_r (N/m)", series(|r| r.stiffness_npm, PALETTE[1])),
                panel("c_r, damping along the approach", "c_r (N s/m)", series(|r| r.damping_nspm, PALETTE[2])),
            ];
            let title = format!("{}: m_r, k_r, c_r against {name} (thesis Fig. 12)", robot.urdf);
            figure::draw(p, &title, &XAxis { label: format!("{name} ({u})"), log: false }, &panels).map_err(Failure::runtime)?;
            output::note(&format!("wrote {} (plot)", p.display()));
        }
    }
    if a.csv.as_deref().is_some_and(output::is_stdout) {
        output::note(text.trim_end());
        Ok(true)
    } else {
        output::print(&text).map(|_| true)
    }
}

/// A pose whose reduced values the plant would refuse (`[robot]` mass, stiffness, damping ranges of
/// scene/robot.rs) is refused here too, with the range: `flinch run` at that pose would not run.
fn within_plant_range(r: Reduced) -> Result<Reduced, String> {
    use flinch_model::scene::{Ty, ROBOT_DAMPING, ROBOT_MASS, ROBOT_STIFFNESS};
    for (key, x) in [(&ROBOT_MASS, r.mass_kg), (&ROBOT_STIFFNESS, r.stiffness_npm), (&ROBOT_DAMPING, r.damping_nspm)] {
        if let Ty::Number(span) = &key.ty {
            if !span.contains(x) {
                return Err(format!("{} = {x:.4e} {} is outside the plant's range for robot.{} ({}): `flinch run` refuses this pose", key.name, span.unit, key.name, span.source));
            }
        }
    }
    Ok(r)
}
