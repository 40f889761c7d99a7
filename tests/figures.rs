//! `ballast::io::figures`: each figure is written as a PNG of the right size and an
//! SVG with the expected elements; bad values are skipped, never a panic.

use crate::scratch;

use ballast::io::figures::{displacement_field, force_chains, line_chart, Arrow, Axes, ForceLine, Series};
use ballast::report::plane::{force_lines_of, polygons_of};
use ballast::scene::SceneFile;
use std::path::Path;

/// Width and height of a PNG, from its IHDR chunk, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.len() > 100, "{} is too small", path.display());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{} is not a PNG", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |k: usize| u32::from_be_bytes(bytes[k..k + 4].try_into().unwrap());
    (be(16), be(20))
}

fn svg(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains("<svg"), "{} is not an SVG", path.display());
    text
}

/// Number of `<tag` elements in `svg` whose opening tag contains `attr`.
fn count(svg: &str, tag: &str, attr: &str) -> usize {
    svg.split(&format!("<{tag} ")).skip(1).filter(|e| e.split('>').next().unwrap().contains(attr)).count()
}

fn axes(title: &str, log_x: bool, log_y: bool) -> Axes {
    Axes { title: title.into(), x_label: "cycles".into(), y_label: "settlement (m)".into(), log_x, log_y }
}

fn square(cx: f64, cy: f64, h: f64) -> Vec<[f64; 2]> {
    vec![[cx - h, cy - h], [cx + h, cy - h], [cx + h, cy + h], [cx - h, cy + h]]
}

/// Two grains on a fixed floor.
fn sample() -> (Vec<Vec<[f64; 2]>>, Vec<bool>) {
    (vec![square(0.0, -0.1, 0.1), square(-0.05, 0.05, 0.05), square(0.05, 0.05, 0.05)], vec![true, false, false])
}

