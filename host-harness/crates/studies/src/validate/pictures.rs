//! The pictures of docs/validation/ (finer grids than the tables): every figure's SVG, Fig. 76's
//! landings and Table 4's timeline.

use flinch_report as report;
use flinch_sim::{self as sim, Sample, Summary};
use crate::sweep::plot::{self as splot, Panel, Series, Style, XAxis, PALETTE};
use crate::sweep::{Axis, Progress, Spacing, Sweep};
use std::path::Path;
use super::{rows::*, context::*, statics::*};

/// Draws every picture into `dir` (the `validation/` folder).
pub fn draw_all(scenes: &Path, dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let cx = Ctx { scenes: scenes.to_path_buf() };
    let history = |name: &str, sets: &[(&str, f64)], file: &str| -> Result<(), String> {
        let sc = cx.scene(name, sets)?;
        let (s, h) = sim::run(&sc, true).map_err(|e| format!("{name}: {e}"))?;
        // Peak-preserving decimation keeps the committed SVGs small.
        let shown = report::stream::decimate_to(&h, sc.duration_s, 2_000, 400);
        report::plot::draw(&dir.join(file), &sc, &s, &shown, &report::trace::Trace::new(&sc), &Vec::new())
    };
    // Fig. 2: V_p against e, free and rigid tool, eq 1 and eq 4 dashed.
    {
        let free = cx.sweep("figures/fig2_free_tool.toml", &[("target.restitution", 0.0, 1.0, 21, false)])?;
        let rigid = cx.sweep("figures/fig2_rigid_tool.toml", &[("target.restitution", 0.0, 1.0, 21, false)])?;
        let es = &free.values[0];
        let series = vec![
            Series { name: "rigid tool, simulated".into(), points: es.iter().copied().zip(rigid.metric("object_final_velocity")).collect(), color: PALETTE[1], style: Style::LineMarked },
            Series { name: "eq 1: (1 + e) v_t".into(), points: es.iter().map(|&e| (e, 1.0 + e)).collect(), color: PALETTE[5], style: Style::Dashed },
            Series { name: "free tool, simulated".into(), points: es.iter().copied().zip(free.metric("object_final_velocity")).collect(), color: PALETTE[0], style: Style::LineMarked },
            Series { name: "eq 4: m_t (1 + e) v_t / (m_t + m_p)".into(), points: es.iter().map(|&e| (e, 0.125 * (1.0 + e) / 0.375)).collect(), color: PALETTE[3], style: Style::Dashed },
        ];
        splot::lines(&dir.join("fig2.svg"), "Fig. 2: object velocity after the impact against e (m_t = 0.125 kg, m_p = 0.25 kg, v_t = 1 m/s)", &XAxis { label: "e".into(), log: false }, &[Panel { caption: "V_p".into(), y_label: "V_p [m/s]".into(), series, ..Default::default() }])?;
    }
    // Fig. 3: V_p against m_t for three e.
    {
        let r = cx.sweep("figures/fig2_free_tool.toml", &[("tool.mass", 0.02, 2.0, 21, true), ("target.restitution", 0.0, 1.0, 3, false)])?;
        let mut series = Vec::new();
        for (j, &e) in r.values[1].iter().enumerate() {
            let pts: Vec<(f64, f64)> = r.values[0].iter().enumerate().map(|(i, &m)| (m, r.at(&[i, j]).map_or(f64::NAN, obj))).collect();
            series.push(Series { name: format!("e = {e}, simulated"), points: pts, color: PALETTE[j], style: Style::LineMarked });
            series.push(Series { name: format!("e = {e}, eq 4"), points: r.values[0].iter().map(|&m| (m, m * (1.0 + e) / (m + 0.25))).collect(), color: PALETTE[j], style: Style::Dashed });
        }
        splot::lines(&dir.join("fig3.svg"), "Fig. 3: object velocity against the moving mass (free tool, m_p = 0.25 kg)", &XAxis { label: "m_t [kg]".into(), log: true }, &[Panel { caption: "V_p".into(), y_label: "V_p [m/s]".into(), series, ..Default::default() }])?;
    }
    history("figures/fig13_compliant_robot.toml", &[], "fig13b.svg")?;
    history("figures/fig13_compliant_robot.toml", &[("target.mass", 2.5)], "fig14a.svg")?;
    history("figures/fig13_compliant_robot.toml", &[("target.mass", 2.5), ("target.stiffness", 1e6)], "fig14b.svg")?;
    // Fig. 16 / 18: V_p against k_t, one line per k_c.
    for (e, file, title) in [(1.0, "fig16.svg", "Fig. 16: e = 1"), (0.1, "fig18.svg", "Fig. 18: e = 0.1 asked (eq 7 achieves about 0.5)")] {
        let axes = vec![Axis::new("decoupler.stiffness", 10.0, 1000.0, 13, Spacing::Log).map_err(|e| e.to_string())?, Axis::new("target.stiffness", 1e3, 1e6, 4, Spacing::Log).map_err(|e| e.to_string())?];
        let t = cx.template("table2_linear.toml")?.with_base(&[("target.restitution", e)]).map_err(|e| e.to_string())?;
        let r = Sweep::new(&t, axes).map_err(|e| e.to_string())?.run(Progress::Hidden);
        let series: Vec<Series> = r.values[1].iter().enumerate().map(|(j, &kc)| Series { name: format!("k_c = {kc:.0e} N/m^1.5"), points: r.values[0].iter().enumerate().map(|(i, &kt)| (kt, r.at(&[i, j]).map_or(f64::NAN, obj))).collect(), color: PALETTE[j], style: Style::LineMarked }).collect();
        splot::lines(&dir.join(file), &format!("{title}: object velocity against k_t (zeta = 1, Table 2 masses, v_t = 1 m/s)"), &XAxis { label: "k_t [N/m]".into(), log: true }, &[Panel { caption: "V_p".into(), y_label: "V_p [m/s]".into(), series, ..Default::default() }])?;
    }
    history("table2_bistable.toml", &[], "fig24a.svg")?;
    history("table2_linear.toml", &[], "fig24b.svg")?;
    history("table2_rigid.toml", &[], "fig26.svg")?;
    history("tables5-7_rigid.toml", &[], "fig39.svg")?;
    history("tables5-7_bistable.toml", &[], "fig40.svg")?;
    history("tables5-7_bistable_v025.toml", &[], "fig41.svg")?;
    for (k, m, f) in [("tool.mass", "peak_contact_force", "fig42.svg"), ("target.stiffness", "peak_contact_force", "fig43.svg"), ("decoupler.spring_rate", "peak_contact_force", "fig44.svg"), ("motion.dead_time", "peak_contact_force", "fig45.svg"), ("tool.mass", "peak_robot_force", "fig46.svg"), ("motion.dead_time", "peak_robot_force", "fig49.svg")] {
        let r = cx.sweep(CH3, &ch3_axes(Grid::Plot, k))?;
        // The force on the robot spans decades (3 N in mode 1, 40 N in mode 2): a log colour scale.
        splot::draw_with(&dir.join(f), &r, m, m == "peak_robot_force")?;
    }
    fig76(&cx, dir)?;
    history("table11_z_prototype.toml", &[], "table11_z_prototype.svg")?;
    {
        let sc = cx.scene("table11_z_prototype.toml", &[])?;
        let z = z_statics(&sc).ok_or("table11: not bi-stable")?;
        let top = (z.l0_m * z.l0_m - z.h_m * z.h_m).max(0.0).sqrt();
        let pts: Vec<(f64, f64)> = (0..=200).map(|i| top * i as f64 / 200.0).map(|c2| (c2 * 1e3, hold(z.k_b, z.l0_m, z.h_m, c2))).collect();
        let panel = Panel {
            caption: format!("N k_b = {} N/m, L0 = {:.1} mm, H = {:.1} mm (Table 10 row 2, Table 11)", sig(z.k_b), z.l0_m * 1e3, z.h_m * 1e3),
            y_label: "force [N]".into(),
            series: vec![
                Series { name: "spring's push toward the back stop at s = -C2 (eq 24-25)".into(), points: pts, color: PALETTE[0], style: Style::Line },
                Series { name: format!("tool weight m_t g = {} N", sig(z.weight_n)), points: vec![(0.0, z.weight_n), (top * 1e3, z.weight_n)], color: PALETTE[1], style: Style::Dashed },
            ],
            marks: vec![(z.c2_m * 1e3, format!("scene's C2 = {:.2} mm: {} N", z.c2_m * 1e3, sig(z.hold_n))), (z.best_c2_m * 1e3, format!("strongest hold: {} N at {:.1} mm", sig(z.best_hold_n), z.best_c2_m * 1e3))],
            ..Default::default()
        };
        splot::lines(&dir.join("table11_statics.svg"), "Tables 9-11: can the Z prototype's spring hold the switched tool against its weight?", &XAxis { label: "back stroke C2 [mm]".into(), log: false }, &[panel])?;
    }
    table4_timeline(&cx, dir)?;
    super::fig69::fig69_picture(&cx, dir)?;
    for s in ["table12_hydraulic_object", "table13_bistable_object", "table14_hydraulic_surface", "table15_bistable_surface", "table14_hydraulic_surface_dt10", "table15_bistable_surface_dt10", "table4_bistable_136g"] {
        history(&format!("{s}.toml"), &[], &format!("{s}.svg"))?;
    }
    Ok(())
}

