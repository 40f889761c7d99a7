//! The drawing of [`super`]'s figures with `plotters` (the crate's `figures`
//! feature): backends, the bundled font, charts, samples, force chains and
//! displacement arrows.

use super::{Arrow, Axes, ForceLine, Series, CHART_SIZE, SAMPLE_HEIGHT, SAMPLE_WIDTH};
use crate::error::Result;
use crate::io::io_error;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

/// The bundled font, registered as plotters' `sans-serif` family.
const FONT: &[u8] = include_bytes!("../../../data/fonts/DejaVuSans.ttf");
const MARGIN: u32 = 20;
const X_LABEL_AREA: u32 = 60;
const Y_LABEL_AREA: u32 = 100;
const FOOTER: u32 = 50;
/// Height of a row of the legend below a chart (px).
const LEGEND_ROW: u32 = 30;
/// Force chains (dark red, `#8B0000` in the SVG).
const FORCE_COLOUR: RGBColor = RGBColor(0x8b, 0, 0);
const GRAIN: RGBColor = RGBColor(215, 215, 215);
const FIXED: RGBColor = RGBColor(140, 140, 140);
const OUTLINE: RGBColor = RGBColor(90, 90, 90);
/// Colours of the curves (matplotlib's tab10).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Line chart of [`super::line_chart`].
pub(super) fn line_chart(stem: &Path, axes: &Axes, series: &[Series]) -> Result<()> {
    write_both(stem, &LineChart { axes, series })
}

/// Force chains of [`super::force_chains_with_axes`].
pub(super) fn force_chains(
    stem: &Path,
    title: &str,
    labels: [&str; 2],
    polygons: &[Vec<[f64; 2]>],
    fixed: &[bool],
    lines: &[ForceLine],
) -> Result<()> {
    let lines: Vec<_> = lines
        .iter()
        .filter(|l| finite(l.from) && finite(l.to) && l.normal_force.is_finite() && l.normal_force > 0.0)
        .copied()
        .collect();
    let fmax = lines.iter().map(|l| l.normal_force).fold(0.0, f64::max);
    let lines: Vec<_> = lines.into_iter().filter(|l| l.normal_force >= 0.01 * fmax).collect();
    let extra: Vec<[f64; 2]> = lines.iter().flat_map(|l| [l.from, l.to]).collect();
    let mut sample = Sample::new(title.to_string(), polygons, fixed, &extra, 0);
    sample.labels = labels.map(String::from);
    write_both(stem, &ForceChains { sample, lines, fmax })
}

/// Displacement field of [`super::displacement_field`].
pub(super) fn displacement_field(
    stem: &Path,
    title: &str,
    polygons: &[Vec<[f64; 2]>],
    fixed: &[bool],
    arrows: &[Arrow],
    scale: f64,
) -> Result<()> {
    let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
    let arrows: Vec<_> = arrows
        .iter()
        .filter(|a| finite(a.from) && finite(a.displacement) && norm(a.displacement) > 0.0)
        .copied()
        .collect();
    let umax = arrows.iter().map(|a| norm(a.displacement)).fold(0.0, f64::max);
    let extra: Vec<[f64; 2]> = arrows.iter().flat_map(|a| [a.from, tip(a, scale)]).collect();
    let title = format!("{title} (arrows: displacement × {})", tick(scale, 0.0));
    let sample = Sample::new(title, polygons, fixed, &extra, FOOTER);
    write_both(stem, &Displacements { sample, arrows, scale, umax })
}

type DrawError = Box<dyn std::error::Error>;
type DrawResult<T = ()> = std::result::Result<T, DrawError>;

/// A figure that draws on any backend.
trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Draws `fig` into `<stem>.png` and `<stem>.svg`.
fn write_both(stem: &Path, fig: &impl Figure) -> Result<()> {
    static FONT_OK: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    if !*FONT_OK.get_or_init(|| plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()) {
        let e = std::io::Error::new(std::io::ErrorKind::InvalidData, "bundled font DejaVuSans.ttf is invalid");
        return Err(io_error(stem, "draw figure", e));
    }
    let with_ext = |ext: &str| {
        let mut s = stem.as_os_str().to_owned();
        s.push(ext);
        PathBuf::from(s)
    };
    let fail = |path: &Path, e: DrawError| io_error(path, "draw figure", std::io::Error::other(e.to_string()));
    let png = with_ext(".png");
    let svg = with_ext(".svg");
    // The backends report failures to write only through `present`; check the
    // directory first so the error names the file.
    if let Some(dir) = png.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::metadata(dir).map_err(|e| io_error(&png, "write", e))?;
    }
    render(BitMapBackend::new(&png, fig.size()).into_drawing_area(), fig).map_err(|e| fail(&png, e))?;
    render(SVGBackend::new(&svg, fig.size()).into_drawing_area(), fig).map_err(|e| fail(&svg, e))
}

