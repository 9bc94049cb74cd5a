//! The picture of one run, the way the thesis draws them (Figs. 39-41, 47, 72-73, 78): velocities,
//! forces (each reported peak marked where the trace tops out, since the summary's peak is found
//! between samples), the decoupler's travel against the switch threshold and the end of the stroke,
//! the gas pressure of a hydraulic module, and with the firmware in the loop its signals: the
//! switch, the stop output and the controller's samples. Contact, detection and braking are marked
//! in every panel; a `--measured` file is drawn under the simulated traces.

use flinch_output::figure::{self, Level, Mark, Note, Panel, Series, Style, XAxis, PALETTE};
use crate::trace::Trace;
use flinch_model::scene::{Decoupler, Scene, Sensor, TargetKind};
use flinch_sim::{Sample, Summary};
use plotters::style::RGBColor;
use std::path::Path;

/// Extra traces over a run: measured columns by convention name.
pub type Overlay = Vec<(String, Vec<(f64, f64)>)>;

const GREY: RGBColor = RGBColor(110, 110, 110);
const MEASURED: RGBColor = RGBColor(150, 150, 150);

fn event_marks(s: &Summary) -> Vec<Mark> {
    [(s.t_contact, "first contact", GREY), (s.t_detect, "detection", RGBColor(230, 159, 0)), (s.t_brake, "braking starts", RGBColor(200, 0, 0))]
        .into_iter()
        .filter_map(|(t, n, c)| t.map(|x| Mark { x, label: n.to_string(), color: c }))
        .collect()
}

/// The end of the stroke (travel at the back stop), m, if the decoupler has one.
fn stroke(scene: &Scene) -> Option<f64> {
    match &scene.decoupler {
        Decoupler::Bistable(b) => Some(b.front_stroke + b.back_stroke),
        Decoupler::Hydraulic(h) => Some(h.stroke),
        _ => None,
    }
}

