//! Speed and separation monitoring (ISO/TS 15066:2016, clause 5.5.4) on the commanded velocity,
//! independent of the potential field: whatever the field and its gains command, the speed that
//! leaves here is at most what the separation to the nearest sensed obstacle allows, and never above
//! the configured cap.
//!
//! # The protective separation (ISO/TS 15066, eq 1 of 5.5.4.2.3)
//!
//! `S_p = S_h + S_r + S_s + C + Z_d + Z_r` with
//!
//! * `S_h = K (T_r + T_s)`: the human approaching at `K` during the robot's reaction time `T_r` and
//!   stopping time `T_s`. A hand or an arm reaches at `K = 2,000 mm/s` at every distance (ISO
//!   13855:2010, 6.2: the 1,600 mm/s of formula (1) beyond 500 mm is the speed of a *walking* body,
//!   not of an arm reaching from where the person stands), so `K = max(2.0 m/s, v_h)` and
//!   `S_p(0) = K (T_r + T_s) + margin`, at least 100 mm. Only where the scene declares that nothing
//!   but a whole body can approach ([`SsmParams::whole_body_only`]) does formula (1)'s rule apply:
//!   `K = max(2, v_h)` when that gives at most 0.5 m, else `K = v_h` (at least 1.6 m/s: the host's
//!   loader refuses less) with the stop separation `max(v_h (T_r + T_s) + margin, 0.5 m)`.
//!   Computed once in [`SafeController::new`]. The same `K` is the approach speed in the age term
//!   below.
//! * `S_r = v_r T_r`: the robot moving on at its commanded speed `v_r` until it reacts;
//! * `S_s = v_r T_s / 2`: the robot braking from `v_r` to rest in `T_s` (constant deceleration);
//! * `C`: the intrusion distance (ISO 13855, 5.3: how far a body part can reach into the sensing
//!   field before it is detected); `Z_d`, `Z_r`: the sensor's and the robot's position uncertainty.
//!
//! The separation `S` used is a lower bound of the true one *now*, built from the last sensed frame:
//! `S = S_capture - |p - p_capture| - K age`: the distance the sensor measured at capture, less the
//! distance the tool has moved since and the distance a person could have covered since the image
//! was taken (`age` counts from capture, so capture, fit and transmission latency are all in it).
//! Stale data therefore stops the robot by distance, not only by a timeout.
//!
//! Solving `S_p(v_r) <= S` for `v_r` gives the speed limit
//! `v_max = (S - S_p(0)) / (T_r + T_s / 2)`, clamped to `[0, cap]`.
//! When the numerator is not positive the robot is in a protective stop (command zero). It resumes by
//! itself when the separation grows again (ISO 10218-1:2011, 5.10.6: SSM may restart automatically).
//!
//! # The robot's speed *towards* the person (ISO/TS 15066, 5.5.4.2.3: `v_r` is directed)
//!
//! The frame carries the separation per [`SECTORS`] sectors of 45 degrees round the tool
//! ([`Sensed::sectors_m`], sector `k` from `45 k` to `45 (k + 1)` degrees counter-clockwise from
//! +x, [`sector_of`]). A point sensed in sector `k` at capture may since have moved by
//! `r = |p - p_capture| + K age` (the bound above), relative to the tool: a point `q_0` of the
//! sector at capture is now `q = q_0 + e`, `|e| <= r` (seen from the tool now). With
//! `u_0` the fastest `v` approaches a direction of the sector (`|v|` within 22.5 degrees of its
//! centre `c_k`, else `(v . c_k) cos 22.5 deg + |v x c_k| sin 22.5 deg`, negative when moving away),
//! `v . q <= |q_0| u_0 + |v| r` and `|q| >= |q_0| - r`, so the speed towards it now is at most
//! `u_k = (s_k u_0 + |v| r) / (s_k - r)` (decreasing in `|q_0|`, which is at least `s_k`), never
//! more than `|v|`, and 0 when the numerator is not positive: moving away is not limited. Where
//! `r >= s_k` the point may lie in any direction: `u_k = |v|`. The command passes the SSM bound
//! when `u_k <= v_max(s_k - r)` in every sector; otherwise it is scaled by the smallest
//! `v_max(s_k - r) / u_k`. That costs a division a sector: the floats (hardware division) do it; the
//! fixed-point types ([`Real::HW_DIV`] false: a software division each) bound the whole speed by
//! the nearest sector (`u_k = |v|`, one division a step), as before the directions were used, and
//! apply no PFL: within the 5,000-instruction step budget only so (`firmware/avoid-cost`); the
//! board's `f32` does both.
//!
//! # Fixed fixtures: the robot's own stop only (issue 29 item 2)
//!
//! A fixture (a tray, a jig, a wall the scene declares, classified by the sensor: [`Sensed::fixture_sectors_m`])
//! does not move, so no human approach is budgeted for it: per fixture sector the command's approach
//! `u_k` (the same directional math, with `r` the tool's motion since capture only, no `K age`) must
//! keep `S_p,fixture(u_k) = u_k T_r + u_k T_s / 2 + margin <= s_k - r` (no `K (T_r + T_s)` term, no
//! 100 mm floor). The same `T_r + T_s / 2` divides both bounds, so the fixed-point types (one division
//! a step) bound the whole speed by the smaller of the person's free distance and the nearest
//! fixture's, without another division. PFL does not apply to a fixture (the limits of Table A.2 are a
//! body's): the command is scaled by `min(max(SSM scale, PFL scale), fixture scale)`.
//!
//! # Power and force limiting (ISO/TS 15066, 5.5.5) beside it
//!
//! With [`SsmParams::pfl`] the command may instead be within the speeds at which a contact with the
//! body regions the scene allows stays within ISO/TS 15066 Table A.2 *with this module*: the
//! velocity's component along the module's axis at most `along_mps` (the module's speed: it yields
//! only along its axis) and the component across it at most `across_mps` (a rigid tool's speed).
//! The command is scaled by `max(SSM scale, PFL scale)`, never above 1 nor the cap: either regime
//! holds at every step. Both PFL speeds are used at 63/64 of their value (the number type's
//! rounding stays inside them).
//!
//! The clamp is the last operation on the command. Lengths are bounded from above by
//! `max + min / 2` (no square root; never below the true length, at most 11.8 % above), computed
//! without overflow, so a command of thousands of m/s from extreme but valid gains, or a non-finite
//! one, ends at or below the cap, or at zero.


