//! One renderer for every line chart Flinch draws (run histories, sweeps, validation figures):
//! stacked panels over a shared x axis, each with its legend in a column beside the data (never
//! over it), linear or logarithmic axes (plotters' `log_scale`, ticks at round values), step lines
//! for discrete quantities, vertical event marks, horizontal reference lines and annotated points.
//! SVG or PNG by the file's extension; the same picture either way.

use crate::font;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

pub type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Solid line.
    Line,
    /// Solid line with a marker at every point (few points: sweeps).
    LineMarked,
    /// Dashed line (a formula beside simulated points).
    Dashed,
    /// Markers only.
    Points,
    /// Crosses only (a failed or refused point).
    Crosses,
    /// A step function: each value holds until the next point (modes, switch levels).
    Steps,
    /// Thin line (measured data under the simulated).
    Thin,
    /// An open ring around the point (a NOT SAFE point of a sweep).
    Ring,
    /// An open diamond (a point not concluded).
    Diamond,
    /// A hollow circle (a point not simulated as commanded).
    Hollow,
}

/// A diamond of half-size `r` px around `(x, y)`, open, as a closed path.
fn diamond((x, y): (i32, i32), r: i32) -> Vec<(i32, i32)> {
    vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y), (x, y - r)]
}

/// A named series; points whose x or y is not finite break the line.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text (empty: not in the legend).
    pub name: String,
    /// (x, y) in the axes' own units.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Style.
    pub style: Style,
}

/// A vertical line across the panel at x, with a legend entry.
#[derive(Debug, Clone)]
pub struct Mark {
    /// x.
    pub x: f64,
    /// Legend text.
    pub label: String,
    /// Colour.
    pub color: RGBColor,
}

/// A horizontal reference line, labelled at its right end inside the plot.
#[derive(Debug, Clone)]
pub struct Level {
    /// y.
    pub y: f64,
    /// Text.
    pub label: String,
    /// Colour.
    pub color: RGBColor,
}

/// A marked point with a text beside it (a reported peak).
#[derive(Debug, Clone)]
pub struct Note {
    /// Where.
    pub at: (f64, f64),
    /// Text.
    pub text: String,
    /// Colour.
    pub color: RGBColor,
}

/// One panel.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Caption above the panel.
    pub caption: String,
    /// Y label, with unit.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// Vertical marks.
    pub marks: Vec<Mark>,
    /// Horizontal levels.
    pub levels: Vec<Level>,
    /// Annotated points.
    pub notes: Vec<Note>,
    /// Logarithmic y (non-positive values are left out).
    pub y_log: bool,
    /// y range to use instead of the data's (e.g. 0..1 for levels).
    pub y_range: Option<(f64, f64)>,
    /// Tick labels for y instead of numbers (value, text), e.g. the working modes.
    pub y_ticks: Vec<(f64, String)>,
    /// Relative height (1.0 = a normal panel).
    pub weight: f64,
}

/// The shared x axis.
#[derive(Debug, Clone)]
pub struct XAxis {
    /// Label, with unit.
    pub label: String,
    /// Logarithmic.
    pub log: bool,
}

/// A palette distinguishable in print and by colour-blind readers (Okabe-Ito, with black).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

/// Width of the legend column, px.
const LEGEND_W: u32 = 270;

/// A number for tick labels: short, exponent when large or small.
pub fn fmt_num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{x:.1e}");
        s.replace(".0e", "e")
    } else if a >= 100.0 {
        format!("{x:.0}")
    } else {
        let s = if a >= 1.0 { format!("{x:.2}") } else { format!("{x:.4}") };
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The range of the finite values, padded by 5 % (a constant series gets a band around it).
pub fn finite_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 * lo.abs().max(1.0) {
        let pad = lo.abs().max(1.0) * 0.05;
        return (lo - pad, hi + pad);
    }
    let pad = (hi - lo) * 0.05;
    (lo - pad, hi + pad)
}

/// A positive range for a log axis: the finite positive values, padded by a few percent in ratio.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    if hi / lo < 1.0 + 1e-9 {
        return (lo / 1.5, hi * 1.5);
    }
    let pad = (hi / lo).powf(0.04);
    (lo / pad, hi * pad)
}

