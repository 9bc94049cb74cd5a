//! The path over the interpolated field, like the thesis's Fig. 88-90: `f*` (evaluation sigma) at the
//! moment of minimum clearance as a colour map, the operator's outline then, the whole path, start and
//! goal. SVG or PNG by the file extension.

use std::path::Path;

use plotters::prelude::*;

use crate::path::PathResult;
use crate::scene::Avoid;

fn colour(v: f64, max: f64) -> RGBColor {
    // Dark blue (plane) -> teal -> yellow (top of the hill).
    let a = if max > 0.0 { (v / max).clamp(0.0, 1.0) } else { 0.0 };
    let lerp = |x: f64, y: f64, t: f64| (x + (y - x) * t) as u8;
    if a < 0.5 {
        let t = a / 0.5;
        RGBColor(lerp(20.0, 30.0, t), lerp(30.0, 150.0, t), lerp(90.0, 140.0, t))
    } else {
        let t = (a - 0.5) / 0.5;
        RGBColor(lerp(30.0, 250.0, t), lerp(150.0, 230.0, t), lerp(140.0, 40.0, t))
    }
}

/// Draw `res` for `scene` into `out` (`.svg` or `.png`).
pub fn plot(scene: &Avoid, res: &PathResult, out: &Path) -> Result<(), String> {
    let is_svg = match out.extension().and_then(|e| e.to_str()) {
        Some("svg") => true,
        Some("png") => false,
        _ => return Err(format!("{}: --plot wants a .svg or .png file", out.display())),
    };
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", out.display());
    if is_svg {
        let root = SVGBackend::new(out, (900, 820)).into_drawing_area();
        draw(scene, res, root).map_err(|e| err(&e))
    } else {
        let root = BitMapBackend::new(out, (900, 820)).into_drawing_area();
        draw(scene, res, root).map_err(|e| err(&e))
    }
}