use super::num::Real;

/// Parameters of the monitor. All in metres, seconds, metres per second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsmParams<R> {
    /// `v_h`, the human's approach speed far from the robot (ISO 13855:2010 6.2: 1.6 m/s); the
    /// monitor raises it to `max(2.0 m/s, v_h)` where its stop separation is within 0.5 m
    /// ([`SafeController::approach_speed_mps`]).
    pub human_speed_mps: R,
    /// `T_r`, from the command leaving the monitor until the robot starts to brake (one control
    /// period plus the drive's own delay). The sensing latency is not in it: it is in `age`.
    pub reaction_time_s: R,
    /// `T_s`, the robot's stopping time from the cap speed.
    pub stopping_time_s: R,
    /// `C + Z_d + Z_r`: intrusion distance plus the sensor's and the robot's uncertainty.
    pub margin_m: R,
    /// Hard cap on the commanded speed (the configured cruise speed).
    pub speed_cap_mps: R,
    /// The scene declares that only a whole (walking) body can approach: `K` may fall to `v_h`
    /// beyond 0.5 m (ISO 13855:2010 6.2, formula (1)). False for hands and arms: `K >= 2.0 m/s`.
    pub whole_body_only: bool,
    /// Power and force limiting beside the SSM bound (`None`: SSM alone).
    pub pfl: Option<Pfl<R>>,
}

/// The PFL speeds (ISO/TS 15066, 5.5.5 and Annex A) of the module on this robot, for the body
/// regions the scene allows to be touched. All m/s, the axis a unit vector in the cell's plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pfl<R> {
    /// The module's axis in the cell's frame (unit length).
    pub axis: [R; 2],
    /// The largest speed along the axis at which a contact stays within the limits with the
    /// module, m/s.
    pub along_mps: R,
    /// The same across the axis, where the module does not yield: a rigid tool's speed, m/s.
    pub across_mps: R,
}

/// Sectors of the directional separation ([`Sensed::sectors_m`]): 45 degrees each.
pub const SECTORS: usize = 8;

/// The sector of direction `(dx, dy)`: `k` covers `45 k` to `45 (k + 1)` degrees counter-clockwise
/// from +x (no trigonometry; a direction on a boundary goes to one of its two sectors, which the
/// monitor's 45-degree cones cover either way).
pub fn sector_of<R: Real>(dx: R, dy: R) -> usize {
    let steep = dy.abs() > dx.abs();
    match (dx >= R::ZERO, dy >= R::ZERO, steep) {
        (true, true, false) => 0,
        (true, true, true) => 1,
        (false, true, true) => 2,
        (false, true, false) => 3,
        (false, false, false) => 4,
        (false, false, true) => 5,
        (true, false, true) => 6,
        (true, false, false) => 7,
    }
}

