//! The robot reduced from joint space (thesis eq 10-16, `host-harness/crates/kinematics`) against
//! closed forms, and the URDFs and configurations it must refuse.
use flinch_harness::kinematics::{reduce, Chain, KinError};
use flinch_tests::scene_path;
use std::f64::consts::PI;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-12)
}

macro_rules! assert_close {
    ($a:expr, $b:expr, $rel:expr) => {{
        let (a, b) = ($a, $b);
        assert!(close(a, b, $rel), "{} = {a} but the closed form {} = {b}", stringify!($a), stringify!($b));
    }};
}

/// A link with an inertial at `x` along the link's x axis.
fn link(name: &str, m: f64, x: f64, ixx: f64, iyy: f64, izz: f64) -> String {
    format!(
        r#"<link name="{name}"><inertial><origin xyz="{x} 0 0" rpy="0 0 0"/><mass value="{m}"/>
        <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial></link>"#
    )
}

fn joint(name: &str, ty: &str, parent: &str, child: &str, xyz: &str, rpy: &str, axis: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{ty}"><parent link="{parent}"/><child link="{child}"/>
        <origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/><limit lower="-10" upper="10" effort="1" velocity="1"/></joint>"#
    )
}

fn robot(parts: &[String]) -> String {
    format!("<robot name=\"t\">{}</robot>", parts.join("\n"))
}

// ---- closed forms ---------------------------------------------------------------------------

/// One-link pendulum: a rod of mass m, centre of mass at lc, inertia I about it, turning about z;
/// the flange at L. M = m lc^2 + I; along the tangent m_r = M / L^2, k_r = K / L^2, c_r = D / L^2;
/// at an angle φ off the tangent (in the plane of motion) each is divided by cos^2 φ.
#[test]
fn one_link_pendulum_matches_closed_form() {
    let (m, lc, i, l) = (4.0, 0.3, 0.05, 0.7);
    let urdf = robot(&[
        "<link name=\"base\"/>".into(),
        link("arm", m, lc, 1e-4, i, i),
        "<link name=\"tip\"/>".into(),
        joint("j", "revolute", "base", "arm", "0 0 0", "0 0 0", "0 0 1"),
        joint("f", "fixed", "arm", "tip", &format!("{l} 0 0"), "0 0 0", "1 0 0"),
    ]);
    let chain = Chain::from_urdf_str(&urdf, "pendulum.urdf", "base", "tip").unwrap();
    let (k, d) = (2.0e4, 15.0);
    let inertia = m * lc * lc + i;
    for q in [0.0, 0.4, -2.0, 3.0] {
        // tangent at the tip: (-sin q, cos q, 0)
        let r = reduce(&chain, &[q], [-q.sin(), q.cos(), 0.0], &[k], &[d]).unwrap();
        assert_close!(r.mass_kg, inertia / (l * l), 1e-9);
        assert_close!(r.stiffness_npm, k / (l * l), 1e-9);
        assert_close!(r.damping_nspm, d / (l * l), 1e-9);
        assert_close!(r.tip_m[0], l * q.cos(), 1e-9);
        for phi in [0.3_f64, 1.0, 1.4] {
            let (t, n) = ([-q.sin(), q.cos()], [q.cos(), q.sin()]);
            let u = [phi.cos() * t[0] + phi.sin() * n[0], phi.cos() * t[1] + phi.sin() * n[1], 0.0];
            let r = reduce(&chain, &[q], u, &[k], &[d]).unwrap();
            let c2 = phi.cos().powi(2);
            assert_close!(r.mass_kg, inertia / (l * l) / c2, 1e-9);
            assert_close!(r.stiffness_npm, k / (l * l) / c2, 1e-9);
        }
    }
}

/// The textbook planar two-link arm (Spong, Hutchinson & Vidyasagar, *Robot Modeling and
/// Control*, 2006, eq 7.87), read from the shipped scenes/robots/two_link.urdf.
fn two_link_closed_form(q: [f64; 2]) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
    let (l1, l2, lc1, lc2, m1, m2) = (0.5, 0.4, 0.25, 0.2, 3.0, 2.0);
    let (i1, i2) = (0.0625, 0.0266666667);
    let c2 = q[1].cos();
    let m11 = m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * c2) + i1 + i2;
    let m12 = m2 * (lc2 * lc2 + l1 * lc2 * c2) + i2;
    let m22 = m2 * lc2 * lc2 + i2;
    let (s1, c1, s12, c12) = (q[0].sin(), q[0].cos(), (q[0] + q[1]).sin(), (q[0] + q[1]).cos());
    let j = [[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]];
    ([[m11, m12], [m12, m22]], j)
}

fn two_link() -> Chain {
    Chain::load(&scene_path("robots/two_link.urdf"), "base", "tip").unwrap()
}

#[test]
fn two_link_mass_matrix_and_reflected_values_match_textbook() {
    let chain = two_link();
    assert_eq!(chain.joint_names, ["shoulder", "elbow"]);
    let (k, d) = ([3.0e4, 1.0e4], [20.0, 4.0]);
    for q in [[0.3, 1.2], [-1.0, 2.5], [2.0, -0.7], [0.0, PI / 2.0]] {
        let at = chain.place(&q);
        let mq = flinch_harness::kinematics::dynamics::mass_matrix(&chain, &at);
        let (mc, j) = two_link_closed_form(q);
        for a in 0..2 {
            for b in 0..2 {
                assert_close!(mq[(a, b)], mc[a][b], 1e-8);
            }
        }
        for u in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.6, -0.8, 0.0], [0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2]] {
            // w = J^T u (planar: z does not move)
            let w = [j[0][0] * u[0] + j[1][0] * u[1], j[0][1] * u[0] + j[1][1] * u[1]];
            let det = mc[0][0] * mc[1][1] - mc[0][1] * mc[1][0];
            let minv = [[mc[1][1] / det, -mc[0][1] / det], [-mc[1][0] / det, mc[0][0] / det]];
            let quad = w[0] * (minv[0][0] * w[0] + minv[0][1] * w[1]) + w[1] * (minv[1][0] * w[0] + minv[1][1] * w[1]);
            let compliance = w[0] * w[0] / k[0] + w[1] * w[1] / k[1];
            let damping = (d[0] * (w[0] / k[0]).powi(2) + d[1] * (w[1] / k[1]).powi(2)) / compliance.powi(2);
            let r = reduce(&chain, &q, u, &k, &d).unwrap();
            let unorm = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
            assert_close!(r.mass_kg, unorm * unorm / quad, 1e-8);
            assert_close!(r.stiffness_npm, unorm * unorm / compliance, 1e-8);
            assert_close!(r.damping_nspm, unorm * unorm * damping, 1e-8);
            let shares: f64 = r.joints.iter().map(|s| s.compliance_share).sum();
            assert_close!(shares, 1.0, 1e-9);
        }
    }
}

