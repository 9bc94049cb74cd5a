//! Pictures of sweeps: line charts for one axis, heat maps with the working-mode regions of
//! Fig. 46 outlined for two. SVG or PNG by the file's extension. Log axes are drawn on log10 of the
//! value, labelled with the value itself.

use super::{Spacing, SweepResult};
use plotters::coord::Shift;
use crate::report::plot::finite_range;
use plotters::prelude::*;
use std::path::Path;

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// One horizontal axis: its label and whether it is logarithmic.
#[derive(Debug, Clone)]
pub struct XAxis {
    /// Label, with unit.
    pub label: String,
    /// Draw on log10.
    pub log: bool,
}

impl XAxis {
    fn fwd(&self, x: f64) -> f64 {
        if self.log { x.log10() } else { x }
    }
    fn label_of(&self, u: f64) -> String {
        fmt_num(if self.log { 10f64.powf(u) } else { u })
    }
}

/// A number for tick labels: short, exponent when large or small.
pub fn fmt_num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{x:.1e}")
    } else if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 1.0 {
        let s = format!("{x:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{x:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Solid line with markers at the points.
    Line,
    /// Dashed line, no markers (a formula drawn beside simulated points).
    Dashed,
    /// Markers only.
    Points,
}

/// A named series of (x, y) points; NaN y values break the line.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// The points, x in the axis's own units (not log10).
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Line style.
    pub style: Style,
}

/// One panel of a line chart.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Panel caption.
    pub caption: String,
    /// Y label, with unit.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Vertical marks (x, label).
    pub marks: Vec<(f64, String)>,
    /// Draw y on log10.
    pub y_log: bool,
}

/// A palette for series, distinguishable in print.
pub const PALETTE: [RGBColor; 6] = [RGBColor(0, 90, 200), RGBColor(200, 0, 120), RGBColor(0, 150, 60), RGBColor(220, 120, 0), RGBColor(110, 60, 170), RGBColor(0, 0, 0)];

fn backend(path: &Path, size: (u32, u32), f: &dyn Fn(&DrawingArea<SVGBackend, Shift>) -> DrawResult, g: &dyn Fn(&DrawingArea<BitMapBackend, Shift>) -> DrawResult) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let res = match ext.as_str() {
        "svg" => f(&SVGBackend::new(path, size).into_drawing_area()),
        "png" => g(&BitMapBackend::new(path, size).into_drawing_area()),
        _ => return Err(format!("{}: the plot file must end in .svg or .png", path.display())),
    };
    res.map_err(|e| format!("{}: could not draw the plot: {e}", path.display()))
}


/// Draws stacked panels sharing an x axis into `path`.
pub fn lines(path: &Path, title: &str, x: &XAxis, panels: &[Panel]) -> Result<(), String> {
    let h = 60 + 360 * panels.len() as u32;
    backend(path, (1000, h), &|r| lines_on(r, title, x, panels), &|r| lines_on(r, title, x, panels))
}