/// Calls `f` with the drawing area of `path` (.svg or .png).
pub fn with_backend(path: &Path, size: (u32, u32), svg: &dyn Fn(&DrawingArea<SVGBackend, Shift>) -> DrawResult, png: &dyn Fn(&DrawingArea<BitMapBackend, Shift>) -> DrawResult) -> Result<(), String> {
    font::ensure();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext != "svg" && ext != "png" {
        return Err(format!("{}: the plot file must end in .svg or .png", path.display()));
    }
    // Drawn to a temporary file beside `path` and renamed over it when complete (crate::writer).
    crate::writer::via_temp(path, |to| {
        let res = if ext == "svg" { svg(&SVGBackend::new(to, size).into_drawing_area()) } else { png(&BitMapBackend::new(to, size).into_drawing_area()) };
        res.map_err(|e| format!("{}: could not draw the plot: {e}", path.display()))
    })
}

/// Checks a plot file name before any work is done.
pub fn check_extension(path: &Path) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext == "svg" || ext == "png" { Ok(()) } else { Err(format!("{}: the plot file must end in .svg or .png", path.display())) }
}

/// Draws stacked panels sharing an x axis into `path`.
pub fn draw(path: &Path, title: &str, x: &XAxis, panels: &[Panel]) -> Result<(), String> {
    let weights: f64 = panels.iter().map(|p| if p.weight > 0.0 { p.weight } else { 1.0 }).sum();
    let h = 50 + (300.0 * weights) as u32;
    with_backend(path, (1150, h), &|r| draw_on(r, title, x, panels), &|r| draw_on(r, title, x, panels))
}

/// Draws the panels onto `root`.
/// Draws `title` centred at the top of `root`, one line per `\n` (a scene's name, then what was
/// simulated), and returns the area below it.
pub fn titled<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str, size: u32) -> Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>>
where
    DB::ErrorType: 'static,
{
    let lines: Vec<&str> = title.lines().collect();
    if lines.len() <= 1 {
        return root.titled(title, ("sans-serif", size));
    }
    let (w, _) = root.dim_in_pixel();
    let step = size as i32 + 6;
    for (i, l) in lines.iter().enumerate() {
        // The first line at the title's size, the rest a little smaller.
        let s = if i == 0 { size } else { size.saturating_sub(3).max(10) };
        let style = TextStyle::from(("sans-serif", s).into_font()).pos(plotters::style::text_anchor::Pos::new(plotters::style::text_anchor::HPos::Center, plotters::style::text_anchor::VPos::Top));
        root.draw(&Text::new(l.to_string(), (w as i32 / 2, 4 + step * i as i32), style))?;
    }
    Ok(root.split_vertically((step * lines.len() as i32 + 8) as u32).1)
}

pub fn draw_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str, x: &XAxis, panels: &[Panel]) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = titled(root, title, 20)?;
    let xs = panels.iter().flat_map(|p| p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)).chain(p.marks.iter().map(|m| m.x)));
    let (x0, x1) = if x.log { log_range(xs) } else { let (a, b) = finite_range(xs); tight(a, b, panels) };
    let total: f64 = panels.iter().map(|p| if p.weight > 0.0 { p.weight } else { 1.0 }).sum();
    let (_, height) = root.dim_in_pixel();
    let mut rest = root;
    for (k, p) in panels.iter().enumerate() {
        let w = if p.weight > 0.0 { p.weight } else { 1.0 };
        let area = if k + 1 == panels.len() {
            rest.clone()
        } else {
            let (a, b) = rest.split_vertically((height as f64 * w / total) as u32);
            rest = b;
            a
        };
        let (plot_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0 - LEGEND_W);
        let ys = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)).chain(p.levels.iter().map(|l| l.y)).chain(p.notes.iter().map(|n| n.at.1));
        let (y0, y1) = p.y_range.unwrap_or_else(|| if p.y_log { log_range(ys) } else { finite_range(ys) });
        match (x.log, p.y_log) {
            (false, false) => panel(&plot_area, x, p, x0..x1, y0..y1)?,
            // Log axes labelled at round values only: 1-2-5 per decade, at least two labels
            // (plotters' own key points put nine in every decade and none below the first power).
            (true, false) => panel(&plot_area, x, p, (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)), y0..y1)?,
            (false, true) => panel(&plot_area, x, p, x0..x1, (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)))?,
            (true, true) => panel(&plot_area, x, p, (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)), (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)))?,
        }
        legend(&legend_area, p)?;
    }
    Ok(())
}

fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    ticks(lo, hi, true)
}

/// A time axis starts at its data (no padding before t = 0).
fn tight(a: f64, b: f64, panels: &[Panel]) -> (f64, f64) {
    let lo = panels.iter().flat_map(|p| p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0))).filter(|v| v.is_finite()).fold(f64::INFINITY, f64::min);
    let hi = panels.iter().flat_map(|p| p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0))).filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, f64::max);
    if lo.is_finite() && hi > lo { (lo, hi) } else { (a, b) }
}

fn runs(points: &[(f64, f64)], xlog: bool, ylog: bool) -> Vec<Vec<(f64, f64)>> {
    let ok = |q: &(f64, f64)| q.0.is_finite() && q.1.is_finite() && (!xlog || q.0 > 0.0) && (!ylog || q.1 > 0.0);
    let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for q in points {
        if ok(q) {
            if let Some(last) = out.last_mut() {
                last.push(*q);
            }
        } else if out.last().is_some_and(|r| !r.is_empty()) {
            out.push(Vec::new());
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

fn panel<DB: DrawingBackend, X, Y>(area: &DrawingArea<DB, Shift>, x: &XAxis, p: &Panel, xr: X, yr: Y) -> DrawResult
where
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area).caption(&p.caption, ("sans-serif", 16)).margin(8).margin_right(16).x_label_area_size(42).y_label_area_size(78).build_cartesian_2d(xr, yr)?;
    let (xa, xb) = (chart.x_range().start, chart.x_range().end);
    let (ya, yb) = (chart.y_range().start, chart.y_range().end);
    let yticks = p.y_ticks.clone();
    // A tick stepped onto zero in floating point (-5.6e-17) is zero: snap anything below 1e-9 of
    // the axis span.
    let snap = |v: f64, a: f64, b: f64| if v.abs() < 1e-9 * (b - a).abs() { 0.0 } else { v };
    let ylab = move |v: &f64| yticks.iter().find(|(t, _)| (t - v).abs() < 1e-9).map_or_else(|| if yticks.is_empty() { fmt_num(snap(*v, ya, yb)) } else { String::new() }, |(_, s)| s.clone());
    let xlab = move |v: &f64| fmt_num(snap(*v, xa, xb));
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(&x.label).y_desc(&p.y_label).x_label_formatter(&xlab).y_label_formatter(&ylab).label_style(("sans-serif", 13)).axis_desc_style(("sans-serif", 14)).light_line_style(RGBColor(247, 247, 247)).bold_line_style(RGBColor(220, 220, 220));
    if !p.y_ticks.is_empty() {
        mesh.y_labels(p.y_ticks.len().max(2) * 4);
    }
    mesh.draw()?;
    // Backend coordinates are the root's; text goes into this area, whose origin is elsewhere.
    let base = area.get_base_pixel();
    let local = |p: (i32, i32)| (p.0 - base.0, p.1 - base.1);
    for lv in &p.levels {
        let c = lv.color;
        chart.draw_series(DashedLineSeries::new(vec![(xa, lv.y), (xb, lv.y)], 8, 5, c.stroke_width(1)))?;
        // At the left end, on a white box: a trace (travel rising to the threshold) is usually at
        // rest there, and it never hides the label.
        let pos = local(chart.backend_coord(&(xa, lv.y)));
        let font = ("sans-serif", 12).into_font();
        let (tw, th) = area.estimate_text_size(&lv.label, &TextStyle::from(font.clone())).unwrap_or((6 * lv.label.len() as u32, 12));
        let (x0, y0) = (pos.0 + 8, pos.1 - 4 - th as i32);
        area.draw(&Rectangle::new([(x0 - 2, y0 - 1), (x0 + tw as i32 + 2, y0 + th as i32 + 1)], WHITE.mix(0.85).filled()))?;
        area.draw(&Text::new(lv.label.clone(), (x0, y0), font.color(&c).pos(plotters::style::text_anchor::Pos::new(plotters::style::text_anchor::HPos::Left, plotters::style::text_anchor::VPos::Top))))?;
    }
    for m in &p.marks {
        chart.draw_series(LineSeries::new(vec![(m.x, ya), (m.x, yb)], m.color.stroke_width(1)))?;
    }
    for s in &p.series {
        let c = s.color;
        for run in runs(&s.points, x.log, p.y_log) {
            match s.style {
                Style::Line => { chart.draw_series(LineSeries::new(run, c.stroke_width(2)))?; }
                Style::Thin => { chart.draw_series(LineSeries::new(run, c.mix(0.8).stroke_width(1)))?; }
                Style::LineMarked => { chart.draw_series(LineSeries::new(run, c.stroke_width(2)).point_size(3))?; }
                Style::Dashed => { chart.draw_series(DashedLineSeries::new(run, 7, 5, c.stroke_width(2)))?; }
                Style::Points => { chart.draw_series(run.iter().map(|&q| Circle::new(q, 4, c.filled())))?; }
                Style::Crosses => { chart.draw_series(run.iter().map(|&q| Cross::new(q, 6, c.stroke_width(2))))?; }
                Style::Ring => { chart.draw_series(run.iter().map(|&q| Circle::new(q, 9, c.stroke_width(2))))?; }
                Style::Hollow => { chart.draw_series(run.iter().map(|&q| Circle::new(q, 6, c.stroke_width(2))))?; }
                Style::Diamond => { chart.draw_series(run.iter().map(|&q| EmptyElement::at(q) + PathElement::new(diamond((0, 0), 8), c.stroke_width(2))))?; }
                Style::Steps => {
                    let mut st = Vec::with_capacity(run.len() * 2);
                    for (i, &(a, b)) in run.iter().enumerate() {
                        if i > 0 {
                            st.push((a, run[i - 1].1));
                        }
                        st.push((a, b));
                    }
                    chart.draw_series(LineSeries::new(st, c.stroke_width(2)))?;
                }
            }
        }
    }
    let mut placed: Vec<(i32, i32)> = Vec::new();
    for n in &p.notes {
        let c = n.color;
        chart.draw_series(std::iter::once(TriangleMarker::new(n.at, 7, c.filled())))?;
        let mut pos = local(chart.backend_coord(&n.at));
        // Two notes at one place: the later one goes below.
        while placed.iter().any(|q| (q.1 - pos.1).abs() < 17 && (q.0 - pos.0).abs() < 220) {
            pos.1 += 17;
        }
        placed.push(pos);
        let (w, _) = area.dim_in_pixel();
        let right = pos.0 > (w as i32) * 2 / 3;
        let anchor = plotters::style::text_anchor::Pos::new(if right { plotters::style::text_anchor::HPos::Right } else { plotters::style::text_anchor::HPos::Left }, plotters::style::text_anchor::VPos::Center);
        // On a white box, so a trace under it does not garble it.
        let font = ("sans-serif", 13).into_font();
        let (tw, th) = area.estimate_text_size(&n.text, &TextStyle::from(font.clone())).unwrap_or((7 * n.text.len() as u32, 13));
        let x0 = if right { pos.0 - 10 - tw as i32 } else { pos.0 + 10 };
        area.draw(&Rectangle::new([(x0 - 2, pos.1 - th as i32 / 2 - 1), (x0 + tw as i32 + 2, pos.1 + th as i32 / 2 + 1)], WHITE.mix(0.85).filled()))?;
        area.draw(&Text::new(n.text.clone(), (pos.0 + if right { -10 } else { 10 }, pos.1), font.color(&c).pos(anchor)))?;
    }
    Ok(())
}

fn legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut y = 40;
    let mut entry = |label: &str, c: RGBColor, style: Style| -> DrawResult {
        if label.is_empty() {
            return Ok(());
        }
        let (x0, x1, ym) = (4, 32, y + 7);
        match style {
            Style::Dashed => area.draw(&PathElement::new(vec![(x0, ym), (x0 + 10, ym)], c.stroke_width(2))).and_then(|_| area.draw(&PathElement::new(vec![(x0 + 17, ym), (x1, ym)], c.stroke_width(2))))?,
            Style::Points => area.draw(&Circle::new(((x0 + x1) / 2, ym), 4, c.filled()))?,
            Style::Crosses => area.draw(&Cross::new(((x0 + x1) / 2, ym), 6, c.stroke_width(2)))?,
            Style::Ring => area.draw(&Circle::new(((x0 + x1) / 2, ym), 8, c.stroke_width(2)))?,
            Style::Hollow => area.draw(&Circle::new(((x0 + x1) / 2, ym), 6, c.stroke_width(2)))?,
            Style::Diamond => area.draw(&PathElement::new(diamond(((x0 + x1) / 2, ym), 7), c.stroke_width(2)))?,
            Style::Thin => area.draw(&PathElement::new(vec![(x0, ym), (x1, ym)], c.stroke_width(1)))?,
            _ => area.draw(&PathElement::new(vec![(x0, ym), (x1, ym)], c.stroke_width(2)))?,
        }
        // Long labels wrap onto a second line.
        let words: Vec<&str> = label.split(' ').collect();
        let mut lines = vec![String::new()];
        for w in words {
            let cur = lines.last_mut().expect("never empty");
            if !cur.is_empty() && cur.len() + w.len() > 30 {
                lines.push(w.to_string());
            } else {
                if !cur.is_empty() {
                    cur.push(' ');
                }
                cur.push_str(w);
            }
        }
        for line in lines {
            area.draw(&Text::new(line, (x1 + 8, y), ("sans-serif", 13).into_font().color(&BLACK)))?;
            y += 17;
        }
        y += 4;
        Ok(())
    };
    for s in &p.series {
        entry(&s.name, s.color, s.style)?;
    }
    for m in &p.marks {
        entry(&m.label, m.color, Style::Thin)?;
    }
    Ok(())
}