/// Joint damping proportional to joint stiffness (D = β K) reduces to c_r = β k_r, whatever the
/// configuration (eq 13 with eq 14).
#[test]
fn proportional_joint_damping_gives_proportional_flange_damping() {
    let chain = two_link();
    let beta = 2.5e-3;
    let k = [3.0e4, 1.0e4];
    let r = reduce(&chain, &[0.7, 1.1], [0.3, 0.9, 0.0], &k, &[beta * k[0], beta * k[1]]).unwrap();
    assert_close!(r.damping_nspm, beta * r.stiffness_npm, 1e-12);
}

/// A prismatic joint: a cart of mass mc on x carrying a pendulum bob mp at l (the cart-pole):
/// M = [[mc + mp, mp l cos q2], [mp l cos q2, mp l^2]].
#[test]
fn prismatic_cart_pole_matches_closed_form() {
    let (mc, mp, l) = (5.0, 1.5, 0.6);
    let urdf = robot(&[
        "<link name=\"rail\"/>".into(),
        link("cart", mc, 0.0, 0.0, 0.0, 0.0),
        link("pole", mp, l, 0.0, 0.0, 0.0),
        "<link name=\"tip\"/>".into(),
        joint("slide", "prismatic", "rail", "cart", "0 0 0", "0 0 0", "1 0 0"),
        // the pole turns about z; at q2 = 0 it points along +x
        joint("hinge", "continuous", "cart", "pole", "0 0 0", "0 0 0", "0 0 1"),
        joint("f", "fixed", "pole", "tip", &format!("{l} 0 0"), "0 0 0", "1 0 0"),
    ]);
    let chain = Chain::from_urdf_str(&urdf, "cartpole.urdf", "rail", "tip").unwrap();
    assert_eq!(chain.joint_kinds, [flinch_harness::kinematics::JointKind::Prismatic, flinch_harness::kinematics::JointKind::Revolute]);
    for q in [[0.2, 0.5], [-0.4, 2.0]] {
        let at = chain.place(&q);
        let m = flinch_harness::kinematics::dynamics::mass_matrix(&chain, &at);
        // bob at (x + l cos q2, l sin q2): d/dq2 = (-l sin q2, l cos q2) so M12 = mp * (-l sin q2)
        let m12 = -mp * l * q[1].sin();
        assert_close!(m[(0, 0)], mc + mp, 1e-12);
        assert_close!(m[(0, 1)], m12, 1e-9);
        assert_close!(m[(1, 1)], mp * l * l, 1e-12);
        assert_close!(at.tip.x, q[0] + l * q[1].cos(), 1e-12);
    }
    // A cart alone: along the rail m_r = mc, k_r = K, c_r = D; at 60° off the rail, / cos^2.
    let cart = robot(&[
        "<link name=\"rail\"/>".into(),
        link("cart", mc, 0.1, 0.01, 0.01, 0.01),
        joint("slide", "prismatic", "rail", "cart", "0 0 0", "0 0 0", "1 0 0"),
    ]);
    let chain = Chain::from_urdf_str(&cart, "cart.urdf", "rail", "cart").unwrap();
    let r = reduce(&chain, &[0.3], [1.0, 0.0, 0.0], &[8.0e4], &[30.0]).unwrap();
    assert_close!(r.mass_kg, mc, 1e-12);
    assert_close!(r.stiffness_npm, 8.0e4, 1e-12);
    assert_close!(r.damping_nspm, 30.0, 1e-12);
    let r = reduce(&chain, &[0.3], [0.5, 0.75_f64.sqrt(), 0.0], &[8.0e4], &[30.0]).unwrap();
    assert_close!(r.mass_kg, mc / 0.25, 1e-9);
}

/// The same arm mounted on a base turned and moved by a fixed joint, with the approach turned the
/// same way, gives the same m_r, k_r, c_r.
#[test]
fn invariant_under_a_rotation_of_the_base() {
    let text = std::fs::read_to_string(scene_path("robots/two_link.urdf")).unwrap();
    let (r, p, y) = (0.3_f64, -0.7_f64, 1.1_f64);
    let mounted = text.replace(
        "<link name=\"base\"/>",
        &format!(
            "<link name=\"world\"/><link name=\"base\"/><joint name=\"mount\" type=\"fixed\"><parent link=\"world\"/>\
             <child link=\"base\"/><origin xyz=\"0.1 -0.2 0.3\" rpy=\"{r} {p} {y}\"/></joint>"
        ),
    );
    let on_world = Chain::from_urdf_str(&mounted, "mounted.urdf", "world", "tip").unwrap();
    let plain = two_link();
    let rot = nalgebra::UnitQuaternion::from_euler_angles(r, p, y);
    let (k, d) = ([3.0e4, 1.0e4], [20.0, 4.0]);
    for (q, u) in [([0.3, 1.2], [0.6, -0.8, 0.0]), ([-1.0, 2.5], [0.2, 0.3, 0.9])] {
        let a = reduce(&plain, &q, u, &k, &d).unwrap();
        let uw = rot * nalgebra::Vector3::from(u);
        let b = reduce(&on_world, &q, [uw.x, uw.y, uw.z], &k, &d).unwrap();
        assert_close!(b.mass_kg, a.mass_kg, 1e-9);
        assert_close!(b.stiffness_npm, a.stiffness_npm, 1e-9);
        assert_close!(b.damping_nspm, a.damping_nspm, 1e-9);
    }
}

