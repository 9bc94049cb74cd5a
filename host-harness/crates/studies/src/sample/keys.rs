//! The scene keys a study varies: what each is (its table, unit, the element it belongs to), its
//! CSV column, and the key written the one canonical way.

use flinch_output::units::SUFFIXES;
use flinch_model::scene::{Decoupler, Scene, Sensor, TargetKind, Ty};
use super::dist::*;

// ---------------------------------------------------------------------------------------------
// Keys: unit and accepted range, from the scene's key tables
// ---------------------------------------------------------------------------------------------

/// What the scene's key tables say about a key: its unit and accepted range.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyInfo {
    /// Unit as the contract writes it ("m/s", "N/m^1.5", "" for a pure number).
    pub unit: String,
    /// Lower end of the accepted range, if any.
    pub lo: Option<f64>,
    /// Upper end, if any.
    pub hi: Option<f64>,
    /// The range as the validator's messages say it.
    pub range: String,
    /// An integer key (a draw must be whole to be accepted).
    pub integer: bool,
}

/// The `kind` that selects a table's keys in this scene.
pub(crate) fn kind_of(base: &Scene, table: &str) -> Option<&'static str> {
    match table {
        "decoupler" | "decoupler.friction" => Some(match base.decoupler {
            Decoupler::Rigid => "rigid",
            Decoupler::Linear(_) => "linear",
            Decoupler::Bistable(_) => "bistable",
            Decoupler::Hydraulic(_) => "hydraulic",
        }),
        "target" => Some(match base.target.kind {
            TargetKind::Obstacle => "obstacle",
            TargetKind::Object { .. } => "object",
            TargetKind::BodyRegion(_) => "body_region",
        }),
        "sensor" => base.sensor.map(|s| match s {
            Sensor::Travel { .. } => "travel",
            Sensor::Force { .. } => "force",
        }),
        _ => None,
    }
}

/// The unit and range of a dotted key in this scene (None for a key the tables do not list, such
/// as an element of `robot.joints`, whose unit is the joint's).
pub fn key_info(base: &Scene, key: &str) -> Option<KeyInfo> {
    let (table, leaf) = key.rsplit_once('.').unwrap_or(("", key));
    let kind = kind_of(base, table);
    let k = flinch_model::scene::key_tables()
        .iter()
        .filter(|t| t.path == table && (t.when.is_empty() || kind.is_some_and(|k| t.when == format!("kind = \"{k}\""))))
        .flat_map(|t| t.keys.iter())
        .find(|k| k.name == leaf)?;
    match k.ty {
        Ty::Number(span) => Some(KeyInfo { unit: span.unit.to_string(), lo: span.lo.value(), hi: span.hi.value(), range: span.range(), integer: false }),
        Ty::Integer { lo, hi, .. } => Some(KeyInfo { unit: String::new(), lo: Some(f64::from(lo)), hi: Some(f64::from(hi)), range: format!("whole numbers {lo} to {hi}"), integer: true }),
        _ => None,
    }
}

/// The column name of a key: the key and its unit's suffix (docs/conventions.md), e.g.
/// `motion.dead_time_s`, `decoupler.spring_rate_n_per_m`; a unit the convention has no suffix for
/// is spelled out (`target.stiffness_n_per_m1_5` for N/m^1.5); a pure number has none.
pub fn column(key: &str, unit: &str) -> String {
    if unit.is_empty() || unit.starts_with("of ") {
        return key.to_string();
    }
    if let Some((s, _)) = SUFFIXES.iter().find(|(_, u)| *u == unit) {
        return format!("{key}{s}");
    }
    let s = unit.to_ascii_lowercase().replace("n s", "ns").replace('/', "_per_").replace('^', "").replace(['.', ' '], "_");
    format!("{key}_{s}")
}

// ---------------------------------------------------------------------------------------------
// The plan: keys, distributions, truncation, the sample range
// ---------------------------------------------------------------------------------------------

/// A varied key, checked against the scene.
#[derive(Debug, Clone)]
pub struct Varied {
    /// As parsed.
    pub spec: VarySpec,
    /// CSV column.
    pub column: String,
    /// Unit and range from the key tables, if listed.
    pub info: Option<KeyInfo>,
    /// The interval draws are confined to (explicit bounds, and with `--truncate` the accepted
    /// range), if any.
    pub within: Option<(f64, f64)>,
    /// F(within.hi) - F(within.lo): the probability the truncation keeps (1 without one).
    pub kept: f64,
    /// F at the lower end of `within` (0 without one); in the upper tail (`upper`), the survival
    /// function 1 - F there instead.
    pub(crate) f_lo: f64,
    /// `within` lies in the upper tail (F at its lower end above 1/2): draws invert the survival
    /// function, whose small values keep their precision where F's round to 1.
    pub(crate) upper: bool,
    /// Without truncation: the probability of a draw outside the key's accepted range (those
    /// samples will be refused and counted).
    pub outside: f64,
}

impl Varied {
    /// The value of this key for uniform number u.
    pub fn value(&self, u: f64) -> f64 {
        if self.upper {
            self.spec.dist.isf(self.f_lo - u * self.kept)
        } else {
            self.spec.dist.quantile(self.f_lo + u * self.kept)
        }
    }
}

/// A dotted key as the scene reads it: an array index is a number, so `stopping.distance.02`,
/// `.+2` and `.2` are one key (each segment that parses as an index is written without sign or
/// leading zeros).
pub fn canonical_key(key: &str) -> String {
    key.split('.').map(|s| s.trim().parse::<usize>().map_or_else(|_| s.trim().to_string(), |i| i.to_string())).collect::<Vec<_>>().join(".")
}
