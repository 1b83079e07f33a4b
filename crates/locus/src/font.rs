//! The one font of every picture (`crate::plot`, `crate::doa`): DejaVu
//! Sans, embedded in the binary (`assets/fonts`, with its license) and
//! registered with plotters under [`FAMILY`], so no system font is needed.

use std::sync::OnceLock;

use anyhow::{Result, anyhow};
use plotters::style::FontStyle;

/// DejaVu Sans (Debian `fonts-dejavu-core`; license beside the file).
const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// The font family every text of a picture uses.
pub const FAMILY: &str = "sans-serif";

/// Registers the embedded font under [`FAMILY`] (once; later calls repeat
/// the first call's answer).
///
/// # Errors
/// The embedded font cannot be read.
pub fn register() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(anyhow!("the embedded DejaVu Sans font is invalid"))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_embedded_font_registers() {
        assert!(super::register().is_ok());
        assert!(super::register().is_ok());
    }
}
