//! The sections of Ch. 2: Fig. 2-3 (eq 1-4), Fig. 13-14 (the compliant robot), Fig. 16 and 18 (the
//! linear decoupler), Fig. 24-26 (Table 2).

use flinch_model::scene::Decoupler;
use flinch_sim::{self as sim, Summary};
use super::{rows::*, context::*};

/// Fig. 2-3, eq 1-4.
pub(crate) fn fig2_3(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let free = |e: f64, mt: f64| cx.run("figures/fig2_free_tool.toml", &[("target.restitution", e), ("tool.mass", mt)]).map(|s| obj(&s));
    let rigid = |e: f64| cx.run("figures/fig2_rigid_tool.toml", &[("target.restitution", e)]).map(|s| obj(&s));
    let eq4 = |e: f64, mt: f64| mt * (1.0 + e) / (mt + 0.25);
    let mut rows = vec![num_row("Fig. 2, rigid tool, e = 1: V_p (eq 1)", 2.0, rigid(1.0)?, "m/s", 0.01), num_row("Fig. 2, rigid tool, e = 0: V_p (eq 1)", 1.0, rigid(0.0)?, "m/s", 0.01)];
    for e in [1.0, 0.5, 0.0] {
        rows.push(num_row(&format!("Fig. 2, free tool, e = {e}: V_p (eq 4)"), eq4(e, 0.125), free(e, 0.125)?, "m/s", 0.01));
    }
    for mt in [0.0625, 0.25, 1.0] {
        rows.push(num_row(&format!("Fig. 3, free tool m_t = {mt} kg, e = 1: V_p (eq 4)"), eq4(1.0, mt), free(1.0, mt)?, "m/s", 0.01));
    }
    open_rest(&mut rows, "none: eq 1-4 take m_t, m_p, e and v_t, all given with the figure");
    out.push(Section {
        title: "Fig. 2-3: instantaneous impact, eq 1-4".into(),
        commands: vec![
            sweep_cmd("figures/fig2_free_tool.toml", &[("target.restitution", 0.0, 1.0, 21, false)], "object_final_velocity", "fig2_free.svg"),
            sweep_cmd("figures/fig2_free_tool.toml", &[("tool.mass", 0.02, 2.0, 21, true), ("target.restitution", 0.0, 1.0, 3, false)], "object_final_velocity", "fig3.svg"),
            "flinch validate --out docs/   (the pictures below: these sweeps, the rigid tool's, and eq 1 and 4 drawn dashed)".into(),
        ],
        plots: vec!["validation/fig2.svg".into(), "validation/fig3.svg".into()],
        rows,
        notes: vec!["The scenes use the `exact` damping law (chi solved for the asked e), so these rows test the momentum balance of eq 2-4, not eq 7; with eq 7 (Hunt-Crossley) e below about 0.5 cannot be reached (MODEL.md, and Fig. 24-26 below).".into()],
    });
    Ok(())
}

