//! Figures as PNG and SVG, drawn with `plotters` and a bundled font (DejaVu Sans,
//! `data/fonts/`), so nothing depends on the system's fonts or libraries.
//!
//! Every function writes both `<stem>.png` and `<stem>.svg`. The inputs are plain
//! data, so any engine can feed them; [`crate::report::plane::polygons_of`] and [`crate::report::plane::force_lines_of`] take
//! them from an NSCD [`crate::nscd::System`]. What they draw, for the figures of Saussine et
//! al. (2006):
//!
//! - [`line_chart`]: curves with a legend (below the plot, never over the data)
//!   and optional shaded spreads, on linear or logarithmic axes: settlement vs
//!   number of cycles (Figs. 6, 11, 12), interpenetration vs time (Figs. 2–4),
//!   NLGS iterations vs tolerance (§3.2 tables); [`si_scale`] picks the unit
//!   prefix that makes an axis's numbers plain;
//! - [`force_chains`]: the grains with the normal forces as segments between the
//!   centres of the bodies in contact, or from a grain's centre to its contact
//!   point with a wall, width proportional to the force (Figs. 8–10);
//!   [`crate::report::force_lines`] makes the segments from a contact list;
//! - [`displacement_field`]: the grains with an arrow per grain from its earlier
//!   centre, coloured by magnitude (Figs. 8–9).
//!
//! Non-finite values are skipped (and non-positive ones on a logarithmic axis); a
//! figure with nothing to draw says "no data" instead of failing.

//!
//! The drawing itself (`plotters`) is in a submodule built with the crate's
//! `figures` feature (on by default); without it every function here returns an
//! error saying so, and [`ENABLED`] is false.

use crate::error::Result;
use std::path::Path;

/// Size of a chart (px).
pub const CHART_SIZE: (u32, u32) = (1200, 800);
/// Width of a sample figure (px); its height follows the sample's aspect ratio
/// within [`SAMPLE_HEIGHT`].
pub const SAMPLE_WIDTH: u32 = 1600;
/// Smallest and largest height of a sample figure (px).
pub const SAMPLE_HEIGHT: (u32, u32) = (300, 1600);

/// Whether this build draws figures (the crate's `figures` feature).
pub const ENABLED: bool = cfg!(feature = "figures");

/// Fails with a one-line error when this build cannot draw figures (without the
/// `figures` feature): called before long work whose end is a figure.
///
/// # Errors
/// [`crate::Error::Scene`] naming the feature.
pub fn require() -> Result<()> {
    if ENABLED {
        Ok(())
    } else {
        Err(crate::Error::Scene(
            "figures: this build of ballast has no figures (enable the crate's `figures` feature)".into(),
        ))
    }
}

#[cfg(feature = "figures")]
mod draw;

/// Stand-ins of the drawing functions in a build without the `figures` feature.
#[cfg(not(feature = "figures"))]
mod draw {
    use super::{require, Arrow, Axes, ForceLine, Series};
    use crate::error::Result;
    use std::path::Path;

    pub(super) fn line_chart(_: &Path, _: &Axes, _: &[Series]) -> Result<()> {
        require()
    }

    pub(super) fn force_chains(
        _: &Path,
        _: &str,
        _: [&str; 2],
        _: &[Vec<[f64; 2]>],
        _: &[bool],
        _: &[ForceLine],
    ) -> Result<()> {
        require()
    }

    pub(super) fn displacement_field(
        _: &Path,
        _: &str,
        _: &[Vec<[f64; 2]>],
        _: &[bool],
        _: &[Arrow],
        _: f64,
    ) -> Result<()> {
        require()
    }
}

/// One curve of a [`line_chart`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    /// Legend entry (none if empty).
    pub label: String,
    /// `(x, y)` points, joined in order.
    pub points: Vec<(f64, f64)>,
    /// `(x, lo, hi)`: a spread drawn as a translucent area behind the curve; may be empty.
    pub band: Vec<(f64, f64, f64)>,
    /// A thin grey line without markers, drawn before the others (one replica
    /// among many, behind their mean); it takes no colour of the palette.
    pub thin: bool,
    /// Markers only, no line (e.g. the computed cycles of an accelerated run).
    pub points_only: bool,
}

