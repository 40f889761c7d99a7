//! `contacts.csv` and the figures of a finished run folder: short runs of both
//! engines through the library's run loop, their contact lists read back
//! through the row type and checked against the physics (an NSCD block resting
//! on a floor carries its weight; an MD run's wall contacts add up to the wall
//! forces of `final.json`), then their figures drawn from the folder alone by
//! `ballast::report::draw_run_figures`, by `ballast run --figures`'s
//! path (`RunOptions::figures`) and by the `ballast figures DIR` command.

use crate::scratch;

use ballast::engine::contacts::{self, ContactKind};
use ballast::engine::FinalState;
use ballast::open::run_file;
use ballast::report::draw_run_figures;
use ballast::run::RunOptions;
use std::path::{Path, PathBuf};
use std::process::Command;

fn options(figures: bool) -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, threads: 1, figures, ..RunOptions::default() }
}

/// Checks that `<stem>.png` is a PNG of some size and `<stem>.svg` an SVG
/// holding `text`.
fn assert_figure(dir: &Path, stem: &str, text: &str) {
    let png = std::fs::read(dir.join(format!("{stem}.png"))).unwrap_or_else(|e| panic!("{stem}.png: {e}"));
    assert!(png.len() > 5000, "{stem}.png has only {} bytes", png.len());
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png is not a PNG");
    let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
    assert!(svg.contains("<svg") && svg.len() > 2000, "{stem}.svg is not a figure");
    assert!(svg.contains(text), "{stem}.svg lacks {text:?}");
    assert!(!svg.contains("NaN"), "{stem}.svg has NaN");
}

fn stems(dir: &Path, written: &[PathBuf]) -> Vec<String> {
    written.iter().map(|p| p.strip_prefix(dir).unwrap().display().to_string()).collect()
}

/// The 10 cm block of `examples/block_on_floor.toml` (2700 kg/m³, so 27 kg),
/// dropped from 1 mm, rests on the floor after 0.5 s: its contact rows are
/// `wall` rows against the floor whose normal forces add up to its weight.
/// Tolerance: at rest each step's impulses balance gravity's over the step,
/// `Σ r_n h = m g h − m Δv_y`; the block's vertical velocity changes by what the
/// solver leaves unconverged (its `quad` criterion, 1e-4 relative on the
/// impulses: 2.6e-2 N here) and by the last bounce's remains, which 0.45 s of
/// rest under restitution 0 have long damped: 1e-3 of the weight (0.26 N)
/// bounds both (measured: 6e-14 N, round-off: at rest the warm start already
/// holds the balancing impulses). Then the figures: from the run loop (`--figures`), again from
/// the folder alone, and by the command line, which also refuses a folder that
/// is not a run with one line naming the missing file.
#[test]
fn nscd_block_contacts_and_figures() {
    let dir = scratch::dir("nscd");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/block_on_floor.toml");
    run_file(&scene, &dir, &options(true), &mut |_| {}).unwrap();
    let rows = contacts::read(&dir.join("contacts.csv")).unwrap();
    let weight = 2700.0 * 0.1 * 0.1 * 9.81;
    let sum: f64 = rows.iter().map(|r| r.f_n).sum();
    eprintln!("{} contact points, Σ f_n = {sum:.6} N, weight {weight:.6} N", rows.len());
    assert_eq!(rows.len(), 2, "the block stands on two corners");
    for r in &rows {
        assert_eq!(
            (r.kind, r.a, r.a_name.as_str(), r.b, r.b_name.as_str()),
            (ContactKind::Wall, 1, "block", 0, "floor")
        );
        assert_eq!((r.normal_x, r.normal_y), (0.0, 1.0), "the floor's normal, towards the block");
        assert!(r.point_z_m.is_none() && r.normal_z.is_none() && r.f_t_z.is_none(), "2D rows have no z");
        assert!(r.point_y_m.abs() < 1e-4 && (r.point_x_m.abs() - 0.05).abs() < 1e-4, "a corner: {r:?}");
        assert!(r.f_t_y == 0.0, "the tangent of a horizontal floor: {r:?}");
    }
    // The corners' friction forces may pull against each other (a statically
    // indeterminate pair), but add up to no horizontal force.
    let friction: f64 = rows.iter().map(|r| r.f_t_x).sum();
    eprintln!("Σ f_n − m g = {:.3e} N, Σ f_t = {friction:.3e} N", sum - weight);
    assert!((sum - weight).abs() < 1e-3 * weight, "Σ f_n = {sum} N, weight {weight} N");
    assert!(friction.abs() < 1e-3 * weight, "Σ f_t = {friction} N");

    let figures = ["interpenetration", "force_chains"];
    for stem in figures {
        assert_figure(&dir, stem, "");
    }
    assert!(!dir.join("settlement.png").exists() && !dir.join("displacements.png").exists(), "no cycles");
    for stem in figures {
        std::fs::remove_file(dir.join(format!("{stem}.png"))).unwrap();
    }
    let drawn = draw_run_figures(&dir).unwrap();
    assert_eq!(stems(&dir, &drawn.written), figures);
    let skipped: Vec<&str> = drawn.skipped.iter().map(|s| s.0.as_str()).collect();
    assert_eq!(skipped, ["settlement", "displacements"]);
    assert_figure(&dir, "interpenetration", "overlap (");
    assert_figure(&dir, "force_chains", "Force chains");

    // The command line.
    let out = Command::new(env!("CARGO_BIN_EXE_ballast")).arg("figures").arg(&dir).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout} {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("force_chains.png") && stdout.contains("skipped settlement"), "{stdout}");
    let empty = scratch::dir("not_a_run");
    let out = Command::new(env!("CARGO_BIN_EXE_ballast")).arg("figures").arg(&empty).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: ") && stderr.contains("final.json"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&empty).unwrap();
}

