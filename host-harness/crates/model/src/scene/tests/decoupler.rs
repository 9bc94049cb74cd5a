//! The decoupler tables: kinds, the bi-stable, the end stops, the hydraulic.

use super::*;

// Decoupler kinds.
case!(
    decoupler_kind_bad,
    BASE,
    "kind = \"bistable\"",
    "kind = \"springy\"",
    "decoupler.kind",
    "springy",
    "must be one of \"rigid\" | \"linear\" | \"bistable\" | \"hydraulic\", got \"springy\""
);
case!(
    decoupler_kind_missing,
    BASE,
    "kind = \"bistable\"\n",
    "",
    "decoupler.kind",
    "[decoupler]",
    "missing required key: one of \"rigid\" | \"linear\""
);
case!(
    decoupler_missing,
    BASE,
    "[decoupler]\nkind = \"bistable\"\n",
    "[decoupler2]\n",
    "decoupler",
    "name",
    "missing required key: a table"
);
case!(
    rigid_with_bistable_keys,
    BASE,
    "kind = \"bistable\"",
    "kind = \"rigid\"",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"rigid\"; allowed keys: kind"
);
case!(linear_stiffness_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = -5\ndamping_ratio = 1\n", "decoupler.stiffness", "stiffness = -5", "allowed range [0, 1e7] N/m (0 (a free tool, Fig. 1b) to 1e7 N/m, as stiff as the stiffest robot flange in range), got -5");
case!(linear_damping_ratio_negative, BASE, "kind = \"bistable\"\nsprings = 2\nspring_rate = 200.0\nfree_length = 0.05\nheight = 0.03\nfront_stroke = 0.015\nback_stroke = 0.015\nfront_stop = { stiffness = 1e6, damping = 278.0 }\nback_stop = { stiffness = 1e6, restitution = 0.6 }\nfriction = { mu = 0.12, v0 = 0.001 }\n", "kind = \"linear\"\nstiffness = 50\ndamping_ratio = -1\n", "decoupler.damping_ratio", "damping_ratio", "allowed range [0, 10] (undamped to 10 times critical; the thesis uses 0-1 (Table 2)), got -1");
case!(
    linear_unknown_key,
    BASE,
    "kind = \"bistable\"",
    "kind = \"linear\"",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"linear\"; allowed keys: kind, stiffness, damping_ratio"
);

// Bi-stable.
case!(
    springs_float,
    BASE,
    "springs = 2",
    "springs = 2.0",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16] (write it without a decimal point), got 2.0"
);
case!(
    springs_zero,
    BASE,
    "springs = 2",
    "springs = 0",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16], got 0"
);
case!(
    springs_string,
    BASE,
    "springs = 2",
    "springs = \"two\"",
    "decoupler.springs",
    "springs",
    "must be an integer in [1, 16], got string"
);
case!(
    springs_missing,
    BASE,
    "springs = 2\n",
    "",
    "decoupler.springs",
    "[decoupler]",
    "missing required key: an integer in [1, 16]"
);
case!(
    spring_rate_zero,
    BASE,
    "spring_rate = 200.0",
    "spring_rate = 0",
    "decoupler.spring_rate",
    "spring_rate",
    "allowed range [1, 100000] N/m (compression springs of a hand-sized module: 50-490 N/m in Tables 2-15), got 0"
);
case!(
    free_length_negative,
    BASE,
    "free_length = 0.05",
    "free_length = -0.05",
    "decoupler.free_length",
    "free_length",
    "allowed range [0.001, 0.5] m (a hand-sized module: 0.05-0.07 m in Tables 2-15), got -0.05"
);
case!(
    height_zero,
    BASE,
    "height = 0.03",
    "height = 0",
    "decoupler.height",
    "height",
    "allowed range [1e-6, 0.5] m (a hand-sized module: 0.028-0.053 m in Tables 2-15; must also be < free_length), got 0"
);
case!(
    front_stroke_zero,
    BASE,
    "front_stroke = 0.015",
    "front_stroke = 0",
    "decoupler.front_stroke",
    "front_stroke",
    "allowed range [1e-4, 0.2] m (a hand-sized module: 0.015-0.024 m in Tables 2-15), got 0"
);
case!(
    back_stroke_zero,
    BASE,
    "back_stroke = 0.015",
    "back_stroke = 0.0",
    "decoupler.back_stroke",
    "back_stroke",
    "allowed range [1e-4, 0.2] m (a hand-sized module: 0.015-0.025 m in Tables 2-15), got 0"
);
case!(
    bistable_unknown_key,
    BASE,
    "springs = 2\n",
    "springs = 2\nstroke = 0.02\n",
    "decoupler.stroke",
    "stroke",
    "unknown key for kind = \"bistable\"; allowed keys: kind, springs, spring_rate"
);
case!(
    springs_do_not_hold_the_tool,
    BASE,
    "free_length = 0.05",
    "free_length = 0.032",
    "decoupler.free_length",
    "free_length",
    "need free_length > sqrt(height^2 + front_stroke^2) = 0.033541 m"
);
case!(
    front_stop_missing,
    BASE,
    "front_stop = { stiffness = 1e6, damping = 278.0 }\n",
    "",
    "decoupler.front_stop",
    "[decoupler]",
    "missing required key: a table ({ stiffness, damping } or { stiffness, restitution })"
);
case!(
    front_stop_not_table,
    BASE,
    "front_stop = { stiffness = 1e6, damping = 278.0 }",
    "front_stop = 1e6",
    "decoupler.front_stop",
    "front_stop",
    "must be a table ({ stiffness, damping } or { stiffness, restitution }), got float"
);
case!(
    front_stop_damping_negative,
    BASE,
    "damping = 278.0 }",
    "damping = -278.0 }",
    "decoupler.front_stop.damping",
    "front_stop",
    "allowed range [0, 100000] N s/m (235-278 N s/m in Tables 2-15; 1e5 N s/m is beyond critical for the stiffest stop and heaviest tool in range), got -278"
);
case!(
    front_stop_stiffness_zero,
    BASE,
    "front_stop = { stiffness = 1e6",
    "front_stop = { stiffness = 0",
    "decoupler.front_stop.stiffness",
    "front_stop",
    "allowed range [1000, 1e9] N/m (soft elastomer to a hard pad: 1e6-2.25e6 N/m in Tables 2-15; stiffer gives wrong forces at the default tolerances), got 0"
);
case!(
    front_stop_both,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, restitution = 0.4 }",
    "decoupler.front_stop.restitution",
    "front_stop",
    "give either damping (N s/m) or restitution, not both"
);
case!(
    front_stop_neither,
    BASE,
    ", damping = 278.0 }",
    " }",
    "decoupler.front_stop.damping",
    "front_stop",
    "missing required key: damping (N s/m >= 0), or restitution in [0, 1]"
);
case!(
    front_stop_restitution_high,
    BASE,
    "damping = 278.0 }",
    "restitution = 1.5 }",
    "decoupler.front_stop.restitution",
    "front_stop",
    "allowed range [0, 1] (a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)), got 1.5"
);
case!(
    front_stop_unknown_key,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, chi = 3 }",
    "decoupler.front_stop.chi",
    "front_stop",
    "allowed keys: stiffness, damping, restitution"
);
case!(
    front_stop_law_unknown,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, law = \"hertz\" }",
    "decoupler.front_stop.law",
    "front_stop",
    "must be one of \"linear\" | \"hunt-crossley\", got \"hertz\""
);
case!(
    front_stop_exponent_without_hunt_crossley,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, exponent = 1.5 }",
    "decoupler.front_stop.exponent",
    "front_stop",
    "only with law = \"hunt-crossley\""
);
case!(
    front_stop_exponent_out_of_range,
    BASE,
    "damping = 278.0 }",
    "restitution = 0.5, law = \"hunt-crossley\", exponent = 3 }",
    "decoupler.front_stop.exponent",
    "front_stop",
    "allowed range [1, 2]"
);
case!(
    front_stop_exponent_with_damping,
    BASE,
    "damping = 278.0 }",
    "damping = 278.0, law = \"hunt-crossley\", exponent = 1.5 }",
    "decoupler.front_stop.damping",
    "front_stop",
    "give restitution instead"
);