/// Fig. 13-14: compliant robot.
pub(crate) fn fig13_14(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let sc = "figures/fig13_compliant_robot.toml";
    let a = cx.run("figures/fig2_rigid_tool.toml", &[("target.restitution", 1.0)])?;
    let b = cx.run(sc, &[])?;
    let c = cx.run(sc, &[("target.mass", 2.5)])?;
    let d = cx.run(sc, &[("target.mass", 2.5), ("target.stiffness", 1e6)])?;
    // k_r, c_r: Fig. 12's are not printed (Table 7's here).
    let c_soft = cx.run(sc, &[("target.mass", 2.5), ("robot.stiffness", 1e5)])?;
    let c_stiff = cx.run(sc, &[("target.mass", 2.5), ("robot.stiffness", 1e6)])?;
    let c_damp = cx.run(sc, &[("target.mass", 2.5), ("robot.damping", 710.0)])?;
    let kr_open = |f: &dyn Fn(&Summary) -> f64, unit: &str| format!("k_r, c_r (Fig. 12 prints neither; Table 7's 2.3e5 N/m, 71 N s/m here): k_r = 1e5 gives {} {unit}, 1e6 gives {} {unit}; c_r = 710 gives {} {unit}", sig(f(&c_soft)), sig(f(&c_stiff)), sig(f(&c_damp)));
    let approach = |s: &Summary| s.approach_speed_mps.unwrap_or(f64::NAN);
    let mut rows = vec![
        num_row("Fig. 13a, rigid robot: V_p", 2.0, obj(&a), "m/s", 0.01),
        num_row("Fig. 13b, compliant robot (m_r + m_t = 5.35 kg): V_p", 1.94, obj(&b), "m/s", 0.02),
        num_row("Fig. 13b: impact velocity", 0.98, b.approach_speed_mps.unwrap_or(f64::NAN), "m/s", 0.02),
        num_row("Fig. 14a, m_p = 2.5 kg, k_c = 1e5: V_p", 1.88, obj(&c), "m/s", 0.03).open(kr_open(&obj, "m/s")),
        num_row("Fig. 14a: impact velocity", 0.95, c.approach_speed_mps.unwrap_or(f64::NAN), "m/s", 0.03).open(kr_open(&approach, "m/s")),
        claim_row("Fig. 14b, k_c = 1e6: V_p", "lower than Fig. 14a (the robot deflects)", format!("{} m/s (14a: {} m/s)", sig(obj(&d)), sig(obj(&c))), "14b < 14a", obj(&d) < obj(&c)),
    ];
    open_rest(&mut rows, "k_r, c_r (Fig. 12 prints neither): Table 7's here; the Fig. 14a rows say how much they move the result");
    out.push(Section {
        title: "Fig. 13-14: the robot's compliance".into(),
        commands: vec![format!("flinch run scenes/{sc} --plot fig13b.svg"), "flinch validate --out docs/   (Fig. 14a/b: target.mass = 2.5, target.stiffness = 1e5 / 1e6)".into()],
        plots: vec!["validation/fig13b.svg".into(), "validation/fig14a.svg".into(), "validation/fig14b.svg".into()],
        rows,
        notes: vec!["k_r and c_r of Fig. 12 are not printed; the scene uses Table 7's (2.3e5 N/m, 71 N s/m). The thesis's impact velocities below 1 m/s come from the tool vibrating after the acceleration (Fig. 11-12, configuration-dependent m_r, k_r, c_r); our one-DOF robot with Table 7's constant parameters meets the object at 0.98 m/s whatever the object (the approach does not depend on it), where the thesis's Fig. 14a run met it at 0.95 m/s. As the thesis argues, the robot then acts as a slider at constant speed, so the object leaves at about twice the impact velocity: 2 x 0.98 against the thesis's 2 x 0.95 = 1.90, which accounts for most of the Fig. 14a difference.".into()],
    });
    Ok(())
}

