//! The robot's link against the people, in three dimensions (issue 29 item 3): the link is a
//! capsule from the base to the tool in plan, `link_width_m` wide, occupying the heights from
//! `link_height_m - link_width_m` to `link_height_m` (its top as the camera sees it); each part of
//! the operator and each obstacle is an extrusion from the plane to its height. A part lower than
//! the link's underside passes beneath it; any other part whose footprint meets the link's in plan
//! is touched. The verdict of `flinch avoid` checks it at every step, beside the tool's wrist disc.

use super::shapes::{dist_to_segment, Obstacle, OperatorShape, RobotShape};

/// Distance between the segments `a`-`b` and `c`-`d` in the plane (0 when they cross).
pub fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    let (d1, d2, d3, d4) = (cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return 0.0;
    }
    dist_to_segment(a, c, d).min(dist_to_segment(b, c, d)).min(dist_to_segment(c, a, b)).min(dist_to_segment(d, a, b))
}

/// Samples along the link for a box obstacle, at most this far apart, m.
const BOX_SAMPLE_M: f64 = 0.002;

/// Signed plan distance from the link (base to `tool`, its half width off) to the footprint of
/// every part tall enough to reach its underside, m (negative: inside; `f64::INFINITY` when no part
/// reaches it). A box is sampled along the link every [`BOX_SAMPLE_M`] at most, less half that
/// (never above the true distance).
pub fn link_signed_distance(robot: &RobotShape, tool: [f64; 2], op: &OperatorShape, hand: [f64; 2]) -> f64 {
    let half = 0.5 * robot.link_width_m;
    let underside = robot.link_height_m - robot.link_width_m;
    let (a, b) = (robot.base_m, tool);
    let mut d = f64::INFINITY;
    if op.hand_height_m >= underside {
        d = d.min(dist_to_segment(hand, a, b) - op.hand_radius_m - half);
    }
    if op.forearm_height_m >= underside {
        d = d.min(segment_distance(a, b, op.entry_m, hand) - 0.5 * op.forearm_width_m - half);
    }
    for o in op.obstacles.iter().filter(|o| o.height_m >= underside) {
        d = d.min(obstacle_distance(o, a, b) - half);
    }
    d
}

fn obstacle_distance(o: &Obstacle, a: [f64; 2], b: [f64; 2]) -> f64 {
    if o.kind != "box" {
        return dist_to_segment(o.center_m, a, b) - o.radius_m;
    }
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    let n = ((len / BOX_SAMPLE_M).ceil() as usize).clamp(1, 100_000);
    (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64;
            o.signed_distance([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])])
        })
        .fold(f64::INFINITY, f64::min)
        - 0.5 * len / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot() -> RobotShape {
        RobotShape { base_m: [0.5, 1.3], wrist_radius_m: 0.045, wrist_height_m: 0.3, link_width_m: 0.07, link_height_m: 0.4 }
    }

    fn op(obstacles: Vec<Obstacle>, hand_height_m: f64) -> OperatorShape {
        OperatorShape { entry_m: [0.0, 0.0], hand_radius_m: 0.05, hand_height_m, forearm_width_m: 0.07, forearm_height_m: 0.15, obstacles }
    }

    fn disc(c: [f64; 2], r: f64, h: f64) -> Obstacle {
        Obstacle { kind: "disc".into(), center_m: c, keyframes: vec![], radius_m: r, size_m: [0.0; 2], height_m: h, fixture: false }
    }

    #[test]
    fn segments_cross_touch_and_miss() {
        assert_eq!(segment_distance([0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]), 0.0);
        assert!((segment_distance([0.0, 0.0], [1.0, 0.0], [0.0, 0.5], [1.0, 0.5]) - 0.5).abs() < 1e-12);
        assert!((segment_distance([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]) - 1.0).abs() < 1e-12);
    }

    /// A standing person (1.7 m) between the tool and the base is touched by the link; a hand
    /// lower than the link's underside passes beneath it; the same hand raised is touched.
    #[test]
    fn heights_decide_what_the_link_touches() {
        let r = robot();
        let person = op(vec![disc([0.5, 0.9], 0.15, 1.7)], 0.2);
        assert!(link_signed_distance(&r, [0.5, 0.5], &person, [0.9, 0.1]) < -0.1);
        let low = op(vec![], 0.2);
        assert_eq!(link_signed_distance(&r, [0.5, 0.5], &low, [0.5, 0.9]), f64::INFINITY, "under the link");
        let high = op(vec![], 0.35);
        assert!(link_signed_distance(&r, [0.5, 0.5], &high, [0.5, 0.9]) < 0.0);
        // Beside the link: its half width and the hand's radius off.
        let d = link_signed_distance(&r, [0.5, 0.5], &high, [0.7, 0.9]);
        assert!((d - (0.2 - 0.05 - 0.035)).abs() < 1e-12, "{d}");
        // A box, sampled, never above the exact distance.
        let bx = Obstacle { kind: "box".into(), center_m: [0.7, 0.9], keyframes: vec![], radius_m: 0.0, size_m: [0.2, 0.2], height_m: 1.0, fixture: false };
        let d = link_signed_distance(&r, [0.5, 0.5], &op(vec![bx], 0.0), [0.0, 0.0]);
        assert!(d <= 0.1 - 0.035 + 1e-12 && d >= 0.1 - 0.035 - 0.002, "{d}");
    }
}