/// Round tick values over [lo, hi]: 1-2-5 steps, or 1-2-5 per decade on a log scale.
pub fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    if log && lo > 0.0 {
        // The sparsest of 1 / 1-2-5 / 1-2-3-5-7 / 1..9 per decade that labels at least two values
        // (1 alone only over more than four decades); within less than a decade, linear round
        // values.
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let sets: [&[f64]; 4] = [&[1.0], &[1.0, 2.0, 5.0], &[1.0, 2.0, 3.0, 5.0, 7.0], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]];
        let first = if b - a > 4 { 0 } else { 1 };
        for per in &sets[first..] {
            let mut out = Vec::new();
            for e in a..=b {
                for m in per.iter() {
                    let v = m * 10f64.powi(e);
                    if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                        out.push(v);
                    }
                }
            }
            if out.len() >= 2 {
                return out;
            }
        }
        let lin = ticks(lo, hi, false);
        return if lin.len() >= 2 { lin } else { vec![lo, hi] };
    }
    let raw = (hi - lo) / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() * step;
    (0..).map(|k| first + k as f64 * step).take_while(|v| *v <= hi + step * 1e-9).map(|v| if v.abs() < step * 1e-9 { 0.0 } else { v }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The text of every `<text>` element of an SVG.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text").skip(1).filter_map(|t| t.split_once('>').and_then(|(_, r)| r.split_once("</text>")).map(|(x, _)| x.trim().to_string())).collect()
    }

    #[test]
    fn log_axes_are_labelled_1_2_5_per_decade_with_the_lowest_decade() {
        let dir = std::env::temp_dir().join(format!("flinch-logaxis-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("log.svg");
        // x over 0.018..0.33 (as a log speed sweep), y over 2.6e5..1.04e7 (k_r against a joint).
        let pts: Vec<(f64, f64)> = (0..50).map(|i| {
            let u = i as f64 / 49.0;
            (0.018 * (0.33f64 / 0.018).powf(u), 2.6e5 * (1.04e7f64 / 2.6e5).powf(u))
        }).collect();
        let p = Panel { caption: "k".into(), y_label: "k [N/m]".into(), y_log: true, series: vec![Series { name: "k".into(), points: pts, color: RGBColor(0, 0, 0), style: Style::Line }], ..Default::default() };
        draw(&path, "log axes", &XAxis { label: "v [m/s]".into(), log: true }, &[p]).unwrap();
        let t = texts(&std::fs::read_to_string(&path).unwrap());
        let _ = std::fs::remove_dir_all(&dir);
        for want in ["0.02", "0.05", "0.1", "0.2", "5e5", "1e6", "2e6", "5e6", "1e7"] {
            assert!(t.iter().any(|x| x == want), "label {want} missing: {t:?}");
        }
        for not in ["0.03", "0.04", "0.09", "9e5", "8e5", "3e6", "9e6"] {
            assert!(!t.iter().any(|x| x == not), "label {not} piles up between the round ones: {t:?}");
        }
    }
}
