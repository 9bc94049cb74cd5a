//! The boundary search `design` and `body_design` share: scan the candidates in parallel for the
//! first change of a verdict, then bisect between the two neighbours.

use rayon::prelude::*;

/// Scans `xs` (ascending) for the first boundary from `want_low` to its opposite and bisects it;
/// `f` is None where the candidate is invalid. Returns the last x on the `want_low` side and the
/// first x past it.
pub fn boundary(xs: &[f64], f: &(dyn Fn(f64) -> Option<bool> + Sync), want_low: bool, iters: usize, show: fn(f64) -> String) -> Result<(f64, f64), String> {
    let scan: Vec<Option<bool>> = xs.par_iter().map(|&x| f(x)).collect();
    let valid: Vec<(f64, bool)> = xs.iter().copied().zip(scan).filter_map(|(x, s)| s.map(|s| (x, s))).collect();
    if valid.is_empty() {
        return Err("the validator refuses every candidate".into());
    }
    let Some(k) = valid.iter().position(|&(_, s)| s != want_low) else {
        return Err(format!("no boundary between {} and {}", show(valid[0].0), show(valid[valid.len() - 1].0)));
    };
    if k == 0 {
        return Err(format!("already past the boundary at the smallest candidate {}", show(valid[0].0)));
    }
    let (mut lo, mut hi) = (valid[k - 1].0, valid[k].0);
    for _ in 0..iters {
        let mid = 0.5 * (lo + hi);
        match f(mid) {
            Some(s) if s == want_low => lo = mid,
            Some(_) => hi = mid,
            None => break,
        }
    }
    Ok((lo, hi))
}