/// Fig. 16, 18: linear decoupler, k_t and k_c.
pub(crate) fn fig16_18(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let sc = "table2_linear.toml";
    let at = |kt: f64, kc: f64, e: f64| cx.run(sc, &[("decoupler.stiffness", kt), ("target.stiffness", kc), ("target.restitution", e)]).map(|s| obj(&s));
    let (a, b) = (at(10.0, 1e5, 1.0)?, at(1000.0, 1e5, 1.0)?);
    let (c, d) = (at(150.0, 1e3, 1.0)?, at(150.0, 1e5, 1.0)?);
    let (f, g) = (at(150.0, 1e3, 0.1)?, at(150.0, 1e5, 0.1)?);
    let gon = cx.variant(sc, "damping_law = \"hunt-crossley\"", "damping_law = \"gonthier\"")?;
    let gat = |kc: f64| -> Result<Summary, String> { let sc = gon.with(&[("decoupler.stiffness", 150.0), ("target.stiffness", kc), ("target.restitution", 0.1)]).map_err(|e| e.to_string())?; sim::run(&sc, false).map(|r| r.0).map_err(|e| e.to_string()) };
    let (g3, g5) = (gat(1e3)?, gat(1e5)?);
    // Braking: Table 2's scene brakes 16 ms after a 1 N detection; the thesis says only "after the collision".
    let (f_nb, g_nb) = (cx.run(sc, &[("decoupler.stiffness", 150.0), ("target.stiffness", 1e3), ("target.restitution", 0.1), ("motion.dead_time", 1.0)]).map(|s| obj(&s))?, cx.run(sc, &[("decoupler.stiffness", 150.0), ("target.stiffness", 1e5), ("target.restitution", 0.1), ("motion.dead_time", 1.0)]).map(|s| obj(&s))?);
    let mut rows = vec![
        claim_row("Fig. 16 (e = 1): V_p as k_t grows 10 -> 1000 N/m (k_c = 1e5)", "increases", format!("{} -> {} m/s", sig(a), sig(b)), "increases", b > a),
        claim_row("Fig. 16 (e = 1): V_p as k_c grows 1e3 -> 1e5 (k_t = 150)", "decreases", format!("{} -> {} m/s", sig(c), sig(d)), "decreases", d < c),
        claim_row("Fig. 18 (e = 0.1): V_p as k_c grows 1e3 -> 1e5 (k_t = 150)", "increases (the k_c effect inverts)", format!("{} -> {} m/s", sig(f), sig(g)), "increases", g > f)
            .open(format!("the damping law (eq 7 as the thesis; e = 0.1 cannot be reached with it): Gonthier gives {} -> {} m/s (row below); braking (the thesis: after the collision; DT = 16 ms here): no braking (DT = 1 s) gives {} -> {} m/s", sig(obj(&g3)), sig(obj(&g5)), sig(f_nb), sig(g_nb))),
        claim_row("Fig. 18 with the Gonthier law (e = 0.1 really achieved)", "increases", format!("{} -> {} m/s (achieved e {} and {})", sig(obj(&g3)), sig(obj(&g5)), sig(g3.achieved_restitution.unwrap_or(f64::NAN)), sig(g5.achieved_restitution.unwrap_or(f64::NAN))), "increases", obj(&g5) > obj(&g3)),
        claim_row("Fig. 16 vs 13a: the decoupler cuts V_p", "well below 2 m/s", format!("{} m/s at most over these points", sig([a, b, c, d].into_iter().fold(0.0, f64::max))), "< 1.5 m/s", [a, b, c, d].into_iter().all(|x| x < 1.5)),
    ];
    open_rest(&mut rows, "zeta (Fig. 16-18 say only that the decoupler is damped; 1 here as Table 2) and the braking (16 ms after a 1 N detection here): not varied for these trend rows");
    out.push(Section {
        title: "Fig. 16 and 18: stiffness of a linear decoupler and of the contact".into(),
        commands: vec![
            sweep_cmd(sc, &[("decoupler.stiffness", 10.0, 1000.0, 13, true), ("target.stiffness", 1e3, 1e6, 4, true)], "object_final_velocity", "fig16.svg") + "   (e = 1: set target.restitution = 1 in a copy)",
            "flinch validate --out docs/   (draws Fig. 16 at e = 1 and Fig. 18 at e = 0.1 as one line per k_c)".into(),
        ],
        plots: vec!["validation/fig16.svg".into(), "validation/fig18.svg".into()],
        rows,
        notes: vec![
            "Fig. 18's e = 0.1 is asked through eq 7 as in the thesis; eq 7 achieves about 0.5 there (MODEL.md), so our Fig. 18 is really an e of about 0.5 curve, and at e = 0.5 the k_c effect keeps the Fig. 16 sign.".into(),
            if obj(&g5) > obj(&g3) {
                format!("With the Gonthier law, which does reach e near 0.1 on the stiff contact, the inversion appears ({} -> {} m/s), though weaker than in the thesis's figure: the thesis's Fig. 18 is an e of about 0.1 effect that eq 7 cannot produce. (On the soft contact the decoupler keeps pushing during the long contact, so the achieved e is {} whatever the law.)", sig(obj(&g3)), sig(obj(&g5)), sig(g3.achieved_restitution.unwrap_or(f64::NAN)))
            } else {
                "With the Gonthier law, which does reach e near 0.1, the inversion does not appear either: it is not reproduced. Table 2's scene brakes 16 ms after a 1 N detection; the thesis says only that the robot brakes after the collision.".into()
            },
        ],
    });
    Ok(())
}