/// The reflected mass is the least kinetic energy over the joint motions that move the tip at
/// unit speed along u: it is never above `q'ᵀ M q' / (uᵀ J q')^2` for any q'. Along the direction
/// the last joint moves the tip, that bounds it by the mass past the last joint (its centre of
/// mass lies inside the tip radius), hence by the total mass past the base.
#[test]
fn reflected_mass_is_bounded_by_any_motion_and_by_the_moving_mass() {
    let chain = two_link();
    let (k, d) = ([3.0e4, 1.0e4], [20.0, 4.0]);
    for q in [[0.3, 1.2], [-1.0, 2.5], [2.0, -0.7]] {
        let (m, j) = two_link_closed_form(q);
        for u in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.6, -0.8, 0.0]] {
            let r = reduce(&chain, &q, u, &k, &d).unwrap();
            for qd in [[1.0, 0.0], [0.0, 1.0], [1.0, -1.0], [0.3, 2.0], [-2.0, 0.5]] {
                let energy2 = qd[0] * (m[0][0] * qd[0] + m[0][1] * qd[1]) + qd[1] * (m[1][0] * qd[0] + m[1][1] * qd[1]);
                let v = u[0] * (j[0][0] * qd[0] + j[0][1] * qd[1]) + u[1] * (j[1][0] * qd[0] + j[1][1] * qd[1]);
                if v.abs() > 1e-6 {
                    assert!(r.mass_kg <= energy2 / (v * v) * (1.0 + 1e-9), "m_r {} above {}", r.mass_kg, energy2 / (v * v));
                }
            }
        }
        // along the elbow's tip motion
        let u = [j[0][1], j[1][1], 0.0];
        let r = reduce(&chain, &q, u, &k, &d).unwrap();
        assert!(r.mass_kg <= 2.0 + 1e-9, "m_r {} above the forearm's 2 kg", r.mass_kg);
        assert!(r.mass_kg <= r.moving_mass_kg, "m_r {} above the moving mass {}", r.mass_kg, r.moving_mass_kg);
        assert_close!(r.moving_mass_kg, 5.0, 1e-12);
    }
}

/// Adversarial: near a singularity the reflected mass is NOT bounded by the moving mass (a
/// stretched arm pushed along its length is a wall); Flinch must give the large value, not clip
/// it, and refuse the singular configuration itself.
#[test]
fn near_singular_mass_grows_and_the_singular_configuration_is_refused() {
    let chain = two_link();
    let (k, d) = ([3.0e4, 1.0e4], [20.0, 4.0]);
    // Nearly stretched (elbow 0.05 rad) pushed along the arm.
    let r = reduce(&chain, &[0.0, 0.05], [1.0, 0.0, 0.0], &k, &d).unwrap();
    assert!(r.mass_kg > 10.0 * r.moving_mass_kg, "m_r {} should exceed 10 x the moving mass", r.mass_kg);
    assert!(r.stiffness_npm > 1.0e5);
    // Stretched: refused.
    let e = reduce(&chain, &[0.0, 0.0], [1.0, 0.0, 0.0], &k, &d).unwrap_err();
    assert!(e.what.contains("singular configuration"), "{e}");
    assert!(e.to_string().contains("two_link.urdf: joints:"), "{e}");
    // Perpendicular to the plane of motion: the tip cannot move along z at all.
    let e = reduce(&chain, &[0.3, 1.0], [0.0, 0.0, 1.0], &k, &d).unwrap_err();
    assert!(e.what.contains("singular configuration"), "{e}");
}

// ---- bad input ------------------------------------------------------------------------------

fn err(text: &str, base: &str, tip: &str) -> KinError {
    Chain::from_urdf_str(text, "bad.urdf", base, tip).unwrap_err()
}

fn two_link_text() -> String {
    std::fs::read_to_string(scene_path("robots/two_link.urdf")).unwrap()
}

#[test]
fn missing_links_and_joints_are_named() {
    let t = two_link_text();
    let e = err(&t, "base", "flange_link");
    assert_eq!((e.file.as_str(), e.element.as_str()), ("bad.urdf", "tip_link"));
    assert!(e.what.contains("\"flange_link\" is not in the URDF") && e.what.contains("link1"), "{e}");
    let e = err(&t, "world", "tip");
    assert_eq!(e.element, "base_link");
    // tip above base
    let e = err(&t, "link2", "link1");
    assert!(e.what.contains("is not below base_link"), "{e}");
    // a joint whose child link is not declared
    let e = err(&t.replace("<child link=\"link2\"/>", "<child link=\"link_2\"/>"), "base", "tip");
    assert_eq!(e.element, "joint \"elbow\"");
    assert!(e.what.contains("child link \"link_2\" is not a <link>"), "{e}");
    // a floating joint on the chain
    let e = err(&t.replace("type=\"revolute\">\n    <parent link=\"link1\"/>", "type=\"floating\">\n    <parent link=\"link1\"/>"), "base", "tip");
    assert_eq!(e.element, "joint \"elbow\"");
    assert!(e.what.contains("type floating"), "{e}");
    // no moving joint
    let e = err(&t, "link2", "tip");
    assert!(e.what.contains("nothing moves"), "{e}");
}

