//! Running the thesis's scenes for the document ([`Ctx`]: a shipped scene with keys set, run), and
//! what is read off a time history (hits, end-stop landings), the sweep commands shown.

use flinch_model::scene::{Decoupler, Scene};
use flinch_sim::{self as sim, Sample, Summary};
use crate::sweep::{Axis, Progress, Spacing, Sweep, SweepResult, Template};
use std::fmt::Write as _;
use std::path::PathBuf;

pub(crate) struct Ctx {
    pub(crate) scenes: PathBuf,
}

impl Ctx {
    pub(crate) fn template(&self, name: &str) -> Result<Template, String> {
        Template::load(&self.scenes.join(name)).map_err(|e| e.to_string())
    }
    /// A shipped scene with one line of text replaced (for string keys the sweep cannot set).
    pub(crate) fn variant(&self, name: &str, from: &str, to: &str) -> Result<Template, String> {
        let text = std::fs::read_to_string(self.scenes.join(name)).map_err(|e| format!("{name}: {e}"))?;
        if !text.contains(from) {
            return Err(format!("{name}: expected {from:?} in the scene"));
        }
        Template::from_text(&text.replace(from, to), name).map_err(|e| e.to_string())
    }
    /// A shipped scene whose front end-stop follows the Hunt-Crossley law instead of eq 28's
    /// (`law = "hunt-crossley"` added to `decoupler.front_stop`; same k_fe, same restitution).
    pub(crate) fn hunt_crossley(&self, name: &str, sets: &[(&str, f64)]) -> Result<Scene, String> {
        let text = std::fs::read_to_string(self.scenes.join(name)).map_err(|e| format!("{name}: {e}"))?;
        let line = text.lines().find(|l| l.trim_start().starts_with("front_stop = {")).ok_or_else(|| format!("{name}: no front_stop line"))?;
        let end = line.find('}').ok_or_else(|| format!("{name}: front_stop is not an inline table"))?;
        let to = format!("{}, law = \"hunt-crossley\" {}", line[..end].trim_end(), &line[end..]);
        Template::from_text(&text.replace(line, &to), name).map_err(|e| e.to_string())?.with(sets).map_err(|e| e.to_string())
    }
    pub(crate) fn run_hc(&self, name: &str, sets: &[(&str, f64)]) -> Result<Summary, String> {
        sim::run(&self.hunt_crossley(name, sets)?, false).map(|r| r.0).map_err(|e| format!("{name}: {e}"))
    }
    pub(crate) fn scene(&self, name: &str, sets: &[(&str, f64)]) -> Result<Scene, String> {
        self.template(name)?.with(sets).map_err(|e| e.to_string())
    }
    pub(crate) fn run(&self, name: &str, sets: &[(&str, f64)]) -> Result<Summary, String> {
        let s = self.scene(name, sets)?;
        sim::run(&s, false).map(|r| r.0).map_err(|e| format!("{name}: {e}"))
    }
    pub(crate) fn history(&self, name: &str, sets: &[(&str, f64)]) -> Result<(Summary, Vec<Sample>), String> {
        let s = self.scene(name, sets)?;
        sim::run(&s, true).map_err(|e| format!("{name}: {e}"))
    }
    /// A run recorded every `dt` seconds (the evidence behind a note: contact onsets, jumps).
    pub(crate) fn fine(&self, name: &str, sets: &[(&str, f64)], dt: f64) -> Result<(Summary, Vec<Sample>), String> {
        let mut s = self.scene(name, sets)?;
        s.solver.output_interval = dt;
        sim::run(&s, true).map_err(|e| format!("{name}: {e}"))
    }
    pub(crate) fn sweep(&self, name: &str, axes: &[(&str, f64, f64, usize, bool)]) -> Result<SweepResult, String> {
        let t = self.template(name)?;
        let axes = axes.iter().map(|&(k, a, b, n, log)| Axis::new(k, a, b, n, if log { Spacing::Log } else { Spacing::Linear })).collect::<Result<Vec<_>, _>>().map_err(|e| e.to_string())?;
        let s = Sweep::new(&t, axes).map_err(|e| e.to_string())?;
        let r = s.run(Progress::Hidden);
        if r.failures() > 0 {
            return Err(format!("{name}: the solver failed at {} points", r.failures()));
        }
        Ok(r)
    }
}

