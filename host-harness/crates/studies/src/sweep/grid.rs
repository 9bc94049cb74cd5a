//! A sweep ([`Sweep`]) over one or two axes, run on all cores: every point's scene, its status
//! (ran, refused by the validator, the solver failed) and summary, in grid order, with progress.

use flinch_model::scene::Scene;
use flinch_sim::{self as sim, Summary};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::{self};
use super::{error::*, axis::*, template::*};



impl std::error::Error for SweepError {}

/// A sweep checked and built: every point's scene is valid, or (built with
/// [`Sweep::keep_going`]) refused with the validator's reason.
pub struct Sweep {
    /// The swept axes (one or two), first varying slowest.
    pub axes: Vec<Axis>,
    /// The values of each axis.
    pub values: Vec<Vec<f64>>,
    pub(crate) scenes: Vec<Scene>,
    /// Per point: the validator's reason when it refused the point's scene (the point does not run).
    pub(crate) refused: Vec<Option<String>>,
    /// Scene name, for titles.
    pub scene_name: String,
}

/// What became of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Ran; the summary is there.
    Ok,
    /// The scene validator refused the point's values; it did not run.
    Refused,
    /// It ran and the solver gave up.
    Failed,
}

impl Status {
    /// As the CSV writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::Refused => "refused",
            Self::Failed => "failed",
        }
    }
}

/// One point of a sweep and its outcome.
#[derive(Debug, Clone)]
pub struct Point {
    /// The swept values, in axis order.
    pub values: Vec<f64>,
    /// Index of each value on its axis.
    pub index: Vec<usize>,
    /// The summary, or why there is none (the validator's or the solver's message).
    pub outcome: Result<Summary, String>,
    /// Ok, refused or failed.
    pub status: Status,
}

/// A finished sweep, points in row-major order (first axis slowest).
#[derive(Debug, Clone)]
pub struct SweepResult {
    /// The axes.
    pub axes: Vec<Axis>,
    /// The values of each axis.
    pub values: Vec<Vec<f64>>,
    /// The points.
    pub points: Vec<Point>,
    /// Scene name.
    pub scene_name: String,
}

/// Progress reporting: a bar on a terminal, nothing when piped or in tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// Draw an `indicatif` bar on stderr if stderr is a terminal.
    Auto,
    /// Never draw.
    Hidden,
}

pub(crate) fn grid_index(sizes: &[usize], mut k: usize) -> Vec<usize> {
    let mut idx = vec![0; sizes.len()];
    for a in (0..sizes.len()).rev() {
        idx[a] = k % sizes[a];
        k /= sizes[a];
    }
    idx
}

impl Sweep {
    /// Checks the axes against the template and builds every point's scene. Nothing runs. A point
    /// whose values the validator refuses refuses the whole sweep (`flinch sweep --strict`).
    pub fn new(template: &Template, axes: Vec<Axis>) -> Result<Self, SweepError> {
        Self::build(template, axes, true)
    }

    /// As [`Sweep::new`], but a refused point becomes a row with status `refused` and the
    /// validator's reason instead of refusing the sweep; bad axes or keys still refuse it.
    pub fn keep_going(template: &Template, axes: Vec<Axis>) -> Result<Self, SweepError> {
        Self::build(template, axes, false)
    }

    pub(crate) fn build(template: &Template, axes: Vec<Axis>, strict: bool) -> Result<Self, SweepError> {
        let (axes, values, plan, sizes, total) = prepare(template, axes)?;
        Self::build_prepared(template, axes, values, plan, sizes, total, strict)
    }

    #[allow(clippy::too_many_arguments)]
    fn build_prepared(template: &Template, axes: Vec<Axis>, values: Vec<Vec<f64>>, plan: Option<SplicePlan>, sizes: Vec<usize>, total: usize, strict: bool) -> Result<Self, SweepError> {
        let built: Vec<Result<Scene, SweepError>> = (0..total)
            .into_par_iter()
            .map(|k| {
                let idx = grid_index(&sizes, k);
                let sets: Vec<(&str, f64)> = axes.iter().zip(&idx).zip(&values).map(|((a, &i), v)| (a.key.as_str(), v[i])).collect();
                match &plan {
                    Some(p) => template.with_spliced(p, &sets),
                    None => template.with(&sets),
                }
            })
            .collect();
        Self::collect_built(template, axes, values, built, total, strict)
    }
}

/// A splice plan of [`Template::splice_plan`].
pub type SplicePlan = Vec<(std::ops::Range<usize>, toml_edit::Value)>;