#[test]
fn joint_count_mismatch_is_refused() {
    let chain = two_link();
    let e = reduce(&chain, &[0.1, 0.2, 0.3], [1.0, 0.0, 0.0], &[1.0, 1.0], &[0.0, 0.0]).unwrap_err();
    assert_eq!(e.element, "joints");
    assert!(e.what.contains("has 3 values") && e.what.contains("2 moving joints (shoulder, elbow)"), "{e}");
    let e = reduce(&chain, &[0.1, 0.2], [1.0, 0.0, 0.0], &[1.0], &[0.0, 0.0]).unwrap_err();
    assert_eq!(e.element, "joint_stiffness");
    let e = reduce(&chain, &[0.1, 0.2], [1.0, 0.0, 0.0], &[1.0, 1.0], &[0.0]).unwrap_err();
    assert_eq!(e.element, "joint_damping");
    let e = reduce(&chain, &[0.1, 0.2], [1.0, 0.0, 0.0], &[1.0, 0.0], &[0.0, 0.0]).unwrap_err();
    assert!(e.element == "joint_stiffness" && e.what.contains("\"elbow\""), "{e}");
    let e = reduce(&chain, &[0.1, 0.2], [1.0, 0.0, 0.0], &[1.0, 1.0], &[0.0, -1.0]).unwrap_err();
    assert_eq!(e.element, "joint_damping");
    let e = reduce(&chain, &[0.1, 0.2], [0.0, 0.0, 0.0], &[1.0, 1.0], &[0.0, 0.0]).unwrap_err();
    assert_eq!(e.element, "direction");
    let e = reduce(&chain, &[0.1, f64::NAN], [1.0, 0.0, 0.0], &[1.0, 1.0], &[0.0, 0.0]).unwrap_err();
    assert_eq!(e.element, "joints");
}

#[test]
fn non_physical_inertia_is_refused() {
    let t = two_link_text();
    let e = err(&t.replace("<mass value=\"2\"/>", "<mass value=\"-2\"/>"), "base", "tip");
    // Held to the URDF range table first, with the file and line (issue 27, urdf_scan.rs).
    assert_eq!(e.element, "link \"link2\"");
    assert!(e.what.contains("<mass value>: allowed range [0, 10000] kg") && e.what.contains("got -2"), "{e}");
    assert!(e.file.starts_with("bad.urdf:"), "{e}");
    let e = err(&t.replace("iyy=\"0.0625\"", "iyy=\"-0.0625\""), "base", "tip");
    assert_eq!(e.element, "link \"link1\"");
    assert!(e.what.contains("<inertia iyy>: allowed range [0, 10000] kg m^2"), "{e}");
    // Every entry in range, the tensor not positive semi-definite: refused by the physics check.
    let e = err(&t.replacen("ixy=\"0\"", "ixy=\"0.06\"", 1), "base", "tip");
    assert!(e.what.contains("negative principal moment"), "{e}");
    // izz larger than ixx + iyy: no body has it
    let e = err(&t.replace("izz=\"0.0625\"", "izz=\"0.5\""), "base", "tip");
    assert!(e.what.contains("triangle inequality"), "{e}");
    // every link massless: the mass matrix is singular
    let massless = t.replace("<mass value=\"3\"/>", "<mass value=\"0\"/>").replace("<mass value=\"2\"/>", "<mass value=\"0\"/>");
    let massless = massless.replace("ixx=\"0.0001\"", "ixx=\"0\"").replace("0.0625", "0").replace("0.0266666667", "0");
    let chain = Chain::from_urdf_str(&massless, "bad.urdf", "base", "tip").unwrap();
    let e = reduce(&chain, &[0.3, 1.0], [1.0, 0.0, 0.0], &[1.0, 1.0], &[0.0, 0.0]).unwrap_err();
    assert!(e.what.contains("not positive definite"), "{e}");
}

#[test]
fn unparseable_urdf_is_refused_with_the_file() {
    let e = err("<robot name=\"x\"><link name=\"a\"></robot>", "a", "a");
    assert_eq!((e.file.as_str(), e.element.as_str()), ("bad.urdf", "<robot>"));
    assert!(e.what.contains("is not a URDF that parses"), "{e}");
    assert!(e.what.contains("line 1") && e.what.contains("not well-formed XML"), "{e}");
    // A number that is not one names the link, the line and the attribute.
    let text = two_link_text();
    let (first, _) = text.split_once("<mass value=").unwrap();
    let line = first.lines().count();
    let e = err(&text.replacen("<mass value=\"", "<mass value=\"three", 1), "base", "tip");
    assert!(e.what.contains("parses") && e.what.contains("<mass value=\"three"), "{e}");
    assert!(e.element.starts_with("link \"") && e.element.ends_with(&format!("(line {line})")), "{e}");
    // A joint without a type names the joint.
    let e = err(&text.replacen("type=\"revolute\"", "", 1), "base", "tip");
    assert!(e.element.starts_with("joint \"") && e.what.contains("has no type"), "{e}");
    let e = Chain::load(std::path::Path::new("/nonexistent/robot.urdf"), "a", "b").unwrap_err();
    assert!(e.to_string().starts_with("/nonexistent/robot.urdf: urdf: cannot be read"), "{e}");
}

// ---- the scene: [robot] urdf = ... ----------------------------------------------------------

fn scene_text() -> String {
    std::fs::read_to_string(scene_path("robot_two_link.toml")).unwrap()
}

/// Parses `text` as if it were scenes/NAME (so `urdf` resolves beside the shipped scenes).
fn parse_as_shipped(text: &str) -> Result<flinch_harness::scene::Scene, flinch_harness::scene::SceneError> {
    flinch_harness::scene::parse(text, &scene_path("robot_two_link.toml").display().to_string())
}