fn render<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &impl Figure) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    fig.draw(&root)?;
    root.present()?;
    Ok(())
}

fn font(size: u32) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

fn finite(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

fn tip(a: &Arrow, scale: f64) -> [f64; 2] {
    [a.from[0] + scale * a.displacement[0], a.from[1] + scale * a.displacement[1]]
}

/// A compact tick label: 4 significant digits, scientific outside [1e-4, 1e5);
/// "0" for a value within rounding error of zero on an axis of width `span`.
fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    if a == 0.0 || a <= 1e-9 * span {
        return "0".into();
    }
    let trim = |s: String| if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if (1e-4..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 7) as usize;
        trim(format!("{v:.decimals$}"))
    } else {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{e}", trim(m.to_string()))
    }
}

/// Writes "no data" in the middle of `area`.
fn no_data<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (w, h) = area.dim_in_pixel();
    let style = font(36).color(&RGBColor(120, 120, 120)).pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new("no data", (w as i32 / 2, h as i32 / 2), style))?;
    Ok(())
}

/// Thin lines ([`Series::thin`]).
const THIN: RGBColor = RGBColor(150, 150, 150);

/// The colour of each series: the palette in turn for the others, [`THIN`] for thin lines.
fn colours(series: &[Series]) -> Vec<RGBColor> {
    let mut k = 0;
    series
        .iter()
        .map(|s| {
            if s.thin {
                THIN
            } else {
                k += 1;
                PALETTE[(k - 1) % PALETTE.len()]
            }
        })
        .collect()
}

struct LineChart<'a> {
    axes: &'a Axes,
    series: &'a [Series],
}

/// Range of the finite values `v` (positive only on a log axis), padded; a default when empty.
fn range(v: impl Iterator<Item = f64>, log: bool) -> (std::ops::Range<f64>, bool) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && (!log || *x > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
    if lo > hi {
        return (if log { 1.0..10.0 } else { 0.0..1.0 }, false);
    }
    let r = if log {
        let (a, b) = if hi / lo < 1.01 { (lo / 2.0, hi * 2.0) } else { (lo, hi) };
        let pad = (b / a).powf(0.03);
        a / pad..b * pad
    } else {
        let d = if hi - lo > 1e-12 * hi.abs().max(lo.abs()) { hi - lo } else { lo.abs().max(1.0) * 0.1 };
        lo - 0.04 * d..hi + 0.04 * d
    };
    (r, true)
}