/// `cos 22.5 deg`, `sin 22.5 deg`: the sector centres' components.
const C22: f64 = 0.923_879_532_511_286_7;
const S22: f64 = 0.382_683_432_365_089_8;
/// The centres of the sectors, `(cos, sin)` of `22.5 + 45 k` degrees.
const CENTRES: [[f64; 2]; SECTORS] = [[C22, S22], [S22, C22], [-S22, C22], [-C22, S22], [-C22, -S22], [-S22, -C22], [S22, -C22], [C22, -S22]];

/// What the sensor saw in the last frame.
#[derive(Clone, Copy, Debug)]
pub struct Sensed<R> {
    /// Distance from the tool to the nearest sensed obstacle when the image was taken, m.
    pub separation_m: R,
    /// Tool position when the image was taken, m.
    pub tool_x_m: R,
    /// See `tool_x_m`.
    pub tool_y_m: R,
    /// Time since the image was taken, s.
    pub age_s: R,
    /// The nearest sensed obstacle point when the image was taken, m (for [`Steer`]: far away when
    /// nothing was sensed).
    pub nearest_x_m: R,
    /// See `nearest_x_m`.
    pub nearest_y_m: R,
    /// The separation per direction when the image was taken: the nearest sensed point in each
    /// sector ([`sector_of`], seen from the tool at capture), from the tool's surface, m; far away
    /// where nothing was sensed. `separation_m` is at most their minimum. People only: a pixel the
    /// host classed as a fixture is in `fixture_sectors_m` instead.
    pub sectors_m: [R; SECTORS],
    /// The same for the fixed fixtures (trays, fixtures, a wall the scene declares; issue 29 item
    /// 2): per sector the nearest fixture pixel from the tool's surface at capture, m; far away
    /// (`NOTHING_SENSED_M` on the host) where there is none. A fixture does not move: its bound
    /// ([`SafeController::limit`]) has no human approach and no age term.
    pub fixture_sectors_m: [R; SECTORS],
}

impl<R: Real> Sensed<R> {
    /// The same separation in every direction (a sensor that gives no direction).
    pub fn sectors_all(separation_m: R) -> [R; SECTORS] {
        [separation_m; SECTORS]
    }
    /// No fixture sensed: every fixture sector far away (10 m).
    pub fn no_fixtures() -> [R; SECTORS] {
        [R::from_int(10); SECTORS]
    }
}

/// The barrier that steers the command round what the sensor sees, before the monitor limits it
/// (ours; off as the thesis wrote it). It keeps the tool where the monitor lets it run at full
/// speed, so that it goes round an obstacle instead of being stopped by it.
///
/// * Obstacle barrier: with `g` the separation at capture less the tool's motion since (the age
///   term left out: it is the monitor's), the tool's approach speed towards the nearest sensed point
///   is limited to `rate (g - barrier_m)`, `rate = cap / band_m` (negative below the barrier: it
///   backs off). The excess is removed along the direction to that point (the radial part: it never
///   climbs towards an obstacle) and turned, with the same magnitude, along the boundary (a vortex
///   bounded by the approach it replaces), its side latched while inside the band so that it does not
///   dither; chosen towards the view's centre when the command is head-on.
/// * Workspace edge: the sensed view is a barrier of the same kind on each axis, the tool's centre
///   kept `edge_margin_m` inside it: it never leaves the region where obstacles are seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Steer<R> {
    /// Separation (from the tool's surface) the barrier holds, m: the host sets it so that the
    /// monitor still allows the cap there with the oldest frame.
    pub barrier_m: R,
    /// Band above the barrier (and inside the view's edges) over which the allowed approach speed
    /// rises from 0 to the cap, m (> 0).
    pub band_m: R,
    /// The sensed view `[x0, y0, x1, y1]`, m.
    pub view_m: [R; 4],
    /// How far inside the view the tool's centre stays, m.
    pub edge_margin_m: R,
}

/// What the monitor did this step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SafeState {
    /// The command passed unchanged.
    Run,
    /// The command was scaled down to the limit.
    Slow,
    /// Separation below the protective separation: zero command.
    ProtectiveStop,
    /// No sensed frame yet: zero command.
    NoData,
    /// Beyond the SSM bound, within the PFL speeds (possibly scaled to them).
    Pfl,
}

/// The monitored command.
#[derive(Clone, Copy, Debug)]
pub struct SafeCommand<R> {
    /// Velocity along x, m/s.
    pub vx: R,
    /// Velocity along y, m/s.
    pub vy: R,
    /// The speed limit that applied, m/s.
    pub limit_mps: R,
    /// The lower bound of the separation now, m.
    pub separation_m: R,
    /// What happened.
    pub state: SafeState,
}