/// The plant gets exactly the reduced values, as it gets Table 7's.
#[test]
fn scene_with_a_urdf_gets_the_reduced_values_and_runs() {
    let s = flinch_harness::scene::load(&scene_path("robot_two_link.toml")).unwrap_or_else(|e| panic!("{e}"));
    let r = reduce(&two_link(), &[0.3, 1.2], [1.0, 0.0, 0.0], &[2.0e4, 1.0e4], &[20.0, 5.0]).unwrap();
    let robot = s.robot.expect("a compliant robot");
    assert_eq!((robot.mass, robot.stiffness, robot.damping), (r.mass_kg, r.stiffness_npm, r.damping_nspm));
    // The same values written as lumped keys give the same run, bit for bit.
    let lumped = scene_text().replace(
        &scene_text()[scene_text().find("[robot]").unwrap()..scene_text().find("[tool]").unwrap()],
        &format!("[robot]\nmass = {:e}\nstiffness = {:e}\ndamping = {:e}\n\n", r.mass_kg, r.stiffness_npm, r.damping_nspm),
    );
    let l = flinch_harness::scene::parse(&lumped, "lumped.toml").unwrap_or_else(|e| panic!("{e}"));
    let a = flinch_harness::sim::run(&s, false).unwrap().0;
    let b = flinch_harness::sim::run(&l, false).unwrap().0;
    assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&b).unwrap());
    assert!(a.peak_contact_force > 0.0);
    // A list gives the same configuration as the table by joint name.
    let listed = scene_text().replace("joints = { shoulder = 0.3, elbow = 1.2 }", "joints = [0.3, 1.2]");
    assert_eq!(parse_as_shipped(&listed).unwrap().robot, s.robot);
    // and a different configuration gives a different robot (the keys are read, not ignored)
    let other = scene_text().replace("elbow = 1.2", "elbow = 2.0");
    assert_ne!(parse_as_shipped(&other).unwrap().robot, s.robot);
}

fn scene_err(text: &str) -> String {
    parse_as_shipped(text).map(|_| ()).unwrap_err().to_string()
}

#[test]
fn scene_refuses_bad_robot_keys_with_line_and_key() {
    let t = scene_text();
    // count mismatch, at the key's line
    let e = scene_err(&t.replace("joint_stiffness = [2.0e4, 1.0e4]", "joint_stiffness = [2.0e4]"));
    assert!(e.contains("robot_two_link.toml:21: robot.joint_stiffness: has 1 values; the chain \"base\" -> \"tip\" has 2 moving joints (shoulder, elbow)"), "{e}");
    // an unknown joint name in the table form
    let e = scene_err(&t.replace("elbow = 1.2", "elbo = 1.2"));
    assert!(e.contains("robot.joints: \"elbo\" is not a moving joint"), "{e}");
    // a missing link, reported at robot.tip_link with the URDF file
    let e = scene_err(&t.replace("tip_link = \"tip\"", "tip_link = \"flange\""));
    assert!(e.contains(":18: robot.tip_link:") && e.contains("two_link.urdf: tip_link: link \"flange\" is not in the URDF"), "{e}");
    // a URDF that does not exist
    let e = scene_err(&t.replace("robots/two_link.urdf", "robots/ur10e.urdf"));
    assert!(e.contains("robot.urdf: cannot read the URDF") && e.contains("ur10e.urdf"), "{e}");
    // lumped values with urdf
    let e = scene_err(&t.replace("base_link = \"base\"", "base_link = \"base\"\nmass = 8.4"));
    assert!(e.contains("robot.mass: is given with urdf"), "{e}");
    // a urdf key without urdf
    let e = scene_err(&t.replace("urdf = \"robots/two_link.urdf\"", "mass = 8.4\nstiffness = 2.3e5\ndamping = 71.0"));
    assert!(e.contains("robot.base_link: is only read with urdf"), "{e}");
    // a singular configuration: stretched arm pushed along its length
    let e = scene_err(&t.replace("shoulder = 0.3, elbow = 1.2", "shoulder = 0.0, elbow = 0.0"));
    assert!(e.contains("robot.joints:") && e.contains("singular configuration"), "{e}");
    // outside the URDF's joint limits
    let e = scene_err(&t.replace("elbow = 1.2", "elbow = 3.2"));
    assert!(e.contains("joint \"elbow\" at 3.2 is outside its URDF <limit> [-3.14, 3.14]"), "{e}");
    // a direction of zeros
    let e = scene_err(&t.replace("direction = [1.0, 0.0, 0.0]", "direction = [0, 0, 0]"));
    assert!(e.contains("robot.direction:"), "{e}");
    // a joint stiffness below the range
    let e = scene_err(&t.replace("joint_stiffness = [2.0e4, 1.0e4]", "joint_stiffness = [2.0e4, -1.0]"));
    assert!(e.contains("robot.joint_stiffness: item 2: allowed range"), "{e}");
}

/// Adversarial: near (not at) the singularity the reduction is valid but huge; the plant's own
/// range for m_r refuses it instead of simulating a 1000 kg flange the user never asked for.
#[test]
fn scene_refuses_a_reduced_mass_outside_the_plant_range() {
    let t = scene_text().replace("shoulder = 0.3, elbow = 1.2", "shoulder = 0.0, elbow = 0.01");
    let e = scene_err(&t);
    assert!(e.contains("robot.urdf: reduces to mass = ") && e.contains("outside the range of [robot] mass"), "{e}");
}

// ---- flinch robot ---------------------------------------------------------------------------

fn robot_args(scene: std::path::PathBuf, joint: Option<&str>, csv: Option<std::path::PathBuf>) -> flinch_harness::kinematics::cli::RobotArgs {
    flinch_harness::kinematics::cli::RobotArgs { scene, sweep_joint: joint.map(str::to_string), from: None, to: None, points: 181, plot: None, csv }
}

