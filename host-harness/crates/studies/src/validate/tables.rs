//! [`tables`]: every section of docs/validation.md, in order (Ch. 2 in `ch2.rs`, Ch. 3 in `ch3.rs`,
//! Ch. 4 and the prototypes in `ch4.rs`).

use std::path::Path;
use super::{rows::*, context::*, ch2::*, ch3::*, ch4::*, fig69::*};

/// Computes every section's numbers.
pub fn tables(scenes: &Path) -> Result<Vec<Section>, String> {
    let cx = Ctx { scenes: scenes.to_path_buf() };
    let mut out = Vec::new();

    fig2_3(&cx, &mut out)?;

    fig13_14(&cx, &mut out)?;

    fig16_18(&cx, &mut out)?;

    fig24_26(&cx, &mut out)?;

    fig39_41(&cx, &mut out)?;

    fig42_49(&cx, &mut out)?;

    ch4_hydraulic(&cx, &mut out)?;

    tables9_11(&cx, &mut out)?;

    table4(&cx, &mut out)?;

    fig69(&cx, &mut out)?;
    Ok(out)
}