fn lines_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, title: &str, x: &XAxis, panels: &[Panel]) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    let xs = panels.iter().flat_map(|p| p.series.iter().flat_map(|s| s.points.iter().map(|q| x.fwd(q.0))).chain(p.marks.iter().map(|m| x.fwd(m.0))));
    let (x0, x1) = finite_range(xs);
    for (area, p) in areas.iter().zip(panels) {
        let yf = |y: f64| if p.y_log { if y > 0.0 { y.log10() } else { f64::NAN } } else { y };
        let (y0, y1) = finite_range(p.series.iter().flat_map(|s| s.points.iter().map(|q| yf(q.1))));
        let mut chart = ChartBuilder::on(area).caption(&p.caption, ("sans-serif", 16)).margin(10).x_label_area_size(35).y_label_area_size(70).build_cartesian_2d(x0..x1, y0..y1)?;
        let ylab = |u: &f64| fmt_num(if p.y_log { 10f64.powf(*u) } else { *u });
        chart.configure_mesh().x_desc(&x.label).y_desc(&p.y_label).x_label_formatter(&|u| x.label_of(*u)).y_label_formatter(&ylab).draw()?;
        for s in &p.series {
            let c = s.color;
            let pts: Vec<(f64, f64)> = s.points.iter().map(|&(a, b)| (x.fwd(a), yf(b))).collect();
            // Split at NaN so a missing value breaks the line instead of joining across it.
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for q in &pts {
                if q.1.is_finite() && q.0.is_finite() {
                    runs.last_mut().expect("never empty").push(*q);
                } else if !runs.last().expect("never empty").is_empty() {
                    runs.push(Vec::new());
                }
            }
            let mut first = true;
            for run in runs.iter().filter(|r| !r.is_empty()) {
                let anno = match s.style {
                    Style::Line => chart.draw_series(LineSeries::new(run.clone(), c.stroke_width(2)).point_size(3))?,
                    Style::Dashed => chart.draw_series(DashedLineSeries::new(run.clone(), 6, 4, c.stroke_width(2)))?,
                    Style::Points => chart.draw_series(run.iter().map(|&q| Circle::new(q, 4, c.filled())))?,
                };
                if first {
                    anno.label(&s.name).legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 20, b)], c.stroke_width(2)));
                    first = false;
                }
            }
        }
        for (k, (m, label)) in p.marks.iter().enumerate() {
            let u = x.fwd(*m);
            let red = [RGBColor(120, 120, 120), RGBColor(180, 0, 0), RGBColor(0, 120, 120)][k % 3];
            chart.draw_series(LineSeries::new(vec![(u, y0), (u, y1)], red.stroke_width(2)))?.label(label.as_str()).legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 20, b)], red.stroke_width(2)));
        }
        chart.configure_series_labels().position(SeriesLabelPosition::UpperLeft).background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    }
    root.present()?;
    Ok(())
}

/// Viridis, sampled at nine points and interpolated (the `colormaps` feature of plotters is off).
pub fn viridis(f: f64) -> RGBColor {
    const V: [(u8, u8, u8); 9] = [(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141), (39, 173, 129), (92, 200, 99), (170, 220, 50), (253, 231, 37)];
    let f = if f.is_finite() { f.clamp(0.0, 1.0) } else { 0.0 };
    let x = f * (V.len() - 1) as f64;
    let i = (x.floor() as usize).min(V.len() - 2);
    let t = x - i as f64;
    let lerp = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * t).round() as u8;
    RGBColor(lerp(V[i].0, V[i + 1].0), lerp(V[i].1, V[i + 1].1), lerp(V[i].2, V[i + 1].2))
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
    /// The metric, row-major with x slowest (`z[i * ny + j]` at xs[i], ys[j]); NaN is grey.
    pub z: Vec<f64>,
    /// Colour-bar label.
    pub z_label: String,
    /// Working mode per cell (outlined where it changes), if the decoupler has one.
    pub modes: Vec<Option<u8>>,
    /// Cells where the stroke ran out (crossed).
    pub exhausted: Vec<bool>,
}

/// Cell edges in drawing coordinates: midpoints between values, half a step beyond the ends.
fn edges(ax: &XAxis, v: &[f64]) -> Vec<f64> {
    let u: Vec<f64> = v.iter().map(|&x| ax.fwd(x)).collect();
    let n = u.len();
    let mut e = Vec::with_capacity(n + 1);
    if n == 1 {
        return vec![u[0] - 0.5, u[0] + 0.5];
    }
    e.push(u[0] - 0.5 * (u[1] - u[0]));
    for i in 0..n - 1 {
        e.push(0.5 * (u[i] + u[i + 1]));
    }
    e.push(u[n - 1] + 0.5 * (u[n - 1] - u[n - 2]));
    e
}

/// Draws a heat map into `path`.
pub fn heat_map(path: &Path, h: &HeatMap) -> Result<(), String> {
    backend(path, (1000, 760), &|r| heat_on(r, h), &|r| heat_on(r, h))
}

