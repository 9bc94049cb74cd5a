//! Pictures of sweeps: line charts for one axis (the working mode as steps), heat maps for two,
//! with the working-mode regions of Fig. 46 outlined, a colour bar with the metric's unit (linear,
//! or logarithmic with `--log-color` so that 3 N and 40 N regions look different), round ticks on
//! logarithmic axes (plotters' `log_scale`), and every point that did not run drawn as such:
//! refused by the validator (light grey, a cross) or failed in the solver (dark grey).

use super::{Spacing, Status, SweepResult};
use flinch_output::figure::{self, with_backend, DrawResult};
pub use flinch_output::figure::{finite_range, fmt_num, ticks, Series, Style, XAxis, PALETTE};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One panel of a line chart, in the short form sweeps and `design` use (see
/// [`figure::Panel`] for every option).
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Panel caption.
    pub caption: String,
    /// Y label, with unit.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Vertical marks (x, label).
    pub marks: Vec<(f64, String)>,
    /// Draw y on a log scale.
    pub y_log: bool,
}

impl From<&Panel> for figure::Panel {
    fn from(p: &Panel) -> Self {
        let colours = [RGBColor(110, 110, 110), RGBColor(200, 0, 0), RGBColor(0, 120, 120)];
        Self {
            caption: p.caption.clone(),
            y_label: p.y_label.clone(),
            series: p.series.clone(),
            marks: p.marks.iter().enumerate().map(|(k, (x, l))| figure::Mark { x: *x, label: l.clone(), color: colours[k % 3] }).collect(),
            y_log: p.y_log,
            ..Default::default()
        }
    }
}

/// Draws stacked panels sharing an x axis into `path` (see [`figure::draw`]).
pub fn lines(path: &Path, title: &str, x: &XAxis, panels: &[Panel]) -> Result<(), String> {
    let full: Vec<figure::Panel> = panels.iter().map(figure::Panel::from).collect();
    figure::draw(path, title, x, &full)
}

/// Viridis (plotters' `colormaps`) at f in [0, 1].
pub fn viridis(f: f64) -> RGBColor {
    let f = if f.is_finite() { f.clamp(0.0, 1.0) } else { 0.0 };
    ViridisRGB.get_color(f)
}

/// A heat map over an nx x ny grid.
#[derive(Debug, Clone)]
pub struct HeatMap {
    /// Title.
    pub title: String,
    /// Horizontal axis (first swept key) and its values.
    pub x: XAxis,
    /// x values.
    pub xs: Vec<f64>,
    /// Vertical axis (second swept key).
    pub y: XAxis,
    /// y values.
    pub ys: Vec<f64>,
    /// The metric, row-major with x slowest (`z[i * ny + j]` at xs[i], ys[j]); NaN is no value.
    pub z: Vec<f64>,
    /// Colour-bar label, with unit.
    pub z_label: String,
    /// Colour on log10 of the metric.
    pub z_log: bool,
    /// Working mode per cell (outlined where it changes), if the decoupler has one.
    pub modes: Vec<Option<u8>>,
    /// Cells where the stroke ran out (red cross).
    pub exhausted: Vec<bool>,
    /// Status of every cell (refused and failed cells are drawn as such).
    pub status: Vec<Status>,
    /// Cells that ran and are NOT SAFE (outlined red).
    pub not_safe: Vec<bool>,
    /// Cells that ran and are not concluded (a dotted orange border).
    pub inconclusive: Vec<bool>,
    /// Cells not simulated as commanded (hatched): the flange had not reached V_c at contact.
    pub not_commanded: Vec<bool>,
    /// A boolean metric: the words for 0 and 1 (two colours and a two-entry key, no colour bar).
    pub boolean: Option<(&'static str, &'static str)>,
}

/// The two colours of a boolean metric: 0 (vermillion) and 1 (bluish green), Okabe-Ito.
pub const BOOL_COLOURS: [RGBColor; 2] = [RGBColor(213, 94, 0), RGBColor(0, 158, 115)];