/// The monitor. Stateless between steps apart from its parameters (and three numbers derived from
/// them once, so that a step costs one division for the limit and two for a scaled command).
#[derive(Clone, Copy, Debug)]
pub struct SafeController<R> {
    params: SsmParams<R>,
    steer: Option<Steer<R>>,
    /// `cap / band_m`, 1/s.
    rate: R,
    /// Side of the boundary-following turn, latched inside the band (0: none).
    side: i8,
    /// `cap / 64`: a command leaning less than this to one side (per unit `|n|^2`) is head-on.
    lean_tol: R,
    /// `K (T_r + T_s) + C + Z_d + Z_r` (at least 0.5 m when `K` is the far-field `v_h`): the
    /// separation at which the limit reaches zero, m (ISO 13855:2010 6.2, see the module's docs).
    stop_separation_m: R,
    /// `K`, the approach speed ISO 13855 6.2 gives for that separation, m/s.
    approach_mps: R,
    /// `T_r + T_s / 2`, s.
    per_speed_s: R,
    /// `1 / (T_r + T_s / 2)`, 1/s, saturating in fixed point (a smaller factor: a lower limit).
    inv_per_speed: R,
    /// One half.
    half: R,
    /// The sector centres in `R`.
    centres: [[R; 2]; SECTORS],
    /// `cos 22.5 deg`, `sin 22.5 deg`: the sectors' half-width.
    c22: R,
    /// See `c22`.
    s22: R,
    /// The PFL speeds at 63/64 of their value (`None`: SSM alone, or a PFL speed not positive).
    pfl: Option<Pfl<R>>,
    /// The separation from a fixture the steering barrier holds, m (`None`: the barrier steers
    /// round people only; the monitor bounds the fixtures either way).
    fixture_barrier_m: Option<R>,
    /// `1 / cap`, 1/(m/s) (saturating in fixed point: a smaller factor, a lower limit).
    inv_cap: R,
}

impl<R: Real> SafeController<R> {
    /// A monitor with these parameters.
    pub fn new(params: SsmParams<R>) -> Self {
        let half = R::ONE.div(R::from_int(2));
        // ISO 13855:2010 6.2, formula (1): K = 2.0 m/s (or the configured v_h if faster) where the
        // resulting separation is at most 0.5 m (and then at least 0.1 m); else the far-field v_h,
        // the separation at least 0.5 m.
        let t = params.reaction_time_s.add(params.stopping_time_s);
        let two = R::from_int(2);
        // NaN-safe: a NaN v_h stays NaN (far field, K NaN: every step stops).
        let near_k = if params.human_speed_mps <= two { two } else { params.human_speed_mps };
        let near = near_k.mul(t).add(params.margin_m);
        // ... and S not less than 100 mm (ISO 13855:2010 6.2, formula (1)).
        let tenth = R::ONE.div(R::from_int(10));
        // A hand or an arm: K = max(2, v_h) at every distance. NaN-safe: a NaN v_h keeps K NaN.
        let (approach_mps, stop_separation_m) = if !params.whole_body_only || near <= half {
            (near_k, if near > tenth { near } else { tenth })
        } else {
            let far = params.human_speed_mps.mul(t).add(params.margin_m);
            // NaN-safe: anything not above 0.5 m is 0.5 m (a NaN parameter: 0.5 m, and the NaN
            // K below stops every step).
            (params.human_speed_mps, if far > half { far } else { half })
        };
        SafeController {
            stop_separation_m,
            approach_mps,
            per_speed_s: params.reaction_time_s.add(params.stopping_time_s.mul(half)),
            inv_per_speed: R::ONE.div(params.reaction_time_s.add(params.stopping_time_s.mul(half))),
            params,
            half,
            steer: None,
            rate: R::ZERO,
            side: 0,
            lean_tol: params.speed_cap_mps.div(R::from_int(64)),
            centres: CENTRES.map(|c| [R::from_f64(c[0]), R::from_f64(c[1])]),
            c22: R::from_f64(C22),
            s22: R::from_f64(S22),
            inv_cap: R::ONE.div(params.speed_cap_mps),
            fixture_barrier_m: None,
            pfl: params.pfl.and_then(|p| {
                let k = R::from_int(63).div(R::from_int(64));
                // Only positive speeds and a finite axis make a PFL regime; anything else is none.
                // The axis of unit length to within 1/64 (the 63/64 margin covers a component
                // under-estimated by that much).
                let n2 = p.axis[0].mul(p.axis[0]).add(p.axis[1].mul(p.axis[1]));
                let ok = p.along_mps > R::ZERO && p.across_mps > R::ZERO && n2 >= k && n2 <= R::from_int(65).div(R::from_int(64));
                ok.then(|| Pfl { axis: p.axis, along_mps: p.along_mps.mul(k), across_mps: p.across_mps.mul(k) })
            }),
        }
    }