fn heat_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, h: &HeatMap) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = root.titled(&h.title, ("sans-serif", 20))?;
    let (main, bar) = root.split_horizontally(860);
    let (nx, ny) = (h.xs.len(), h.ys.len());
    let ex = edges(&h.x, &h.xs);
    let ey = edges(&h.y, &h.ys);
    let mut chart = ChartBuilder::on(&main).margin(15).x_label_area_size(45).y_label_area_size(75).build_cartesian_2d(ex[0]..ex[nx], ey[0]..ey[ny])?;
    chart.configure_mesh().disable_mesh().x_desc(&h.x.label).y_desc(&h.y.label).x_label_formatter(&|u| h.x.label_of(*u)).y_label_formatter(&|u| h.y.label_of(*u)).draw()?;
    let (zlo, zhi) = {
        let f: Vec<f64> = h.z.iter().copied().filter(|v| v.is_finite()).collect();
        let lo = f.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() { (lo, if hi > lo { hi } else { lo + 1.0 }) } else { (0.0, 1.0) }
    };
    let grey = RGBColor(190, 190, 190);
    chart.draw_series((0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))).map(|(i, j)| {
        let z = h.z[i * ny + j];
        let c = if z.is_finite() { viridis((z - zlo) / (zhi - zlo)) } else { grey };
        Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], c.filled())
    }))?;
    // Stroke exhausted: a cross in the cell.
    let red = RGBColor(230, 30, 30);
    for i in 0..nx {
        for j in 0..ny {
            if h.exhausted.get(i * ny + j).copied().unwrap_or(false) {
                let (a, b, c, d) = (ex[i] + 0.25 * (ex[i + 1] - ex[i]), ex[i + 1] - 0.25 * (ex[i + 1] - ex[i]), ey[j] + 0.25 * (ey[j + 1] - ey[j]), ey[j + 1] - 0.25 * (ey[j + 1] - ey[j]));
                chart.draw_series(LineSeries::new(vec![(a, c), (b, d)], red.stroke_width(2)))?;
                chart.draw_series(LineSeries::new(vec![(a, d), (b, c)], red.stroke_width(2)))?;
            }
        }
    }
    // Mode boundaries: a thick white-on-black line on every edge between cells of different mode.
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
        // Label each mode region at the centre of its cells.
        for mode in 1..=3u8 {
            let cells: Vec<(usize, usize)> = (0..nx).flat_map(|i| (0..ny).map(move |j| (i, j))).filter(|&(i, j)| m(i, j) == Some(mode)).collect();
            if cells.is_empty() {
                continue;
            }
            // The cell nearest the centroid, so the label sits inside the region.
            let (ci, cj) = cells.iter().fold((0.0, 0.0), |a, &(i, j)| (a.0 + i as f64, a.1 + j as f64));
            let (ci, cj) = (ci / cells.len() as f64, cj / cells.len() as f64);
            let &(i, j) = cells.iter().min_by(|a, b| {
                let da = (a.0 as f64 - ci).powi(2) + (a.1 as f64 - cj).powi(2);
                let db = (b.0 as f64 - ci).powi(2) + (b.1 as f64 - cj).powi(2);
                da.total_cmp(&db)
            }).expect("non-empty");
            let at = (0.5 * (ex[i] + ex[i + 1]), 0.5 * (ey[j] + ey[j + 1]));
            chart.draw_series(std::iter::once(EmptyElement::at(at) + Rectangle::new([(-34, -12), (34, 12)], WHITE.mix(0.85).filled()) + Text::new(format!("mode {mode}"), (-28, -8), ("sans-serif", 16).into_font().color(&BLACK))))?;
        }
    }
    // Colour bar.
    let mut cb = ChartBuilder::on(&bar).margin_top(15).margin_bottom(60).margin_right(55).y_label_area_size(0).right_y_label_area_size(50).x_label_area_size(0).build_cartesian_2d(0.0..1.0, zlo..zhi)?;
    cb.configure_mesh().disable_mesh().disable_x_axis().y_label_formatter(&|v| fmt_num(*v)).y_desc(&h.z_label).draw()?;
    let steps = 100;
    cb.draw_series((0..steps).map(|k| {
        let a = zlo + (zhi - zlo) * k as f64 / steps as f64;
        let b = zlo + (zhi - zlo) * (k + 1) as f64 / steps as f64;
        Rectangle::new([(0.0, a), (1.0, b)], viridis((k as f64 + 0.5) / steps as f64).filled())
    }))?;
    root.present()?;
    Ok(())
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