/// The words for 0 and 1 of a boolean metric, `None` for a number.
pub fn boolean_words(metric: &str) -> Option<(&'static str, &'static str)> {
    match metric {
        "safe" => Some(("NOT SAFE", "SAFE")),
        "stroke_exhausted" | "concluded" | "as_commanded" | "body_limits_pass" => Some(("no", "yes")),
        _ => None,
    }
}

/// Cell edges in value coordinates: midpoints between values (geometric on a log axis), half a
/// step beyond the ends.
fn edges(ax: &XAxis, v: &[f64]) -> Vec<f64> {
    let fwd = |x: f64| if ax.log { x.ln() } else { x };
    let back = |u: f64| if ax.log { u.exp() } else { u };
    let u: Vec<f64> = v.iter().map(|&x| fwd(x)).collect();
    let n = u.len();
    if n == 1 {
        return vec![back(u[0] - 0.5), back(u[0] + 0.5)];
    }
    let mut e = Vec::with_capacity(n + 1);
    e.push(u[0] - 0.5 * (u[1] - u[0]));
    for i in 0..n - 1 {
        e.push(0.5 * (u[i] + u[i + 1]));
    }
    e.push(u[n - 1] + 0.5 * (u[n - 1] - u[n - 2]));
    e.into_iter().map(back).collect()
}

/// Draws a heat map into `path`.
pub fn heat_map(path: &Path, h: &HeatMap) -> Result<(), String> {
    with_backend(path, (1150, 780), &|r| heat_on(r, h), &|r| heat_on(r, h))
}