fn draw<DB: DrawingBackend>(scene: &Avoid, res: &PathResult, root: DrawingArea<DB, plotters::coord::Shift>) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (w, h) = scene.extent_m();
    let snap = &res.snapshot;
    let title = format!(
        "{}{}: min {:.0} mm, {} steps over SSM{} | f* (sigma' {:.2} sigma) at t = {:.2} s",
        res.status.name(),
        res.status.reason().map_or(String::new(), |r| format!(" ({})", r.name())),
        res.min_signed_distance_m * 1e3,
        res.ssm_violations,
        if res.pfl.is_some() { format!(" and PFL, {} within PFL", res.steps_in_pfl) } else { String::new() },
        scene.fit.eval_sigma_factor,
        snap.t_s
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 17))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..w, 0.0..h)
        .map_err(e)?;
    chart.configure_mesh().x_desc("x [m]").y_desc("y [m]").disable_mesh().draw().map_err(e)?;

    // Field as cells of a raster at most 105 px a side (enough for the eye, small SVG).
    let n = 105usize;
    let (cw, ch) = (w / n as f64, h / n as f64);
    let mut max = 0.0f64;
    let mut vals = Vec::with_capacity(n * n);
    for r in 0..n {
        for c in 0..n {
            let v = snap.field.sample((c as f64 + 0.5) * cw, (r as f64 + 0.5) * ch).0;
            max = max.max(v);
            vals.push(v);
        }
    }
    chart
        .draw_series((0..n * n).map(|k| {
            let (r, c) = (k / n, k % n);
            let (x, y) = (c as f64 * cw, r as f64 * ch);
            Rectangle::new([(x, y), (x + cw, y + ch)], colour(vals[k], max).filled())
        }))
        .map_err(e)?;

    // Operator outline at the snapshot: forearm segment and hand circle.
    let op = scene.operator_shape();
    let red = RGBColor(230, 40, 40);
    chart
        .draw_series(std::iter::once(PathElement::new(vec![(op.entry_m[0], op.entry_m[1]), (snap.hand_m[0], snap.hand_m[1])], red.stroke_width(3))))
        .map_err(e)?;
    let circle: Vec<(f64, f64)> = (0..=48)
        .map(|k| {
            let a = k as f64 / 48.0 * std::f64::consts::TAU;
            (snap.hand_m[0] + op.hand_radius_m * a.cos(), snap.hand_m[1] + op.hand_radius_m * a.sin())
        })
        .collect();
    chart.draw_series(std::iter::once(PathElement::new(circle, red.stroke_width(2)))).map_err(e)?.label("operator at min clearance").legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], red.stroke_width(2)));

    // Obstacles (boxes and discs), where they stand at the snapshot; a moving one also with its
    // path and where it was at every whole second (labelled with the time), as the hand's below.
    let grey = RGBColor(235, 235, 235);
    let t_end = res.rows.last().map_or(0.0, |r| r.t_s);
    for o in &scene.operator.obstacles {
        if o.moves() {
            let cyan = RGBColor(80, 220, 255);
            let steps = (t_end / 0.05).ceil().max(1.0) as usize;
            let trail: Vec<(f64, f64)> = (0..=steps).map(|k| o.center_at(k as f64 * 0.05)).map(|c| (c[0], c[1])).collect();
            chart
                .draw_series(std::iter::once(PathElement::new(trail, cyan.stroke_width(2))))
                .map_err(e)?
                .label("obstacle path (dots every 1 s, tool's in white)")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], cyan.stroke_width(2)));
            // Held after its last key frame: one label there, not a pile.
            let last = o.keyframes.last().map_or(0.0, |k| k.t_s);
            for sec in (0..=(t_end.floor() as usize)).filter(|&s| s as f64 <= last.ceil()) {
                let c = o.center_at(sec as f64);
                chart.draw_series(std::iter::once(Circle::new((c[0], c[1]), 4, cyan.filled()))).map_err(e)?;
                chart.draw_series(std::iter::once(Text::new(format!("{sec}"), (c[0] + 0.012 * w, c[1]), ("sans-serif", 13).into_font().color(&cyan)))).map_err(e)?;
            }
        }
        let o = &o.at(snap.t_s);
        let [cx, cy] = o.center_m;
        if o.kind == "box" {
            let [sx, sy] = o.size_m;
            let r = [(cx - sx / 2.0, cy - sy / 2.0), (cx + sx / 2.0, cy - sy / 2.0), (cx + sx / 2.0, cy + sy / 2.0), (cx - sx / 2.0, cy + sy / 2.0), (cx - sx / 2.0, cy - sy / 2.0)];
            chart.draw_series(std::iter::once(PathElement::new(r.to_vec(), grey.stroke_width(2)))).map_err(e)?;
        } else {
            let c: Vec<(f64, f64)> = (0..=48).map(|k| k as f64 / 48.0 * std::f64::consts::TAU).map(|a| (cx + o.radius_m * a.cos(), cy + o.radius_m * a.sin())).collect();
            chart.draw_series(std::iter::once(PathElement::new(c, grey.stroke_width(2)))).map_err(e)?;
        }
    }

    // A moving hand: its path over the run, and where the hand and the tool were at every whole
    // second (labelled with the time), so that one can see which was where when.
    let moves = scene.operator.keyframes.windows(2).any(|k| k[0].hand_m != k[1].hand_m);
    let tool_dots = |chart: &mut ChartContext<DB, _>, sec: usize| -> Result<(), String> {
        let t = sec as f64;
        let tool = res.points.get(((t / res.dt_s).round() as usize).min(res.points.len().saturating_sub(1))).copied().unwrap_or(scene.start_m);
        chart.draw_series(std::iter::once(Circle::new((tool[0], tool[1]), 3, WHITE.filled()))).map_err(e)?;
        chart.draw_series(std::iter::once(Text::new(format!("{sec}"), (tool[0] + 0.012 * w, tool[1]), ("sans-serif", 13).into_font().color(&WHITE)))).map_err(e)?;
        Ok(())
    };
    if !moves && scene.operator.obstacles.iter().any(|o| o.moves()) {
        for sec in 0..=(t_end.floor() as usize) {
            tool_dots(&mut chart, sec)?;
        }
    }
    if moves {
        let orange = RGBColor(255, 150, 40);
        let steps = (t_end / 0.05).ceil().max(1.0) as usize;
        let trail: Vec<(f64, f64)> = (0..=steps).map(|k| scene.hand_at(k as f64 * 0.05)).map(|h| (h[0], h[1])).collect();
        chart
            .draw_series(std::iter::once(PathElement::new(trail, orange.stroke_width(2))))
            .map_err(e)?
            .label("hand path (dots: hand and tool every 1 s)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], orange.stroke_width(2)));
        for sec in 0..=(t_end.floor() as usize) {
            let t = sec as f64;
            let h = scene.hand_at(t);
            let label = format!("{sec}");
            chart.draw_series(std::iter::once(Circle::new((h[0], h[1]), 4, orange.filled()))).map_err(e)?;
            chart.draw_series(std::iter::once(Text::new(label, (h[0] + 0.012 * w, h[1]), ("sans-serif", 13).into_font().color(&orange)))).map_err(e)?;
            tool_dots(&mut chart, sec)?;
        }
    }

    // The path, start, goal, tool at the snapshot.
    chart
        .draw_series(std::iter::once(PathElement::new(res.points.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>(), WHITE.stroke_width(2))))
        .map_err(e)?
        .label("tool path")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    // Steps carried by PFL (beyond the SSM bound, within the PFL speeds: small yellow dots), where
    // the run's own verdict failed: steps faster towards the person than the SSM bound at the true
    // separation allows and beyond PFL (red crosses at the step's start), and steps whose swept
    // segment entered an obstacle (red dots at the step's end).
    let yellow = RGBColor(250, 220, 40);
    let pfl: Vec<(f64, f64)> = res.rows.iter().enumerate().filter(|(_, w)| w.beyond_ssm == Some(true)).map(|(k, _)| (res.points[k][0], res.points[k][1])).collect();
    if !pfl.is_empty() {
        chart
            .draw_series(pfl.into_iter().map(|p| Circle::new(p, 2, yellow.filled())))
            .map_err(e)?
            .label("step beyond the SSM bound, within PFL (allowed)")
            .legend(move |(x, y)| Circle::new((x + 9, y), 2, yellow.filled()));
    }
    let over: Vec<(f64, f64)> = res.rows.iter().enumerate().filter(|(_, w)| w.beyond_ssm == Some(false)).map(|(k, _)| (res.points[k][0], res.points[k][1])).collect();
    if !over.is_empty() {
        chart
            .draw_series(over.into_iter().map(|p| Cross::new(p, 5, red.stroke_width(2))))
            .map_err(e)?
            .label("over the SSM bound and beyond PFL (true separation)")
            .legend(move |(x, y)| Cross::new((x + 9, y), 5, red.stroke_width(2)));
    }
    let inside: Vec<(f64, f64)> = res.rows.iter().filter(|w| w.swept_separation_m < 0.0).map(|w| (w.p_m[0], w.p_m[1])).collect();
    if !inside.is_empty() {
        chart
            .draw_series(inside.into_iter().map(|p| Circle::new(p, 3, red.filled())))
            .map_err(e)?
            .label("step entered an obstacle (swept)")
            .legend(move |(x, y)| Circle::new((x + 9, y), 3, red.filled()));
    }
    chart.draw_series(std::iter::once(Circle::new((scene.start_m[0], scene.start_m[1]), 6, GREEN.filled()))).map_err(e)?.label("start").legend(|(x, y)| Circle::new((x + 9, y), 5, GREEN.filled()));
    chart.draw_series(std::iter::once(Cross::new((scene.goal_m[0], scene.goal_m[1]), 8, MAGENTA.stroke_width(3)))).map_err(e)?.label("goal").legend(|(x, y)| Cross::new((x + 9, y), 5, MAGENTA.stroke_width(2)));
    chart.draw_series(std::iter::once(Circle::new((snap.tool_m[0], snap.tool_m[1]), 5, WHITE.stroke_width(2)))).map_err(e)?;
    // The robot at the snapshot (issue 29 item 3): its link from the base to the tool, clipped to
    // the view (the base may stand beyond it), and its wrist disc to scale.
    let robot = RGBColor(215, 215, 215);
    if let Some((a, b)) = clip_to_view(scene.robot.base_m, snap.tool_m, w, h) {
        chart
            .draw_series(std::iter::once(PathElement::new(vec![(a[0], a[1]), (b[0], b[1])], robot.mix(0.6).stroke_width(5))))
            .map_err(e)?
            .label(format!("robot link ({:.0} mm wide) and wrist at min clearance", scene.robot.link_width_m * 1e3))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RGBColor(110, 110, 110).stroke_width(5)));
    }
    let wrist: Vec<(f64, f64)> = (0..=48)
        .map(|k| {
            let a = k as f64 / 48.0 * std::f64::consts::TAU;
            (snap.tool_m[0] + scene.robot.wrist_radius_m * a.cos(), snap.tool_m[1] + scene.robot.wrist_radius_m * a.sin())
        })
        .collect();
    chart.draw_series(std::iter::once(PathElement::new(wrist, robot.stroke_width(2)))).map_err(e)?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// The part of the segment `a`-`b` inside the view `[0, w] x [0, h]` (Liang-Barsky), if any.
fn clip_to_view(a: [f64; 2], b: [f64; 2], w: f64, h: f64) -> Option<([f64; 2], [f64; 2])> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a[0]), (dx, w - a[0]), (-dy, a[1]), (dy, h - a[1])] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| ([a[0] + t0 * dx, a[1] + t0 * dy], [a[0] + t1 * dx, a[1] + t1 * dy]))
}

#[cfg(test)]
mod tests {
    use super::clip_to_view;

    #[test]
    fn the_link_is_clipped_to_the_view() {
        let (a, b) = clip_to_view([0.5, 1.5], [0.5, 0.5], 1.0, 1.0).unwrap();
        assert_eq!((a, b), ([0.5, 1.0], [0.5, 0.5]));
        assert!(clip_to_view([2.0, 2.0], [3.0, 3.0], 1.0, 1.0).is_none());
        assert_eq!(clip_to_view([0.2, 0.2], [0.4, 0.4], 1.0, 1.0), Some(([0.2, 0.2], [0.4, 0.4])));
    }
}
