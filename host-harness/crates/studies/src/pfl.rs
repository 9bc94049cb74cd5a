//! `[avoid.pfl]`: the PFL speeds (ISO/TS 15066 5.5.5, Annex A) of the module an avoidance scene
//! names, computed by [`crate::body_design::design`] (the computation of `flinch design
//! --body-region`), so that the avoidance's monitor, its verdict and the board use the module's own
//! simulated speed on its own robot, never a number typed into the avoidance scene.
//!
//! * Along the module's axis: with the module, the largest speed at which the run is safe (the
//!   body limits hold and the stroke is not exhausted: `speed_safe_mps`), the smallest over the
//!   regions the scene allows to be touched.
//! * Across it: the rigid tool's largest speed at which the limits hold (`speed_simulated_mps`),
//!   the smallest over the regions: a 1-D module does not yield across its axis.
//!
//! A region with no such speed (none found, or the contact not permitted) is refused by name: the
//! scene must then leave that region out, or `[avoid.pfl]` altogether. A speed that holds at every
//! speed scanned is taken as the largest speed scanned (the validator's 5 m/s). The answers are
//! kept per module text and regions for the life of the process (a test suite resolves the same
//! module many times).

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Mutex, OnceLock};

use flinch_model::avoid::scene::{Avoid, PflResolved};
use sha2::{Digest, Sha256};

use crate::body_design::{design, Answer, RIGID_SENSOR_N};
use crate::sweep::Template;

/// The largest speed the body-region search scans, m/s: a speed that holds at every speed scanned
/// holds at least up to it.
const LARGEST_SCANNED_MPS: f64 = 5.0;

type Cache = Mutex<HashMap<(String, Vec<String>), PflResolved>>;

fn cache() -> &'static Cache {
    static C: OnceLock<Cache> = OnceLock::new();
    C.get_or_init(|| Mutex::new(HashMap::new()))
}

/// Fills in `scene.pfl.resolved` (nothing to do without `[avoid.pfl]`). The error names the key,
/// the module scene and why.
pub fn resolve_pfl(scene: &mut Avoid) -> Result<(), String> {
    let Some(p) = scene.pfl.as_mut() else { return Ok(()) };
    if p.resolved.is_some() {
        return Ok(());
    }
    let (file, text) = flinch_model::shipped::read(&p.module_path)
        .or_else(|_| flinch_model::shipped::read(Path::new(&p.module)))
        .map_err(|e| format!("avoid.pfl.module: {}", e.0))?;
    let sha: String = Sha256::digest(text.as_bytes()).iter().map(|b| format!("{b:02x}")).collect();
    let key = (sha.clone(), p.body_regions.clone());
    if let Some(r) = cache().lock().ok().and_then(|c| c.get(&key).cloned()) {
        p.resolved = Some(r);
        return Ok(());
    }
    let t = Template::from_text(&text, &file).map_err(|e| format!("avoid.pfl.module: {}", e.0))?;
    let mut along: Option<(f64, String, f64)> = None;
    let mut across: Option<(f64, String)> = None;
    let mut contact = String::new();
    for region in &p.body_regions {
        let d = design(&t, region, None, RIGID_SENSOR_N).map_err(|e| format!("avoid.pfl.module: {file}: {e}"))?;
        contact = d.contact.clone();
        let Some(r) = d.regions.first() else { return Err(format!("avoid.pfl.body_regions: {region}: no answer from {file}")) };
        let force = r.force_limit_n.ok_or_else(|| format!("avoid.pfl.body_regions: {region}: ISO/TS 15066 Table A.2 permits no {} contact there", d.contact))?;
        let module_speed = match &r.with_module {
            Some(a) => safe_speed(a).ok_or_else(|| format!("avoid.pfl.body_regions: {region}: {file} gives no speed at which a contact with the module is safe ({}); leave the region out", a.safe_search_note.clone().or_else(|| a.search_note.clone()).unwrap_or_default()))?,
            // A rigid tool in the module scene: its own speed along the axis too.
            None => rigid_speed(&r.rigid_tool).ok_or_else(|| format!("avoid.pfl.body_regions: {region}: {file} gives no speed at which a contact with the rigid tool holds; leave the region out"))?,
        };
        let rigid = rigid_speed(&r.rigid_tool).ok_or_else(|| format!("avoid.pfl.body_regions: {region}: {file} gives no speed at which a contact with a rigid tool holds ({}); leave the region out", r.rigid_tool.search_note.clone().unwrap_or_default()))?;
        if along.as_ref().map_or(true, |a| module_speed < a.0) {
            along = Some((module_speed, region.clone(), force));
        }
        if across.as_ref().map_or(true, |a| rigid < a.0) {
            across = Some((rigid, region.clone()));
        }
    }
    let (Some((along_mps, along_region, along_force_limit_n)), Some((across_mps, across_region))) = (along, across) else {
        return Err("avoid.pfl.body_regions: must name at least one region".into());
    };
    let r = PflResolved { along_mps, along_region, across_mps, across_region, along_force_limit_n, contact, module_sha256: sha };
    if let Ok(mut c) = cache().lock() {
        c.insert(key, r.clone());
    }
    p.resolved = Some(r);
    Ok(())
}

/// With the module: the largest safe speed (limits and stroke).
fn safe_speed(a: &Answer) -> Option<f64> {
    a.speed_safe_mps.filter(|v| *v > 0.0)
}

/// The rigid tool: the largest speed at which the limits hold.
fn rigid_speed(a: &Answer) -> Option<f64> {
    if a.holds_at_every_speed {
        Some(LARGEST_SCANNED_MPS)
    } else {
        a.speed_simulated_mps.filter(|v| *v > 0.0)
    }
}
