//! `flinch validate`: its arguments and the command.

use std::path::PathBuf;
use super::{rows::*, tables::*, document::*, pictures::*};

/// `flinch validate [--out DIR] [--scenes DIR]`.
#[derive(clap::Args, Debug)]
pub struct ValidateArgs {
    /// Where validation.md and validation/*.svg go.
    #[arg(long, value_name = "DIR", default_value = "docs")]
    pub out: PathBuf,
    /// The scenes folder (with figures/ inside).
    #[arg(long, value_name = "DIR", default_value = "scenes")]
    pub scenes: PathBuf,
    /// Only print the markdown (no pictures, nothing written).
    #[arg(long)]
    pub check: bool,
}

/// Runs `flinch validate`.
pub fn run(a: &ValidateArgs) -> Result<(), String> {
    let sections = tables(&a.scenes)?;
    let md = markdown(&sections);
    if a.check {
        print!("{md}");
        return Ok(());
    }
    draw_all(&a.scenes, &a.out.join("validation"))?;
    let path = a.out.join("validation.md");
    std::fs::write(&path, &md).map_err(|e| format!("{}: {e}", path.display()))?;
    let differ = sections.iter().flat_map(|s| &s.rows).filter(|r| r.verdict == Verdict::Differs).count();
    eprintln!("{}: {} sections, {} comparisons, {differ} differ; pictures in {}", path.display(), sections.len(), sections.iter().map(|s| s.rows.len()).sum::<usize>(), a.out.join("validation").display());
    Ok(())
}