/// Checks the axes against the template (one or two, distinct keys, each a numeric key of the
/// scene, at most a million points): the axes, their values, the splice plan, the sizes, the total.
pub(crate) fn prepare(template: &Template, axes: Vec<Axis>) -> Result<(Vec<Axis>, Vec<Vec<f64>>, Option<SplicePlan>, Vec<usize>, usize), SweepError> {
    if axes.is_empty() {
        return err("nothing to sweep: give --vary KEY=START:STOP:N once or twice");
    }
    if axes.len() > 2 {
        return err(format!("{} --vary axes given: a sweep has one or two", axes.len()));
    }
    if axes.len() == 2 && axes[0].key == axes[1].key {
        return err(format!("--vary {} is given twice: the two axes must be different keys", axes[0].key));
    }
    for a in &axes {
        template.check_key(&a.key, a.start)?;
    }
    let values: Vec<Vec<f64>> = axes.iter().map(Axis::values).collect();
    let keys: Vec<&str> = axes.iter().map(|a| a.key.as_str()).collect();
    let plan = template.splice_plan(&keys);
    let sizes: Vec<usize> = values.iter().map(Vec::len).collect();
    let total: usize = sizes.iter().product();
    if total > 1_000_000 {
        return err(format!("{total} points: more than a million; use fewer steps"));
    }
    Ok((axes, values, plan, sizes, total))
}

impl Sweep {
    fn collect_built(template: &Template, axes: Vec<Axis>, values: Vec<Vec<f64>>, built: Vec<Result<Scene, SweepError>>, total: usize, strict: bool) -> Result<Self, SweepError> {
        let n_refused = built.iter().filter(|b| b.is_err()).count();
        let mut scenes = Vec::with_capacity(total);
        let mut refused = Vec::with_capacity(total);
        for b in built {
            match b {
                Ok(s) => {
                    scenes.push(s);
                    refused.push(None);
                }
                Err(e) if strict => {
                    let of = if total > 1 { format!("{n_refused} of {total} points refused; the first: ") } else { String::new() };
                    return err(format!("{of}{e}"));
                }
                Err(e) => {
                    // Never run; the template's scene stands in so indices stay aligned.
                    scenes.push(template.base.clone());
                    refused.push(Some(e.0));
                }
            }
        }
        Ok(Self { axes, values, scenes, refused, scene_name: flinch_model::headline::headline(&template.base).flagged_name() })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.scenes.len()
    }

    /// True when there are no points (never, for a built sweep).
    pub fn is_empty(&self) -> bool {
        self.scenes.is_empty()
    }

    /// The scene of point `k` (row-major); for a refused point, the template's (it does not run).
    pub fn scene(&self, k: usize) -> &Scene {
        &self.scenes[k]
    }

    /// Why point `k` was refused, if it was.
    pub fn refusal(&self, k: usize) -> Option<&str> {
        self.refused.get(k).and_then(|r| r.as_deref())
    }

    /// Points the validator refused.
    pub fn refused_count(&self) -> usize {
        self.refused.iter().filter(|r| r.is_some()).count()
    }

    /// Runs every point on the current rayon pool; the order of the result does not depend on it.
    pub fn run(&self, progress: Progress) -> SweepResult {
        use std::io::IsTerminal;
        let bar = if progress == Progress::Auto && io::stderr().is_terminal() {
            let b = ProgressBar::new(self.len() as u64);
            if let Ok(style) = ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} points, {per_sec}, eta {eta}") {
                b.set_style(style.progress_chars("=> "));
            }
            b
        } else {
            ProgressBar::hidden()
        };
        let sizes: Vec<usize> = self.values.iter().map(Vec::len).collect();
        let points = self
            .scenes
            .par_iter()
            .enumerate()
            .map(|(k, sc)| {
                let index = grid_index(&sizes, k);
                let values = index.iter().zip(&self.values).map(|(&i, v)| v[i]).collect();
                let (outcome, status) = match &self.refused[k] {
                    Some(why) => (Err(why.clone()), Status::Refused),
                    None => match sim::run(sc, false) {
                        Ok((s, _)) => (Ok(s), Status::Ok),
                        Err(e) => (Err(e.to_string()), Status::Failed),
                    },
                };
                bar.inc(1);
                Point { values, index, outcome, status }
            })
            .collect();
        bar.finish_and_clear();
        SweepResult { axes: self.axes.clone(), values: self.values.clone(), points, scene_name: self.scene_name.clone() }
    }

    /// Runs on a pool of `jobs` threads (None: all cores).
    pub fn run_with_jobs(&self, progress: Progress, jobs: Option<usize>) -> Result<SweepResult, SweepError> {
        match jobs {
            None => Ok(self.run(progress)),
            Some(0) => err("--jobs must be at least 1"),
            Some(j) => {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(j).build().map_err(|e| SweepError(format!("--jobs {j}: {e}")))?;
                Ok(pool.install(|| self.run(progress)))
            }
        }
    }
}
