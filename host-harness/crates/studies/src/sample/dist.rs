//! `flinch sample`: the counter-based random numbers and the distributions a key is drawn from.


use crate::sweep::SweepError;
use super::common::*;
use super::stats;

// ---------------------------------------------------------------------------------------------
// Random numbers
// ---------------------------------------------------------------------------------------------

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (Steele, Lea, Flood 2014): a bijection of u64 that mixes well.
fn mix(z: u64) -> u64 {
    let mut z = z.wrapping_add(GOLDEN);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The uniform number in (0, 1) of draw `draw` (the key's position in `--vary`) of sample `index`
/// for `seed`: `mix(mix(mix(seed) ^ index) ^ draw)`, its top 53 bits, offset by half a step so
/// neither 0 nor 1 comes out. Counter-based: no state, so any sample can be drawn anywhere.
pub fn uniform01(seed: u64, index: u64, draw: u64) -> f64 {
    let h = mix(mix(mix(seed) ^ index) ^ draw);
    ((h >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

// ---------------------------------------------------------------------------------------------
// Distributions
// ---------------------------------------------------------------------------------------------

/// A distribution a key is drawn from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dist {
    /// `normal:MEAN:SD`.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation, > 0.
        sd: f64,
    },
    /// `lognormal:MU:SIGMA`: ln X is normal with mean MU and standard deviation SIGMA (as numpy's
    /// `lognormal(mean, sigma)`); the median is exp(MU).
    LogNormal {
        /// Mean of ln X.
        mu: f64,
        /// Standard deviation of ln X, > 0.
        sigma: f64,
    },
    /// `uniform:LO:HI`.
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end, > LO.
        hi: f64,
    },
    /// `triangular:LO:MODE:HI`.
    Triangular {
        /// Lower end.
        lo: f64,
        /// Most likely value, in [LO, HI].
        mode: f64,
        /// Upper end, > LO.
        hi: f64,
    },
}

impl Dist {
    /// The distribution function.
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => stats::normal_cdf((x - mean) / sd),
            Dist::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    0.0
                } else {
                    stats::normal_cdf((x.ln() - mu) / sigma)
                }
            }
            Dist::Uniform { lo, hi } => ((x - lo) / (hi - lo)).clamp(0.0, 1.0),
            Dist::Triangular { lo, mode, hi } => {
                if x <= lo {
                    0.0
                } else if x >= hi {
                    1.0
                } else if x <= mode {
                    (x - lo) * (x - lo) / ((hi - lo) * (mode - lo))
                } else {
                    1.0 - (hi - x) * (hi - x) / ((hi - lo) * (hi - mode))
                }
            }
        }
    }

    /// The survival function 1 - F(x), computed without the cancellation of `1 - cdf` in the upper
    /// tail.
    pub fn sf(&self, x: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => stats::normal_cdf(-(x - mean) / sd),
            Dist::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    1.0
                } else {
                    stats::normal_cdf(-(x.ln() - mu) / sigma)
                }
            }
            _ => 1.0 - self.cdf(x),
        }
    }

    /// The inverse survival function: the x with 1 - F(x) = q, q in (0, 1); exact in the upper
    /// tail where `quantile(1 - q)` would round q away.
    pub fn isf(&self, q: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => mean - sd * stats::normal_quantile(q),
            Dist::LogNormal { mu, sigma } => (mu - sigma * stats::normal_quantile(q)).exp(),
            Dist::Uniform { lo, hi } => hi - (hi - lo) * q,
            Dist::Triangular { .. } => self.quantile(1.0 - q),
        }
    }

    /// The quantile (inverse distribution function) at u in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Dist::Normal { mean, sd } => mean + sd * stats::normal_quantile(u),
            Dist::LogNormal { mu, sigma } => (mu + sigma * stats::normal_quantile(u)).exp(),
            Dist::Uniform { lo, hi } => lo + (hi - lo) * u,
            Dist::Triangular { lo, mode, hi } => {
                let f = (mode - lo) / (hi - lo);
                if u < f {
                    lo + (u * (hi - lo) * (mode - lo)).sqrt()
                } else {
                    hi - ((1.0 - u) * (hi - lo) * (hi - mode)).sqrt()
                }
            }
        }
    }

    /// As written on the command line (numbers in the shortest round-trip form, [`num`]).
    pub fn spec(&self) -> String {
        match *self {
            Dist::Normal { mean, sd } => format!("normal:{}:{}", num(mean), num(sd)),
            Dist::LogNormal { mu, sigma } => format!("lognormal:{}:{}", num(mu), num(sigma)),
            Dist::Uniform { lo, hi } => format!("uniform:{}:{}", num(lo), num(hi)),
            Dist::Triangular { lo, mode, hi } => format!("triangular:{}:{}:{}", num(lo), num(mode), num(hi)),
        }
    }

    /// The median, for a lognormal exp(MU) (the parameters are of ln X).
    pub fn median(&self) -> f64 {
        self.quantile(0.5)
    }
}