#[test]
fn front_stop_hunt_crossley_keeps_k_and_matches_the_linear_restitution() {
    use crate::damping_law::{hunt_crossley_restitution, linear_restitution};
    let stop = |text: &str| {
        let s = parse(&mutate(BASE, "damping = 278.0 }", text), "hc.toml").unwrap();
        let Decoupler::Bistable(b) = s.decoupler else { panic!("not bistable") };
        b.front_stop
    };
    let lin = stop("damping = 278.0 }");
    assert_eq!(lin.law, FrontStopLaw::Linear);
    let hc = stop("damping = 278.0, law = \"hunt-crossley\" }");
    assert_eq!((hc.stiffness, hc.damping), (lin.stiffness, lin.damping));
    let FrontStopLaw::HuntCrossley { exponent, alpha, restitution } = hc.law else { panic!("{:?}", hc.law) };
    assert_eq!(exponent, 1.0);
    // BASE's tool is 0.75 kg: zeta = 278 / (2 sqrt(1e6 x 0.75)).
    let e = linear_restitution(278.0 / (2.0 * (1e6_f64 * 0.75).sqrt()));
    assert!((restitution - e).abs() < 1e-12 && (0.5..0.95).contains(&e), "{restitution} {e}");
    assert!((hunt_crossley_restitution(alpha, 1.0) - e).abs() < 1e-4);
    // A restitution given is matched as asked, at any exponent.
    let h15 = stop("restitution = 0.4, law = \"hunt-crossley\", exponent = 1.5 }");
    let FrontStopLaw::HuntCrossley { exponent, alpha, .. } = h15.law else { panic!() };
    assert_eq!(exponent, 1.5);
    assert!((hunt_crossley_restitution(alpha, 1.5) - 0.4).abs() < 1e-4);
}
case!(
    back_stop_stiffness_negative,
    BASE,
    "back_stop = { stiffness = 1e6",
    "back_stop = { stiffness = -1",
    "decoupler.back_stop.stiffness",
    "back_stop",
    "allowed range [1000, 1e10] N/m^1.5 (foam to metal on metal: 1e6-2.25e6 N/m^1.5 in Tables 2-15), got -1"
);
case!(
    back_stop_restitution_negative,
    BASE,
    "restitution = 0.6 }",
    "restitution = -0.6 }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "allowed range [0, 1] (a restitution is a ratio of speeds: 0 (plastic) to 1 (elastic)), got -0.6"
);
case!(
    back_stop_chi_and_restitution,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0.6, chi = 5.0 }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "give either chi (a fixed damping) or restitution with damping_law, not both"
);
case!(
    back_stop_chi_and_law,
    BASE,
    "restitution = 0.6 }",
    "damping_law = \"flores\", chi = 5.0 }",
    "decoupler.back_stop.damping_law",
    "back_stop",
    "give either chi"
);
case!(
    back_stop_chi_negative,
    BASE,
    "restitution = 0.6 }",
    "chi = -5.0 }",
    "decoupler.back_stop.chi",
    "back_stop",
    "allowed range [0, 1e8] N s/m^2.5 (4.5e4-1.35e6 N s/m^2.5 in Table 12; 1e8 is overdamped for every stiffness in range), got -5"
);
case!(
    back_stop_no_damping,
    BASE,
    ", restitution = 0.6 }",
    " }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "missing required key: restitution in [0, 1] (with damping_law), or chi"
);
case!(back_stop_law_bad, BASE, "restitution = 0.6 }", "restitution = 0.6, damping_law = \"hertz\" }", "decoupler.back_stop.damping_law", "back_stop", "must be one of \"hunt-crossley\" | \"lankarani-nikravesh\" | \"flores\" | \"gonthier\" | \"exact\", got \"hertz\"");
case!(
    back_stop_law_without_restitution,
    BASE,
    "restitution = 0.6 }",
    "damping_law = \"hertz\" }",
    "decoupler.back_stop.damping_law",
    "back_stop",
    "must be one of"
);
case!(
    back_stop_unknown_key,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0.6, damping = 3 }",
    "decoupler.back_stop.damping",
    "back_stop",
    "allowed keys: stiffness, restitution, damping_law, chi"
);
case!(
    back_stop_gonthier_zero,
    BASE,
    "restitution = 0.6 }",
    "restitution = 0, damping_law = \"gonthier\" }",
    "decoupler.back_stop.restitution",
    "back_stop",
    "must be in (0, 1] with damping_law \"flores\" or \"gonthier\""
);
case!(
    friction_unknown_key,
    BASE,
    "v0 = 0.001 }",
    "v0 = 0.001, static = 0.2 }",
    "decoupler.friction.static",
    "friction",
    "allowed keys: mu, v0"
);
case!(
    friction_mu_negative,
    BASE,
    "mu = 0.12",
    "mu = -0.12",
    "decoupler.friction.mu",
    "friction",
    "allowed range [0, 1] (dry sliding friction: 0.04 (PTFE) to about 1 (rubber on steel); 0.12-0.23 in Tables 5-15), got -0.12"
);
case!(
    friction_v0_negative,
    BASE,
    "v0 = 0.001 }",
    "v0 = -0.001 }",
    "decoupler.friction.v0",
    "friction",
    "allowed range [0, 0.1] m/s (0 is the Coulomb limit (Tables 4, 8, 11, 13); 1e-3 m/s in Table 15; beyond 0.1 m/s friction is no longer dry), got -0.001"
);
case!(
    friction_v0_missing,
    BASE,
    ", v0 = 0.001 }",
    " }",
    "decoupler.friction.v0",
    "friction",
    "missing required key: a number in [0, 0.1] m/s"
);
case!(
    friction_not_table,
    BASE,
    "friction = { mu = 0.12, v0 = 0.001 }",
    "friction = 0.12",
    "decoupler.friction",
    "friction",
    "must be a table ({ mu, v0, law }"
);
case!(
    friction_law_unknown,
    BASE,
    "friction = { mu = 0.12, v0 = 0.001 }",
    "friction = { mu = 0.12, v0 = 0.001, law = \"karnopp\" }",
    "decoupler.friction.law",
    "karnopp",
    "must be one of \"stick-slip\" | \"regularised\", got \"karnopp\""
);
case!(
    friction_stick_slip_with_v0,
    BASE,
    "friction = { mu = 0.12, v0 = 0.001 }",
    "friction = { mu = 0.12, v0 = 0.001, law = \"stick-slip\" }",
    "decoupler.friction.law",
    "law = \"stick-slip\"",
    "needs v0 = 0, got v0 = 0.001 m/s"
);

