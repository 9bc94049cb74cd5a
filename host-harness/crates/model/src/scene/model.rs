//! The validated scene: plain Rust values in SI units, built by [`super::load`] from a TOML file.
//!
//! The names follow `docs/SCENES.md` (the public contract) and the thesis's symbols. Everything
//! here has already been checked: a `Scene` that exists is physically meaningful, so the plant never
//! re-validates. Optional elements are `Option`s: a scene models only what it needs.

/// A whole scene: the motion law, the robot, the tool and its decoupler, the target, the sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Human-readable name, echoed in the summary.
    pub name: String,
    /// Simulated time from the start of the motion (t = 0), s.
    pub duration_s: f64,
    /// Commanded flange motion (trapezoid, then braking).
    pub motion: Motion,
    /// Robot compliance; `None` is a rigid robot (x_r = x_c).
    pub robot: Option<Robot>,
    /// The tool (end-effector) carried by the decoupler.
    pub tool: Tool,
    /// What holds the tool on the flange.
    pub decoupler: Decoupler,
    /// What the tool runs into.
    pub target: Target,
    /// What detects the collision; `None` means nothing does and the robot never brakes.
    pub sensor: Option<Sensor>,
    /// How to integrate (the `[solver]` table; defaults documented in `scene::load`).
    pub solver: SolverSettings,
    /// The robot controller for firmware-in-the-loop runs (`[controller]`); `None` in plain runs.
    pub controller: Option<Controller>,
    /// The planar plant's inputs (`scene/planar.rs`); `None`: the 1-D plant runs the scene.
    pub planar: Option<Planar>,
}

/// Motion law, MODEL.md element 1: accelerate at `accel` to `speed`, cruise; braking at `decel`
/// starts `dead_time` after detection and ends at standstill.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// V_c, m/s, > 0.
    pub speed: f64,
    /// a_c, m/s^2, > 0.
    pub accel: f64,
    /// d_c, m/s^2, > 0; with `stopping`, the table's equivalent at V_c (model/src/stopping.rs; the
    /// plant recomputes it at the speed the stop is signalled at).
    pub decel: f64,
    /// DT, s, >= 0, from detection to the start of braking; with `stopping`, from detection to the
    /// stop signal at the robot (the table's times include the robot's reaction).
    pub dead_time: f64,
    /// `motion.stopping`: the robot's own stopping table, instead of `decel`.
    pub stopping: Option<crate::stopping::StoppingTable>,
    /// `motion.stopping.payload`, kg: the payload the table was measured with.
    pub stopping_payload: Option<f64>,
    /// m/s^2 along the approach direction (9.81 for a tool moving down), acts on the tool.
    pub gravity: f64,
    /// `motion.start_at_speed`: at t = 0 flange, robot and tool already cruise at V_c (the
    /// Ch. 2 set-ups, where v_t = 1 m/s at impact); `accel` is then unused.
    pub start_at_speed: bool,
    /// `motion.brake_after_contact`: braking does not start before tool-target contact number N
    /// has ended (0: off, braking starts `dead_time` after detection). A test device for the
    /// thesis's account of Table 4 (Ch. 2.5: the object detached before the deceleration began),
    /// not a controller: it delays the stop.
    pub brake_after_contact: u32,
}

impl Motion {
    /// Distance and time the flange travels from detection to standstill when it was moving at `v`
    /// and the stop signal (or, without a table, braking) came `dead_time` after detection:
    /// `v DT + v^2 / 2 d_c` and `DT + v / d_c`, or with the table `v DT + D(v)` and `DT + T(v)`.
    /// `None` above the table's largest speed (not extrapolated).
    pub fn stop_after_detection(&self, v: f64, dead_time: f64) -> Option<(f64, f64)> {
        match &self.stopping {
            Some(s) => s.at(v).map(|(d, t)| (v * dead_time + d, dead_time + t)),
            None => Some((v * dead_time + v * v / (2.0 * self.decel), dead_time + v / self.decel)),
        }
    }

