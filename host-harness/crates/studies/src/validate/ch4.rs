//! The sections of Ch. 4 (hydraulic against bi-stable, Tables 12-15), the Z-axis prototype (Tables
//! 9-11) and the Table 4 experiments.

use flinch_model::scene::Decoupler;
use flinch_sim::{self as sim, Summary};
use super::{rows::*, context::*, statics::*};

/// Ch. 4: hydraulic vs bi-stable.
pub(crate) fn ch4_hydraulic(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let h70 = cx.run("table12_hydraulic_object.toml", &[])?;
    let b70 = cx.run("table13_bistable_object.toml", &[])?;
    let h10 = cx.run("table12_hydraulic_object_dt10.toml", &[])?;
    let b10 = cx.run("table13_bistable_object_dt10.toml", &[])?;
    let hs70 = cx.run("table14_hydraulic_surface.toml", &[])?;
    let bs70 = cx.run("table15_bistable_surface.toml", &[])?;
    let hs10 = cx.run("table14_hydraulic_surface_dt10.toml", &[])?;
    let bs10 = cx.run("table15_bistable_surface_dt10.toml", &[])?;
    let k_hyd = match &cx.scene("table14_hydraulic_surface.toml", &[])?.decoupler {
        Decoupler::Hydraulic(h) => flinch_plant::decoupler::hydraulic::HydraulicCylinder::new(h).k_hyd(),
        _ => f64::NAN,
    };
    let k_bm = match &cx.scene("table15_bistable_surface.toml", &[])?.decoupler {
        Decoupler::Bistable(b) => {
            let l = (b.height * b.height + b.front_stroke * b.front_stroke).sqrt();
            b.springs as f64 * b.spring_rate * (b.free_length - l) / l
        }
        _ => f64::NAN,
    };
    // Fig. 76's evidence: what each peak on the robot belongs to (issue 15).
    let sc_h10 = cx.scene("table12_hydraulic_object_dt10.toml", &[])?;
    let (_, hist_h10) = cx.fine("table12_hydraulic_object_dt10.toml", &[], 1e-5)?;
    let (_, hist_h70) = cx.fine("table12_hydraulic_object.toml", &[], 1e-5)?;
    let c_fe = front_damping(&sc_h10);
    let tc = h10.t_contact.unwrap_or(f64::NAN);
    let ret10 = front_stop_return(&hist_h10, tc).ok_or("table12_hydraulic_object_dt10: the tool never returns onto the front stop")?;
    let ret70 = front_stop_return(&hist_h70, tc).ok_or("table12_hydraulic_object: the tool never returns onto the front stop")?;
    let first = |s: &Summary| s.first_impact_peak_robot_force_n.unwrap_or(f64::NAN);
    let first_at = |s: &Summary| ms_after(s.first_impact_peak_robot_force_t_s.unwrap_or(f64::NAN), s.t_contact.unwrap_or(f64::NAN));
    let whole = |s: &Summary| format!("{} N at {} ({})", sig(s.peak_robot_force), ms_after(s.peak_robot_force_t_s, s.t_contact.unwrap_or(f64::NAN)), s.peak_robot_force_event.replace('_', " "));
    // d_c: Table 12 gives none (the scenes use 5 m/s^2, Table 3's smallest).
    let h10_d9 = cx.run("table12_hydraulic_object_dt10.toml", &[("motion.decel", 9.0)])?;
    let b10_d9 = cx.run("table13_bistable_object_dt10.toml", &[("motion.decel", 9.0)])?;
    let h70_d9 = cx.run("table12_hydraulic_object.toml", &[("motion.decel", 9.0)])?;
    let b70_d9 = cx.run("table13_bistable_object.toml", &[("motion.decel", 9.0)])?;
    // The front stop's law: eq 28 (linear) against Hunt-Crossley with the same k_fe and the
    // same restitution (issue 15).
    let h10_hc = cx.run_hc("table12_hydraulic_object_dt10.toml", &[])?;
    let b10_hc = cx.run_hc("table13_bistable_object_dt10.toml", &[])?;
    let h70_hc = cx.run_hc("table12_hydraulic_object.toml", &[])?;
    let b70_hc = cx.run_hc("table13_bistable_object.toml", &[])?;
    let (hc_e, hc_alpha) = match &cx.hunt_crossley("table12_hydraulic_object_dt10.toml", &[])?.decoupler {
        Decoupler::Hydraulic(h) => match h.front_stop.law {
            flinch_model::scene::FrontStopLaw::HuntCrossley { alpha, restitution, .. } => (restitution, alpha),
            _ => (f64::NAN, f64::NAN),
        },
        _ => (f64::NAN, f64::NAN),
    };
    let hist_h10_hc = {
        let mut sc = cx.hunt_crossley("table12_hydraulic_object_dt10.toml", &[])?;
        sc.solver.output_interval = 1e-5;
        sim::run(&sc, true).map_err(|e| format!("table12_hydraulic_object_dt10 (Hunt-Crossley): {e}"))?.1
    };
    let ret10_hc = front_stop_return(&hist_h10_hc, tc).ok_or("table12_hydraulic_object_dt10 (Hunt-Crossley): the tool never returns onto the front stop")?;
    // k_fe: Table 12 gives 1e6 N/m; a ten times softer pad.
    let h10_soft = cx.run("table12_hydraulic_object_dt10.toml", &[("decoupler.front_stop.stiffness", 1e5)])?;
    let h10_soft_hc = cx.run_hc("table12_hydraulic_object_dt10.toml", &[("decoupler.front_stop.stiffness", 1e5)])?;
    let m_t = sc_h10.tool.mass;
    let k_fe = match &sc_h10.decoupler {
        Decoupler::Hydraulic(h) => h.front_stop.stiffness,
        _ => f64::NAN,
    };
    // The hard surface at DT = 70 ms: d_c (Table 14 gives none; 2 m/s^2 here).
    let hs70_d5 = cx.run("table14_hydraulic_surface.toml", &[("motion.decel", 5.0)])?;
    let bs70_d5 = cx.run("table15_bistable_surface.toml", &[("motion.decel", 5.0)])?;
    let hs10_d5 = cx.run("table14_hydraulic_surface_dt10.toml", &[("motion.decel", 5.0)])?;
    let bs10_d5 = cx.run("table15_bistable_surface_dt10.toml", &[("motion.decel", 5.0)])?;
    let k_hyd_at = |kappa: f64| -> Result<f64, String> {
        match &cx.scene("table14_hydraulic_surface.toml", &[("decoupler.adiabatic_exponent", kappa)])?.decoupler {
            Decoupler::Hydraulic(h) => Ok(flinch_plant::decoupler::hydraulic::HydraulicCylinder::new(h).k_hyd()),
            _ => Ok(f64::NAN),
        }
    };
    let k_hyd_132 = k_hyd_at(1.32)?;
    let vs = |h: &Summary, b: &Summary| format!("hydraulic {} vs bi-stable {}", sig(obj(h)), sig(obj(b)));
    let fs = |h: &Summary, b: &Summary| format!("hydraulic {} N vs bi-stable {} N", sig(h.peak_robot_force), sig(b.peak_robot_force));
    let law_open = |h: &Summary, b: &Summary| format!("front-stop law (eq 28, linear, here): Hunt-Crossley with the same k_fe and restitution gives hydraulic {} N ({}), bi-stable {} N", sig(h.peak_robot_force), h.peak_robot_force_event.replace('_', " "), sig(b.peak_robot_force));
    let rows = vec![
        claim_row("Fig. 72-74, objects, DT = 70 ms: object velocity", "lower with the hydraulic", vs(&h70, &b70) + " m/s", "hydraulic < bi-stable", obj(&h70) < obj(&b70))
            .open(format!("d_c (Table 12 gives none; 5 m/s^2 here): 9 m/s^2 gives hydraulic {} m/s, bi-stable {} m/s; front-stop law: Hunt-Crossley gives hydraulic {} m/s, bi-stable {} m/s", sig(obj(&h70_d9)), sig(obj(&b70_d9)), sig(obj(&h70_hc)), sig(obj(&b70_hc)))),
        claim_row("Fig. 73-74, objects, DT = 70 ms: force on the robot (front stop: eq 28, linear)", "lower with the hydraulic", format!("whole run: hydraulic {} vs bi-stable {}; first impact: hydraulic {} N, bi-stable {} N", whole(&h70), whole(&b70), sig(first(&h70)), sig(first(&b70))), "hydraulic < bi-stable", h70.peak_robot_force < b70.peak_robot_force)
            .open(format!("{}; d_c 9 m/s^2: hydraulic {} N, bi-stable {} N", law_open(&h70_hc, &b70_hc), sig(h70_d9.peak_robot_force), sig(b70_d9.peak_robot_force))),
        claim_row("Fig. 73-74, objects, DT = 70 ms: force on the robot, front stop Hunt-Crossley", "lower with the hydraulic", format!("whole run: hydraulic {} vs bi-stable {}; first impact: hydraulic {} N, bi-stable {} N", whole(&h70_hc), whole(&b70_hc), sig(first(&h70_hc)), sig(first(&b70_hc))), "hydraulic < bi-stable", h70_hc.peak_robot_force < b70_hc.peak_robot_force)
            .open(format!("the law moves the hydraulic's whole-run peak {} -> {} N ({} %), its first impact {} -> {} N", sig(h70.peak_robot_force), sig(h70_hc.peak_robot_force), signed((h70_hc.peak_robot_force / h70.peak_robot_force - 1.0) * 100.0, 0), sig(first(&h70)), sig(first(&h70_hc)))),
        claim_row("Fig. 75, objects, DT = 10 ms: object velocity", "lower with the bi-stable", vs(&h10, &b10) + " m/s", "bi-stable < hydraulic", obj(&b10) < obj(&h10))
            .open(format!("d_c 9 m/s^2: hydraulic {} m/s, bi-stable {} m/s; front-stop law: Hunt-Crossley gives hydraulic {} m/s, bi-stable {} m/s", sig(obj(&h10_d9)), sig(obj(&b10_d9)), sig(obj(&h10_hc)), sig(obj(&b10_hc)))),
        claim_row("Fig. 76, objects, DT = 10 ms: force on the robot (front stop: eq 28, linear)", "still lower with the hydraulic", format!("whole run: hydraulic {} vs bi-stable {}", whole(&h10), whole(&b10)), "hydraulic < bi-stable", h10.peak_robot_force < b10.peak_robot_force)
            .open(format!("d_c (Table 12 gives none; 5 m/s^2 here): 9 m/s^2 gives hydraulic {} N, bi-stable {} N; {}; k_fe (Table 12: 1e6 N/m): 1e5 N/m gives hydraulic {} N (eq 28), {} N (Hunt-Crossley)", sig(h10_d9.peak_robot_force), sig(b10_d9.peak_robot_force), law_open(&h10_hc, &b10_hc), sig(h10_soft.peak_robot_force), sig(h10_soft_hc.peak_robot_force))),
        claim_row("Fig. 76, objects, DT = 10 ms: force on the robot, front stop Hunt-Crossley", "still lower with the hydraulic", format!("whole run: hydraulic {} vs bi-stable {}", whole(&h10_hc), whole(&b10_hc)), "hydraulic < bi-stable", h10_hc.peak_robot_force < b10_hc.peak_robot_force)
            .open(format!("the law moves the hydraulic's whole-run peak {} -> {} N ({} %), its first impact {} -> {} N", sig(h10.peak_robot_force), sig(h10_hc.peak_robot_force), signed((h10_hc.peak_robot_force / h10.peak_robot_force - 1.0) * 100.0, 0), sig(first(&h10)), sig(first(&h10_hc)))),
        claim_row("Fig. 76, objects, DT = 10 ms: force on the robot in the first impact alone", "lower with the hydraulic", format!("hydraulic {} N at {} vs bi-stable {} N at {}", sig(first(&h10)), first_at(&h10), sig(first(&b10)), first_at(&b10)), "hydraulic < bi-stable", first(&h10) < first(&b10))
            .open(format!("orifice (R_o, c0: Table 12): the orifice term 0.5 c0 rho A_p^3 / A_o^2 s'^2 decides it; d_c 5 -> 9 m/s^2: hydraulic {} N; front-stop law: Hunt-Crossley gives hydraulic {} N, bi-stable {} N", sig(first(&h10_d9)), sig(first(&h10_hc)), sig(first(&b10_hc)))),
        claim_row("Fig. 78-79, hard surface, DT = 70 ms: force on the robot", "lower with the hydraulic", fs(&hs70, &bs70) + &format!("; hydraulic stroke exhausted: {}", hs70.stroke_exhausted), "hydraulic < bi-stable", hs70.peak_robot_force < bs70.peak_robot_force)
            .open(format!("d_c (Table 14 gives none; 2 m/s^2 here, as a_c): 5 m/s^2 gives hydraulic {} N (stroke exhausted: {}), bi-stable {} N", sig(hs70_d5.peak_robot_force), hs70_d5.stroke_exhausted, sig(bs70_d5.peak_robot_force))),
        claim_row("Fig. 80, hard surface, DT = 10 ms: bi-stable switches?", "no (mode 1)", fmt_mode(bs10.mode), "mode 1", bs10.mode == Some(1))
            .open(format!("d_c 5 m/s^2: mode {}", fmt_mode(bs10_d5.mode))),
        claim_row("Fig. 80, hard surface, DT = 10 ms: force on the robot", "lower with the bi-stable", fs(&hs10, &bs10), "bi-stable < hydraulic", bs10.peak_robot_force < hs10.peak_robot_force)
            .open(format!("d_c 5 m/s^2: {}", fs(&hs10_d5, &bs10_d5))),
        num_row("Eq 63, Table 12/14: k_hyd", 27.28, k_hyd, "N/m", 0.02)
            .open(format!("kappa (not in Table 12; 1.4, air, here): 1.32 gives {} N/m", sig(k_hyd_132))),
        num_row("Eq 64, Table 15: k_bm at the front stop", 34.0, k_bm, "N/m", 0.02).open("none: N, k_b, L0, H and C1 are all in Table 15".into()),
    ];
    out.push(Section {
        title: "Ch. 4: hydraulic against bi-stable (Tables 12-15), DT = 70 ms and 10 ms".into(),
        commands: ["table12_hydraulic_object", "table13_bistable_object", "table12_hydraulic_object_dt10", "table13_bistable_object_dt10", "table14_hydraulic_surface", "table15_bistable_surface", "table14_hydraulic_surface_dt10", "table15_bistable_surface_dt10"]
            .iter()
            .map(|s| format!("flinch run scenes/{s}.toml --plot {s}.svg"))
            .chain(["flinch run scenes/figures/fig76_hydraulic_hunt_crossley.toml   (Fig. 76a with a Hunt-Crossley front stop; the other Hunt-Crossley numbers: law = \"hunt-crossley\" added to decoupler.front_stop of the scene named)".to_string()])
            .collect(),
        plots: ["fig76", "fig76_landing", "table12_hydraulic_object", "table13_bistable_object", "table14_hydraulic_surface", "table15_bistable_surface", "table14_hydraulic_surface_dt10", "table15_bistable_surface_dt10"].iter().map(|s| format!("validation/{s}.svg")).collect(),
        rows,
        notes: vec![
            format!("Hard surface at DT = 70 ms: after detection the flange still closes 0.25 x 0.07 + 0.25^2 / 4 = 33 mm (`flinch check scenes/table14_hydraulic_surface.toml`), more than the hydraulic's 23 mm stroke, so in our run the flange reaches the surface and the robot sees {} N; the thesis's Fig. 78 shows no such impact. Either its stroke or its braking differ from Tables 12/14, or the flange-obstacle contact was not modelled. The bi-stable (47 mm) does not run out.", sig(hs70.peak_robot_force)),
            format!(
                "Objects, Fig. 76 (validation/fig76.svg, drawn from `flinch run scenes/table12_hydraulic_object_dt10.toml --csv -` with `solver.output_interval = 1e-5`): the hydraulic's whole-run peak, {} N, is not its first impact. The first impact puts {} N on the robot {} after contact (Table 12's orifice term 0.5 c0 rho A_p^3 / A_o^2 s'^2, about 66 N per (m/s)^2, at about 0.67 m/s). The {} N comes {} after contact (DT = 10 ms; {} at DT = 70 ms), when the gas spring brings the tool back onto the front end-stop at s' = {} m/s: eq 28's linear law jumps at the instant of contact to c_fe s' = {} x {} = {} N (f_robot goes from {} N to {} N between two samples 10 us apart). A force step at contact onset is the known artefact of a linear (Kelvin-Voigt) contact law, the reason Hunt and Crossley's law exists; the next note runs the same scenes with that law. The bi-stable's {} N is a back-stop impact {} after contact, after the robot has braked. So on the first impact alone the hydraulic puts more on the robot than the bi-stable does on its whole run, and the thesis's order (hydraulic lower) is not reproduced either way; its Fig. 76 force scale cannot be read from the text.",
                sig(h10.peak_robot_force), sig(first(&h10)), first_at(&h10), sig(h10.peak_robot_force), ms_after(h10.peak_robot_force_t_s, tc), ms_after(h70.peak_robot_force_t_s, h70.t_contact.unwrap_or(f64::NAN)),
                sig(ret10.1.v_t - ret10.1.v_r), sig(c_fe), sig(ret10.1.v_t - ret10.1.v_r), sig(c_fe * (ret10.1.v_t - ret10.1.v_r)), sig(ret10.1.f_robot), sig(ret10.0.f_robot),
                sig(b10.peak_robot_force), ms_after(b10.peak_robot_force_t_s, b10.t_contact.unwrap_or(f64::NAN)),
            ),
            format!(
                "The front stop under both laws (rows marked Hunt-Crossley; `flinch run scenes/figures/fig76_hydraulic_hunt_crossley.toml`, the others with `law = \"hunt-crossley\"` added to `decoupler.front_stop` of the same scenes). How the nonlinear law is made comparable: exponent n = 1 and the same k_fe = {:e} N/m, so the static stiffness, the rest position and every slow press on the stop are eq 28's; alpha in F = k_fe d (1 + alpha d' / v_in) is chosen so that an isolated landing of the tool (m_t = {} kg) loses the same share of its energy as on eq 28's stop: zeta = c_fe / (2 sqrt(k_fe m_t)) = {:.3}, the linear law as modelled (clamped so it never pulls) returns e = {:.3} of the landing speed, and alpha = {:.3} returns the same (both laws' e is independent of the landing speed, so the match holds at every landing). Result: the jump is gone (the sample 10 us after the landing shows {} N against eq 28's {} N), but the hydraulic's whole-run peak rises from {} to {} N ({} after contact, {:.2} ms after the landing), and at DT = 70 ms from {} to {} N; the first impact (orifice, {} N) and the bi-stable's peaks barely move. The same energy loss taken later in a landing, where the spring force is already large, gives a larger peak: the size of this force is set by the stop's stiffness meeting the tool's momentum (an undamped stop alone gives s' sqrt(k_fe m_t) = {} x sqrt({:e} x {}) = {} N), not by eq 28's jump, and a ten times softer pad (k_fe = 1e5 N/m) leaves eq 28's whole-run peak at {} N (its jump c_fe s' does not depend on k_fe) while with Hunt-Crossley it becomes {} N ({}). The thesis's order of Fig. 76 (hydraulic lower) is not reproduced under either law.",
                k_fe, m_t, c_fe / (2.0 * (k_fe * m_t).sqrt()), hc_e, hc_alpha, sig(ret10_hc.0.f_robot), sig(ret10.0.f_robot), sig(h10.peak_robot_force), sig(h10_hc.peak_robot_force), ms_after(h10_hc.peak_robot_force_t_s, tc), (h10_hc.peak_robot_force_t_s - ret10_hc.0.t) * 1e3, sig(h70.peak_robot_force), sig(h70_hc.peak_robot_force), sig(first(&h10)),
                sig(ret10.1.v_t - ret10.1.v_r), k_fe, m_t, sig((ret10.1.v_t - ret10.1.v_r) * (k_fe * m_t).sqrt()), sig(h10_soft.peak_robot_force), sig(h10_soft_hc.peak_robot_force), h10_soft_hc.peak_robot_force_event.replace('_', " "),
            ),
            format!("The front-stop returns, from the recorded histories: DT = 10 ms at {} after contact, DT = 70 ms at {} (s' = {} m/s). The two peaks act in opposite directions: the first impact pushes the robot back (f_robot < 0), the front-stop return pulls it forward (f_robot > 0); `peak_robot_force` is a magnitude, and the summary now gives `first_impact_peak_robot_force_n` and `peak_robot_force_event` beside it.", ms_after(ret10.0.t, tc), ms_after(ret70.0.t, h70.t_contact.unwrap_or(f64::NAN)), sig(ret70.1.v_t - ret70.1.v_r)),
            "Eq 63 with Table 12's values (R_p = 20 mm, p10 = 1000 Pa, V_g0 = 7.63e-5 m^3, kappa = 1.4) gives 28.97 N/m; the thesis prints 27.28 N/m (6 % lower, as if kappa were about 1.32 or V_g0 about 8.1e-5 m^3).".into(),
        ],
    });
    Ok(())
}