/// Adversarial: a sweep through the singularity (stretched arm pushed along itself) must mark that
/// point refused in the CSV, never print a finite m_r for it, and still give the others.
#[test]
fn robot_sweep_through_a_singularity_marks_it_refused() {
    let dir = std::env::temp_dir().join(format!("flinch-robot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = scene_path("robots/two_link.urdf").canonicalize().unwrap();
    let text = scene_text()
        .replace("robots/two_link.urdf", &urdf.display().to_string())
        .replace("shoulder = 0.3, elbow = 1.2", "shoulder = 0.0, elbow = 1.2");
    let scene = dir.join("stretched.toml");
    std::fs::write(&scene, text).unwrap();
    let csv = dir.join("sweep.csv");
    assert_eq!(flinch_harness::kinematics::cli::run(&robot_args(scene.clone(), Some("2"), Some(csv.clone()))), Ok(true));
    let out = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(rows.len(), 181);
    assert!(out.starts_with("elbow_rad,mass_kg,stiffness_n_per_m,damping_ns_per_m,mobility,status,reason\n"));
    let at_zero = rows.iter().find(|r| r.split(',').next().unwrap().parse::<f64>().unwrap().abs() < 1e-9).expect("elbow = 0 is a point");
    assert!(at_zero.contains(",,,,,refused,") && at_zero.contains("singular configuration"), "{at_zero}");
    let ok = rows.iter().filter(|r| r.contains(",ok,")).count();
    assert!(ok >= 170, "only {ok} points reduced");
    // Near the singularity m_r grows past what the plant accepts (500 kg): those poses are refused
    // with the range, never listed as ok, since `flinch run` would refuse them.
    assert!(rows.iter().any(|r| r.contains("outside the plant's range for robot.mass")), "{out}");
    for r in rows.iter().filter(|r| r.contains(",ok,")) {
        let m: f64 = r.split(',').nth(1).unwrap().parse().unwrap();
        assert!((0.1..=500.0).contains(&m), "{r}");
    }
    // the unswept joint named, a joint that is not there, and a scene without a URDF: bad input (2)
    let e = flinch_harness::kinematics::cli::run(&robot_args(scene.clone(), Some("wrist"), None)).unwrap_err();
    assert_eq!(e.code, 2);
    assert!(e.message.contains("joints: shoulder, elbow"), "{}", e.message);
    let e = flinch_harness::kinematics::cli::run(&robot_args(scene_path("tables5-7_bistable.toml"), None, None)).unwrap_err();
    assert_eq!(e.code, 2);
    assert!(e.message.contains("[robot] is not given by a URDF"), "{}", e.message);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn robot_report_says_where_each_value_comes_from() {
    let s = flinch_harness::scene::urdf_robot(&scene_text(), &scene_path("robot_two_link.toml").display().to_string()).unwrap().unwrap();
    let r = s.reduce().unwrap();
    let t = flinch_harness::kinematics::cli::describe("x", &s, &r);
    assert!(t.contains(&format!("m_r = {:.4} kg", r.mass_kg)), "{t}");
    assert!(t.contains("shoulder") && t.contains("elbow") && t.contains("%"), "{t}");
    assert!(t.contains("not defined (needs six joints"), "{t}");
}

// ---- six joints: the Viper s650 stand-in ----------------------------------------------------

fn viper() -> Chain {
    Chain::load(&scene_path("robots/viper_s650_standin.urdf"), "base", "flange").unwrap()
}

/// The URDF's frames are the standard Denavit-Hartenberg ones it says: the flange position is the
/// product of `Rz(θ) Tz(d) Tx(a) Rx(α)`.
#[test]
fn viper_standin_frames_follow_its_dh_table() {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
    let dh = [(0.075, 0.335, -PI / 2.0), (0.270, 0.0, 0.0), (-0.090, 0.0, PI / 2.0), (0.0, 0.295, -PI / 2.0), (0.0, 0.0, PI / 2.0), (0.0, 0.080, 0.0)];
    let chain = viper();
    assert_eq!(chain.dof(), 6);
    assert_close!(chain.moving_mass(), 20.8, 1e-12);
    for q in [[0.0; 6], [0.1, -0.5, 0.7, 0.3, -0.9, 0.2], [1.0, 0.4, -1.2, 2.0, 0.5, -1.0]] {
        let mut t = Isometry3::identity();
        for (i, (a, d, al)) in dh.iter().enumerate() {
            t = t * Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[i]))
                * Isometry3::from_parts(Translation3::new(*a, 0.0, *d), UnitQuaternion::from_axis_angle(&Vector3::x_axis(), *al));
        }
        let at = chain.place(&q);
        assert!((at.tip - t.translation.vector).norm() < 1e-12, "{q:?}: {} vs {}", at.tip, t.translation.vector);
    }
}

/// The stand-in's arm is the published Viper 650's, not its mirror image: its wrist centre and
/// forearm (joint 4) axis are those of ViSP's model of the real robot at the same q1, q2, q3.
/// Source: github.com/lagadic/visp, modules/robot/src/real-robot/viper/vpViper650.cpp (a1 = 0.075,
/// a2 = 0.270, a3 = 0.090, d1 = 0.335, d4 = 0.295 m) and vpViper.cpp, `vpViper::get_fMw` (the wrist
/// frame; its z column at q4 = q5 = 0 is the forearm axis). With the file's twists (+90 deg at
/// joint 3) that arm is a3 = -0.090 in the URDF; a3 = +0.090 (the file before this test) put the
/// elbow offset on the other side of the forearm, a mirror image no joint zero can turn into the
/// real arm (the wrist then missed get_fMw's by up to 2 a3 = 0.18 m).
#[test]
fn viper_standin_wrist_is_visps_viper650() {
    let (a1, a2, a3, d1, d4) = (0.075, 0.270, 0.090, 0.335, 0.295);
    let chain = viper();
    let mut worst: f64 = 0.0;
    for q in [[0.0f64; 6], [0.1, -0.5, 0.7, 0.3, -0.9, 0.2], [1.0, 0.4, -1.2, 2.0, 0.5, -1.0], [-2.5, 1.3, 2.9, 0.0, 0.0, 0.0], [0.7, -1.9, -0.4, 1.0, 2.0, 3.0]] {
        let (c1, s1, c2, s2) = (q[0].cos(), q[0].sin(), q[1].cos(), q[1].sin());
        let (c23, s23) = ((q[1] + q[2]).cos(), (q[1] + q[2]).sin());
        let reach = -c23 * a3 + s23 * d4 + a1 + a2 * c2;
        let wrist = [c1 * reach, s1 * reach, s23 * a3 + c23 * d4 - a2 * s2 + d1];
        let forearm = [c1 * s23, s1 * s23, c23];
        let at = chain.place(&q);
        // Joint 5's origin is the wrist centre (the three wrist axes meet there), joint 4's axis the
        // forearm's.
        for k in 0..3 {
            worst = worst.max((at.points[4][k] - wrist[k]).abs());
            worst = worst.max((at.axes[3][k] - forearm[k]).abs());
        }
    }
    assert!(worst < 1e-12, "the stand-in's wrist is {worst} m (or its forearm axis that far) from ViSP's Viper 650");
}

/// The thesis's eq 12-14 element (flange held in the other five directions) is never below the
/// free-flange value Flinch uses (Cauchy-Schwarz); both are given for a six-joint arm.
#[test]
fn viper_held_element_is_never_below_the_free_value() {
    let chain = viper();
    let k = [1.5e5, 1.5e5, 8.0e4, 2.0e4, 2.0e4, 1.0e4];
    let d = [60.0, 60.0, 30.0, 8.0, 8.0, 4.0];
    let mut compared = 0;
    for q in [[0.1, -0.5, 0.7, 0.3, -0.9, 0.2], [1.0, 0.4, -1.2, 2.0, 0.5, -1.0], [0.0, -1.0, 1.5, 0.0, 1.0, 0.0]] {
        for u in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.3, -0.5, 0.8]] {
            let r = reduce(&chain, &q, u, &k, &d).unwrap();
            let (m, ks, _) = r.held.expect("six joints away from a singularity");
            assert!(m >= r.mass_kg * (1.0 - 1e-9), "held {m} < free {}", r.mass_kg);
            assert!(ks >= r.stiffness_npm * (1.0 - 1e-9), "held {ks} < free {}", r.stiffness_npm);
            compared += 1;
        }
    }
    assert_eq!(compared, 12);
}