/// A number for people and specs: the shortest form that reads back to the same f64, with an
/// exponent when it is tiny or huge (`1e-300`, not 300 zeros; `0.05` stays `0.05`).
pub fn num(x: f64) -> String {
    if x == 0.0 || (1e-5..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The extreme uniform numbers a draw's finiteness is checked at: [`uniform01`]'s smallest,
/// 0.5 / 2^53, and the largest f64 below 1, 1 - 2^-53.
pub const U_EXTREMES: (f64, f64) = (0.5 / 9_007_199_254_740_992.0, 1.0 - 1.0 / 9_007_199_254_740_992.0);

/// The forms `--vary` accepts, for messages.
pub const FORMS: &str = "normal:MEAN:SD, lognormal:MU:SIGMA (of ln X; median exp(MU)), uniform:LO:HI, triangular:LO:MODE:HI; normal and lognormal may end in :LO:HI to truncate them to [LO, HI]";

/// One `--vary KEY=DIST` as parsed: the key, the distribution and optional explicit bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct VarySpec {
    /// Dotted key path.
    pub key: String,
    /// The distribution.
    pub dist: Dist,
    /// `:LO:HI` given after a normal or lognormal.
    pub bounds: Option<(f64, f64)>,
}

impl VarySpec {
    /// Parses `KEY=normal:MEAN:SD[:LO:HI]`, `KEY=lognormal:MU:SIGMA[:LO:HI]`, `KEY=uniform:LO:HI`,
    /// `KEY=triangular:LO:MODE:HI`.
    pub fn parse(spec: &str) -> Result<Self, SweepError> {
        let Some((key, dist)) = spec.split_once('=') else {
            return err(format!("--vary {spec:?}: expected KEY=DIST, e.g. motion.dead_time=uniform:0.016:0.032; DIST is one of {FORMS}"));
        };
        let key = key.trim();
        if key.is_empty() || key.split('.').any(|s| s.trim().is_empty()) {
            return err(format!("--vary {spec:?}: the key must be a dotted path such as motion.speed"));
        }
        let parts: Vec<&str> = dist.split(':').map(str::trim).collect();
        let kind = parts[0].to_ascii_lowercase();
        let mut nums = Vec::new();
        for p in &parts[1..] {
            match p.parse::<f64>() {
                Ok(x) if x.is_finite() => nums.push(x),
                _ => return err(format!("--vary {spec:?}: {p:?} is not a finite number")),
            }
        }
        let want = |n: &[usize], form: &str| -> Result<(), SweepError> {
            if n.contains(&nums.len()) {
                Ok(())
            } else {
                err(format!("--vary {spec:?}: expected {key}={form} ({} numbers after {kind}:), got {}", n.iter().map(usize::to_string).collect::<Vec<_>>().join(" or "), nums.len()))
            }
        };
        let (dist, bounds) = match kind.as_str() {
            "normal" => {
                want(&[2, 4], "normal:MEAN:SD[:LO:HI]")?;
                if nums[1] <= 0.0 {
                    return err(format!("--vary {spec:?}: SD must be > 0, got {}", nums[1]));
                }
                (Dist::Normal { mean: nums[0], sd: nums[1] }, (nums.len() == 4).then(|| (nums[2], nums[3])))
            }
            "lognormal" => {
                want(&[2, 4], "lognormal:MU:SIGMA[:LO:HI] (MU and SIGMA of ln X)")?;
                if nums[1] <= 0.0 {
                    return err(format!("--vary {spec:?}: SIGMA must be > 0, got {}", nums[1]));
                }
                (Dist::LogNormal { mu: nums[0], sigma: nums[1] }, (nums.len() == 4).then(|| (nums[2], nums[3])))
            }
            "uniform" => {
                want(&[2], "uniform:LO:HI")?;
                (Dist::Uniform { lo: nums[0], hi: nums[1] }, None)
            }
            "triangular" => {
                want(&[3], "triangular:LO:MODE:HI")?;
                if !(nums[0] <= nums[1] && nums[1] <= nums[2]) {
                    return err(format!("--vary {spec:?}: need LO <= MODE <= HI, got {} {} {}", nums[0], nums[1], nums[2]));
                }
                (Dist::Triangular { lo: nums[0], mode: nums[1], hi: nums[2] }, None)
            }
            _ => return err(format!("--vary {spec:?}: unknown distribution {:?}; one of {FORMS}", parts[0])),
        };
        match dist {
            Dist::Uniform { lo, hi } | Dist::Triangular { lo, hi, .. } if lo >= hi => {
                return err(format!("--vary {spec:?}: LO must be below HI, got {lo} >= {hi}"));
            }
            _ => {}
        }
        if let Some((lo, hi)) = bounds {
            if lo >= hi {
                return err(format!("--vary {spec:?}: the truncation LO must be below HI, got {lo} >= {hi}"));
            }
        }
        // Every draw must be a finite number: a width beyond the largest f64 (uniform or
        // triangular from -1e308 to 1e308) or a spread whose extreme quantiles overflow draws inf.
        let (u0, u1) = U_EXTREMES;
        let width_ok = match dist {
            Dist::Uniform { lo, hi } | Dist::Triangular { lo, hi, .. } => (hi - lo).is_finite(),
            _ => true,
        };
        if !width_ok || !dist.quantile(u0).is_finite() || !dist.quantile(u1).is_finite() || !dist.isf(u0).is_finite() {
            return err(format!("--vary {spec:?}: the distribution reaches beyond the largest number (1.8e308): some draws would be infinite; give a narrower one"));
        }
        Ok(Self { key: key.to_string(), dist, bounds })
    }

    /// As written (canonical numbers).
    pub fn spec(&self) -> String {
        match self.bounds {
            Some((lo, hi)) => format!("{}={}:{}:{}", self.key, self.dist.spec(), num(lo), num(hi)),
            None => format!("{}={}", self.key, self.dist.spec()),
        }
    }
}