    /// The same monitor with the [`Steer`] barrier before it.
    pub fn with_steer(mut self, steer: Steer<R>) -> Self {
        self.rate = if steer.band_m > R::ZERO { self.params.speed_cap_mps.div(steer.band_m) } else { R::ZERO };
        self.steer = Some(steer);
        self
    }

    /// The steering barrier also round the fixtures, holding `barrier_m` from them (from the tool's
    /// surface; the host sets it so that the fixture bound allows the cap there with the oldest
    /// frame: no human approach in it).
    pub fn with_fixture_barrier(mut self, barrier_m: R) -> Self {
        self.fixture_barrier_m = Some(barrier_m);
        self
    }

    /// The [`Steer`] barrier on a requested command (unchanged without one): approach towards the
    /// nearest sensed point and towards the view's edges limited, the blocked approach turned along
    /// the boundary. The result still goes through [`Self::limit`].
    pub fn steer(&mut self, vx: R, vy: R, x: R, y: R, sensed: Option<&Sensed<R>>) -> (R, R) {
        let Some(st) = self.steer else { return (vx, vy) };
        let (mut vx, mut vy) = (vx, vy);
        let [x0, y0, x1, y1] = st.view_m;
        let mut inside_band = false;
        if let Some(f) = sensed {
            let moved = self.norm_bound(x.sub(f.tool_x_m), y.sub(f.tool_y_m));
            let g = f.separation_m.sub(moved);
            let mut free = g.sub(st.barrier_m);
            // A fixture nearer, in its own barrier's terms, steers as a person does (the nearest
            // point the host gives is the nearest of either class).
            if let Some(fb) = self.fixture_barrier_m {
                let ff = min_of(&f.fixture_sectors_m).sub(moved).sub(fb);
                if ff < free {
                    free = ff;
                }
            }
            if free < st.band_m {
                inside_band = true;
                // Towards the nearest point (not normalised): v.n <= a |n| with a the allowed
                // approach speed; |n| bounded from above (max + min / 2), which allows up to 11.8 %
                // more approach in the band and backs off up to 11.8 % faster below it.
                let (nx, ny) = (f.nearest_x_m.sub(x), f.nearest_y_m.sub(y));
                let n2 = nx.mul(nx).add(ny.mul(ny));
                let a = free.mul(self.rate);
                let vn = vx.mul(nx).add(vy.mul(ny));
                let over = vn.sub(a.mul(self.norm_bound(nx, ny)));
                if over > R::ZERO && n2 > R::ZERO {
                    let e = over.div(n2);
                    vx = vx.sub(e.mul(nx));
                    vy = vy.sub(e.mul(ny));
                    // Left tangent (-ny, nx); the side: latched, else the side the command leans
                    // to, else towards the view's centre.
                    if self.side == 0 {
                        let lean = vy.mul(nx).sub(vx.mul(ny));
                        let tol = self.lean_tol.mul(n2);
                        self.side = if lean > tol {
                            1
                        } else if lean < tol.neg() {
                            -1
                        } else {
                            let (cx, cy) = (x0.add(x1).mul(self.half).sub(x), y0.add(y1).mul(self.half).sub(y));
                            if cy.mul(nx).sub(cx.mul(ny)) < R::ZERO {
                                -1
                            } else {
                                1
                            }
                        };
                    }
                    // The turn, only when the command wanted to approach: as large as the cut
                    // (the blocked approach, plus the backing off below the barrier: at most
                    // `vn + 1.118 rate (barrier - g)`), so the tool keeps going round a person who
                    // comes closer; the monitor's limit bounds the sum.
                    let t = if vn > R::ZERO { e } else { R::ZERO };
                    let t = if self.side < 0 { t.neg() } else { t };
                    vx = vx.sub(t.mul(ny));
                    vy = vy.add(t.mul(nx));
                }
            }
        }
        if !inside_band {
            self.side = 0;
        }
        // The view's edges: per axis, the speed towards an edge at most `rate` times the room left.
        let m = st.edge_margin_m;
        let clamp = |v: R, lo: R, hi: R| if v < lo { lo } else if v > hi { hi } else { v };
        let (lox, hix) = (x0.add(m).sub(x).mul(self.rate), x1.sub(m).sub(x).mul(self.rate));
        let (loy, hiy) = (y0.add(m).sub(y).mul(self.rate), y1.sub(m).sub(y).mul(self.rate));
        vx = if lox > hix { R::ZERO } else { clamp(vx, lox, hix) };
        vy = if loy > hiy { R::ZERO } else { clamp(vy, loy, hiy) };
        (vx, vy)
    }