/// The panels of a run.
pub fn panels(scene: &Scene, s: &Summary, h: &[Sample], trace: &Trace, measured: &Overlay) -> Vec<Panel> {
    let marks = event_marks(s);
    let series = |name: &str, c: RGBColor, style: Style, f: &dyn Fn(&Sample) -> f64| Series { name: name.into(), points: h.iter().map(|x| (x.t, f(x))).collect(), color: c, style };
    let overlay = |col: &str, scale: f64, label: &str| -> Option<Series> {
        measured.iter().find(|(c, _)| c == col).map(|(_, p)| Series { name: format!("measured {label}"), points: p.iter().map(|&(t, v)| (t, v * scale)).collect(), color: MEASURED, style: Style::Thin })
    };
    // A body part in transient contact (ISO/TS 15066) is a free mass too: draw its velocity.
    let object = matches!(scene.target.kind, TargetKind::Object { .. }) || matches!(scene.target.kind, TargetKind::BodyRegion(b) if b.contact == flinch_model::body::BodyContact::Transient);
    let mut out = Vec::new();

    // Velocities.
    let mut vel: Vec<Series> = ["v_t_mps", "v_r_mps", "v_p_mps", "v_c_mps"].iter().zip(["tool x_t'", "robot x_r'", "object x_p'", "commanded x_c'"]).filter_map(|(c, l)| overlay(c, 1.0, l)).collect();
    vel.push(series("commanded x_c'", PALETTE[6], Style::Dashed, &|x| x.v_c));
    if scene.robot.is_some() {
        vel.push(series("robot flange x_r'", PALETTE[0], Style::Line, &|x| x.v_r));
    }
    if !matches!(scene.decoupler, Decoupler::Rigid) {
        vel.push(series("tool x_t'", PALETTE[1], Style::Line, &|x| x.v_t));
    }
    if object {
        vel.push(series("object x_p'", PALETTE[2], Style::Line, &|x| x.v_p));
    }
    out.push(Panel { caption: "velocities".into(), y_label: "velocity [m/s]".into(), series: vel, marks: marks.clone(), ..Default::default() });

    // Forces, the reported peaks marked where their traces top out.
    let mut forces: Vec<Series> = [("f_contact_n", "contact force", 1.0), ("f_robot_n", "|force on robot|", 1.0)].iter().filter_map(|&(c, l, k)| overlay(c, k, l)).map(|mut o| {
        if o.name.contains("robot") {
            o.points.iter_mut().for_each(|p| p.1 = p.1.abs());
        }
        o
    }).collect();
    forces.push(series("contact force", PALETTE[3], Style::Line, &|x| x.f_contact));
    forces.push(series("|force on robot|", PALETTE[0], Style::Line, &|x| x.f_robot.abs()));
    let mut notes = Vec::new();
    let at_max = |f: &dyn Fn(&Sample) -> f64| h.iter().map(|x| (x.t, f(x))).fold((f64::NAN, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a }).0;
    if s.peak_contact_force > 0.0 {
        notes.push(Note { at: (at_max(&|x| x.f_contact), s.peak_contact_force), text: format!("peak contact force {:.2} N", s.peak_contact_force), color: PALETTE[3] });
    }
    if s.peak_robot_force > 0.0 {
        notes.push(Note { at: (at_max(&|x| x.f_robot.abs()), s.peak_robot_force), text: format!("peak on robot {:.2} N", s.peak_robot_force), color: PALETTE[0] });
    }
    out.push(Panel { caption: "forces (triangles: the reported peaks, located between samples)".into(), y_label: "force [N]".into(), series: forces, marks: marks.clone(), notes, ..Default::default() });

    // Travel against the switch threshold and the end of the stroke.
    if !matches!(scene.decoupler, Decoupler::Rigid) {
        let mut levels = Vec::new();
        if let Some(Sensor::Travel { threshold }) = scene.sensor {
            levels.push(Level { y: threshold * 1e3, label: format!("switch threshold {:.1} mm", threshold * 1e3), color: RGBColor(230, 159, 0) });
        }
        if let Some(c) = stroke(scene) {
            levels.push(Level { y: c * 1e3, label: format!("end of stroke {:.1} mm", c * 1e3), color: RGBColor(200, 0, 0) });
        }
        let mut tr: Vec<Series> = overlay("travel_m", 1e3, "travel").into_iter().collect();
        tr.push(series("travel back from the front stop", PALETTE[1], Style::Line, &|x| trace.travel(x) * 1e3));
        out.push(Panel { caption: format!("decoupler travel (max {:.2} mm)", s.max_travel * 1e3), y_label: "travel [mm]".into(), series: tr, marks: marks.clone(), levels, ..Default::default() });
    }

    // Gas pressure of a hydraulic module.
    if trace.has_gas() {
        let p = series("gas pressure p1 (eq 47)", PALETTE[2], Style::Line, &|x| trace.gas_pressure(x).unwrap_or(f64::NAN) * 1e-3);
        out.push(Panel { caption: "hydraulic gas spring".into(), y_label: "gas pressure [kPa]".into(), series: vec![p], marks: marks.clone(), ..Default::default() });
    }

    // Firmware in the loop.
    if let Some(hil) = &trace.hil {
        let row = |base: f64, on: &dyn Fn(&Sample) -> bool| -> Vec<(f64, f64)> { h.iter().map(|x| (x.t, base + if on(x) { 0.7 } else { 0.0 })).collect() };
        let mut sig = vec![
            Series { name: "switch tripped (travel >= threshold)".into(), points: row(2.0, &|x| trace.switch_tripped(x) == Some(true)), color: PALETTE[1], style: Style::Steps },
            Series { name: "firmware stop output dropped (latched)".into(), points: row(1.0, &|x| trace.stop_requested(x.t) == Some(true)), color: RGBColor(200, 0, 0), style: Style::Steps },
            Series { name: "stop as the controller sampled it".into(), points: row(0.0, &|x| trace.stop_seen(x.t) == Some(true)), color: PALETTE[0], style: Style::Steps },
        ];
        if hil.controller_samples_s.len() <= 400 {
            sig.push(Series { name: "controller samples (scan cycle)".into(), points: hil.controller_samples_s.iter().map(|&t| (t, 0.35)).collect(), color: PALETTE[0], style: Style::Points });
        }
        out.push(Panel {
            caption: "firmware in the loop".into(),
            y_label: "signal".into(),
            series: sig,
            marks: marks.clone(),
            y_range: Some((-0.2, 2.9)),
            y_ticks: vec![(0.0, "controller".into()), (1.0, "stop out".into()), (2.0, "switch".into())],
            weight: 0.8,
            ..Default::default()
        });
    }
    out
}

/// Draws a run into `path` (.svg or .png).
pub fn draw(path: &Path, scene: &Scene, summary: &Summary, history: &[Sample], trace: &Trace, measured: &Overlay) -> Result<(), String> {
    let p = panels(scene, summary, history, trace, measured);
    let title = flinch_model::headline::headline(scene).title();
    figure::draw(path, &title, &XAxis { label: "t [s]".into(), log: false }, &p)
}