impl LineChart<'_> {
    fn ok(&self, x: f64, y: f64) -> bool {
        x.is_finite() && y.is_finite() && (!self.axes.log_x || x > 0.0) && (!self.axes.log_y || y > 0.0)
    }

    fn draw_on<'a, DB: DrawingBackend + 'a, X, Y>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<X, Y>>,
        spans: (f64, f64),
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let (fx, fy) = (|v: &f64| tick(*v, spans.0), |v: &f64| tick(*v, spans.1));
        chart
            .configure_mesh()
            .x_desc(&self.axes.x_label)
            .y_desc(&self.axes.y_label)
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .label_style(font(18))
            .axis_desc_style(font(22))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(200, 200, 200))
            .draw()?;
        let colours = colours(self.series);
        // Thin lines first, behind the bands and the coloured curves.
        for s in self.series.iter().filter(|s| s.thin) {
            let points: Vec<_> = s.points.iter().copied().filter(|p| self.ok(p.0, p.1)).collect();
            chart.draw_series(std::iter::once(PathElement::new(points, THIN.stroke_width(1))))?;
        }
        for (k, s) in self.series.iter().enumerate().filter(|(_, s)| !s.thin) {
            let colour = colours[k];
            let band: Vec<_> = s.band.iter().filter(|b| self.ok(b.0, b.1) && self.ok(b.0, b.2)).collect();
            if band.len() >= 2 {
                let outline = band.iter().map(|b| (b.0, b.1)).chain(band.iter().rev().map(|b| (b.0, b.2)));
                chart.draw_series(std::iter::once(Polygon::new(
                    outline.collect::<Vec<_>>(),
                    colour.mix(0.2).filled(),
                )))?;
            }
            let points: Vec<_> = s.points.iter().copied().filter(|p| self.ok(p.0, p.1)).collect();
            if s.points_only {
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
                continue;
            }
            let line = colour.stroke_width(3);
            chart.draw_series(std::iter::once(PathElement::new(points.clone(), line)))?;
            if points.len() <= 40 {
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
            }
        }
        Ok(())
    }

    /// The legend entries (series index, label) laid out in rows below the plot:
    /// each entry's left edge (px from the plot's left edge) and row; and the
    /// number of rows, for `width` px.
    fn legend_layout<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        width: u32,
    ) -> (Vec<(usize, i32, u32)>, u32) {
        let (sample, gap) = (36, 30);
        let (mut x, mut row, mut out) = (0i32, 0u32, Vec::new());
        for (k, s) in self.series.iter().enumerate().filter(|(_, s)| !s.label.is_empty()) {
            let text = area.estimate_text_size(&s.label, &font(20)).map_or(12 * s.label.len() as u32, |e| e.0);
            let w = (sample + text) as i32;
            if x > 0 && x + w > width as i32 {
                (x, row) = (0, row + 1);
            }
            out.push((k, x, row));
            x += w + gap;
        }
        let rows = if out.is_empty() { 0 } else { row + 1 };
        (out, rows)
    }
}

impl Figure for LineChart<'_> {
    fn size(&self) -> (u32, u32) {
        CHART_SIZE
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let a = self.axes;
        let valid = |s: &Series| {
            let p = s.points.iter().filter(|p| self.ok(p.0, p.1)).map(|p| (p.0, p.1, p.1));
            p.chain(s.band.iter().filter(|b| self.ok(b.0, b.1) && self.ok(b.0, b.2)).copied()).collect::<Vec<_>>()
        };
        let all: Vec<_> = self.series.iter().flat_map(valid).collect();
        let (xr, any) = range(all.iter().map(|p| p.0), a.log_x);
        let (yr, _) = range(all.iter().flat_map(|p| [p.1, p.2]), a.log_y);
        // The legend goes below the plot, in rows as wide as the plot.
        let (w, h) = root.dim_in_pixel();
        let left = (MARGIN + Y_LABEL_AREA) as i32;
        let (entries, rows) = self.legend_layout(root, w.saturating_sub(2 * MARGIN + Y_LABEL_AREA));
        let legend_h = if rows > 0 { rows * LEGEND_ROW + 10 } else { 0 };
        let (plot, legend) = root.split_vertically(h.saturating_sub(legend_h));
        let colours = colours(self.series);
        for (k, x, row) in entries {
            let y = (row * LEGEND_ROW + LEGEND_ROW / 2) as i32;
            let width = if self.series[k].thin { 1 } else { 3 };
            legend.draw(&PathElement::new(vec![(left + x, y), (left + x + 28, y)], colours[k].stroke_width(width)))?;
            let style = font(20).pos(Pos::new(HPos::Left, VPos::Center));
            legend.draw(&Text::new(self.series[k].label.clone(), (left + x + 36, y), style))?;
        }
        let root = &plot;
        let mut b = ChartBuilder::on(root);
        b.caption(&a.title, font(30)).margin(MARGIN).x_label_area_size(X_LABEL_AREA).y_label_area_size(Y_LABEL_AREA);
        let spans = (if a.log_x { 0.0 } else { xr.end - xr.start }, if a.log_y { 0.0 } else { yr.end - yr.start });
        match (a.log_x, a.log_y) {
            (false, false) => self.draw_on(b.build_cartesian_2d(xr, yr)?, spans)?,
            (true, false) => self.draw_on(b.build_cartesian_2d(xr.log_scale(), yr)?, spans)?,
            (false, true) => self.draw_on(b.build_cartesian_2d(xr, yr.log_scale())?, spans)?,
            (true, true) => self.draw_on(b.build_cartesian_2d(xr.log_scale(), yr.log_scale())?, spans)?,
        }
        if !any {
            no_data(root)?;
        }
        Ok(())
    }
}