/// Title, axis labels (with their SI units) and scales of a [`line_chart`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Axes {
    /// Title above the chart.
    pub title: String,
    /// Label of the horizontal axis, with its unit.
    pub x_label: String,
    /// Label of the vertical axis, with its unit.
    pub y_label: String,
    /// Logarithmic horizontal axis.
    pub log_x: bool,
    /// Logarithmic vertical axis.
    pub log_y: bool,
}

/// A force chain segment of [`force_chains`] (m, in the plane of the figure):
/// between the centres of two bodies in contact, or from a body's centre to its
/// contact point with a wall, with the normal force (N) it carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceLine {
    /// Start of the segment (m).
    pub from: [f64; 2],
    /// End of the segment (m).
    pub to: [f64; 2],
    /// Normal force it carries (N); sets the line width.
    pub normal_force: f64,
}

/// A grain's displacement (m) from its earlier centre `from` (m), for [`displacement_field`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrow {
    /// Earlier centre (m).
    pub from: [f64; 2],
    /// Displacement from it (m).
    pub displacement: [f64; 2],
}

/// Line chart of several series with a legend, each band drawn as a translucent
/// area behind its line, in [`CHART_SIZE`].
pub fn line_chart(stem: &Path, axes: &Axes, series: &[Series]) -> Result<()> {
    draw::line_chart(stem, axes, series)
}

/// A 2D sample: `polygons` (world coordinates, m) filled light grey, darker where
/// `fixed[i]`; force chains as segments ([`ForceLine`]) whose width is
/// proportional to the normal force (the largest is a fifth of the smallest free
/// grain's equivalent diameter, at most 40 px; forces below 1% of the largest are
/// omitted);
/// equal aspect ratio; axes `x (m)` and `y (m)`.
pub fn force_chains(
    stem: &Path,
    title: &str,
    polygons: &[Vec<[f64; 2]>],
    fixed: &[bool],
    lines: &[ForceLine],
) -> Result<()> {
    force_chains_with_axes(stem, title, ["x (m)", "y (m)"], polygons, fixed, lines)
}

/// [`force_chains`] with other axis labels (`[horizontal, vertical]`, with their
/// units): a projection of a 3D sample, say.
pub fn force_chains_with_axes(
    stem: &Path,
    title: &str,
    labels: [&str; 2],
    polygons: &[Vec<[f64; 2]>],
    fixed: &[bool],
    lines: &[ForceLine],
) -> Result<()> {
    draw::force_chains(stem, title, labels, polygons, fixed, lines)
}

/// Displacement field between two states: `polygons` at the later state and an
/// arrow per grain from its earlier centre, `scale` times the displacement, coloured
/// by magnitude (colour bar below; the scale is stated in the title).
pub fn displacement_field(
    stem: &Path,
    title: &str,
    polygons: &[Vec<[f64; 2]>],
    fixed: &[bool],
    arrows: &[Arrow],
    scale: f64,
) -> Result<()> {
    draw::displacement_field(stem, title, polygons, fixed, arrows, scale)
}

/// The SI prefix for values up to `max_abs` in `unit`: the factor to multiply
/// them by and the prefixed unit, so that the largest is between 1 and 1000
/// (`si_scale(2.3e-5, "m")` is `(1e6, "µm")`); `(1, unit)` for 0 or a non-finite
/// value. From pico to giga.
pub fn si_scale(max_abs: f64, unit: &str) -> (f64, String) {
    const PREFIXES: [(&str, f64); 8] =
        [("G", 1e9), ("M", 1e6), ("k", 1e3), ("", 1.0), ("m", 1e-3), ("µ", 1e-6), ("n", 1e-9), ("p", 1e-12)];
    let a = max_abs.abs();
    if !(a.is_finite() && a > 0.0) {
        return (1.0, unit.to_string());
    }
    // The largest prefix not above the value (the smallest one below a pico).
    let (p, s) = PREFIXES.iter().find(|(_, s)| a >= *s * (1.0 - 1e-12)).unwrap_or(&PREFIXES[PREFIXES.len() - 1]);
    (1.0 / s, format!("{p}{unit}"))
}
