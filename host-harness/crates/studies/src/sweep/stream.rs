//! A sweep streamed (issue 27): rows written as they finish, in grid order, with memory that does
//! not grow with the number of points, and Ctrl-C keeping the complete prefix.
//!
//! [`stream`] builds no scene ahead: the points run in blocks of [`block_len`] in grid order; each
//! worker builds and validates its point's scene from the template (the splice plan, as
//! [`Sweep::new`] does), runs it and returns the [`Point`]; the block's points are handed to the
//! caller in grid order before the next block starts. Memory: one block of points and one scene per
//! worker, whatever the grid (measured in docs/conventions.md). The cost: a block waits for its
//! slowest point before the next starts (a thread idles meanwhile), and `--strict` validates every
//! point twice (a validation pass first keeps its promise: refused before anything runs).
//!
//! Ctrl-C sets [`STOP`]: the block under way finishes, its rows are handed over, and [`stream`]
//! returns with `interrupted` set: the caller has every point before that one, in grid order.
use super::{axis::*, error::*, grid::*, template::*};
use flinch_model::scene::Scene;
use flinch_sim as sim;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by Ctrl-C during a streamed sweep.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Points run per block: enough to keep every thread busy, few enough to hold.
pub fn block_len(threads: usize) -> usize {
    (threads * 64).clamp(64, 4096)
}

/// What a streamed sweep saw.
#[derive(Debug, Clone, Default)]
pub struct Streamed {
    /// Points handed over (a complete prefix of the grid).
    pub done: usize,
    /// Points of the grid.
    pub total: usize,
    /// Refused by the validator, among those done.
    pub refused: usize,
    /// The solver failed, among those done.
    pub failed: usize,
    /// Points where the tool meets the target before the flange reaches motion.speed.
    pub early: usize,
    /// The first refusal's reason.
    pub first_refusal: Option<String>,
    /// Ctrl-C stopped it.
    pub interrupted: bool,
}

/// The scene of grid point `k`, or the validator's refusal.
fn point_scene(template: &Template, axes: &[Axis], values: &[Vec<f64>], plan: &Option<SplicePlan>, sizes: &[usize], k: usize) -> Result<Scene, SweepError> {
    let idx = grid_index(sizes, k);
    let sets: Vec<(&str, f64)> = axes.iter().zip(&idx).zip(values).map(|((a, &i), v)| (a.key.as_str(), v[i])).collect();
    match plan {
        Some(p) => template.with_spliced(p, &sets),
        None => template.with(&sets),
    }
}

/// Runs the sweep of `axes` over `template` in grid order, handing each point to `row` as soon as
/// the points before it are handed over. `strict`: a refused point refuses the sweep before any
/// point runs. Stops early (with `interrupted`) when [`STOP`] is set, or when `row` fails (its
/// error is returned).
pub fn stream(template: &Template, axes: Vec<Axis>, strict: bool, progress: Progress, pool: Option<&rayon::ThreadPool>, row: &mut dyn FnMut(Point) -> std::io::Result<()>) -> Result<Result<Streamed, std::io::Error>, SweepError> {
    let (axes, values, plan, sizes, total) = prepare(template, axes)?;
    if strict {
        let refusals: Vec<String> = (0..total).into_par_iter().filter_map(|k| point_scene(template, &axes, &values, &plan, &sizes, k).err().map(|e| e.0)).collect::<Vec<_>>();
        if let Some(first) = refusals.first() {
            let of = if total > 1 { format!("{} of {total} points refused; the first: ", refusals.len()) } else { String::new() };
            return err(format!("{of}{first}"));
        }
    }
    use std::io::IsTerminal;
    let bar = if progress == Progress::Auto && std::io::stderr().is_terminal() {
        let b = ProgressBar::new(total as u64);
        if let Ok(style) = ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} points written, {per_sec}, eta {eta}") {
            b.set_style(style.progress_chars("=> "));
        }
        b
    } else {
        ProgressBar::hidden()
    };
    let mut s = Streamed { total, ..Streamed::default() };
    let block = block_len(pool.map_or_else(rayon::current_num_threads, rayon::ThreadPool::current_num_threads));
    let mut start = 0;
    while start < total {
        if STOP.load(Ordering::SeqCst) {
            s.interrupted = true;
            break;
        }
        let end = (start + block).min(total);
        let run_block = || -> Vec<(Point, bool)> {
            (start..end)
            .into_par_iter()
            .map(|k| {
                let index = grid_index(&sizes, k);
                let vals = index.iter().zip(&values).map(|(&i, v)| v[i]).collect();
                let (outcome, status, early) = match point_scene(template, &axes, &values, &plan, &sizes, k) {
                    Err(e) => (Err(e.0), Status::Refused, false),
                    Ok(sc) => {
                        let early = !sc.motion.start_at_speed && sc.target.gap < sc.motion.speed * sc.motion.speed / (2.0 * sc.motion.accel);
                        match sim::run(&sc, false) {
                            Ok((sum, _)) => (Ok(sum), Status::Ok, early),
                            Err(e) => (Err(e.to_string()), Status::Failed, early),
                        }
                    }
                };
                (Point { values: vals, index, outcome, status }, early)
            })
            .collect()
        };
        let points = match pool {
            Some(p) => p.install(run_block),
            None => run_block(),
        };
        for (p, early) in points {
            match p.status {
                Status::Refused => {
                    s.refused += 1;
                    if s.first_refusal.is_none() {
                        s.first_refusal = p.outcome.as_ref().err().cloned();
                    }
                }
                Status::Failed => s.failed += 1,
                Status::Ok => {}
            }
            s.early += usize::from(early);
            if let Err(e) = row(p) {
                bar.finish_and_clear();
                return Ok(Err(e));
            }
            s.done += 1;
        }
        bar.set_position(s.done as u64);
        start = end;
    }
    bar.finish_and_clear();
    Ok(Ok(s))
}