/// The grains of a sample figure and its world bounding box.
struct Sample {
    title: String,
    /// Axis labels, horizontal and vertical, with their units.
    labels: [String; 2],
    polygons: Vec<(Vec<(f64, f64)>, bool)>,
    /// `(x0, y0, x1, y1)` (m), `None` when there is nothing to draw.
    bbox: Option<[f64; 4]>,
    /// Pixels below the plot for a legend.
    footer: u32,
}

impl Sample {
    fn new(title: String, polygons: &[Vec<[f64; 2]>], fixed: &[bool], extra: &[[f64; 2]], footer: u32) -> Self {
        let polygons: Vec<_> = polygons
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let v: Vec<_> = p.iter().filter(|v| finite(**v)).map(|v| (v[0], v[1])).collect();
                (v, fixed.get(i).copied().unwrap_or(false))
            })
            .filter(|(v, _)| v.len() >= 3)
            .collect();
        let points = polygons.iter().flat_map(|(v, _)| v.iter().copied()).chain(extra.iter().map(|p| (p[0], p[1])));
        let bbox = points.fold(None, |b: Option<[f64; 4]>, (x, y)| {
            Some(b.map_or([x, y, x, y], |b| [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]))
        });
        Self { title, labels: ["x (m)".into(), "y (m)".into()], polygons, bbox, footer }
    }

    /// The box with a 3% margin, never flat.
    fn padded(&self) -> [f64; 4] {
        let [x0, y0, x1, y1] = self.bbox.unwrap_or([0.0, 0.0, 1.0, 1.0]);
        let d = (x1 - x0).max(y1 - y0);
        let d = if d > 0.0 { d } else { x0.abs().max(y0.abs()).max(1.0) * 0.1 };
        let p = 0.03 * d;
        [x0 - p, y0 - p, x1.max(x0 + 0.01 * d) + p, y1.max(y0 + 0.01 * d) + p]
    }

    fn size(&self) -> (u32, u32) {
        let [x0, y0, x1, y1] = self.padded();
        let plot_w = (SAMPLE_WIDTH - 2 * MARGIN - Y_LABEL_AREA) as f64;
        let extra = 2 * MARGIN + X_LABEL_AREA + 60 + self.footer;
        let h = (plot_w * (y1 - y0) / (x1 - x0)).round() as u32 + extra;
        (SAMPLE_WIDTH, h.clamp(SAMPLE_HEIGHT.0, SAMPLE_HEIGHT.1))
    }

    /// Draws the title, axes and grains on `root`, returning the chart (equal
    /// aspect ratio), its pixels per metre and the footer area.
    fn draw<'a, DB: DrawingBackend>(
        &self,
        root: &'a DrawingArea<DB, Shift>,
    ) -> DrawResult<(SampleChart<'a, DB>, f64, DrawingArea<DB, Shift>)>
    where
        DB::ErrorType: 'static,
    {
        let area = root.margin(10, 0, 0, 0).titled(&self.title, font(30))?;
        let (w, h) = area.dim_in_pixel();
        let (area, footer) = area.split_vertically(h.saturating_sub(self.footer));
        let (w, h) = (w, h.saturating_sub(self.footer));
        let pw = w.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1) as f64;
        let ph = h.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1) as f64;
        let [x0, y0, x1, y1] = self.padded();
        let s = (pw / (x1 - x0)).min(ph / (y1 - y0));
        let (cx, cy, hw, hh) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0, pw / s / 2.0, ph / s / 2.0);
        let mut chart = ChartBuilder::on(&area)
            .margin(MARGIN)
            .x_label_area_size(X_LABEL_AREA)
            .y_label_area_size(Y_LABEL_AREA)
            .build_cartesian_2d(cx - hw..cx + hw, cy - hh..cy + hh)?;
        let fmt = |v: &f64| tick(*v, 2.0 * hw.max(hh));
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&self.labels[0])
            .y_desc(&self.labels[1])
            .x_label_formatter(&fmt)
            .y_label_formatter(&fmt)
            .label_style(font(18))
            .axis_desc_style(font(22))
            .draw()?;
        for (v, fixed) in &self.polygons {
            chart.draw_series(std::iter::once(Polygon::new(v.clone(), if *fixed { FIXED } else { GRAIN }.filled())))?;
            let closed: Vec<_> = v.iter().chain(v.first()).copied().collect();
            chart.draw_series(std::iter::once(PathElement::new(closed, OUTLINE.stroke_width(1))))?;
        }
        if self.bbox.is_none() {
            no_data(root)?;
        }
        Ok((chart, s, footer))
    }
}

type SampleChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

struct ForceChains {
    sample: Sample,
    lines: Vec<ForceLine>,
    fmax: f64,
}

impl Figure for ForceChains {
    fn size(&self) -> (u32, u32) {
        self.sample.size()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (mut chart, s, _) = self.sample.draw(root)?;
        // Smallest equivalent diameter of the free grains (of all if none is free).
        let diameter = |v: &Vec<(f64, f64)>| {
            let a: f64 = v.iter().zip(v.iter().cycle().skip(1)).map(|(p, q)| p.0 * q.1 - q.0 * p.1).sum();
            (2.0 * a.abs() / std::f64::consts::PI).sqrt()
        };
        let free = self.sample.polygons.iter().filter(|p| !p.1).map(|p| diameter(&p.0)).fold(f64::INFINITY, f64::min);
        let d = if free.is_finite() {
            free
        } else {
            self.sample.polygons.iter().map(|p| diameter(&p.0)).fold(f64::INFINITY, f64::min)
        };
        let max_width = if d.is_finite() && d > 0.0 { (d * s / 5.0).clamp(1.0, 40.0) } else { 4.0 };
        chart.draw_series(self.lines.iter().map(|l| {
            let w = (max_width * l.normal_force / self.fmax).round().max(1.0) as u32;
            PathElement::new(vec![(l.from[0], l.from[1]), (l.to[0], l.to[1])], FORCE_COLOUR.stroke_width(w))
        }))?;
        Ok(())
    }
}

struct Displacements {
    sample: Sample,
    arrows: Vec<Arrow>,
    scale: f64,
    umax: f64,
}

/// Colour of `t` in [0, 1]: navy, blue, purple, red, all dark enough to show on grey.
fn colour_map(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 4] = [(8, 48, 107), (33, 113, 181), (150, 50, 160), (215, 30, 40)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f64;
    let k = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

impl Figure for Displacements {
    fn size(&self) -> (u32, u32) {
        self.sample.size()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (mut chart, s, footer) = self.sample.draw(root)?;
        chart.draw_series(self.arrows.iter().map(|a| {
            let [x1, y1] = tip(a, self.scale);
            let (dx, dy) = (x1 - a.from[0], y1 - a.from[1]);
            let len = dx.hypot(dy);
            // Head: 30% of the arrow, at most 14 px, barbs at ±25°.
            let head = (0.3 * len).min(14.0 / s);
            let (ux, uy) = (dx / len * head, dy / len * head);
            let (c, sn) = (25f64.to_radians().cos(), 25f64.to_radians().sin());
            let barb = |sg: f64| (x1 - (c * ux - sg * sn * uy), y1 - (sg * sn * ux + c * uy));
            let path = vec![(a.from[0], a.from[1]), (x1, y1), barb(1.0), (x1, y1), barb(-1.0)];
            PathElement::new(path, colour_map(norm(a.displacement) / self.umax).stroke_width(2))
        }))?;
        // Colour bar: |u| from 0 to the largest displacement.
        let (w, _) = footer.dim_in_pixel();
        let (x0, bar_w, y) = (w as i32 / 2 - 200, 400, 10);
        let steps = 40;
        for k in 0..steps {
            let xa = x0 + bar_w * k / steps;
            let xb = x0 + bar_w * (k + 1) / steps;
            let c = colour_map((k as f64 + 0.5) / steps as f64);
            footer.draw(&Rectangle::new([(xa, y), (xb, y + 20)], c.filled()))?;
        }
        let right = Pos::new(HPos::Right, VPos::Center);
        footer.draw(&Text::new("|u| = 0", (x0 - 10, y + 10), font(18).pos(right)))?;
        let label = format!("{} m", tick(self.umax, 0.0));
        footer.draw(&Text::new(label, (x0 + bar_w + 10, y + 10), font(18).pos(Pos::new(HPos::Left, VPos::Center))))?;
        Ok(())
    }
}
