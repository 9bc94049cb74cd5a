//! When a run is at rest: the robot stopped and every body settled, so the state is held from
//! there to the end instead of integrating a standstill (`Summary::at_rest_from_s`).

//! A scene run: the plant integrated with its events, and what the summary reports.
//!
//! Events (located, not sampled): 0 tool-target contact onset/separation, 1 front end-stop
//! entry/exit, 2 back end-stop entry/exit, 3 the sensor's threshold, and 4-6 the instants where
//! the contact, the front stop or the back stop stops pushing (or starts again) while still
//! penetrated: its damping term cancels the spring term and the clamp at zero force (no adhesion)
//! takes over. That clamp is a kink in the right-hand side; located as an event, the step ends on
//! it instead of the error control hacking at it with a dozen rejected steps (docs/accuracy.md).
//! Event 7 switches a Coulomb slide (`decoupler.friction.law = "stick-slip"`, `plant::friction`)
//! between sticking and slipping. Breakpoints: end of the
//! acceleration, start and end of braking. Contact dampings chi are fixed at each onset from the
//! approach velocity (eq 7).

use flinch_plant::{self as plant, State, N};
use crate::simulation::Simulation;

impl Simulation {
    /// True when the plant is at rest at (t, y) for the rest of the run, so that holding the state
    /// from here to `duration` is the integration's answer to within the solver's tolerance. Called
    /// only once the commanded flange has stopped (t >= t_stop: x_c is constant from there, so the
    /// plant is autonomous and nothing outside it can move it again).
    ///
    /// The bodies the plant integrates (compliant robot, tool on a decoupler, free object) are
    /// near a static equilibrium: with every velocity set to zero the net forces F (springs,
    /// stops, contacts, weight; dampers and friction vanish at rest) are linearised, F(x + dx) =
    /// F - K dx, K by central differences (1e-7 m). If K is positive definite the equilibrium is
    /// stable and x_eq = x + K^-1 F; the energy about it, E = v^T M v / 2 + dx_eq^T K dx_eq / 2,
    /// can only fall (dampers and friction dissipate), so from here on every body stays within
    /// `|dx_eq_i| + sqrt(2 E (K^-1)_ii)` of where it is and below `sqrt(2 E / m_i)` in speed. The
    /// plant is at rest when those are within the solver's tolerance: `atol + rtol |x_i|` and
    /// `atol + rtol V_c` (V_c = motion.speed, the run's velocity scale). A body without any
    /// restoring force (a free object off the tool) must instead not move by the same tolerance
    /// when its velocity and static acceleration are extrapolated over the remaining time T:
    /// `|v| T + |a| T^2 / 2`. A tool balanced on the bi-stable's dead centre (K not positive), a
    /// body creeping under regularised friction or still swinging is not at rest.
    ///
    /// Why: a tool pressed into an end stop and the target at standstill can be the stiffest state
    /// of the run (a Hunt-Crossley damping chi d^1.5 grows with the penetration: the table11 scene
    /// with decel = 0.159 m/s^2 and duration = 19 s, 13.5 kN on the back stop, has about 7e5 1/s
    /// over the tool's mass, tests/box.rs). An explicit method's step is limited by stability there
    /// while nothing moves, and the integrated velocity does not even decay: it sits at 1.3e-9
    /// m/s (the stiff mode on the stability boundary, its damper and friction balancing 1e-6 N of
    /// static residual) while the position does not move in its last digit. That standstill cost
    /// 3.8 million steps for 17 s; its distance to the true equilibrium is 1e-12 m.
    pub(crate) fn at_rest(&self, t: f64, y: &State) -> bool {
        let rem = self.duration - t;
        let (rtol, atol, v_scale) = self.rest_tol;
        let tol_v = atol + rtol * v_scale;
        // (position, velocity, mass) of every integrated body.
        let mut dofs: Vec<(usize, usize, f64)> = Vec::with_capacity(3);
        if let Some(r) = self.plant.robot {
            dofs.push((plant::XR, plant::VR, r.mass));
        }
        if !self.plant.decoupler.is_rigid() {
            dofs.push((plant::XT, plant::VT, self.plant.tool_mass));
        }
        if let plant::target::Target::Object { mass, .. } = self.plant.target {
            dofs.push((plant::XP, plant::VP, mass));
        }
        if let Some(d) = self.plant.planar_dof() {
            dofs.push(d);
        }
        if dofs.iter().any(|&(_, v, _)| y[v].is_nan() || tol_v.is_nan() || y[v].abs() > tol_v) {
            return false;
        }
        let mut still = *y;
        for &(_, v, _) in &dofs {
            still[v] = 0.0;
        }
        let force = |z: &State| {
            let mut dz = [0.0; N];
            self.plant.eval(t, z, &mut dz);
            let mut f = [0.0; 3];
            for (i, &(_, v, m)) in dofs.iter().enumerate() {
                f[i] = m * dz[v];
            }
            f
        };
        let f0 = force(&still);
        let n = dofs.len();
        const H: f64 = 1e-7;
        let mut k = [[0.0; 3]; 3];
        for j in 0..n {
            let (mut a, mut b) = (still, still);
            a[dofs[j].0] += H;
            b[dofs[j].0] -= H;
            let (fa, fb) = (force(&a), force(&b));
            for i in 0..n {
                k[i][j] = -(fa[i] - fb[i]) / (2.0 * H);
            }
        }
        // Bodies with no restoring force and no coupling (a free object off the tool): extrapolated.
        let mut bound = Vec::with_capacity(3);
        for i in 0..n {
            let (x, v, m) = dofs[i];
            if (0..n).all(|j| k[i][j] == 0.0 && k[j][i] == 0.0) {
                let a = f0[i] / m;
                if y[v].abs() * rem + 0.5 * a.abs() * rem * rem > atol + rtol * y[x].abs() || a.abs() * rem > tol_v {
                    return false;
                }
            } else {
                bound.push(i);
            }
        }
        let m = bound.len();
        if m == 0 {
            return true;
        }
        let mut ks = [[0.0; 3]; 3];
        for (p, &i) in bound.iter().enumerate() {
            for (q, &j) in bound.iter().enumerate() {
                ks[p][q] = 0.5 * (k[i][j] + k[j][i]);
            }
        }
        let Some(inv) = spd_inverse(&ks, m) else { return false };
        let mut dx = [0.0; 3];
        for p in 0..m {
            dx[p] = (0..m).map(|q| inv[p][q] * f0[bound[q]]).sum();
        }
        let potential: f64 = 0.5 * (0..m).map(|p| dx[p] * f0[bound[p]]).sum::<f64>();
        let kinetic: f64 = 0.5 * (0..m).map(|p| dofs[bound[p]].2 * y[dofs[bound[p]].1].powi(2)).sum::<f64>();
        let energy = potential.max(0.0) + kinetic;
        (0..m).all(|p| {
            let (x, _, mass) = dofs[bound[p]];
            dx[p].abs() + (2.0 * energy * inv[p][p]).sqrt() <= atol + rtol * y[x].abs() && (2.0 * energy / mass).sqrt() <= tol_v
        })
    }
}

/// The inverse of the symmetric `n` x `n` (n <= 3) matrix `a` if it is positive definite
/// (Cholesky), else `None`.
fn spd_inverse(a: &[[f64; 3]; 3], n: usize) -> Option<[[f64; 3]; 3]> {
    let mut l = [[0.0; 3]; 3];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if !s.is_finite() || s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut inv = [[0.0; 3]; 3];
    for c in 0..n {
        // Solve L z = e_c, then L^T x = z.
        let mut z = [0.0; 3];
        for i in 0..n {
            let e = if i == c { 1.0 } else { 0.0 };
            z[i] = (e - (0..i).map(|k| l[i][k] * z[k]).sum::<f64>()) / l[i][i];
        }
        let mut x = [0.0; 3];
        for i in (0..n).rev() {
            x[i] = (z[i] - (i + 1..n).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
        }
        for (row, xi) in inv.iter_mut().zip(x).take(n) {
            row[c] = xi;
        }
    }
    Some(inv)
}