    /// The whole delay from detection to the start of braking at V_c, s: `dead_time`, plus with the
    /// table its equivalent dead time at V_c (what the firmware's budget needs).
    pub fn total_dead_time(&self) -> f64 {
        self.dead_time + self.stopping.and_then(|s| s.equivalent(self.speed)).map_or(0.0, |e| e.dead_time)
    }
}

/// Compliant robot, a base-excited mass (eq 33): Table 7 gives the Viper s650 values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robot {
    /// m_r, kg, > 0.
    pub mass: f64,
    /// k_r, N/m, > 0.
    pub stiffness: f64,
    /// c_r, N s/m, >= 0.
    pub damping: f64,
}

/// The tool (end-effector).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tool {
    /// m_t, kg, > 0.
    pub mass: f64,
}

/// The decoupler between flange and tool (MODEL.md element 3).
#[derive(Debug, Clone, PartialEq)]
pub enum Decoupler {
    /// No decoupler: the tool is fastened to the flange, its mass added to the robot's.
    Rigid,
    /// Linear spring-damper (eq 17, 23), no end-stops.
    Linear(LinearDecoupler),
    /// Bi-stable spring mechanism (eq 24-42).
    Bistable(Bistable),
    /// Hydraulic cylinder with orifice and gas spring (eq 46-56).
    Hydraulic(Hydraulic),
}

/// Linear decoupler parameters. k_t = 0 with zeta = 0 is the free tool of Fig. 1b / 4b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearDecoupler {
    /// k_t, N/m, >= 0.
    pub stiffness: f64,
    /// zeta = c_t / (2 sqrt(k_t m_t)), >= 0 (eq 23).
    pub damping_ratio: f64,
}

/// Bi-stable mechanism parameters (Tables 2, 4, 5, 8, 13, 15).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bistable {
    /// N, number of springs, >= 1.
    pub springs: u32,
    /// k_b, N/m, > 0.
    pub spring_rate: f64,
    /// L0, m, > 0.
    pub free_length: f64,
    /// H, m, > 0.
    pub height: f64,
    /// C1, m, > 0: the front end-stop is at s = +C1.
    pub front_stroke: f64,
    /// C2, m, > 0: the back end-stop (flange) is at s = -C2.
    pub back_stroke: f64,
    /// Linear front end-stop (eq 28/38).
    pub front_stop: LinearStop,
    /// Nonlinear back end-stop (eq 29/37).
    pub back_stop: NonlinearStop,
    /// Slide friction (eq 41-42); `None` is frictionless.
    pub friction: Option<TanhFriction>,
}

/// Hydraulic decoupler parameters (Tables 12, 14). Travel u >= 0 is measured back from the front stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hydraulic {
    /// L, piston stroke, m, > 0.
    pub stroke: f64,
    /// R_p, main cylinder radius, m, > 0.
    pub piston_radius: f64,
    /// R_o, orifice radius, m, > 0 and < R_p.
    pub orifice_radius: f64,
    /// p10, gas preload pressure, Pa, > 0.
    pub gas_pressure: f64,
    /// V_g0, gas volume at the front stop, m^3, > A_p * L.
    pub gas_volume: f64,
    /// c0, orifice discharge coefficient, > 0.
    pub discharge_coefficient: f64,
    /// rho_L, kg/m^3, > 0.
    pub liquid_density: f64,
    /// d, dry friction, N, >= 0.
    pub dry_friction: f64,
    /// b, viscous friction, N s/m, >= 0.
    pub viscous_friction: f64,
    /// kappa, adiabatic exponent (1.4 for air).
    pub adiabatic_exponent: f64,
    /// Velocity that regularises sgn() in the dry friction (m/s, > 0).
    pub friction_v0: f64,
    /// Linear front end-stop.
    pub front_stop: LinearStop,
    /// Nonlinear back end-stop.
    pub back_stop: NonlinearStop,
}