#[test]
fn line_chart_writes_png_and_svg_with_legend_and_band() {
    let dir = scratch::dir("line");
    let stem = dir.join("settlement");
    let series = [
        Series {
            label: "mean".into(),
            points: (0..20).map(|k| (k as f64, 1e-3 * (k as f64).sqrt())).collect(),
            band: (0..20).map(|k| (k as f64, 0.8e-3 * (k as f64).sqrt(), 1.2e-3 * (k as f64).sqrt())).collect(),
            thin: false,
            points_only: false,
        },
        Series {
            label: "sample 2".into(),
            points: vec![(0.0, 0.0), (5.0, f64::NAN), (10.0, 2e-3), (f64::INFINITY, 1.0), (19.0, 3e-3)],
            band: vec![],
            thin: false,
            points_only: false,
        },
    ];
    line_chart(&stem, &axes("Settlement vs cycles", false, false), &series).unwrap();
    assert_eq!(png_size(&dir.join("settlement.png")), (1200, 800));
    let s = svg(&dir.join("settlement.svg"));
    for text in ["Settlement vs cycles", "cycles", "settlement (m)", "mean", "sample 2"] {
        assert!(s.contains(text), "SVG lacks {text:?}");
    }
    assert_eq!(count(&s, "polygon", ""), 1, "one band");
    assert!(!s.contains("NaN") && !s.contains("inf"), "non-finite points are skipped");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_axes_skip_non_positive_and_nan_values() {
    let dir = scratch::dir("log");
    let series = [Series {
        label: "NLGS".into(),
        points: vec![(1e-6, 900.0), (0.0, 50.0), (-1e-3, 10.0), (1e-4, f64::NAN), (1e-3, 40.0), (1e-2, 0.0)],
        band: vec![(1e-6, 800.0, 1000.0), (1e-4, -1.0, 200.0), (1e-3, 30.0, 50.0)],
        thin: false,
        points_only: false,
    }];
    for (lx, ly) in [(true, false), (false, true), (true, true)] {
        let stem = dir.join(format!("iterations_{lx}_{ly}"));
        line_chart(&stem, &axes("Iterations vs tolerance", lx, ly), &series).unwrap();
        assert_eq!(png_size(&stem.with_extension("png")), (1200, 800));
        let s = svg(&stem.with_extension("svg"));
        assert!(s.contains("Iterations vs tolerance"));
        assert!(!s.contains("NaN") && !s.contains("inf"));
    }
    // Nothing positive at all on a log axis: "no data".
    let none = [Series {
        label: "x".into(),
        points: vec![(0.0, -1.0), (f64::NAN, 1.0)],
        band: vec![],
        thin: false,
        points_only: false,
    }];
    line_chart(&dir.join("none"), &axes("t", true, true), &none).unwrap();
    assert!(svg(&dir.join("none.svg")).contains("no data"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn empty_inputs_give_a_no_data_figure() {
    let dir = scratch::dir("empty");
    line_chart(&dir.join("chart"), &axes("Empty", false, false), &[]).unwrap();
    assert_eq!(png_size(&dir.join("chart.png")), (1200, 800));
    assert!(svg(&dir.join("chart.svg")).contains("no data"));
    force_chains(&dir.join("forces"), "No grains", &[], &[], &[]).unwrap();
    assert_eq!(png_size(&dir.join("forces.png")).0, 1600);
    assert!(svg(&dir.join("forces.svg")).contains("no data"));
    displacement_field(&dir.join("disp"), "No grains", &[], &[], &[], 10.0).unwrap();
    assert!(svg(&dir.join("disp.svg")).contains("no data"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn force_chains_draws_polygons_and_lines_above_one_percent() {
    let dir = scratch::dir("forces");
    let (polygons, fixed) = sample();
    let lines = [
        ForceLine { from: [-0.05, 0.05], to: [0.0, -0.1], normal_force: 10.0 },
        ForceLine { from: [0.05, 0.05], to: [0.0, -0.1], normal_force: 5.0 },
        ForceLine { from: [-0.05, 0.05], to: [0.05, 0.05], normal_force: 0.05 }, // < 1% of the largest
        ForceLine { from: [f64::NAN, 0.0], to: [0.05, 0.05], normal_force: 7.0 },
    ];
    force_chains(&dir.join("chains"), "Force chains, cycle 3", &polygons, &fixed, &lines).unwrap();
    let (w, h) = png_size(&dir.join("chains.png"));
    assert_eq!(w, 1600);
    assert!((300..=1600).contains(&h), "height {h}");
    let s = svg(&dir.join("chains.svg"));
    assert!(s.contains("Force chains, cycle 3"));
    assert_eq!(count(&s, "polygon", ""), 3);
    assert_eq!(count(&s, "polyline", "stroke=\"#8B0000\""), 2);
    // The 10 N line is twice as wide as the 5 N one, and at most a third of the
    // smallest grain (0.1 m).
    let widths: Vec<f64> = s
        .split("<polyline ")
        .skip(1)
        .map(|e| e.split('>').next().unwrap())
        .filter(|e| e.contains("#8B0000"))
        .map(|e| e.split("stroke-width=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap())
        .collect();
    assert!((widths[0] / widths[1] - 2.0).abs() < 0.1, "{widths:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn displacement_field_draws_one_arrow_per_moving_grain() {
    let dir = scratch::dir("disp");
    let (polygons, fixed) = sample();
    let arrows = [
        Arrow { from: [-0.05, 0.06], displacement: [0.0, -0.01] },
        Arrow { from: [0.05, 0.055], displacement: [0.001, -0.005] },
        Arrow { from: [0.0, -0.1], displacement: [0.0, 0.0] },
        Arrow { from: [0.0, 0.0], displacement: [f64::NAN, 0.0] },
    ];
    displacement_field(&dir.join("field"), "Displacements", &polygons, &fixed, &arrows, 5.0).unwrap();
    assert_eq!(png_size(&dir.join("field.png")).0, 1600);
    let s = svg(&dir.join("field.svg"));
    assert!(s.contains("Displacements") && s.contains("× 5"));
    assert_eq!(count(&s, "polygon", ""), 3);
    // The two arrows (2 px; outlines and ticks are 1 px), coloured by magnitude.
    assert_eq!(count(&s, "polyline", "stroke-width=\"2\""), 2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn unwritable_path_is_an_io_error_naming_the_file() {
    let dir = scratch::dir("err");
    let stem = dir.join("missing").join("fig");
    let err = line_chart(&stem, &axes("t", false, false), &[]).unwrap_err();
    assert!(matches!(err, ballast::Error::Io(_)));
    assert!(err.to_string().contains("fig.png"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn adapters_read_the_engine_state() {
    let scene =
        ballast::scene::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/block_on_floor.toml")).unwrap();
    let mut sys = scene.build().unwrap();
    for _ in 0..100 {
        sys.step().unwrap();
    }
    let (polygons, fixed) = polygons_of(&sys);
    assert_eq!(polygons.len(), 2);
    assert_eq!(fixed, [true, false]);
    assert!(polygons.iter().all(|p| p.len() == 4));
    let lines = force_lines_of(&sys);
    // The floor is fixed: one line from the block's centre to each contact point
    // (its corners), not to the floor's centre.
    assert_eq!(lines.len(), 2, "one line per contact point with the floor: {lines:?}");
    let q = sys.bodies.q[1];
    for l in &lines {
        assert_eq!(l.from, [q[0], q[1]]);
        assert!(l.to[1].abs() < 1e-6 && (l.to[0].abs() - 0.05).abs() < 1e-3, "a corner on the floor: {l:?}");
    }
    let weight = 2700.0 * 0.1 * 0.1 * 9.81;
    let total: f64 = lines.iter().map(|l| l.normal_force).sum();
    assert!((total - weight).abs() < 0.05 * weight, "{lines:?}");
    let dir = scratch::dir("adapters");
    force_chains(&dir.join("block"), "Block on floor", &polygons, &fixed, &lines).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