    /// The parameters.
    pub fn params(&self) -> &SsmParams<R> {
        &self.params
    }

    /// `K`, the human's approach speed the monitor uses (ISO 13855:2010 6.2: `max(2.0, v_h)` where
    /// the stop separation is within 0.5 m, else `v_h`), m/s.
    pub fn approach_speed_mps(&self) -> R {
        self.approach_mps
    }

    /// The protective separation at rest `S_p(0) = K (T_r + T_s) + margin` (at least 0.5 m with
    /// the far-field `K`): below it the limit is zero, m.
    pub fn stop_separation_m(&self) -> R {
        self.stop_separation_m
    }

    /// The speed limit for a separation lower bound `s`, m/s (0: protective stop).
    pub fn speed_limit(&self, s: R) -> R {
        self.limit_free(s.sub(self.stop_separation_m))
    }

    /// The speed limit for a fixture at separation lower bound `s` (the tool's motion since capture
    /// taken off), m/s: `S_p,fixture(v) = v (T_r + T_s / 2) + margin <= s` (no human approach).
    pub fn fixture_speed_limit(&self, s: R) -> R {
        self.limit_free(s.sub(self.params.margin_m))
    }

    /// `free / (T_r + T_s / 2)` within `[0, cap]`, m/s.
    fn limit_free(&self, free: R) -> R {
        let cap = self.params.speed_cap_mps;
        // NaN-safe: only a positive margin gives a positive limit.
        if free > R::ZERO {
            // `free / per_speed <= cap` without dividing when the cap applies anyway.
            if free >= cap.mul(self.per_speed_s) {
                cap
            } else {
                // `free / per_speed` as a product (no division a step); where `1 / per_speed`
                // saturates the product is smaller: a lower limit.
                let v = free.mul(self.inv_per_speed);
                if v < cap {
                    v
                } else {
                    cap
                }
            }
        } else {
            R::ZERO
        }
    }