/// Links off the chain ride as payload: a 1 kg point mass hung at the tip on a side branch (a fixed
/// joint, or a revolute joint off the chain, held at zero) adds `m Jᵀ J` to the mass matrix.
#[test]
fn side_branch_links_count_as_payload_at_their_place() {
    let t = two_link_text();
    let payload = |ty: &str| {
        t.replace(
            "<link name=\"tip\"/>",
            &format!(
                "<link name=\"tip\"/><link name=\"camera\"><inertial><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/><mass value=\"1\"/>\
                 <inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/></inertial></link>\
                 <joint name=\"cam\" type=\"{ty}\"><parent link=\"link2\"/><child link=\"camera\"/><origin xyz=\"0.4 0 0\" rpy=\"0.3 0.2 0.1\"/>\
                 <axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
            ),
        )
    };
    let plain = two_link();
    for ty in ["fixed", "revolute"] {
        let branched = Chain::from_urdf_str(&payload(ty), "branched.urdf", "base", "tip").unwrap();
        assert_eq!(branched.joint_names, ["shoulder", "elbow"], "{ty}: the side joint is not in the chain");
        assert_close!(branched.moving_mass(), 6.0, 1e-12);
        for q in [[0.3, 1.2], [-1.0, 2.5]] {
            let (_, j) = two_link_closed_form(q);
            let a = flinch_harness::kinematics::dynamics::mass_matrix(&plain, &plain.place(&q));
            let b = flinch_harness::kinematics::dynamics::mass_matrix(&branched, &branched.place(&q));
            for r in 0..2 {
                for c in 0..2 {
                    let add = j[0][r] * j[0][c] + j[1][r] * j[1][c];
                    assert_close!(b[(r, c)], a[(r, c)] + add, 1e-9);
                }
            }
        }
    }
}

/// End to end beyond `run`: the stroke check and the firmware in the loop take the URDF scene, and
/// a sweep over a joint refuses the singular pose (the stretched arm) instead of running it.
#[test]
fn check_hil_and_a_joint_sweep_take_the_urdf_scene() {
    use flinch_harness::sweep::{Axis, Progress, Status, Sweep, Template};
    let s = flinch_harness::scene::load(&scene_path("robot_two_link.toml")).unwrap();
    let c = flinch_harness::check::check(&s).unwrap();
    assert!(c.fits, "the example module's stroke absorbs the stop");
    let ctl = flinch_harness::scene::Controller::new(0.016, 0.0, 1e-4);
    let (rep, _) = flinch_harness::hil::run(&s, &ctl, false).unwrap();
    assert!(rep.firmware.switch_time.is_some(), "the switch fires and the firmware sees it");

    let text = scene_text().replace("shoulder = 0.3, elbow = 1.2", "shoulder = 0.0, elbow = 1.2");
    let t = Template::from_text(&text, &scene_path("robot_two_link.toml").display().to_string()).unwrap();
    let r = Sweep::keep_going(&t, vec![Axis::parse("robot.joints.elbow=0:1.2:3", false).unwrap()]).unwrap().run(Progress::Hidden);
    assert_eq!(r.points.len(), 3);
    assert_eq!(r.points[0].status, Status::Refused, "elbow = 0 is the stretched arm pushed along itself");
    assert!(r.points[0].outcome.as_ref().unwrap_err().contains("singular configuration"));
    let f: Vec<f64> = r.points[1..].iter().map(|p| p.outcome.as_ref().unwrap().peak_contact_force).collect();
    assert!(f[0] != f[1], "a different pose is a different robot: {f:?}");
}

