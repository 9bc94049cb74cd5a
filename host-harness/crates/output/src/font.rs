//! The font every plot uses, compiled in: DejaVu Sans from the `dejavu` crate, registered with
//! plotters' `ab_glyph` text renderer under the family name `sans-serif`. No system font, no
//! fontconfig, at build time or at run time; SVGs still name `sans-serif`, so a viewer may
//! substitute its own, and their layout was measured with DejaVu's metrics.

use plotters::style::{register_font, FontStyle};
use std::sync::Once;

static ONCE: Once = Once::new();

/// Registers the embedded font (once per process; cheap afterwards). Every drawing entry point
/// calls it, so a library user needs nothing else.
pub fn ensure() {
    ONCE.call_once(|| {
        for (style, bytes) in [(FontStyle::Normal, dejavu::sans::regular()), (FontStyle::Bold, dejavu::sans::bold()), (FontStyle::Italic, dejavu::sans::oblique()), (FontStyle::Oblique, dejavu::sans::oblique())] {
            // The bytes are a font the crate ships: it parses, or the build is broken.
            if register_font("sans-serif", style, bytes).is_err() {
                eprintln!("warning: the embedded DejaVu Sans font did not parse; plots will lack text");
            }
        }
    });
}