    /// The monitored command for a requested `(vx, vy)` with the tool at `(x, y)`.
    ///
    /// First the cap: a command whose length bound is above it is scaled to the bound (its speed
    /// ends between 89.4 % of the cap and the cap); a non-finite one stops. Then the directional SSM
    /// bound over the sectors and the PFL speeds (module docs): the command is scaled by the larger
    /// of the two scales, never enlarged. Lengths are bounded from above without a square root:
    /// `|(a, b)| <= max + min / 2` (within 11.8 % above); the tool's motion since capture is
    /// over-estimated by it (the separation is under-estimated: conservative).
    pub fn limit(&self, vx: R, vy: R, x: R, y: R, sensed: Option<&Sensed<R>>) -> SafeCommand<R> {
        let stop = |state, separation_m| SafeCommand { vx: R::ZERO, vy: R::ZERO, limit_mps: R::ZERO, separation_m, state };
        let Some(f) = sensed else { return stop(SafeState::NoData, R::ZERO) };
        // What may have changed since capture: the tool's motion and the person's at K.
        let moved = self.norm_bound(x.sub(f.tool_x_m), y.sub(f.tool_y_m));
        let r = moved.add(self.approach_mps.mul(f.age_s));
        let s = f.separation_m.sub(r);
        // The nearest fixture: no human approach, no age term (module docs).
        let fix_free = min_of(&f.fixture_sectors_m).sub(moved).sub(self.params.margin_m);
        let person_free = s.sub(self.stop_separation_m);
        // NaN-safe: a NaN fixture separation is not above the person's free distance: it is taken.
        let omni = self.limit_free(if fix_free >= person_free { person_free } else { fix_free });
        let fix_omni = self.limit_free(fix_free);
        let pfl_omni = match self.pfl {
            _ if !R::HW_DIV => R::ZERO,
            Some(p) if p.along_mps < p.across_mps => p.along_mps,
            Some(p) => p.across_mps,
            None => R::ZERO,
        };
        // PFL permits no contact with a fixture: never above the fixture's bound.
        let pfl_omni = if pfl_omni > fix_omni { fix_omni } else { pfl_omni };
        let any_dir = if omni > pfl_omni { omni } else { pfl_omni };
        let Some((vx, vy, capped, speed)) = self.capped(vx, vy) else { return stop(SafeState::ProtectiveStop, s) };
        if speed.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
            // No motion asked: nothing to limit; a protective stop when no direction is free.
            let state = if any_dir > R::ZERO { SafeState::Run } else { SafeState::ProtectiveStop };
            return SafeCommand { vx: R::ZERO, vy: R::ZERO, limit_mps: any_dir, separation_m: s, state };
        }
        // The SSM scale: the approach towards each sector within its bound. One division a
        // sector at most (none for a sector the command moves away from), `1 / speed` once.
        let mut k_ssm = R::ONE;
        let mut inv_speed: Option<R> = None;
        // Fixed point: the whole speed within the nearest separation's bound (one division a
        // step, in budget: docs/avoidance.md); never less safe than the directions.
        let sectors: &[R] = if R::HW_DIV { &f.sectors_m } else { &[] };
        if !R::HW_DIV && omni < speed {
            // A capped command's length bound is the cap (to rounding): no division then.
            k_ssm = omni.mul(if capped { self.inv_cap } else { R::ONE.div(speed) });
        }
        for (c, &s0) in self.centres.iter().zip(sectors.iter()) {
            // NaN-safe: a NaN separation gives a zero limit.
            let l = self.speed_limit(s0.sub(r));
            if let Some(q) = self.sector_scale(c, s0, r, l, vx, vy, speed, &mut inv_speed) {
                if q < k_ssm {
                    k_ssm = q;
                }
            }
        }
        // The fixtures' scale: the same directions, the tool's motion only. Fixed point: the
        // nearest fixture is already in `omni` (the whole speed).
        let mut k_fix = R::ONE;
        let fixtures: &[R] = if R::HW_DIV { &f.fixture_sectors_m } else { &[] };
        for (c, &s0) in self.centres.iter().zip(fixtures.iter()) {
            let l = self.fixture_speed_limit(s0.sub(moved));
            if let Some(q) = self.sector_scale(c, s0, moved, l, vx, vy, speed, &mut inv_speed) {
                if q < k_fix {
                    k_fix = q;
                }
            }
        }
        // The PFL scale: along and across the module's axis within their speeds.
        // Only where the SSM bound cuts, and a division only where PFL could allow more.
        // Fixed point: SSM alone (no division a step for PFL; docs/avoidance.md, the budget).
        let k_pfl = match self.pfl {
            Some(p) if k_ssm < R::ONE && R::HW_DIV => {
                let along = vx.mul(p.axis[0]).add(vy.mul(p.axis[1])).abs();
                let across = vx.mul(p.axis[1]).sub(vy.mul(p.axis[0])).abs();
                // `lim / x <= k_ssm` when `lim <= x k_ssm`: PFL gives no more than SSM there.
                if p.along_mps <= along.mul(k_ssm) || p.across_mps <= across.mul(k_ssm) {
                    R::ZERO
                } else {
                    let (a, b) = (ratio(along, p.along_mps), ratio(across, p.across_mps));
                    if a < b {
                        a
                    } else {
                        b
                    }
                }
            }
            _ => R::ZERO,
        };
        let (k, state) = if k_ssm >= R::ONE {
            (R::ONE, if capped { SafeState::Slow } else { SafeState::Run })
        } else if k_pfl > k_ssm {
            (if k_pfl < R::ONE { k_pfl } else { R::ONE }, SafeState::Pfl)
        } else if k_ssm > R::ZERO {
            (k_ssm, SafeState::Slow)
        } else {
            (R::ZERO, SafeState::ProtectiveStop)
        };
        // A fixture bounds either regime. NaN-safe: only a scale known to be smaller is taken.
        let (k, state) = if k_fix < k { (k_fix, if k_fix > R::ZERO { SafeState::Slow } else { SafeState::ProtectiveStop }) } else { (k, state) };
        if state == SafeState::ProtectiveStop {
            return SafeCommand { vx: R::ZERO, vy: R::ZERO, limit_mps: R::ZERO, separation_m: s, state: SafeState::ProtectiveStop };
        }
        let limit = speed.mul(k);
        let limit_mps = if limit > any_dir { limit } else { any_dir };
        if k >= R::ONE {
            SafeCommand { vx, vy, limit_mps, separation_m: s, state }
        } else {
            SafeCommand { vx: vx.mul(k), vy: vy.mul(k), limit_mps, separation_m: s, state }
        }
    }

    /// The scale that brings the approach towards sector `c` (separation `s0` at capture, `r` what
    /// may have changed since, `l` the limit at `s0 - r`) within `l`: `None` when it does not
    /// limit (module docs: `u_k`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn sector_scale(&self, c: &[R; 2], s0: R, r: R, l: R, vx: R, vy: R, speed: R, inv_speed: &mut Option<R>) -> Option<R> {
        if l >= speed {
            return None;
        }
        // `l / u` for the sector's fastest approach `u` (module docs): `u = |v|`, or
        // `(s_k u_0 + |v| r) / (s_k - r)` where that is smaller, 0 when it is not positive.
        if s0 > r {
            let dot = vx.mul(c[0]).add(vy.mul(c[1]));
            let cross = vx.mul(c[1]).sub(vy.mul(c[0])).abs();
            // Within 22.5 degrees of the centre: straight at a point of the sector.
            let u0 = if self.s22.mul(dot) >= self.c22.mul(cross) { speed } else { dot.mul(self.c22).add(cross.mul(self.s22)) };
            let num = s0.mul(u0).add(speed.mul(r));
            if num.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
                // Moving away from every point the sector can hold now.
                return None;
            }
            let den = s0.sub(r);
            if num < speed.mul(den) {
                return Some(l.mul(den).div(num));
            }
        }
        let inv = *inv_speed.get_or_insert_with(|| R::ONE.div(speed));
        Some(l.mul(inv))
    }

    /// The command within the cap: `(vx, vy, scaled, length bound)`; `None` when it is not
    /// finite. A command whose length bound is within the cap passes unchanged; otherwise it is
    /// scaled to the bound, its speed between 89.4 % of the cap and the cap (its length bound the
    /// cap, to rounding).
    fn capped(&self, vx: R, vy: R) -> Option<(R, R, bool, R)> {
        let cap = self.params.speed_cap_mps;
        // `speed` may saturate in fixed point; it is then far above the cap.
        let speed = self.norm_bound(vx, vy);
        if speed <= cap {
            return Some((vx, vy, false, speed));
        }
        let (ax, ay) = (vx.abs(), vy.abs());
        let m = if ax > ay { ax } else { ay };
        if speed > R::ZERO && m > R::ZERO {
            // Unit components `v / m` in [-1, 1] (no overflow), the bound over `m` in [1, 1.5]:
            // the result's bound is the cap (to rounding).
            // Up to 1 m/s a component (every command of a cruise speed), one division (below).
            // Above it, two.
            if m <= R::ONE {
                // `m (1 + min / (2 m)) = max + min / 2 = speed`: one division, `cap / speed`
                // at most 1, every component at most 1 m/s: no overflow.
                let k = cap.div(speed);
                return Some((vx.mul(k), vy.mul(k), true, cap));
            }
            let (ux, uy) = (vx.div(m), vy.div(m));
            let (bx, by) = (ux.abs(), uy.abs());
            let r = R::ONE.add(if bx < by { bx } else { by }.mul(self.half));
            let k = cap.div(r);
            Some((ux.mul(k), uy.mul(k), true, cap))
        } else {
            // Not comparable (NaN) or a NaN cap: stop.
            None
        }
    }

    /// `max(|a|, |b|) + min(|a|, |b|) / 2`: at least `sqrt(a^2 + b^2)` (since `max >= 3 min / 4`),
    /// at most 11.8 % more; saturates in fixed point, NaN in gives NaN.
    fn norm_bound(&self, a: R, b: R) -> R {
        let (aa, bb) = (a.abs(), b.abs());
        if !(aa >= R::ZERO && bb >= R::ZERO) {
            return a.add(b);
        }
        let (m, n) = if aa > bb { (aa, bb) } else { (bb, aa) };
        m.add(n.halve())
    }
}

/// The smallest of the sectors (NaN-safe: a NaN sector is taken).
fn min_of<R: Real>(v: &[R; SECTORS]) -> R {
    let mut m = v[0];
    for &x in &v[1..] {
        match x.partial_cmp(&m) {
            Some(core::cmp::Ordering::Less) => m = x,
            // `x` NaN: taken (a NaN separation stops); `m` NaN already: kept.
            None if m.partial_cmp(&m).is_some() => m = x,
            _ => {}
        }
    }
    m
}

/// The factor that brings `x >= 0` within `lim`: 1 when it is, `lim / x` when `lim` is positive,
/// else 0 (NaN-safe: a NaN `x` or `lim` gives 0).
fn ratio<R: Real>(x: R, lim: R) -> R {
    if x <= lim {
        R::ONE
    } else if lim > R::ZERO && x > R::ZERO {
        lim.div(x)
    } else {
        R::ZERO
    }
}

#[cfg(test)]
mod tests;