/// Tables 9-11: the Z-axis prototype.
pub(crate) fn tables9_11(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let name = "table11_z_prototype.toml";
    let sc = cx.scene(name, &[])?;
    let z = z_statics(&sc).ok_or("table11_z_prototype: not a bi-stable scene")?;
    // Where the run ends (s < 0: past the centre), from its history.
    let end_s = |sets: &[(&str, f64)]| -> Result<(Summary, f64), String> {
        let (s, h) = cx.history(name, sets)?;
        Ok((s, h.last().map_or(f64::NAN, |x| x.s)))
    };
    let (run, s_end) = end_s(&[])?;
    let (centre, rest) = z.holds_m.unwrap_or((f64::NAN, f64::NAN));
    let switched = s_end < -centre;
    let mut c2_effect = Vec::new();
    for c2 in [0.015, z.best_c2_m] {
        let (r, e) = end_s(&[("decoupler.back_stroke", c2)])?;
        c2_effect.push(format!("C2 = {:.1} mm: mode {}, ends at s = {:.1} mm", c2 * 1e3, fmt_mode(r.mode), e * 1e3));
    }
    let (rc1, ec1) = end_s(&[("decoupler.front_stroke", 0.02525), ("decoupler.back_stroke", 0.01525)])?;
    let rows = vec![
        claim_row("Ch. 3.4, Fig. 61 (third test): the module switches", "it switches", format!("the run ends at s = {:.1} mm (mode {}): {} the weight-shifted dead centre s = -{:.1} mm", s_end * 1e3, fmt_mode(run.mode), if switched { "past" } else { "short of" }, centre * 1e3), "past the dead centre", switched)
            .open(format!("C2 (given nowhere; {:.2} mm here): {}; C1 (Table 9: 15.25 or 25.25 mm; 15.25 here): 25.25 mm with C2 = 15.25 mm gives mode {}, ends at s = {:.1} mm; the spring (Table 10 row 2 here): row 1 is not bi-stable (row below)", z.c2_m * 1e3, c2_effect.join("; "), fmt_mode(rc1.mode), ec1 * 1e3)),
        claim_row("Ch. 3.4: the spring holds the switched tool on the back stop against its weight", "- (Table 11 gives no C2)", format!("spring {} N toward the back stop at C2 = {:.2} mm, weight {} N: it cannot; the switched tool rests where the two balance, s = -{:.1} mm, {:.1} mm short of the back stop", sig(z.hold_n), z.c2_m * 1e3, sig(z.weight_n), rest * 1e3, (z.c2_m - rest) * 1e3), "the run ends between the dead centre and that rest point (or on the back stop)", s_end <= -centre && s_end >= -z.c2_m - 1e-3)
            .open(match z.holds_m {
                Some((a, b)) => format!("C2: the spring holds the tool on the back stop only for C2 in [{:.1}, {:.1}] mm (at most {} N, at {:.1} mm)", a * 1e3, b * 1e3, sig(z.best_hold_n), z.best_c2_m * 1e3),
                None => format!("C2: no back stroke lets the spring hold the weight (at most {} N, at {:.1} mm)", sig(z.best_hold_n), z.best_c2_m * 1e3),
            }),
        claim_row("Table 10, spring 1 (L0 = 34.1 mm) on Table 11's H = 35 mm", "a spring for this module", "L0 < H: the spring is stretched at every s and pulls the tool to s = 0, one stable position".into(), "bi-stable: L0 > H", 0.0341 > z.h_m)
            .open("none: L0 (Table 10) and H (Table 11) are both printed; which spring the prototype used is not said (row 2 here)".into()),
    ];
    out.push(Section {
        title: "Tables 9-11: the Z-axis prototype's statics".into(),
        commands: vec![format!("flinch run scenes/{name} --plot table11_z_prototype.svg"), "flinch validate --out docs/   (the spring's push against the back stroke C2, eq 24-25: validation/table11_statics.svg; C1, C2 set as decoupler.front_stroke, decoupler.back_stroke)".into()],
        plots: vec!["validation/table11_statics.svg".into(), "validation/table11_z_prototype.svg".into()],
        rows,
        notes: vec![
            format!("Statics (eq 24-25 with the weight along the approach; N = 1, k_b = {} N/m, L0 = {:.1} mm, H = {:.1} mm, m_t g = {} N): past the centre the spring pushes the tool toward the back stop with N k_b (L0 - L) |s| / L, L = sqrt(H^2 + s^2), at most {} N (at |s| = {:.1} mm), while the weight pulls it forward with {} N. So the dead centre moves from s = 0 to s = -{:.1} mm (where the push first equals the weight), and the switched tool's stable rest is s = -{:.1} mm, where the push falls back to the weight. At the scene's back stop (C2 = {:.2} mm, L = {:.2} mm) the push is only {} N: the tool cannot rest on the back stop, it rests {:.1} mm short of it. The thesis gives no C2 for this prototype (our {:.2} mm makes C = 40.5 mm so Table 9's two C1 are mirror images).", sig(z.k_b), z.l0_m * 1e3, z.h_m * 1e3, sig(z.weight_n), sig(z.best_hold_n), z.best_c2_m * 1e3, sig(z.weight_n), centre * 1e3, rest * 1e3, z.c2_m * 1e3, ((z.h_m * z.h_m + z.c2_m * z.c2_m).sqrt()) * 1e3, sig(z.hold_n), (z.c2_m - rest) * 1e3, z.c2_m * 1e3),
            "The working mode (Fig. 46) says whether the tool reached the back stop, not whether it switched: this run is mode 1 and switched.".into(),
            "Table 10's spring 1 has a free length of 34.1 mm, shorter than Table 11's H = 35 mm: it is in tension at every position and has a single stable position, so it is not bi-stable with this H at all.".into(),
        ],
    });
    Ok(())
}