/// Front end-stop: eq 28/38's linear law `F = -k (s - C1) - c s'`, pushing only, or (`law =
/// "hunt-crossley"`) the nonlinear law of [`FrontStopLaw::HuntCrossley`] with the same k and the
/// same energy loss per impact (`scene/decoupler/end_stop.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearStop {
    /// k_fe, N/m (N/m^n with the Hunt-Crossley law's exponent n), > 0.
    pub stiffness: f64,
    /// c_fe, N s/m, >= 0: eq 28's damping (with the Hunt-Crossley law, the linear damping whose
    /// restitution the nonlinear law matches).
    pub damping: f64,
    /// Which law the stop follows.
    pub law: FrontStopLaw,
}

/// The front end-stop's contact law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrontStopLaw {
    /// Eq 28/38: `F = -k d - c d'`, d = s - C1; jumps to `c d'` at contact onset.
    Linear,
    /// Hunt-Crossley: `F = -k d^n (1 + alpha d' / v_in)`, v_in the approach speed at onset; zero
    /// at contact onset, no jump.
    HuntCrossley {
        /// n, the exponent of d (1: the same static stiffness as eq 28).
        exponent: f64,
        /// alpha, chosen so an isolated impact has the linear law's restitution.
        alpha: f64,
        /// That restitution, the linear law's (clamped, as modelled) for c_fe and the tool mass.
        restitution: f64,
    },
}

/// Nonlinear end-stop law `F = k d^1.5 + chi d^1.5 d'`, pushing only (eq 29/37).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearStop {
    /// k_be, N/m^1.5, > 0.
    pub stiffness: f64,
    /// How chi is set (restitution and law, or chi directly).
    pub damping: ContactDamping,
}

/// Slide friction (eq 41-42): `F = mu F_n tanh(v_rel / v0)`, or with v0 = 0 the Coulomb law the
/// thesis writes (Tables 4, 8, 11, 13), integrated as a stick/slip hybrid (`plant::friction`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TanhFriction {
    /// mu, >= 0.
    pub mu: f64,
    /// v0, m/s, >= 0; 0 is the Coulomb limit (see `law`).
    pub v0: f64,
    /// How the law is integrated.
    pub law: FrictionLaw,
}

/// How the slide's dry friction is integrated (`decoupler.friction.law`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionLaw {
    /// Coulomb with v0 = 0: sticking and slipping as discrete states switched by located events
    /// (Karnopp); the default when v0 = 0.
    StickSlip,
    /// `mu F_n tanh(v / v0)`, v0 raised to 1 mm/s if smaller; the default when v0 > 0.
    Regularised,
}

/// How the damping constant chi of a nonlinear contact is obtained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactDamping {
    /// chi from a restitution e in [0, 1] and a law, times k / v_in.
    Restitution {
        /// Requested coefficient of restitution e.
        restitution: f64,
        /// The law that maps e to chi.
        law: DampingLaw,
    },
    /// A fixed chi, N s / m^2.5 (Table 12).
    FixedChi(f64),
}

/// Laws mapping restitution e to chi = factor(e) * k / v_in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DampingLaw {
    /// 3 (1 - e) / 2 (eq 7, as the thesis).
    HuntCrossley,
    /// 3 (1 - e^2) / 4.
    LankaraniNikravesh,
    /// 8 (1 - e) / (5 e).
    Flores,
    /// (1 - e^2) / e.
    Gonthier,
    /// chi solved so that the achieved restitution equals e.
    Exact,
}

/// The target of the collision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Fixed obstacle or free object.
    pub kind: TargetKind,
    /// Gap between the tool and the target at t = 0, m, > 0.
    pub gap: f64,
    /// k_c, N/m^1.5, > 0 (a body region: its linear k, N/m).
    pub stiffness: f64,
    /// How chi is set (a body region: a fixed chi of 0, undamped as Annex A).
    pub damping: ContactDamping,
}

/// Fixed obstacle, free object, or a human body region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetKind {
    /// A fixed obstacle surface.
    Obstacle,
    /// A human body region of ISO/TS 15066 Annex A (`crate::body`): an undamped linear spring k
    /// (`Target::stiffness`, N/m here) in front of a free effective mass m_H (transient contact)
    /// or of a rigid surface (quasi-static, clamped).
    BodyRegion(crate::body::BodyTarget),
    /// A free object of mass m_p, optionally with floor friction.
    Object {
        /// m_p, kg, > 0.
        mass: f64,
        /// Coulomb floor friction coefficient (regularised), `None` for none.
        floor_friction: Option<f64>,
    },
}