fn heat_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, h: &HeatMap) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = root.titled(&h.title, ("sans-serif", 19))?;
    let (main, side) = root.split_horizontally(860);
    let ex = edges(&h.x, &h.xs);
    let ey = edges(&h.y, &h.ys);
    let (nx, ny) = (h.xs.len(), h.ys.len());
    let (x0, x1, y0, y1) = (ex[0], ex[nx], ey[0], ey[ny]);
    // The colour scale: the finite values (positive ones on a log scale).
    let finite: Vec<f64> = h.z.iter().copied().filter(|v| v.is_finite() && (!h.z_log || *v > 0.0)).collect();
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (zlo, zhi) = if !lo.is_finite() { (0.0, 1.0) } else if hi > lo { (lo, hi) } else if h.z_log { (lo / 2.0, lo * 2.0) } else { (lo - 0.5, lo + 0.5) };
    let frac = |z: f64| if h.z_log { (z.ln() - zlo.ln()) / (zhi.ln() - zlo.ln()) } else { (z - zlo) / (zhi - zlo) };
    match (h.x.log, h.y.log) {
        (false, false) => cells(&main, h, x0..x1, y0..y1, &ex, &ey, &frac)?,
        // Log axes labelled at round values only (plotters' own key points start at the first power
        // of ten and put nine labels in every decade).
        (true, false) => cells(&main, h, (x0..x1).log_scale().with_key_points(ticks(x0, x1, true)), y0..y1, &ex, &ey, &frac)?,
        (false, true) => cells(&main, h, x0..x1, (y0..y1).log_scale().with_key_points(ticks(y0, y1, true)), &ex, &ey, &frac)?,
        (true, true) => cells(&main, h, (x0..x1).log_scale().with_key_points(ticks(x0, x1, true)), (y0..y1).log_scale().with_key_points(ticks(y0, y1, true)), &ex, &ey, &frac)?,
    }
    if h.boolean.is_some() {
        two_colour_key(&side, h)?;
    } else {
        colour_bar(&side, h, zlo, zhi)?;
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn cells<DB: DrawingBackend, X, Y>(area: &DrawingArea<DB, Shift>, h: &HeatMap, xr: X, yr: Y, ex: &[f64], ey: &[f64], frac: &dyn Fn(f64) -> f64) -> DrawResult
where
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let (nx, ny) = (h.xs.len(), h.ys.len());
    let mut chart = ChartBuilder::on(area).margin(15).margin_right(25).x_label_area_size(48).y_label_area_size(80).build_cartesian_2d(xr, yr)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(&h.x.label)
        .y_desc(&h.y.label)
        .x_label_formatter(&|v| fmt_num(*v))
        .y_label_formatter(&|v| fmt_num(*v))
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .draw()?;
    let refused = RGBColor(215, 215, 215);
    let failed = RGBColor(120, 120, 120);
    let status = |i: usize, j: usize| h.status.get(i * ny + j).copied().unwrap_or(Status::Ok);
    chart.draw_series((0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))).map(|(i, j)| {
        let z = h.z[i * ny + j];
        let c = match status(i, j) {
            Status::Refused => refused,
            Status::Failed => failed,
            Status::Ok if z.is_finite() && h.boolean.is_some() => BOOL_COLOURS[usize::from(z >= 0.5)],
            Status::Ok if z.is_finite() && (!h.z_log || z > 0.0) => viridis(frac(z)),
            Status::Ok => refused,
        };
        Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], c.filled())
    }))?;
    // A cross in a cell: red where the stroke ran out, dark grey where the validator refused it.
    let mut cross = |i: usize, j: usize, c: RGBColor| -> DrawResult {
        let p = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let mid = |e: &[f64], k: usize, t: f64, log: bool| if log { (p(e[k].ln(), e[k + 1].ln(), t)).exp() } else { p(e[k], e[k + 1], t) };
        let (a, b) = (mid(ex, i, 0.25, h.x.log), mid(ex, i, 0.75, h.x.log));
        let (c0, d) = (mid(ey, j, 0.25, h.y.log), mid(ey, j, 0.75, h.y.log));
        chart.draw_series(LineSeries::new(vec![(a, c0), (b, d)], c.stroke_width(2)))?;
        chart.draw_series(LineSeries::new(vec![(a, d), (b, c0)], c.stroke_width(2)))?;
        Ok(())
    };
    for i in 0..nx {
        for j in 0..ny {
            if status(i, j) == Status::Refused {
                cross(i, j, RGBColor(90, 90, 90))?;
            } else if h.exhausted.get(i * ny + j).copied().unwrap_or(false) {
                cross(i, j, RGBColor(230, 30, 30))?;
            }
        }
    }
    // What a cell did not test: hatched (not as commanded), a dotted orange border (not
    // concluded), a red outline (NOT SAFE); drawn inside the cell so neighbours stay apart.
    let lerp = |e: &[f64], k: usize, t: f64, log: bool| if log { (e[k].ln() + (e[k + 1].ln() - e[k].ln()) * t).exp() } else { e[k] + (e[k + 1] - e[k]) * t };
    let flag = |v: &[bool], i: usize, j: usize| v.get(i * ny + j).copied().unwrap_or(false);
    for i in 0..nx {
        for j in 0..ny {
            let at = |tx: f64, ty: f64| (lerp(ex, i, tx, h.x.log), lerp(ey, j, ty, h.y.log));
            if flag(&h.not_commanded, i, j) {
                for k in 1..5 {
                    let t = k as f64 / 5.0;
                    chart.draw_series(LineSeries::new(vec![at(t, 0.04), at(0.04, t)], RGBColor(70, 70, 70).stroke_width(1)))?;
                    chart.draw_series(LineSeries::new(vec![at(0.96, t), at(t, 0.96)], RGBColor(70, 70, 70).stroke_width(1)))?;
                }
            }
            if flag(&h.inconclusive, i, j) {
                let ring = [at(0.12, 0.12), at(0.88, 0.12), at(0.88, 0.88), at(0.12, 0.88), at(0.12, 0.12)];
                chart.draw_series(DashedLineSeries::new(ring, 3, 4, RGBColor(230, 159, 0).stroke_width(3)))?;
            }
            if flag(&h.not_safe, i, j) {
                let ring = vec![at(0.06, 0.06), at(0.94, 0.06), at(0.94, 0.94), at(0.06, 0.94), at(0.06, 0.06)];
                chart.draw_series(LineSeries::new(ring, RGBColor(200, 0, 0).stroke_width(3)))?;
            }
        }
    }
    // Mode boundaries: a white-on-black line on every edge between cells of different mode.
    if h.modes.len() == nx * ny && h.modes.iter().any(Option::is_some) {
        let m = |i: usize, j: usize| h.modes[i * ny + j];
        let mut segs: Vec<[(f64, f64); 2]> = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                if i + 1 < nx && m(i, j) != m(i + 1, j) {
                    segs.push([(ex[i + 1], ey[j]), (ex[i + 1], ey[j + 1])]);
                }
                if j + 1 < ny && m(i, j) != m(i, j + 1) {
                    segs.push([(ex[i], ey[j + 1]), (ex[i + 1], ey[j + 1])]);
                }
            }
        }
        for s in &segs {
            chart.draw_series(LineSeries::new(s.to_vec(), WHITE.stroke_width(5)))?;
        }
        for s in &segs {
            chart.draw_series(LineSeries::new(s.to_vec(), BLACK.stroke_width(2)))?;
        }
        // Label each mode region at the cell nearest its centroid, so the label sits inside it; a
        // label that would touch one already placed moves down (then up) by a label's height.
        let mut placed: Vec<(i32, i32)> = Vec::new();
        for mode in 1..=3u8 {
            let cells: Vec<(usize, usize)> = (0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))).filter(|&(i, j)| m(i, j) == Some(mode)).collect();
            if cells.is_empty() {
                continue;
            }
            let (ci, cj) = cells.iter().fold((0.0, 0.0), |a, &(i, j)| (a.0 + i as f64, a.1 + j as f64));
            let (ci, cj) = (ci / cells.len() as f64, cj / cells.len() as f64);
            let Some(&(i, j)) = cells.iter().min_by(|a, b| {
                let da = (a.0 as f64 - ci).powi(2) + (a.1 as f64 - cj).powi(2);
                let db = (b.0 as f64 - ci).powi(2) + (b.1 as f64 - cj).powi(2);
                da.total_cmp(&db)
            }) else {
                continue;
            };
            let centre = |e: &[f64], k: usize, log: bool| if log { (e[k] * e[k + 1]).sqrt() } else { 0.5 * (e[k] + e[k + 1]) };
            let at = chart.backend_coord(&(centre(ex, i, h.x.log), centre(ey, j, h.y.log)));
            let (l, t) = (area.get_base_pixel().0, area.get_base_pixel().1);
            let mut at = (at.0 - l, at.1 - t);
            let clear = |p: (i32, i32), placed: &[(i32, i32)]| placed.iter().all(|q| (q.0 - p.0).abs() >= 80 || (q.1 - p.1).abs() >= 30);
            if let Some(free) = (0..12).map(|k| (at.0, at.1 + if k % 2 == 0 { 1 } else { -1 } * 30 * (k / 2 + 1))).find(|&p| clear(p, &placed)).filter(|_| !clear(at, &placed)) {
                at = free;
            }
            placed.push(at);
            area.draw(&Rectangle::new([(at.0 - 36, at.1 - 12), (at.0 + 36, at.1 + 12)], WHITE.mix(0.85).filled()))?;
            area.draw(&Text::new(format!("mode {mode}"), at, ("sans-serif", 16).into_font().color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center))))?;
        }
    }
    Ok(())
}