/// (x, y) of a history from `t0 - before` to `t0 + after`, x in ms after `t0`, thinned to at
/// most 2 x `buckets` points keeping each bucket's extremes (a force step stays a step).
pub(crate) fn trace(h: &[Sample], t0: f64, before: f64, after: f64, y: impl Fn(&Sample) -> f64, buckets: usize) -> Vec<(f64, f64)> {
    let w: Vec<&Sample> = h.iter().filter(|x| x.t >= t0 - before && x.t <= t0 + after).collect();
    let per = w.len().div_ceil(buckets.max(1)).max(1);
    let mut out = Vec::new();
    for chunk in w.chunks(per) {
        let (lo, hi) = chunk.iter().enumerate().fold((0, 0), |(lo, hi), (i, x)| (if y(x) < y(chunk[lo]) { i } else { lo }, if y(x) > y(chunk[hi]) { i } else { hi }));
        for i in if lo <= hi { [lo, hi] } else { [hi, lo] } {
            out.push(((chunk[i].t - t0) * 1e3, y(chunk[i])));
        }
    }
    out.dedup_by(|a, b| a.0 == b.0);
    out
}

/// Fig. 76's evidence: the force on the robot against time, the hydraulic's first impact and its
/// return onto the front end-stop marked (issue 15).
pub(crate) fn fig76(cx: &Ctx, dir: &Path) -> Result<(), String> {
    let (h10, hh10) = cx.fine("table12_hydraulic_object_dt10.toml", &[], 1e-5)?;
    let (b10, hb10) = cx.fine("table13_bistable_object_dt10.toml", &[], 1e-5)?;
    let (h70, hh70) = cx.fine("table12_hydraulic_object.toml", &[], 1e-5)?;
    let fine_hc = |name: &str| -> Result<(Summary, Vec<Sample>), String> {
        let mut sc = cx.hunt_crossley(name, &[])?;
        sc.solver.output_interval = 1e-5;
        sim::run(&sc, true).map_err(|e| format!("{name} (Hunt-Crossley): {e}"))
    };
    let (c10, hc10) = fine_hc("table12_hydraulic_object_dt10.toml")?;
    let t0 = h10.t_contact.ok_or("fig76: no contact")?;
    let t70 = h70.t_contact.ok_or("fig76: no contact")?;
    let first = |s: &Summary| s.first_impact_peak_robot_force_t_s.unwrap_or(f64::NAN);
    let marks = |s: &Summary, tc: f64| {
        vec![
            ((first(s) - tc) * 1e3, format!("first impact: {} N", sig(s.first_impact_peak_robot_force_n.unwrap_or(f64::NAN)))),
            ((s.t_brake.unwrap_or(f64::NAN) - tc) * 1e3, "braking starts".to_string()),
            ((s.peak_robot_force_t_s - tc) * 1e3, format!("whole-run peak: {} N ({})", sig(s.peak_robot_force), s.peak_robot_force_event.replace('_', " "))),
        ]
    };
    let (before, after) = (0.01, 0.2);
    let p1 = Panel {
        caption: "DT = 10 ms (Fig. 76a): hydraulic, Table 12, front stop eq 28 (linear)".into(),
        y_label: "force on the robot [N]".into(),
        series: vec![Series { name: "hydraulic f_robot, eq 28".into(), points: trace(&hh10, t0, before, after, |x| x.f_robot, 800), color: PALETTE[0], style: Style::Line }],
        marks: marks(&h10, t0),
        ..Default::default()
    };
    // The landing on the front stop, close up: eq 28's jump against Hunt-Crossley's rise.
    let land = |h: &[Sample]| front_stop_return(h, t0).map_or(f64::NAN, |r| r.0.t);
    let (l_lin, l_hc) = (land(&hh10), land(&hc10));
    let p1b = Panel {
        caption: format!("DT = 10 ms, landing on the front stop: eq 28 peak {} N, Hunt-Crossley {} N", sig(h10.peak_robot_force), sig(c10.peak_robot_force)),
        y_label: "force on the robot [N]".into(),
        series: vec![
            Series { name: "eq 28, linear".into(), points: trace(&hh10, l_lin, 0.0005, 0.0015, |x| x.f_robot, 400), color: PALETTE[0], style: Style::Line },
            Series { name: "Hunt-Crossley".into(), points: trace(&hc10, l_hc, 0.0005, 0.0015, |x| x.f_robot, 400), color: PALETTE[3], style: Style::Line },
        ],
        ..Default::default()
    };
    let p2 = Panel {
        caption: "DT = 10 ms (Fig. 76b): bi-stable, Table 13".into(),
        y_label: "force on the robot [N]".into(),
        series: vec![Series { name: "bi-stable f_robot".into(), points: trace(&hb10, b10.t_contact.unwrap_or(t0), before, after, |x| x.f_robot, 800), color: PALETTE[1], style: Style::Line }],
        marks: marks(&b10, b10.t_contact.unwrap_or(t0)),
        ..Default::default()
    };
    let p3 = Panel {
        caption: "DT = 70 ms (Fig. 74): hydraulic".into(),
        y_label: "force on the robot [N]".into(),
        series: vec![Series { name: "hydraulic f_robot, DT = 70 ms".into(), points: trace(&hh70, t70, before, after, |x| x.f_robot, 800), color: PALETTE[2], style: Style::Line }],
        marks: marks(&h70, t70),
        ..Default::default()
    };
    let p4 = Panel {
        caption: "stroke back from the front end-stop (0: tool on the front stop)".into(),
        y_label: "front stop - s [mm]".into(),
        series: vec![
            Series { name: "hydraulic, DT = 10 ms".into(), points: trace(&hh10, t0, before, after, |x| (x.s - hh10[0].s) * -1e3, 800), color: PALETTE[0], style: Style::Line },
            Series { name: "hydraulic, DT = 70 ms".into(), points: trace(&hh70, t70, before, after, |x| (x.s - hh70[0].s) * -1e3, 800), color: PALETTE[2], style: Style::Line },
        ],
        ..Default::default()
    };
    splot::lines(&dir.join("fig76.svg"), "Fig. 76: what the peaks on the robot are (objects, Tables 12-13)", &XAxis { label: "time after first contact [ms]".into(), log: false }, &[p1, p2, p3, p4])?;
    // The close-up has its own time axis (ms after each landing).
    splot::lines(&dir.join("fig76_landing.svg"), "Fig. 76: the hydraulic's tool landing on the front stop, eq 28 vs Hunt-Crossley", &XAxis { label: "time after the landing [ms]".into(), log: false }, &[p1b])
}