/// Collision detector (MODEL.md element 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sensor {
    /// Travel switch: fires once the tool has moved `threshold` m back from its rest position.
    Travel {
        /// d_sw, m, > 0.
        threshold: f64,
    },
    /// Force threshold on the contact force, N, > 0.
    Force {
        /// N.
        threshold: f64,
    },
}

/// Integration method and accuracy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// The method.
    pub method: Method,
    /// Relative tolerance for adaptive methods.
    pub rtol: f64,
    /// Absolute tolerance for adaptive methods (on positions in m and velocities in m/s).
    pub atol: f64,
    /// Fixed step for fixed-step methods, and the largest step for adaptive ones, s.
    pub max_step: f64,
    /// Interval between recorded samples of the time history, s (0 = every step).
    pub output_interval: f64,
    /// What accuracy the scene asks for (`solver.fidelity`); it sets the tolerance defaults.
    pub fidelity: Fidelity,
    /// Parts of the model the scene allows the simulator to drop (`solver.simplify`); every one
    /// applied is reported in the summary.
    pub simplify: Simplify,
}

/// The accuracy a scene asks for (docs/accuracy.md gives what each costs and buys).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fidelity {
    /// Looser tolerance (`FAST_*`): within 1.2e-3 of the reference on the shipped scenes, about
    /// 1.2-1.4x faster than the default (docs/accuracy.md).
    Fast,
    /// The measured default: within 1 % of the reference on peak forces and detection time.
    Default,
    /// The reference: the full model at the tightest tolerance, to check the others against.
    Reference,
}

/// Simplifications of the model, each an explicit option (all `false`: the full model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Simplify {
    /// Drop the robot's compliance: x_r = x_c (removes the robot mode and two states).
    pub rigid_robot: bool,
    /// Drop friction: the decoupler's slide friction, the hydraulic dry and viscous friction, the
    /// floor under a free object.
    pub no_friction: bool,
}

/// Integration methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Dormand-Prince 5(4), adaptive, events located on the dense output.
    Dopri5,
    /// Classical Runge-Kutta 4, fixed step `max_step`.
    Rk4,
    /// Semi-implicit (symplectic) Euler, fixed step `max_step`.
    SemiImplicitEuler,
}

/// The robot controller model for firmware-in-the-loop runs (`flinch hil`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controller {
    /// Scan cycle, s, > 0: inputs are sampled once per cycle.
    pub scan_cycle: f64,
    /// Phase of the first sample in [0, 1) of a cycle.
    pub phase: f64,
    /// Firmware tick period, s, > 0.
    pub firmware_tick: f64,
    /// Category-0 stop: brake engagement delay, s (`plant/brake.rs`; default 0.08).
    pub brake_delay: f64,
    /// Category-0 stop: braking deceleration, m/s^2 (default 5).
    pub brake_decel: f64,
    /// The robot's reaction once a scan sample has seen the stop, s (`[controller] reaction_time`):
    /// from that sample to braking (with `motion.stopping`, to the table's stop signal). `None`:
    /// the scene's `motion.dead_time` less one scan cycle ([`Controller::reaction`]).
    pub reaction_time: Option<f64>,
}

/// Where a firmware-in-the-loop run's robot reaction came from ([`Controller::reaction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReactionSource {
    /// `[controller] reaction_time` (or `flinch hil --reaction-time`).
    Given,
    /// `motion.dead_time - scan_cycle`: the scene's DT split into one scan and the reaction.
    DeadTimeLessScan,
    /// 0: `motion.dead_time` is shorter than one scan cycle, so no split of it leaves a reaction.
    DeadTimeShorterThanScan,
}