/// Draws one key entry's symbol with its left end at a point of the area.
type KeySymbol<'a, DB> = dyn Fn(&DrawingArea<DB, Shift>, (i32, i32)) -> DrawResult + 'a;

/// The colour bar, drawn by hand: a gradient, ticks at round values with labels, the metric's
/// name and unit, and the key to the symbols.
fn colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &HeatMap, zlo: f64, zhi: f64) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (_, height) = area.dim_in_pixel();
    let (bx0, bx1) = (30, 62);
    let (top, bottom) = (30, (height as i32 - 280).max(200));
    let frac = |z: f64| if h.z_log { (z.ln() - zlo.ln()) / (zhi.ln() - zlo.ln()) } else { (z - zlo) / (zhi - zlo) };
    let ypix = |f: f64| bottom - ((bottom - top) as f64 * f).round() as i32;
    let steps = 200;
    for k in 0..steps {
        let f0 = k as f64 / steps as f64;
        let f1 = (k + 1) as f64 / steps as f64;
        area.draw(&Rectangle::new([(bx0, ypix(f1)), (bx1, ypix(f0))], viridis(0.5 * (f0 + f1)).filled()))?;
    }
    area.draw(&Rectangle::new([(bx0, top), (bx1, bottom)], BLACK.stroke_width(1)))?;
    let label_font = ("sans-serif", 13).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    for t in ticks(zlo, zhi, h.z_log) {
        let y = ypix(frac(t));
        area.draw(&PathElement::new(vec![(bx1, y), (bx1 + 6, y)], BLACK.stroke_width(1)))?;
        area.draw(&Text::new(fmt_num(t), (bx1 + 10, y), label_font.clone()))?;
    }
    // The metric's name and unit, rotated beside the bar.
    let desc = ("sans-serif", 15).into_font().color(&BLACK).transform(FontTransform::Rotate270).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new(format!("{}{}", h.z_label, if h.z_log { " (log scale)" } else { "" }), (12, (top + bottom) / 2), desc))?;
    symbols_key(area, h, bottom + 30)
}