#[test]
fn friction_law_defaults_follow_v0() {
    use crate::scene::{Decoupler, FrictionLaw};
    let law = |from: &str, to: &str| {
        let s = parse(&mutate(BASE, from, to), "f.toml").unwrap();
        let Decoupler::Bistable(b) = s.decoupler else { panic!("not bi-stable") };
        b.friction.unwrap().law
    };
    let f = "friction = { mu = 0.12, v0 = 0.001 }";
    assert_eq!(law(f, f), FrictionLaw::Regularised);
    assert_eq!(law(f, "friction = { mu = 0.12, v0 = 0.0 }"), FrictionLaw::StickSlip);
    assert_eq!(law(f, "friction = { mu = 0.12, v0 = 0.0, law = \"regularised\" }"), FrictionLaw::Regularised);
    assert_eq!(law(f, "friction = { mu = 0.12, v0 = 0.0, law = \"stick-slip\" }"), FrictionLaw::StickSlip);
}

// Hydraulic.
case!(
    stroke_zero,
    HYD,
    "stroke = 0.023",
    "stroke = 0",
    "decoupler.stroke",
    "stroke = 0",
    "allowed range [0.001, 0.2] m (a hand-sized module: 0.023 m in Tables 12 and 14), got 0"
);
case!(
    piston_radius_negative,
    HYD,
    "piston_radius = 0.020",
    "piston_radius = -0.02",
    "decoupler.piston_radius",
    "piston_radius",
    "allowed range [0.001, 0.1] m (a hand-sized module: 0.02 m in Tables 12 and 14), got -0.02"
);
case!(
    orifice_radius_zero,
    HYD,
    "orifice_radius = 0.008",
    "orifice_radius = 0",
    "decoupler.orifice_radius",
    "orifice_radius",
    "allowed range [1e-5, 0.1] m (0.008 m in Tables 12 and 14; must also be < piston_radius), got 0"
);
case!(
    orifice_not_smaller,
    HYD,
    "orifice_radius = 0.008",
    "orifice_radius = 0.02",
    "decoupler.orifice_radius",
    "orifice_radius",
    "must be < decoupler.piston_radius = 0.02 m, got 0.02"
);
case!(
    gas_pressure_zero,
    HYD,
    "gas_pressure = 1000.0",
    "gas_pressure = 0",
    "decoupler.gas_pressure",
    "gas_pressure",
    "allowed range [100, 1e7] Pa (1000 Pa in Tables 12 and 14; 100 bar is the top of small gas springs), got 0"
);
case!(
    gas_volume_negative,
    HYD,
    "gas_volume = 7.63e-5",
    "gas_volume = -1",
    "decoupler.gas_volume",
    "gas_volume",
    "allowed range [1e-9, 0.01] m^3 (7.63e-5 m^3 in Tables 12 and 14; 10 litres is far beyond a hand-sized module), got -1"
);
case!(
    gas_driven_to_zero,
    HYD,
    "gas_volume = 7.63e-5",
    "gas_volume = 2.8e-5",
    "decoupler.gas_volume",
    "gas_volume",
    "must be > the volume the piston sweeps, pi * piston_radius^2 * stroke = 2.89027e-5 m^3"
);
case!(
    discharge_coefficient_zero,
    HYD,
    "discharge_coefficient = 3.0",
    "discharge_coefficient = 0",
    "decoupler.discharge_coefficient",
    "discharge_coefficient",
    "allowed range [0.1, 10] (3.0 in Tables 12 and 14 (eq 50)), got 0"
);
case!(
    liquid_density_zero,
    HYD,
    "liquid_density = 900.0",
    "liquid_density = 0",
    "decoupler.liquid_density",
    "liquid_density",
    "allowed range [500, 2000] kg/m^3 (hydraulic oils 850-900 kg/m^3, water 1000, glycerol 1260; 900 in Tables 12 and 14), got 0"
);
case!(
    dry_friction_negative,
    HYD,
    "dry_friction = 0.0",
    "dry_friction = -1",
    "decoupler.dry_friction",
    "dry_friction",
    "allowed range [0, 1000] N (seal friction: 0-0.2 N in Tables 12 and 14; the solver gives up near 4000 N), got -1"
);
case!(
    viscous_friction_negative,
    HYD,
    "viscous_friction = 0.5",
    "viscous_friction = -0.5",
    "decoupler.viscous_friction",
    "viscous_friction",
    "allowed range [0, 10000] N s/m (0.5 N s/m in Tables 12 and 14), got -0.5"
);
case!(
    adiabatic_exponent_out_of_range,
    HYD,
    "viscous_friction = 0.5\n",
    "viscous_friction = 0.5\nadiabatic_exponent = 2\n",
    "decoupler.adiabatic_exponent",
    "adiabatic_exponent",
    "allowed range [1, 1.6666666666666667] (1 is isothermal, 5/3 a monatomic gas: nothing outside is a gas), got 2"
);
case!(
    friction_v0_zero,
    HYD,
    "viscous_friction = 0.5\n",
    "viscous_friction = 0.5\nfriction_v0 = 0\n",
    "decoupler.friction_v0",
    "friction_v0",
    "allowed range [1e-5, 0.1] m/s (regularisation of sgn() (eq 48), 1e-3 m/s by default; below 1e-5 m/s the solver grinds), got 0"
);
case!(
    hydraulic_missing_key,
    HYD,
    "liquid_density = 900.0\n",
    "",
    "decoupler.liquid_density",
    "[decoupler]",
    "missing required key: a number in [500, 2000] kg/m^3"
);
case!(
    hydraulic_unknown_key,
    HYD,
    "stroke = 0.023\n",
    "stroke = 0.023\nsprings = 1\n",
    "decoupler.springs",
    "springs",
    "unknown key for kind = \"hydraulic\"; allowed keys: kind, stroke, piston_radius"
);
case!(hydraulic_back_stop_missing, HYD, "back_stop = { stiffness = 1e6, chi = 2e5 }\n", "", "decoupler.back_stop", "[decoupler]", "missing required key: a table ({ stiffness, restitution, damping_law } or { stiffness, chi })");