// The category-0 brake's defaults (`[controller] brake_delay`, `brake_decel`; plant/brake.rs models the brake):
// * [`DEFAULT_BRAKE_DELAY_S`] = 80 ms: the brake engagement time of the Pilz PRBT 6 arm, "from the
//   moment the STO signal on the robot arm is reset until the moment at which all brakes are
//   engaged" (Pilz, System Description Service Robotics Modules 1004870-EN-05, 4.12).
// * [`DEFAULT_BRAKE_DECEL_MPS2`] = 5 m/s^2: the Universal Robots UR5/CB3 manual's category-0 stop of
//   joint 1 (shoulder, the slowest of the three listed), 183 deg/s to rest in 530 ms (Appendix A.1,
//   v3.4.5): a mean 6.0 rad/s^2, 5.1 m/s^2 at the arm's 0.85 m reach, rounded down. Those 530 ms
//   include the brakes' own engagement, so adding the 80 ms delay counts it twice: the default
//   stops later than that robot, not sooner.
//
/// Default brake engagement delay, s (Pilz PRBT 6, see above).
pub const DEFAULT_BRAKE_DELAY_S: f64 = 0.08;
/// Default braking deceleration once engaged, m/s^2 (UR5/CB3 joint 1, see above).
pub const DEFAULT_BRAKE_DECEL_MPS2: f64 = 5.0;

impl Controller {
    /// A controller with the category-0 brake's defaults (`plant/brake.rs`).
    pub const fn new(scan_cycle: f64, phase: f64, firmware_tick: f64) -> Self {
        Self { scan_cycle, phase, firmware_tick, brake_delay: DEFAULT_BRAKE_DELAY_S, brake_decel: DEFAULT_BRAKE_DECEL_MPS2, reaction_time: None }
    }

    /// The robot's reaction after the scan sample that saw the stop, s, and where it came from:
    /// `reaction_time` when given, else the part of `dead_time` (the scene's DT) beyond one scan
    /// cycle, DT = scan_cycle + reaction (the worst case of a scan: the sample came just before the
    /// stop), and 0 when DT is shorter than one scan.
    pub fn reaction(&self, dead_time: f64) -> (f64, ReactionSource) {
        match self.reaction_time {
            Some(r) => (r, ReactionSource::Given),
            None if dead_time >= self.scan_cycle => (dead_time - self.scan_cycle, ReactionSource::DeadTimeLessScan),
            None => (0.0, ReactionSource::DeadTimeShorterThanScan),
        }
    }
}

/// The planar plant's inputs (issue 30, `scene/planar.rs`, `plant/planar/`), resolved: present when
/// a scene sets a planar key or `solver.plant = "planar"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Planar {
    /// beta, deg: from the decoupler's axis u (at rest) to the flange's commanded velocity.
    pub off_axis_deg: f64,
    /// theta, deg (Fig. 68a): the surface's outward normal is R(theta - 90 deg) u.
    pub surface_angle_deg: f64,
    /// Coulomb friction coefficient at the tool-target contact (0: frictionless).
    pub contact_mu: f64,
    /// The 2-D rotational module's stage (`[decoupler.rotational]`); `None` for a 1-D module.
    pub rotational: Option<Stage>,
}

/// The 2-D rotational module's stage (`scene/decoupler/rotational.rs`, Ch. 3.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stage {
    /// The stage's and tool's own moment of inertia, kg m^2.
    pub inertia: f64,
    /// l, m: stage axis to tool axis along the guide (tool on its front stop), trailing positive.
    pub lever: f64,
    /// b, m: the tool's axis across the guide, positive on the side R(-90 deg) u.
    pub offset_b: f64,
    /// r_t, m: the tool's disc radius.
    pub tool_radius: f64,
    /// k_phi, N m/rad.
    pub stiffness: f64,
    /// M0, N m.
    pub preload: f64,
    /// Bearing friction moment, N m.
    pub bearing_torque: f64,
}

impl Planar {
    /// The axial scene through the planar plant: beta = 0, theta = -90, no contact friction.
    pub const AXIAL: Planar = Planar { off_axis_deg: 0.0, surface_angle_deg: -90.0, contact_mu: 0.0, rotational: None };

    /// e_p . (-n): the share of the flange's speed that closes the gap along the surface's normal.
    pub fn closing(&self) -> f64 {
        let d = (self.off_axis_deg - (self.surface_angle_deg + 90.0)).to_radians();
        d.cos()
    }
}
