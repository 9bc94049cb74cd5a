//! The decoupler between flange and tool (MODEL.md element 3). It acts +F on the tool and -F on
//! the robot, as a function of the stroke coordinate s = x_t - x_r and its rate s' (m, m/s).
//! One mechanism per file; the end-stops and friction they share live beside them.

pub mod bistable;
pub mod end_stop;
pub mod hydraulic;
pub mod linear;

use flinch_model::scene::{self, Tool};
use bistable::BistableMechanism;
use end_stop::{BackStop, FrontStop};
use hydraulic::HydraulicCylinder;
use linear::LinearSpringDamper;

/// A decoupler, ready to evaluate.
#[derive(Debug, Clone, Copy)]
pub enum Decoupler {
    /// Tool fastened to the flange: no relative motion.
    Rigid,
    /// Spring-damper.
    Linear(LinearSpringDamper),
    /// Bi-stable mechanism.
    Bistable(BistableMechanism),
    /// Hydraulic cylinder.
    Hydraulic(HydraulicCylinder),
}

/// The decoupler's force on the tool, split into its parts (N); the robot gets -`total`.
#[derive(Debug, Clone, Copy, Default)]
pub struct DecouplerForce {
    /// Sum of all parts, N.
    pub total: f64,
    /// Spring (bi-stable or linear) or hydraulic force, N.
    pub spring: f64,
    /// Front end-stop, N (<= 0).
    pub front_stop: f64,
    /// Back end-stop, N (>= 0).
    pub back_stop: f64,
    /// Friction, N.
    pub friction: f64,
    /// Gas pressure p1 (hydraulic only), Pa.
    pub gas_pressure: Option<f64>,
}

impl Decoupler {
    /// From the scene.
    pub fn new(d: &scene::Decoupler, tool: &Tool) -> Self {
        match d {
            scene::Decoupler::Rigid => Self::Rigid,
            scene::Decoupler::Linear(p) => Self::Linear(LinearSpringDamper::new(p, tool.mass)),
            scene::Decoupler::Bistable(p) => Self::Bistable(BistableMechanism::new(p)),
            scene::Decoupler::Hydraulic(p) => Self::Hydraulic(HydraulicCylinder::new(p)),
        }
    }

    /// True for a tool fastened to the flange.
    pub fn is_rigid(&self) -> bool {
        matches!(self, Self::Rigid)
    }

    /// The front end-stop, where the tool rests, if there is one.
    pub fn front_stop(&self) -> Option<&FrontStop> {
        match self {
            Self::Bistable(b) => Some(&b.front),
            Self::Hydraulic(h) => Some(&h.front),
            _ => None,
        }
    }

    /// The back end-stop (the flange), if there is one.
    pub fn back_stop(&self) -> Option<&BackStop> {
        match self {
            Self::Bistable(b) => Some(&b.back),
            Self::Hydraulic(h) => Some(&h.back),
            _ => None,
        }
    }

    /// Force on the tool at s, s'; `front_chi` and `back_chi` are the stops' dampings fixed at
    /// their contact onsets (`front_chi` only for a Hunt-Crossley front stop).
    pub fn force(&self, s: f64, s_dot: f64, front_chi: f64, back_chi: f64) -> DecouplerForce {
        let mut f = DecouplerForce::default();
        match self {
            Self::Rigid => {}
            Self::Linear(l) => f.spring = l.force(s, s_dot),
            Self::Bistable(b) => {
                (f.spring, f.friction) = b.spring_and_friction(s, s_dot);
                f.front_stop = b.front.force(s, s_dot, front_chi);
                f.back_stop = b.back.force(s, s_dot, back_chi);
            }
            Self::Hydraulic(h) => {
                let hf = h.force(s, s_dot);
                f.spring = hf.hydraulic;
                f.friction = hf.friction;
                f.gas_pressure = Some(hf.gas_pressure);
                f.front_stop = h.front.force(s, s_dot, front_chi);
                f.back_stop = h.back.force(s, s_dot, back_chi);
            }
        }
        f.total = f.spring + f.front_stop + f.back_stop + f.friction;
        f
    }

    /// True when the scene's friction v0 was below the floor and was raised (reported to the user).
    pub fn friction_regularised(&self) -> bool {
        matches!(self, Self::Bistable(BistableMechanism { friction: Some(bistable::SlideFriction::Regularised(f)), .. }) if f.regularised)
    }

    /// mu of a bi-stable slide with stick-slip (Coulomb) friction.
    pub fn stick_slip_mu(&self) -> Option<f64> {
        match self {
            Self::Bistable(b) => b.stick_slip_mu(),
            _ => None,
        }
    }

    /// mu |F_n| at s: the stick-slip slide's friction limit, N (0 without one).
    pub fn friction_limit(&self, s: f64) -> f64 {
        match self {
            Self::Bistable(b) => b.stick_slip_mu().map_or(0.0, |mu| mu * b.normal_force(s).abs()),
            _ => 0.0,
        }
    }
}