/// Table 4 experiments.
pub(crate) fn table4(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let pk = |s: &Summary| s.object_peak_velocity.unwrap_or(f64::NAN);
    let r136 = cx.run("table4_rigid_136g.toml", &[])?;
    // The contact timeline (issue 15): first hit, second hit, braking.
    let mut timeline = Vec::new();
    let mut rows = Vec::new();
    let mut detached = true;
    let mut decel_text = Vec::new();
    let mut decel_same = true;
    let mut story = Vec::new();
    let mut detached45 = Vec::new();
    let (mut detached_h45, mut decel_h45) = (Vec::new(), Vec::new());
    let mut claims_h45 = true;
    let mut detached_fit45 = true;
    for (m, name, measured, sd) in [(136, "table4_bistable_136g.toml", 1.231, 0.054), (246, "table4_bistable_246g.toml", 1.430, 0.040)] {
        let (s, h) = cx.fine(name, &[], 1e-5)?;
        let tc = s.t_contact.unwrap_or(f64::NAN);
        let tb = s.t_brake.unwrap_or(f64::INFINITY);
        let hs = hits(&h);
        let h45 = cx.run(name, &[("decoupler.height", 0.045)])?;
        // Fig. 34 tests 5 and 9 m/s^2 (the 136 g scene brakes at 5, the 246 g at 9): the other one.
        let d_base = cx.scene(name, &[])?.motion.decel;
        let d_alt = if d_base < 7.0 { 9.0 } else { 5.0 };
        let d9 = cx.run(name, &[("motion.decel", d_alt)])?;
        detached &= hs.iter().all(|x| x.off_s <= tb);
        // The same two claims at Table 3's other H.
        {
            let (s45, h45h) = cx.fine(name, &[("decoupler.height", 0.045)], 1e-5)?;
            let tb45 = s45.t_brake.unwrap_or(f64::INFINITY);
            let late = h45h.iter().filter(|x| x.t > tb45 && x.f_contact > 0.0).count() > 0;
            let d45 = cx.run(name, &[("decoupler.height", 0.045), ("motion.decel", d_alt)])?;
            detached_h45.push(format!("{m} g: {}", if late { "touching after braking starts" } else { "detached before braking" }));
            decel_h45.push(format!("{m} g: {} m/s at {d_base}, {} at {d_alt}", sig(pk(&h45)), sig(pk(&d45))));
            claims_h45 &= !late && (pk(&d45) - pk(&h45)).abs() <= 2.0 * sd;
        }
        decel_same &= (pk(&d9) - pk(&s)).abs() <= 2.0 * sd;
        decel_text.push(format!("{m} g: {} m/s at {d_base} m/s^2, {} at {d_alt}", sig(pk(&s)), sig(pk(&d9))));
        let first = hs.first().map_or(f64::NAN, |x| x.object_mps);
        let list: Vec<String> = hs.iter().enumerate().map(|(i, x)| format!("hit {} {} to {} (object leaves at {} m/s)", i + 1, ms_after(x.on_s, tc), ms_after(x.off_s, tc), sig(x.object_mps))).collect();
        timeline.push(format!("{m} g: {}; braking starts {}", list.join(", "), ms_after(tb, tc)));
        let back = back_stop_hit(&h, tc);
        let second = hs.get(1).map_or(f64::NAN, |x| x.on_s);
        let thrown = back.map_or(f64::NAN, |b| h.iter().filter(|x| x.t >= b.t && x.t <= second).map(|x| x.v_t).fold(f64::NAN, f64::max));
        story.push(format!(
            "{m} g: the first hit leaves the object at {} m/s; the flange catches the paddle up (back end-stop {}) and throws it forward at up to {} m/s; it hits the object again at {} (braking starts {}, {} the second hit)",
            sig(first), back.map_or("-".into(), |b| ms_after(b.t, tc)), sig(thrown), ms_after(second, tc), ms_after(tb, tc),
            if tb < second { "before".to_string() } else { format!("{:.1} ms into", (tb - second) * 1e3) },
        ));
        rows.push(
            num_row(&format!("Table 4, bi-stable, {m} g object: peak object velocity (measured {measured:.3} +- {sd:.3})"), measured, pk(&s), "m/s", 2.0 * sd / measured)
                .open(format!("H (Table 4 omits it; Table 3 tests 45 and 53 mm, 53 here): 45 mm gives {} m/s (mode {}); d_robot (5 or 9 m/s^2, Fig. 34; {d_base} here): {d_alt} gives {} m/s; the first hit alone gives {} m/s", sig(pk(&h45)), fmt_mode(h45.mode), sig(pk(&d9)), sig(first))),
        );
    }
    // The thesis's account taken literally: braking only once the object has left for good.
    for (m, name, base, measured, sd) in [(136, "figures/table4_bistable_136g_detached.toml", "table4_bistable_136g.toml", 1.231, 0.054), (246, "figures/table4_bistable_246g_detached.toml", "table4_bistable_246g.toml", 1.430, 0.040)] {
        let v = cx.run(name, &[])?;
        let b = cx.run(base, &[])?;
        let tc = v.t_contact.unwrap_or(f64::NAN);
        rows.push(
            num_row(&format!("Table 4 variant, braking after the second hit (Ch. 2.5's account), H = 53 mm, {m} g: peak object velocity (measured {measured:.3} +- {sd:.3})"), measured, pk(&v), "m/s", 2.0 * sd / measured)
                .open(format!("braking onset (the thesis: after the object detached; DT = 60 ms puts it at {}): held until hit {} has ended ({}) it moves ours from {} to {} m/s", ms_after(b.t_brake.unwrap_or(f64::NAN), tc), v.contacts, ms_after(v.t_brake.unwrap_or(f64::NAN), tc), sig(pk(&b)), sig(pk(&v)))),
        );
        // Table 3's other H: the same account, H = 45 mm.
        let name45 = name.replace("_detached.toml", "_detached_h45.toml");
        let v45 = cx.run(&name45, &[])?;
        let fits = (pk(&v45) - measured).abs() <= 2.0 * sd;
        detached45.push(format!("{m} g: {} m/s ({})", sig(pk(&v45)), if fits { "fits" } else { "does not fit" }));
        detached_fit45 &= fits;
        rows.push(
            num_row(&format!("Table 4 variant, braking after the second hit (Ch. 2.5's account), H = 45 mm, {m} g: peak object velocity (measured {measured:.3} +- {sd:.3})"), measured, pk(&v45), "m/s", 2.0 * sd / measured)
                .open(format!("H (Table 4 omits it; Table 3's other value): 45 mm instead of 53 mm moves it from {} to {} m/s (mode {}, {} tool-object contacts): `flinch run scenes/{name45}`", sig(pk(&v)), sig(pk(&v45)), fmt_mode(v45.mode), v45.contacts)),
        );
    }
    rows.push(num_row("Table 4, rigid tool, 136 g object: peak object velocity (measured 1.798 +- 0.037)", 1.798, pk(&r136), "m/s", 0.04).open("none that matters: no decoupler, the contact's k_c and e decide it".into()));
    rows.push(claim_row("Ch. 2.5, Fig. 34: the object detached from the tool before the deceleration begins", "yes", timeline.join("; "), "no tool-object contact after braking starts", detached)
        .open(format!("H (Table 4 omits it; 53 mm here): at 45 mm, {}; the braking onset (DT = 60 ms after detection here): the `_detached` rows above hold it off", detached_h45.join(", "))));
    rows.push(claim_row("Fig. 34: the deceleration (5 or 9 m/s^2) makes no difference", "no difference", decel_text.join("; "), "within two measured standard deviations", decel_same)
        .open(format!("H: at 45 mm, {}", decel_h45.join("; "))));
    out.push(Section {
        title: "Table 4: the Ch. 2 prototype against the experiments".into(),
        commands: vec![
            "flinch run scenes/table4_bistable_136g.toml --plot table4_bistable_136g.svg".into(),
            "flinch run scenes/table4_bistable_246g.toml".into(),
            "flinch run scenes/table4_rigid_136g.toml".into(),
            "flinch validate --out docs/   (the contact timeline: the two scenes recorded every 10 us, validation/table4_timeline.svg; H = 45 mm and the other d_robot of Fig. 34 set as decoupler.height and motion.decel)".into(),
            "flinch run scenes/figures/table4_bistable_136g_detached.toml   (and _246g_detached: braking held until the second hit has ended, motion.brake_after_contact = 2)".into(),
            "flinch run scenes/figures/table4_bistable_136g_detached_h45.toml   (and _246g_detached_h45: the same account at Table 3's other H, 45 mm)".into(),
        ],
        plots: vec!["validation/table4_timeline.svg".into(), "validation/table4_bistable_136g.svg".into()],
        rows,
        notes: vec![
            "Tolerance: two measured standard deviations.".into(),
            format!("What our number is (validation/table4_timeline.svg, from the two scenes recorded every 10 us): the first impact alone leaves the object far below the measured peak; the rest comes from a second hit. {}.", story.join("; ")),
            format!("The thesis's account taken literally (braking held until the object has left, the `_detached` scenes) fits both measured peaks at H = 53 mm only: at Table 3's other height, H = 45 mm, the same scenes give {} against the measurements{}. Table 4 does not say which H its tests used, so the fit is evidence for H = 53 mm and for the account only together.{}", detached45.join(", "), if detached_fit45 { " (it fits there too)" } else { "" },
                if claims_h45 { " At H = 45 mm the account's two qualitative claims do hold in our scenes as shipped (the object has left before braking starts, and 5 or 9 m/s^2 makes no difference: rows above), but the peaks are then far from the measured ones. With Table 4's braking as scheduled (DT = 60 ms), no single H reproduces both: at 53 mm the numbers fit only once braking is held until the object has left, at 45 mm the account holds and the numbers do not." } else { "" }),
            format!("The thesis's account (Ch. 2.5, Fig. 34) is that the object detached from the tool before the deceleration begins and that the deceleration made no difference. In our scenes the tool is still hitting the object after braking starts (row above) and the deceleration can move the result ({}). An earlier version of this page said the measured peak was the first impact's and blamed the contact stiffness and eq 7's restitution floor; the timeline shows that was wrong.", decel_text.join("; ")),
        ],
    });
    Ok(())
}
