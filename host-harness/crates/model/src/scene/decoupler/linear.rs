//! `kind = "linear"`: a spring-damper between flange and tool, no end-stops (Ch. 2.3, eq 17, 23;
//! `plant/decoupler/linear.rs`). k_t = 0 with zeta = 0 is the free tool of Fig. 1b / 4b.
use super::super::check::{Bound::*, Ctx, Key, Tab};
use super::super::model::LinearDecoupler;
use super::kind::KIND;

/// k_t.
pub const STIFFNESS: Key = Key::number("stiffness", "N/m", Incl(0.0), Incl(1e7), "0 (a free tool, Fig. 1b) to 1e7 N/m, as stiff as the stiffest robot flange in range", "k_t, the spring between flange and tool (0: a free tool)");
/// zeta.
pub const DAMPING_RATIO: Key = Key::number("damping_ratio", "", Incl(0.0), Incl(10.0), "undamped to 10 times critical; the thesis uses 0-1 (Table 2)", "zeta = c_t / (2 sqrt(k_t m_t)) (eq 23)");

/// The keys of a linear decoupler.
pub const KEYS: &[Key] = &[KIND, STIFFNESS, DAMPING_RATIO];

/// Reads a linear decoupler.
pub(in super::super) fn linear(cx: &mut Ctx, t: &Tab) -> Option<LinearDecoupler> {
    let stiffness = cx.number(t, &STIFFNESS);
    let damping_ratio = cx.number(t, &DAMPING_RATIO);
    Some(LinearDecoupler {
        stiffness: stiffness?,
        damping_ratio: damping_ratio?,
    })
}
