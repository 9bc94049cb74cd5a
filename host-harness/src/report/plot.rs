//! Plots of a run the way the thesis draws them (Fig. 39-41, 47): (a) velocities x_c', x_r', x_t'
//! (and x_p') against time, (b) the contact force and the force on the robot, both with the
//! contact, detection and braking instants marked. SVG or PNG by the file's extension.

use crate::sim::{Sample, Summary};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Draws the two panels into `path` (.svg or .png).
pub fn draw(path: &Path, summary: &Summary, history: &[Sample], object: bool, rigid_robot: bool) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let size = (1000, 800);
    let res = match ext.as_str() {
        "svg" => panels(&SVGBackend::new(path, size).into_drawing_area(), summary, history, object, rigid_robot),
        "png" => panels(&BitMapBackend::new(path, size).into_drawing_area(), summary, history, object, rigid_robot),
        _ => return Err(format!("{}: the plot file must end in .svg or .png", path.display())),
    };
    res.map_err(|e| format!("{}: could not draw the plot: {e}", path.display()))
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The range of the finite values, padded by 5 % (a constant series gets a band around it).
pub(crate) fn finite_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
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

fn panels<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, s: &Summary, h: &[Sample], object: bool, rigid_robot: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(400);
    let t_end = h.last().map_or(1.0, |x| x.t);
    let marks: Vec<(f64, &str, RGBColor)> = [(s.t_contact, "contact", RGBColor(120, 120, 120)), (s.t_detect, "detection", RGBColor(200, 120, 0)), (s.t_brake, "braking", RGBColor(180, 0, 0))]
        .into_iter()
        .filter_map(|(t, n, c)| t.map(|t| (t, n, c)))
        .collect();

    // (a) velocities
    let mut vel: Vec<(&str, RGBColor, Box<dyn Fn(&Sample) -> f64>)> = vec![("x_c' commanded", RGBColor(0, 0, 0), Box::new(|x: &Sample| x.v_c))];
    if !rigid_robot {
        vel.push(("x_r' robot", RGBColor(0, 90, 200), Box::new(|x: &Sample| x.v_r)));
    }
    vel.push(("x_t' tool", RGBColor(220, 60, 0), Box::new(|x: &Sample| x.v_t)));
    if object {
        vel.push(("x_p' object", RGBColor(0, 150, 60), Box::new(|x: &Sample| x.v_p)));
    }
    let (lo, hi) = finite_range(vel.iter().flat_map(|(_, _, f)| h.iter().map(f)));
    let mut chart = ChartBuilder::on(&top)
        .caption(format!("{}: velocities", s.scene), ("sans-serif", 18))
        .margin(10).x_label_area_size(35).y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart.configure_mesh().x_desc("t [s]").y_desc("velocity [m/s]").draw()?;
    for (name, color, f) in &vel {
        chart.draw_series(LineSeries::new(h.iter().map(|x| (x.t, f(x))), color.stroke_width(2)))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    for &(t, name, c) in &marks {
        chart.draw_series(LineSeries::new(vec![(t, lo), (t, hi)], c.stroke_width(1)))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;

    // (b) forces, drawn positive as the thesis does (Fig. 39b, 40b)
    let (lo, hi) = finite_range(h.iter().flat_map(|x| [x.f_contact, x.f_robot.abs(), 0.0]));
    let mut chart = ChartBuilder::on(&bottom)
        .caption("contact force and force on the robot", ("sans-serif", 18))
        .margin(10).x_label_area_size(35).y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart.configure_mesh().x_desc("t [s]").y_desc("force [N]").draw()?;
    let fc = RGBColor(200, 0, 120);
    let fr = RGBColor(0, 90, 200);
    chart.draw_series(LineSeries::new(h.iter().map(|x| (x.t, x.f_contact)), fc.stroke_width(2)))?
        .label(format!("contact force (peak {:.1} N)", s.peak_contact_force))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], fc.stroke_width(2)));
    chart.draw_series(LineSeries::new(h.iter().map(|x| (x.t, x.f_robot.abs())), fr.stroke_width(2)))?
        .label(format!("|force on robot| (peak {:.1} N)", s.peak_robot_force))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], fr.stroke_width(2)));
    for &(t, _, c) in &marks {
        chart.draw_series(LineSeries::new(vec![(t, lo), (t, hi)], c.stroke_width(1)))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(())
}
