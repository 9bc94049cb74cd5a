//! The plane of a planar scene (issue 30, docs/planar.md): vectors, rotations and the directions of
//! the approach. Units: m, m/s, N (vectors), rad inside, deg in keys and summaries.
//!
//! Convention (one everywhere): z towards the viewer, angles counter-clockwise positive. The world
//! frame is the module's frame at rest: x along the decoupler's axis u (the 1-D approach axis,
//! MODEL.md: from the flange to the tool), y = u turned by +90 deg.
//! - e_p = R(beta) u, beta = `motion.off_axis_deg`: the flange's commanded direction; e_q = R(90) e_p.
//! - n = R(theta - 90 deg) u, theta = `target.surface_angle_deg` (Fig. 68a): the surface's outward
//!   normal. The plant uses m = -n, the direction the tool pushes into the target, and the tangent
//!   t = R(90) m; a penetration is measured along m.

/// A vector in the plane.
pub type V2 = [f64; 2];

/// a . b.
#[inline]
pub fn dot(a: V2, b: V2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// v turned by +90 deg.
#[inline]
pub fn perp(v: V2) -> V2 {
    [-v[1], v[0]]
}

/// The z component of a x b.
#[inline]
pub fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// x a + y b.
#[inline]
pub fn comb(x: f64, a: V2, y: f64, b: V2) -> V2 {
    [x * a[0] + y * b[0], x * a[1] + y * b[1]]
}

/// v turned by `a` rad.
#[inline]
pub fn rot(a: f64, v: V2) -> V2 {
    let (s, c) = a.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// The unit vector at `deg` degrees from +x, exact at multiples of 90 deg (so that an axial scene's
/// planar arithmetic is the 1-D plant's to the last bit: cos 90 deg is 6e-17 in f64, not 0).
pub fn unit_deg(deg: f64) -> V2 {
    let w = deg.rem_euclid(360.0);
    if w == 0.0 {
        [1.0, 0.0]
    } else if w == 90.0 {
        [0.0, 1.0]
    } else if w == 180.0 {
        [-1.0, 0.0]
    } else if w == 270.0 {
        [0.0, -1.0]
    } else {
        let (s, c) = w.to_radians().sin_cos();
        [c, s]
    }
}

/// The fixed directions of a scene's approach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Directions {
    /// u, the decoupler's axis at rest (+x).
    pub u: V2,
    /// w = R(90) u.
    pub w: V2,
    /// e_p, along the commanded path.
    pub ep: V2,
    /// e_q = R(90) e_p, across the path.
    pub eq: V2,
    /// m = -n, into the target.
    pub m: V2,
    /// t = R(90) m, the contact's tangent.
    pub t: V2,
}

impl Directions {
    /// From beta and theta, deg.
    pub fn new(off_axis_deg: f64, surface_angle_deg: f64) -> Self {
        let ep = unit_deg(off_axis_deg);
        // m = -n = -R(theta - 90) u = R(theta + 90) u.
        let m = unit_deg(surface_angle_deg + 90.0);
        Self { u: [1.0, 0.0], w: [0.0, 1.0], ep, eq: perp(ep), m, t: perp(m) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axial_directions_are_exact() {
        let d = Directions::new(0.0, -90.0);
        assert_eq!(d.ep, [1.0, 0.0]);
        assert_eq!(d.m, [1.0, 0.0]);
        assert_eq!(d.eq, [-0.0, 1.0]);
    }

    #[test]
    fn the_surface_normal_follows_fig_68a() {
        // theta = 0: the surface is parallel to the guide, its normal R(-90) u = (0, -1), so the
        // tool pushes into it along m = (0, 1).
        let d = Directions::new(90.0, 0.0);
        assert_eq!(d.m, [0.0, 1.0]);
        // theta = +90: the push is along +u (onto the front stop), m = -u.
        assert_eq!(Directions::new(180.0, 90.0).m, [-1.0, 0.0]);
        let d = Directions::new(30.0, -45.0);
        assert!((dot(d.m, d.m) - 1.0).abs() < 1e-15 && dot(d.m, d.t).abs() < 1e-15);
        assert!((cross(d.u, d.w) - 1.0).abs() < 1e-15);
        assert!((rot(std::f64::consts::FRAC_PI_2, [1.0, 0.0])[1] - 1.0).abs() < 1e-15);
    }
}