/// Joints written as a list: `robot.joints.1` is the second joint and changes the robot; a name or
/// an index past the end is refused before anything runs, never swept as the unchanged scene.
#[test]
fn a_joint_list_is_swept_by_index_and_a_bad_path_is_refused() {
    use flinch_harness::sweep::{Axis, Progress, Sweep, Template};
    let text = scene_text().replace("joints = { shoulder = 0.3, elbow = 1.2 }", "joints = [0.3, 1.2]");
    assert!(text.contains("joints = [0.3, 1.2]"));
    let t = Template::from_text(&text, &scene_path("robot_two_link.toml").display().to_string()).unwrap();
    assert!(t.numeric_keys().iter().any(|k| k == "robot.joints.1"), "{:?}", t.numeric_keys());
    let r = Sweep::keep_going(&t, vec![Axis::parse("robot.joints.1=0.6:1.2:2", false).unwrap()]).unwrap().run(Progress::Hidden);
    let f: Vec<f64> = r.points.iter().map(|p| p.outcome.as_ref().unwrap().peak_contact_force).collect();
    assert!(f[0] != f[1], "the elbow moved, so the robot changed: {f:?}");
    for bad in ["robot.joints.elbow=0.6:1.2:2", "robot.joints.2=0.6:1.2:2", "robot.joints.foo=0.6:1.2:2"] {
        let e = match Sweep::keep_going(&t, vec![Axis::parse(bad, false).unwrap()]) {
            Ok(_) => panic!("{bad}: accepted, so the sweep would run the unchanged robot"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("cannot be set") && e.contains("robot.joints.1"), "{bad}: {e}");
    }
}

/// A user's scene elsewhere whose `urdf` is missing is refused with the path: the project's own
/// stand-in robot of the same relative name is used only for the shipped scene run by name.
#[test]
fn a_missing_urdf_is_never_replaced_by_the_shipped_stand_in() {
    let dir = std::env::temp_dir().join(format!("flinch-urdf-missing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("mine.toml");
    std::fs::write(&file, scene_text()).unwrap();
    let e = flinch_harness::scene::load(&file).unwrap_err().to_string();
    assert!(e.contains("cannot read the URDF") && e.contains("two_link.urdf"), "{e}");
    let by_name = flinch_harness::shipped::read(std::path::Path::new("robot_two_link")).unwrap();
    assert!(flinch_harness::scene::parse(&by_name.1, &by_name.0).is_ok(), "the shipped scene by name still runs");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `flinch design` on the URDF scene: the budget's answer and its simulated confirmation, with the
/// robot reduced from its URDF; the limit's run is safe by the one definition.
#[test]
fn design_takes_the_urdf_scene() {
    use flinch_harness::design::design;
    use flinch_harness::sweep::Template;
    let t = Template::load(&scene_path("robot_two_link.toml")).unwrap();
    let r = design(&t, None, None, Some(0.07)).unwrap_or_else(|e| panic!("{e}"));
    assert!(r.speed_limit_formula > 0.0);
    let v = r.speed_limit_simulated.unwrap_or_else(|| panic!("no simulated limit: {:?}", r.speed_search_note));
    assert!(r.at_limit.as_ref().is_some_and(|a| a.summary.safe && !a.summary.stroke_exhausted));
    assert!((v / r.speed_limit_formula - 1.0).abs() < 0.25, "simulated {v} against the budget's {}", r.speed_limit_formula);
}

/// A spatial arm (a yaw joint, then a pitch joint off the axis) whose second link's inertia is given
/// two ways: principal moments in an inertial frame turned by `rpy`, and the same tensor written in
/// the link frame with its products of inertia (R I R^T). Both must reduce to the same m_r for
/// every pose and direction: a reader that ignored the inertial frame's rotation, or the products
/// of inertia, fails here (the two-link and pendulum closed forms are planar and diagonal).
#[test]
fn a_rotated_inertial_frame_equals_its_products_of_inertia() {
    use nalgebra::{Matrix3, Rotation3};
    let (r, p, y) = (0.3, -0.5, 0.9);
    let principal = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.03, 0.05, 0.07));
    let rot = Rotation3::from_euler_angles(r, p, y); // URDF rpy: Rz(y) Ry(p) Rx(r)
    let full = rot.matrix() * principal * rot.matrix().transpose();
    let arm2 = |inertial: String| {
        robot(&[
            "<link name=\"base\"/>".into(),
            link("arm1", 3.0, 0.1, 0.01, 0.02, 0.02),
            inertial,
            "<link name=\"tip\"/>".into(),
            joint("yaw", "revolute", "base", "arm1", "0 0 0.2", "0 0 0", "0 0 1"),
            joint("pitch", "revolute", "arm1", "arm2", "0.25 0 0", "0 0 0", "0 1 0"),
            joint("flange", "fixed", "arm2", "tip", "0.4 0.05 0", "0 0 0", "1 0 0"),
        ])
    };
    let rotated = format!(
        r#"<link name="arm2"><inertial><origin xyz="0.2 0.02 0.01" rpy="{r} {p} {y}"/><mass value="2"/>
        <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.07"/></inertial></link>"#
    );
    let products = format!(
        r#"<link name="arm2"><inertial><origin xyz="0.2 0.02 0.01" rpy="0 0 0"/><mass value="2"/>
        <inertia ixx="{}" ixy="{}" ixz="{}" iyy="{}" iyz="{}" izz="{}"/></inertial></link>"#,
        full[(0, 0)], full[(0, 1)], full[(0, 2)], full[(1, 1)], full[(1, 2)], full[(2, 2)]
    );
    let a = Chain::from_urdf_str(&arm2(rotated), "rotated.urdf", "base", "tip").unwrap();
    let b = Chain::from_urdf_str(&arm2(products), "products.urdf", "base", "tip").unwrap();
    let diagonal = Chain::from_urdf_str(&arm2(link("arm2", 2.0, 0.2, 0.03, 0.05, 0.07).replace("xyz=\"0.2 0 0\"", "xyz=\"0.2 0.02 0.01\"")), "diag.urdf", "base", "tip").unwrap();
    let mut differs = false;
    for q in [[0.0, 0.5], [1.0, -0.8], [-2.0, 1.3]] {
        for u in [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.3, -0.5, 0.8]] {
            let ra = reduce(&a, &q, u, &[1e5, 1e5], &[10.0, 10.0]).unwrap();
            let rb = reduce(&b, &q, u, &[1e5, 1e5], &[10.0, 10.0]).unwrap();
            let rd = reduce(&diagonal, &q, u, &[1e5, 1e5], &[10.0, 10.0]).unwrap();
            assert_close!(ra.mass_kg, rb.mass_kg, 1e-9);
            differs |= !close(ra.mass_kg, rd.mass_kg, 1e-6);
        }
    }
    assert!(differs, "the rotation changes m_r somewhere, so the test can tell the frames apart");
}