/// A boolean metric's key: two swatches with their words, then the symbols.
fn two_colour_key<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &HeatMap) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (no, yes) = h.boolean.unwrap_or(("0", "1"));
    let font = ("sans-serif", 15).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(h.z_label.clone(), (18, 30), font.clone()))?;
    for (k, (word, c)) in [(yes, BOOL_COLOURS[1]), (no, BOOL_COLOURS[0])].into_iter().enumerate() {
        let y = 64 + 34 * k as i32;
        area.draw(&Rectangle::new([(18, y - 12), (50, y + 12)], c.filled()))?;
        area.draw(&Text::new(word.to_string(), (60, y), font.clone()))?;
    }
    symbols_key(area, h, 160)
}

/// The key to the symbols drawn on cells, from `y0` down; an entry only for what is present.
fn symbols_key<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &HeatMap, y0: i32) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut y = y0;
    let key = ("sans-serif", 13).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    let mut entry = |draw: &KeySymbol<'_, DB>, text: &str| -> DrawResult {
        draw(area, (18, y))?;
        area.draw(&Text::new(text.to_string(), (44, y), key.clone()))?;
        y += 24;
        Ok(())
    };
    let x_mark = |c: RGBColor| move |a: &DrawingArea<DB, Shift>, (x, y): (i32, i32)| -> DrawResult {
        a.draw(&PathElement::new(vec![(x, y - 7), (x + 14, y + 7)], c.stroke_width(2)))?;
        a.draw(&PathElement::new(vec![(x, y + 7), (x + 14, y - 7)], c.stroke_width(2)))?;
        Ok(())
    };
    if h.modes.iter().any(Option::is_some) {
        entry(&|a, (x, y)| { a.draw(&PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(3)))?; Ok(()) }, "working-mode boundary")?;
    }
    if h.exhausted.iter().any(|&e| e) {
        entry(&x_mark(RGBColor(230, 30, 30)), "stroke exhausted")?;
    }
    if h.not_safe.iter().any(|&b| b) {
        entry(&|a, (x, y)| { a.draw(&Rectangle::new([(x, y - 8), (x + 16, y + 8)], RGBColor(200, 0, 0).stroke_width(3)))?; Ok(()) }, "NOT SAFE (outlined)")?;
    }
    if h.inconclusive.iter().any(|&b| b) {
        entry(&|a, (x, y)| { a.draw(&PathElement::new(vec![(x, y - 8), (x + 16, y - 8), (x + 16, y + 8), (x, y + 8), (x, y - 8)], RGBColor(230, 159, 0).stroke_width(3)))?; Ok(()) }, "not concluded (orange border)")?;
    }
    if h.not_commanded.iter().any(|&b| b) {
        entry(&|a, (x, y)| { for k in 0..4 { a.draw(&PathElement::new(vec![(x + 4 * k, y + 8), (x + 4 * k + 8, y - 8)], RGBColor(70, 70, 70).stroke_width(1)))?; } Ok(()) }, "V_c not reached (hatched)")?;
    }
    if h.status.contains(&Status::Refused) {
        entry(&|a, (x, y)| { a.draw(&Rectangle::new([(x, y - 8), (x + 16, y + 8)], RGBColor(215, 215, 215).filled()))?; x_mark(RGBColor(90, 90, 90))(a, (x + 1, y)) }, "refused by the validator")?;
    }
    if h.status.contains(&Status::Failed) {
        entry(&|a, (x, y)| { a.draw(&Rectangle::new([(x, y - 8), (x + 16, y + 8)], RGBColor(120, 120, 120).filled()))?; Ok(()) }, "solver failed")?;
    }
    Ok(())
}