/// Fig. 24-26: Table 2.
pub(crate) fn fig24_26(cx: &Ctx, out: &mut Vec<Section>) -> Result<(), String> {
    let (b, bh) = cx.history("table2_bistable.toml", &[])?;
    let l = cx.run("table2_linear.toml", &[])?;
    let r = cx.run("table2_rigid.toml", &[])?;
    // The tool's velocity when the first contact ends (the collision complete, Fig. 24a).
    let tc = b.t_contact.unwrap_or(0.0);
    let after = bh.iter().skip_while(|s| s.t < tc || s.f_contact <= 0.0).find(|s| s.f_contact <= 0.0).map_or(f64::NAN, |s| s.v_t);
    let cut = 1.0 - obj(&b) / obj(&r);
    // The restitution law: e = 0.1 really achieved (exact law) instead of eq 7's floor.
    let ex = cx.variant("table2_bistable.toml", "damping_law = \"hunt-crossley\"", "damping_law = \"exact\"")?.with(&[]).map_err(|e| e.to_string())?;
    let (bx, bxh) = sim::run(&ex, true).map_err(|e| format!("table2_bistable (exact): {e}"))?;
    let tcx = bx.t_contact.unwrap_or(0.0);
    let after_x = bxh.iter().skip_while(|s| s.t < tcx || s.f_contact <= 0.0).find(|s| s.f_contact <= 0.0).map_or(f64::NAN, |s| s.v_t);
    let kb = |k: f64| -> Result<f64, String> {
        let (s, h) = cx.history("table2_bistable.toml", &[("decoupler.spring_rate", k)])?;
        let tc = s.t_contact.unwrap_or(0.0);
        Ok(h.iter().skip_while(|x| x.t < tc || x.f_contact <= 0.0).find(|x| x.f_contact <= 0.0).map_or(f64::NAN, |x| x.v_t))
    };
    let kb_base = match &cx.scene("table2_bistable.toml", &[])?.decoupler { Decoupler::Bistable(b) => b.spring_rate, _ => f64::NAN };
    let after_kb = kb(10.0 * kb_base)?;
    let mut rows = vec![
        num_row("Fig. 24a: tool velocity when the collision is over", 0.4, after, "m/s", 0.15)
            .open(format!("the damping law (e = 0.1 through eq 7, as the thesis, achieves about 0.5): the exact law (e = 0.1 achieved) gives {} m/s; k_b (Table 2: {} N/m): ten times it gives {} m/s; the thesis's 0.4 m/s is read off a figure", sig(after_x), sig(kb_base), sig(after_kb))),
        num_row("Fig. 24a vs 26: object-velocity cut, bi-stable vs rigid tool", 51.0, cut * 100.0, "%", 0.10),
        claim_row("Fig. 25: decoupler impulse, bi-stable vs linear", "bi-stable smaller", format!("{} vs {} N s", sig(b.decoupler_impulse), sig(l.decoupler_impulse)), "bi-stable < linear", b.decoupler_impulse < l.decoupler_impulse),
        claim_row("Fig. 24: object velocity, bi-stable vs linear", "bi-stable smaller", format!("{} vs {} m/s", sig(obj(&b)), sig(obj(&l))), "bi-stable < linear", obj(&b) < obj(&l)),
    ];
    open_rest(&mut rows, &format!("the damping law (eq 7 here, as the thesis): the exact law (e = 0.1 achieved) gives the bi-stable's object {} m/s", sig(obj(&bx))));
    out.push(Section {
        title: "Fig. 24-26: bi-stable, linear and rigid end-effectors against a free object (Table 2)".into(),
        commands: vec!["flinch run scenes/table2_bistable.toml --plot fig24a.svg".into(), "flinch run scenes/table2_linear.toml --plot fig24b.svg".into(), "flinch run scenes/table2_rigid.toml --plot fig26.svg".into()],
        plots: vec!["validation/fig24a.svg".into(), "validation/fig24b.svg".into(), "validation/fig26.svg".into()],
        rows,
        notes: vec!["Table 2 asks e = 0.1 through eq 7, which achieves about 0.5 (MODEL.md): the object leaves faster than the thesis's e = 0.1 would give with either end-effector, which is why the cut is about 49 % rather than 51 %. The same floor explains the tool's velocity after the collision: eq 3 gives V_t = 1 - (2/3)(1 + e) m/s, 0.27 m/s at e = 0.1 but 0 at e = 0.5; the thesis's 0.4 m/s (read off Fig. 24a) is above even the e = 0.1 value, so its decoupler must push harder during the contact than Table 2's k_b = 50 N/m does in ours.".into()],
    });
    Ok(())
}
