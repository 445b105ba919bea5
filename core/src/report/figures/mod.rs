//! The figures, one file per kind, and the frame they share: a title line,
//! a legend strip, the panels.

pub(crate) mod beyond;
pub(crate) mod identifiability;
pub(crate) mod lengths;
pub(crate) mod map;
pub(crate) mod parameters;
pub(crate) mod points;
pub(crate) mod positions;
pub(crate) mod residuals;
pub(crate) mod solver;

use plotters::style::text_anchor::{HPos, VPos};

use super::svg::{Area, DrawResult, Key, WIDTH, font_at, legend, legend_height};

/// Height of the title line, px.
const TITLE: u32 = 30;
/// Size of legend text, px.
pub(crate) const LEGEND_PX: f64 = 13.0;

/// Height of the title and legend above the panels of a figure.
pub(crate) fn header_height(entries: &[(Key, String)]) -> u32 {
    TITLE
        + if entries.is_empty() {
            0
        } else {
            legend_height(WIDTH, entries, LEGEND_PX)
        }
}

/// Draws the title and the legend; returns the area below them.
pub(crate) fn frame<'a>(
    root: &Area<'a>,
    title: &str,
    entries: &[(Key, String)],
) -> DrawResult<Area<'a>> {
    root.draw_text(
        title,
        &font_at(16.5, HPos::Left, VPos::Center).clone(),
        (12, 16),
    )?;
    let (_, rest) = root.split_vertically(TITLE);
    if entries.is_empty() {
        return Ok(rest);
    }
    let (strip, rest) = rest.split_vertically(legend_height(WIDTH, entries, LEGEND_PX));
    legend(&strip, entries, LEGEND_PX)?;
    Ok(rest)
}

/// A short number for legends: 4 significant digits, no exponent between
/// 1e-4 and 1e6.
pub(crate) fn short(v: f64) -> String {
    if !v.is_finite() {
        return "-".to_string();
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let mag = v.abs().log10().floor() as i32;
    if (-4..6).contains(&mag) {
        let decimals = (3 - mag).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// A series' legend: its name, its poses, and the mean and largest of its
/// per-pose errors (mm).
pub(crate) fn series_label(s: &crate::report::PoseErrors) -> String {
    let n = s.error_mm.len().max(1) as f64;
    format!(
        "{}: {} poses, mean {} mm, max {} mm",
        s.name,
        s.error_mm.len(),
        short(s.error_mm.iter().sum::<f64>() / n),
        short(s.error_mm.iter().copied().fold(0.0, f64::max))
    )
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn short_numbers() {
        assert_eq!(short(3.65149), "3.651");
        assert_eq!(short(0.052), "0.05200");
        assert_eq!(short(1254018.0), "1.254e6");
        assert_eq!(short(f64::NAN), "-");
    }
}