/// The marks of a line chart at `metric`'s value: NOT SAFE (red ring), not concluded (orange
/// diamond), not as commanded (hollow grey circle; the legend gives the fastest impact reached),
/// each series only when such a point exists.
fn marks(r: &SweepResult, metric: &str) -> Vec<Series> {
    let at = |pred: &dyn Fn(&flinch_sim::Summary) -> bool| -> Vec<(f64, f64)> {
        r.points.iter().filter_map(|p| p.outcome.as_ref().ok().filter(|s| pred(s)).and_then(|s| super::metric(s, metric).map(|y| (p.values[0], y)))).collect()
    };
    let mut out = Vec::new();
    let not_safe = at(&|s| !s.safe);
    if !not_safe.is_empty() {
        out.push(Series { name: "NOT SAFE".into(), points: not_safe, color: RGBColor(200, 0, 0), style: Style::Ring });
    }
    let open = at(&|s| !s.concluded);
    if !open.is_empty() {
        out.push(Series { name: "not concluded (counts as NOT SAFE)".into(), points: open, color: RGBColor(230, 159, 0), style: Style::Diamond });
    }
    let short = at(&|s| !s.as_commanded);
    if !short.is_empty() {
        let reached = r.points.iter().filter_map(|p| p.outcome.as_ref().ok()).filter(|s| !s.as_commanded).filter_map(|s| s.approach_speed_mps).fold(0.0, f64::max);
        out.push(Series { name: format!("not as commanded: V_c not reached at contact (impact <= {reached:.3} m/s)"), points: short, color: RGBColor(90, 90, 90), style: Style::Hollow });
    }
    out
}

/// A label for a swept key (the key, and its unit when it is a well-known one).
pub fn key_label(key: &str) -> String {
    let unit = match key.rsplit('.').next().unwrap_or(key) {
        "speed" => "m/s",
        "accel" | "decel" | "gravity" => "m/s^2",
        "dead_time" | "duration" => "s",
        "mass" => "kg",
        "spring_rate" => "N/m",
        "free_length" | "height" | "front_stroke" | "back_stroke" | "stroke" | "gap" | "piston_radius" | "orifice_radius" => "m",
        "threshold" => "m or N",
        "gas_pressure" => "Pa",
        "gas_volume" => "m^3",
        "stiffness" if key.starts_with("target") || key.ends_with("back_stop.stiffness") => "N/m^1.5",
        "stiffness" => "N/m",
        "damping" => "N s/m",
        "chi" => "N s/m^2.5",
        _ => "",
    };
    if unit.is_empty() { key.to_string() } else { format!("{key} [{unit}]") }
}