pub(crate) fn obj(s: &Summary) -> f64 {
    s.object_final_velocity.unwrap_or(f64::NAN)
}

/// A tool-target contact as a recorded history shows it.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    /// First sample with contact force, s.
    pub on_s: f64,
    /// First sample without, s (the run's end if the contact lasts).
    pub off_s: f64,
    /// Object velocity at `off_s`, m/s.
    pub object_mps: f64,
}

/// The tool-target contacts of a recorded history (sampled: resolution is its output interval).
pub fn hits(h: &[Sample]) -> Vec<Hit> {
    let mut out = Vec::new();
    let mut on = None;
    for x in h {
        match (on, x.f_contact > 0.0) {
            (None, true) => on = Some(x.t),
            (Some(t0), false) => {
                out.push(Hit { on_s: t0, off_s: x.t, object_mps: x.v_p });
                on = None;
            }
            _ => {}
        }
    }
    if let (Some(t0), Some(l)) = (on, h.last()) {
        out.push(Hit { on_s: t0, off_s: l.t, object_mps: l.v_p });
    }
    out
}

/// The tool landing on the back end-stop (the flange) after `after`: the first sample where the
/// stops push the tool forward (f_stops > 0) after one where they did not.
pub fn back_stop_hit(h: &[Sample], after: f64) -> Option<Sample> {
    h.windows(2).find(|w| w[0].t > after && w[0].f_stops <= 0.0 && w[1].f_stops > 0.0).map(|w| w[1])
}

/// The tool landing back on the front end-stop after `after`: the first sample where the stops
/// push the tool back (f_stops < 0) after a sample where nothing did. Returns (that sample, the
/// one before it).
pub fn front_stop_return(h: &[Sample], after: f64) -> Option<(Sample, Sample)> {
    h.windows(2).find(|w| w[0].t > after && w[0].f_stops == 0.0 && w[1].f_stops < 0.0).map(|w| (w[1], w[0]))
}

/// c_fe of a scene's front end-stop, N s/m.
pub(crate) fn front_damping(sc: &Scene) -> f64 {
    match &sc.decoupler {
        Decoupler::Hydraulic(h) => h.front_stop.damping,
        Decoupler::Bistable(b) => b.front_stop.damping,
        _ => f64::NAN,
    }
}

/// The command line of a sweep, as the doc prints it.
pub(crate) fn sweep_cmd(scene: &str, axes: &[(&str, f64, f64, usize, bool)], metric: &str, plot: &str) -> String {
    let mut c = format!("flinch sweep scenes/{scene}");
    for &(k, a, b, n, log) in axes {
        let _ = write!(c, " --vary {k}={}{a}:{b}:{n}", if log { "log:" } else { "" });
    }
    let _ = write!(c, " --metric {metric}{} --plot {plot}", if metric == "peak_robot_force" { " --log-color" } else { "" });
    c
}

/// Grid sizes: coarse for the tables (and the test), fine for the pictures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Grid {
    Table,
    Plot,
}

pub(crate) fn ch3_axes(g: Grid, second: &str) -> Vec<(&'static str, f64, f64, usize, bool)> {
    let fine = g == Grid::Plot;
    let v = ("motion.speed", 0.05, 0.3, if fine { 26 } else { 6 }, false);
    let other = match second {
        "tool.mass" => ("tool.mass", 0.25, 1.25, if fine { 21 } else { 5 }, false),
        "target.stiffness" => ("target.stiffness", 1e6, 1e8, if fine { 9 } else { 3 }, true),
        "decoupler.spring_rate" => ("decoupler.spring_rate", 100.0, 300.0, if fine { 9 } else { 3 }, false),
        _ => ("motion.dead_time", 0.0, 0.1, if fine { 21 } else { 5 }, false),
    };
    vec![v, other]
}

pub(crate) const CH3: &str = "figures/ch3_bistable_sweep.toml";