/// A label for a summary metric, with its unit.
pub fn metric_label(m: &str) -> String {
    let unit = match m {
        "peak_contact_force" | "peak_robot_force" => "N",
        "t_contact" | "t_detect" | "t_brake" | "detection_delay" | "reaction_time" | "t_stop" => "s",
        "object_final_velocity" | "approach_velocity" | "object_peak_velocity" => "m/s",
        "max_travel" => "m",
        "decoupler_impulse" => "N s",
        "peak_gas_pressure" => "Pa",
        _ => "",
    };
    if unit.is_empty() { m.to_string() } else { format!("{m} [{unit}]") }
}

/// The default picture of a sweep: for one axis, peak contact and robot force and the working
/// mode against the value; for two, a heat map of `metric` with the mode regions outlined.
pub fn draw(path: &Path, r: &SweepResult, metric: &str) -> Result<(), String> {
    let axis = |k: usize| XAxis { label: key_label(&r.axes[k].key), log: r.axes[k].spacing == Spacing::Log };
    let title = format!("{}: sweep", r.scene_name);
    match r.axes.len() {
        1 => {
            let xs = &r.values[0];
            let series = |name: &str, m: &str, c: RGBColor| Series { name: name.into(), points: xs.iter().copied().zip(r.metric(m)).collect(), color: c, style: Style::Line };
            let mut force = vec![series("peak contact force", "peak_contact_force", PALETTE[1]), series("peak force on the robot", "peak_robot_force", PALETTE[0])];
            let exhausted: Vec<(f64, f64)> = xs.iter().copied().zip(r.metric("stroke_exhausted")).zip(r.metric("peak_robot_force")).filter(|((_, e), _)| *e == 1.0).map(|((x, _), f)| (x, f)).collect();
            if !exhausted.is_empty() {
                force.push(Series { name: "stroke exhausted (flange reached the target)".into(), points: exhausted, color: RGBColor(230, 30, 30), style: Style::Points });
            }
            let mut panels = vec![Panel { caption: "peak forces".into(), y_label: "force [N]".into(), series: force, marks: vec![], y_log: false }];
            if metric != "peak_robot_force" && metric != "peak_contact_force" {
                panels.push(Panel { caption: metric.into(), y_label: metric_label(metric), series: vec![series(metric, metric, PALETTE[2])], marks: vec![], y_log: false });
            }
            let modes = r.metric("mode");
            if modes.iter().any(|m| m.is_finite()) {
                panels.push(Panel { caption: "working mode (Fig. 46: 1 no back-stop impact, 2 after the robot stopped, 3 before)".into(), y_label: "mode".into(), series: vec![Series { name: "mode".into(), points: xs.iter().copied().zip(modes).collect(), color: PALETTE[5], style: Style::Line }], marks: vec![], y_log: false });
            }
            lines(path, &title, &axis(0), &panels)
        }
        2 => {
            let modes: Vec<Option<u8>> = r.points.iter().map(|p| p.outcome.as_ref().ok().and_then(|s| s.mode)).collect();
            let exhausted: Vec<bool> = r.points.iter().map(|p| p.outcome.as_ref().is_ok_and(|s| s.stroke_exhausted)).collect();
            let h = HeatMap {
                title: format!("{title}: {metric}{}", if exhausted.iter().any(|&e| e) { " (x: stroke exhausted)" } else { "" }),
                x: axis(0),
                xs: r.values[0].clone(),
                y: axis(1),
                ys: r.values[1].clone(),
                z: r.metric(metric),
                z_label: metric_label(metric),
                modes,
                exhausted,
            };
            heat_map(path, &h)
        }
        n => Err(format!("cannot draw a sweep of {n} axes")),
    }
}