/// A label for a summary metric, with its unit (from the JSON Schema's unit table).
pub fn metric_label(m: &str) -> String {
    match flinch_output::units::unit_of(m) {
        Some("1") | None => m.to_string(),
        Some(u) => format!("{m} [{u}]"),
    }
}

/// The default picture of a sweep (see [`draw_with`]), linear colours.
pub fn draw(path: &Path, r: &SweepResult, metric: &str) -> Result<(), String> {
    draw_with(path, r, metric, false)
}

/// The picture of a sweep: for one axis, the peak forces, `metric` and the working mode (as steps)
/// against the value, points that did not run marked; for two, a heat map of `metric`.
pub fn draw_with(path: &Path, r: &SweepResult, metric: &str, log_color: bool) -> Result<(), String> {
    let axis = |k: usize| XAxis { label: key_label(&r.axes[k].key), log: r.axes[k].spacing == Spacing::Log };
    let title = format!("{}: sweep", r.scene_name);
    match r.axes.len() {
        1 => {
            let xs = &r.values[0];
            let series = |name: &str, m: &str, c: RGBColor| Series { name: name.into(), points: xs.iter().copied().zip(r.metric(m)).collect(), color: c, style: Style::LineMarked };
            let mut force = vec![series("peak contact force", "peak_contact_force", PALETTE[3]), series("peak force on the robot", "peak_robot_force", PALETTE[0])];
            let exhausted: Vec<(f64, f64)> = xs.iter().copied().zip(r.metric("stroke_exhausted")).zip(r.metric("peak_robot_force")).filter(|((_, e), _)| *e == 1.0).map(|((x, _), f)| (x, f)).collect();
            if !exhausted.is_empty() {
                force.push(Series { name: "stroke exhausted (flange reached the target)".into(), points: exhausted, color: RGBColor(230, 30, 30), style: Style::Points });
            }
            // Points without a value sit on the axis, as crosses.
            let floor = r.metric("peak_contact_force").into_iter().chain(r.metric("peak_robot_force")).filter(|v| v.is_finite()).fold(f64::INFINITY, f64::min);
            let floor = if floor.is_finite() { floor } else { 0.0 };
            for (status, name, c) in [(Status::Refused, "refused by the validator (no value)", RGBColor(90, 90, 90)), (Status::Failed, "solver failed (no value)", RGBColor(200, 0, 0))] {
                let pts: Vec<(f64, f64)> = r.points.iter().filter(|p| p.status == status).map(|p| (p.values[0], floor)).collect();
                if !pts.is_empty() {
                    force.push(Series { name: name.into(), points: pts, color: c, style: Style::Crosses });
                }
            }
            force.extend(marks(r, "peak_robot_force"));
            let mut panels = vec![figure::Panel { caption: "peak forces".into(), y_label: "force [N]".into(), series: force, ..Default::default() }];
            if metric != "peak_robot_force" && metric != "peak_contact_force" {
                let mut s = vec![series(metric, metric, PALETTE[2])];
                let words = boolean_words(metric);
                if words.is_some() {
                    s[0].style = Style::Steps;
                }
                s.extend(marks(r, metric));
                panels.push(figure::Panel {
                    caption: metric.into(),
                    y_label: metric_label(metric),
                    series: s,
                    y_range: words.map(|_| (-0.3, 1.3)),
                    y_ticks: words.map_or(Vec::new(), |(no, yes)| vec![(0.0, no.to_string()), (1.0, yes.to_string())]),
                    weight: if words.is_some() { 0.6 } else { 1.0 },
                    ..Default::default()
                });
            }
            let modes = r.metric("mode");
            if modes.iter().any(|m| m.is_finite()) {
                // A mode holds over the interval up to the next point: a step, not a slope.
                panels.push(figure::Panel {
                    caption: "working mode (Fig. 46: 1 no back-stop impact, 2 after the robot stopped, 3 before)".into(),
                    y_label: "working mode".into(),
                    series: vec![Series { name: "working mode".into(), points: xs.iter().copied().zip(modes).collect(), color: PALETTE[6], style: Style::Steps }],
                    y_range: Some((0.5, 3.5)),
                    y_ticks: vec![(1.0, "1".into()), (2.0, "2".into()), (3.0, "3".into())],
                    weight: 0.6,
                    ..Default::default()
                });
            }
            figure::draw(path, &title, &axis(0), &panels)
        }
        2 => {
            let modes: Vec<Option<u8>> = r.points.iter().map(|p| p.outcome.as_ref().ok().and_then(|s| s.mode)).collect();
            let exhausted: Vec<bool> = r.points.iter().map(|p| p.outcome.as_ref().is_ok_and(|s| s.stroke_exhausted)).collect();
            let h = HeatMap {
                title: format!("{title}: {metric}"),
                x: axis(0),
                xs: r.values[0].clone(),
                y: axis(1),
                ys: r.values[1].clone(),
                z: r.metric(metric),
                z_label: metric_label(metric),
                z_log: log_color,
                modes,
                exhausted,
                status: r.points.iter().map(|p| p.status).collect(),
                not_safe: r.points.iter().map(|p| p.outcome.as_ref().is_ok_and(|s| !s.safe)).collect(),
                inconclusive: r.points.iter().map(|p| p.outcome.as_ref().is_ok_and(|s| !s.concluded)).collect(),
                not_commanded: r.points.iter().map(|p| p.outcome.as_ref().is_ok_and(|s| !s.as_commanded)).collect(),
                boolean: boolean_words(metric),
            };
            heat_map(path, &h)
        }
        n => Err(format!("cannot draw a sweep of {n} axes")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round() {
        let shown = |v: Vec<f64>| v.into_iter().map(fmt_num).collect::<Vec<_>>().join(" ");
        assert_eq!(shown(ticks(0.0, 1.0, false)), "0 0.2 0.4 0.6 0.8 1");
        assert_eq!(shown(ticks(2.96, 43.9, false)), "10 20 30 40");
        assert_eq!(shown(ticks(3.0, 40.0, true)), "5 10 20");
        assert_eq!(ticks(1e6, 1e8, true), vec![1e6, 2e6, 5e6, 1e7, 2e7, 5e7, 1e8]);
    }

    #[test]
    fn log_ticks_are_thin_and_never_fewer_than_two() {
        let shown = |v: Vec<f64>| v.into_iter().map(fmt_num).collect::<Vec<_>>().join(" ");
        // The lowest decade gets its label (plotters' key points started at 0.1).
        assert_eq!(shown(ticks(0.018, 0.33, true)), "0.02 0.05 0.1 0.2");
        // 1-2-5 per decade, not nine labels a decade (`1e6 9e5 8e5 ...` piled up).
        assert_eq!(shown(ticks(2.4e5, 1.1e7, true)), "5e5 1e6 2e6 5e6 1e7");
        // Over many decades, the powers of ten only.
        assert_eq!(ticks(1e-3, 1e3, true).len(), 7);
        // Narrow ranges still get two labels.
        for (lo, hi) in [(0.07, 0.1), (0.12, 0.18), (3.0, 4.0), (101.0, 102.0), (0.95, 1.05)] {
            let t = ticks(lo, hi, true);
            assert!(t.len() >= 2 && t.len() <= 12, "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|&v| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9)), "{lo}..{hi}: {t:?}");
        }
    }
}