/// Eight soft spheres in a box under a servo plate whose force cycles at
/// 100 Hz (the plate of Karrech et al. in miniature), 0.05 s: the wall rows of
/// `contacts.csv` add up, wall by wall, to the forces of `final.json` (both the
/// last evaluation's; CSV and JSON write floats that read back exactly, so the
/// difference is the round-off of summing in another order: 1e-12 of the
/// largest wall force); then every MD figure.
const MD_SCENE: &str = r#"
[simulation]
engine = "md"
dimension = 3
dt = 2.0e-5
duration = 0.05
gravity = [0.0, 0.0, -9.81]

[md]
integrator = "verlet"

[output]
every = 25
cycles = { frequency = 100.0 }

[[material]]
name = "rock"
density = 2000.0
young = 1.0e7
poisson = 0.25

[[material]]
name = "steel"
density = 7850.0
young = 1.0e7
poisson = 0.25

[[contact]]
between = ["rock", "rock"]
model = "hertz"
friction = 0.5
restitution = 0.5

[[contact]]
between = ["rock", "steel"]
model = "hertz"
friction = 0.3
restitution = 0.5

[[wall]]
name = "base"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

[[wall]]
name = "x0"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }

[[wall]]
name = "x1"
material = "steel"
plane = { point = [0.043, 0.0, 0.0], normal = [-1.0, 0.0, 0.0] }

[[wall]]
name = "y0"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] }

[[wall]]
name = "y1"
material = "steel"
plane = { point = [0.0, 0.043, 0.0], normal = [0.0, -1.0, 0.0] }

[[wall]]
name = "plate"
material = "steel"
plane = { point = [0.0, 0.0, 0.046], normal = [0.0, 0.0, -1.0] }
servo = { mass = 0.05, viscosity = 2.0, force = 2.0, amplitude = 2.0, period = 0.01 }
"#;

#[test]
fn md_contacts_and_figures() {
    let dir = scratch::dir("md");
    let mut text = MD_SCENE.to_string();
    for k in 0..8 {
        let (i, j, l) = (k % 2, (k / 2) % 2, k / 4);
        let at = |n: usize, shift: f64| 0.0105 + 0.0215 * n as f64 + shift;
        text.push_str(&format!(
            "\n[[body]]\nname = \"s{k}\"\nmaterial = \"rock\"\nsphere = 0.01\nposition = [{}, {}, {}]\n",
            at(i, 1e-4 * k as f64),
            at(j, -1e-4 * k as f64),
            at(l, 0.0)
        ));
    }
    let scene = dir.join("eight.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("run");
    run_file(&scene, &out, &options(true), &mut |_| {}).unwrap();

    let rows = contacts::read(&out.join("contacts.csv")).unwrap();
    let fin = FinalState::read(&out.join("final.json")).unwrap();
    let mut on_wall = vec![[0.0f64; 3]; fin.walls.len()];
    let mut scale = 0.0f64;
    for r in &rows {
        assert!(r.point_z_m.is_some() && r.normal_z.is_some() && r.f_t_z.is_some(), "3D rows have z");
        assert!(r.gap_m < 0.0 && r.f_n >= 0.0, "{r:?}");
        let f = r.force();
        scale = scale.max(f.iter().map(|x| x * x).sum::<f64>().sqrt());
        if r.kind == ContactKind::Wall {
            assert_eq!(r.b_name, fin.walls[r.b].name);
            for k in 0..3 {
                on_wall[r.b][k] -= f[k];
            }
        }
    }
    let kinds = |k| rows.iter().filter(|r| r.kind == k).count();
    eprintln!("{} pair and {} wall contacts; walls {on_wall:?}", kinds(ContactKind::Pair), kinds(ContactKind::Wall));
    assert!(kinds(ContactKind::Pair) >= 4 && kinds(ContactKind::Wall) >= 8, "a packed box: {rows:?}");
    for (w, sum) in fin.walls.iter().zip(&on_wall) {
        let d = (0..3).map(|k| (w.force[k] - sum[k]).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-12 * 8.0 * scale, "wall {}: {:?} vs {sum:?}", w.name, w.force);
    }
    let plate = fin.walls.iter().position(|w| w.name == "plate").unwrap();
    assert!(fin.walls[plate].force[2] > 0.0, "the spheres hold the plate up: {:?}", fin.walls[plate]);

    let figures = [
        "energies",
        "coordination",
        "overlaps",
        "wall_forces",
        "plate_settlement",
        "plate_settlement_cycles",
        "side_view",
    ];
    let drawn = draw_run_figures(&out).unwrap();
    assert_eq!(stems(&out, &drawn.written), figures);
    assert!(drawn.skipped.is_empty(), "{:?}", drawn.skipped);
    assert_figure(&out, "energies", "kinetic");
    assert_figure(&out, "coordination", "Coordination");
    assert_figure(&out, "overlaps", "µm");
    assert_figure(&out, "wall_forces", "plate");
    assert_figure(&out, "plate_settlement", "plate");
    assert_figure(&out, "plate_settlement_cycles", "cycles");
    assert_figure(&out, "side_view", "z (m)");
    std::fs::remove_dir_all(&dir).unwrap();
}