/// Table 4's contact timeline: velocities, the hits and the start of braking marked.
pub(crate) fn table4_timeline(cx: &Ctx, dir: &Path) -> Result<(), String> {
    let mut panels = Vec::new();
    for (m, name) in [(136, "table4_bistable_136g.toml"), (246, "table4_bistable_246g.toml")] {
        let (s, h) = cx.fine(name, &[], 1e-5)?;
        let tc = s.t_contact.ok_or("table4: no contact")?;
        let hs = hits(&h);
        let mut marks: Vec<(f64, String)> = hs.iter().enumerate().map(|(i, x)| ((x.on_s - tc) * 1e3, format!("hit {} ({} to {})", i + 1, ms_after(x.on_s, tc), ms_after(x.off_s, tc)))).collect();
        marks.push(((s.t_brake.unwrap_or(f64::NAN) - tc) * 1e3, format!("braking starts ({})", ms_after(s.t_brake.unwrap_or(f64::NAN), tc))));
        let (before, after) = (0.01, 0.2);
        panels.push(Panel {
            caption: format!("{m} g object: velocities (measured object peak: {})", if m == 136 { "1.231 +- 0.054 m/s" } else { "1.430 +- 0.040 m/s" }),
            y_label: "velocity [m/s]".into(),
            series: vec![
                Series { name: "object v_p".into(), points: trace(&h, tc, before, after, |x| x.v_p, 600), color: PALETTE[1], style: Style::Line },
                Series { name: "tool v_t".into(), points: trace(&h, tc, before, after, |x| x.v_t, 600), color: PALETTE[0], style: Style::Line },
                Series { name: "flange v_c".into(), points: trace(&h, tc, before, after, |x| x.v_c, 600), color: PALETTE[5], style: Style::Dashed },
            ],
            marks,
            ..Default::default()
        });
        panels.push(Panel {
            caption: format!("{m} g object: contact force and stop forces"),
            y_label: "force [N]".into(),
            series: vec![
                Series { name: "tool-object contact".into(), points: trace(&h, tc, before, after, |x| x.f_contact, 600), color: PALETTE[3], style: Style::Line },
                Series { name: "end-stops on the tool".into(), points: trace(&h, tc, before, after, |x| x.f_stops, 600), color: PALETTE[2], style: Style::Line },
            ],
            ..Default::default()
        });
    }
    splot::lines(&dir.join("table4_timeline.svg"), "Table 4: first hit, second hit (the paddle riding the flange) and the start of braking (DT = 60 ms)", &XAxis { label: "time after first contact [ms]".into(), log: false }, &panels)
}
