//! The 3D NSCD engine (`ballast::nscd::d3`) under the run loop (`ballast::run::Runner`), on scenes built in code:
//! a floor, three frictionless walls or none, and a dozen cubes, boxes, spheres and hulls. The run folder's files
//! read back through their types (series, cycles, final state with orientations, contacts with their z columns,
//! VTK snapshots that parse as XML with one polygon per face); a run stopped and resumed writes the same bytes
//! as the run made straight, the warm start being part of the checkpoint; a diverging run stops naming the step
//! and the body and leaves its last good state; the cycle rows of a cube dropped on the floor report its fall
//! (free fall in closed form, then at rest on the floor); the configuration written back and the model checks.

use crate::scratch;

use ballast::engine::{contacts, ContactKind, Engine, FinalState, RelaxSettings};
use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::rows::{read_cycles, read_series};
use ballast::nscd::d3::system::{Params3, StepStats3, System3};
use ballast::nscd::d3::vtk::polygons_of;
use ballast::nscd::method::criterion::evaluate;
use ballast::nscd::method::{NlgsSettings, OnStall, Policy, SweepNorms};
use ballast::run::{CyclePlan, RunEnd, RunOptions, RunPlan, Runner, Status};
use ballast::space::bodies::BodyInfo;
use ballast::Error;
use nalgebra::UnitQuaternion;
use std::path::{Path, PathBuf};

const G: f64 = 9.81;
const RHO: f64 = 2700.0;
/// Lattice cell (m): wider than two bounding spheres of the largest grain (2 × 0.0347 m).
const CELL: f64 = 0.08;
/// Half size of the cubes (m).
const HALF: f64 = 0.02;
/// Materials: grains, the floor, the walls.
const GRAIN: u32 = 0;
const FLOOR: u32 = 1;
const WALL: u32 = 2;
/// Friction between grains and with the floor; the walls are frictionless.
const MU: f64 = 0.5;

fn quiet() -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() }
}

fn half_space(name: &str, material: u32, point: Vec3, normal: Vec3) -> (BodyInfo, Pose) {
    let rotation = UnitQuaternion::rotation_between(&Vec3::z(), &normal).unwrap_or_else(UnitQuaternion::identity);
    (BodyInfo::fixed(name, Solid::HalfSpace, material), Pose { position: point, rotation })
}

/// A hull of 10 points on an ellipsoid of semi-axes 25, 20, 15 mm (deterministic), placed with its principal
/// frame's pose `pose0` composed after `pose`.
fn rock(k: usize, pose: Pose) -> (Solid, Pose) {
    let points: Vec<[f64; 3]> = (0..10)
        .map(|j| {
            let (a, b) = (2.399_963 * (j + k) as f64, 1.0 - 2.0 * (j as f64 + 0.5) / 10.0);
            let r = (1.0 - b * b).sqrt();
            [0.025 * r * a.cos(), 0.020 * r * a.sin(), 0.015 * b]
        })
        .collect();
    let (p, pose0) = Polyhedron::from_points(&points, Polyhedron::MERGE_ANGLE).expect("a valid hull");
    let placed = Pose { position: pose.point(&pose0.position), rotation: pose.rotation * pose0.rotation };
    (Solid::Polyhedron(p), placed)
}

/// A box of `3 × 2 × 2` cells on a floor (z ≤ 0), with three frictionless walls (x = 0, x = 3 CELL, y = 0) when
/// `walls`: 12 grains (cubes, flat boxes, spheres and hulls in turn), the bottom layer resting on the floor
/// (turned about z only), the top one turned every way and dropped from 1 to 3 cm above it.
fn pile(dt: f64, walls: bool) -> System3 {
    let nlgs =
        NlgsSettings { policy: Policy::Quad, tolerance: 1e-8, max_iterations: 20_000, ..NlgsSettings::default() };
    let params = Params3 { dt, gravity: Vec3::new(0.0, 0.0, -G), alert_distance: 1e-3, nlgs, ..Params3::default() };
    let mut sys = System3::new(params, 3);
    sys.set_law(0, 0, ContactLaw { friction: MU, ..ContactLaw::default() });
    sys.set_law(0, 1, ContactLaw { friction: MU, ..ContactLaw::default() });
    sys.set_law(0, 2, ContactLaw::default());
    let (floor, pose) = half_space("floor", FLOOR, Vec3::zeros(), Vec3::z());
    sys.bodies.push(floor, pose, [0.0; 6]);
    if walls {
        let w = 3.0 * CELL;
        for (name, point, normal) in [
            ("wall_x0", Vec3::zeros(), Vec3::x()),
            ("wall_x1", Vec3::new(w, 0.0, 0.0), -Vec3::x()),
            ("wall_y0", Vec3::zeros(), Vec3::y()),
        ] {
            let (info, pose) = half_space(name, WALL, point, normal);
            sys.bodies.push(info, pose, [0.0; 6]);
        }
    }
    for k in 0..12 {
        let (i, j, l) = (k % 3, (k / 3) % 2, k / 6);
        let centre = Vec3::new((i as f64 + 0.5) * CELL, (j as f64 + 0.5) * CELL, 0.0);
        let turn = |z: f64| {
            if l == 0 {
                UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3 * k as f64)
            } else {
                UnitQuaternion::from_euler_angles(0.7 * k as f64, 0.4 * k as f64 + z, 0.2 * k as f64)
            }
        };
        // Bottom layer: resting (its lowest point on the floor); top layer: 1 to 3 cm above the bottom cells.
        let lift = if l == 0 { 0.0 } else { CELL + 0.01 + 0.01 * (k % 3) as f64 };
        let (name, solid, pose) = match k % 4 {
            0 => {
                let pose = Pose { position: centre + Vec3::new(0.0, 0.0, HALF + lift), rotation: turn(0.0) };
                (format!("cube{k}"), Solid::Polyhedron(Polyhedron::cuboid([HALF; 3]).unwrap()), pose)
            }
            1 => {
                let pose = Pose { position: centre + Vec3::new(0.0, 0.0, 0.01 + lift), rotation: turn(0.1) };
                (format!("box{k}"), Solid::Polyhedron(Polyhedron::cuboid([0.025, 0.02, 0.01]).unwrap()), pose)
            }
            2 => (
                format!("ball{k}"),
                Solid::Sphere { radius: 0.02 },
                Pose::at(centre + Vec3::new(0.0, 0.0, 0.02 + lift)),
            ),
            _ => {
                let (solid, pose) =
                    rock(k, Pose { position: centre + Vec3::new(0.0, 0.0, 0.03 + lift), rotation: turn(0.2) });
                (format!("rock{k}"), solid, pose)
            }
        };
        sys.bodies.push(BodyInfo::mobile(&name, solid, GRAIN, RHO).unwrap(), pose, [0.0; 6]);
    }
    sys
}

/// The pile without walls and a cube `lone` standing apart (at x = −0.5 m), dropped from `drop` (m) above the
/// floor; its index.
fn with_lone_cube(mut sys: System3, drop: f64) -> (System3, usize) {
    let cube = BodyInfo::mobile("lone", Solid::Polyhedron(Polyhedron::cuboid([HALF; 3]).unwrap()), GRAIN, RHO);
    let i = sys.bodies.push(cube.unwrap(), Pose::at(Vec3::new(-0.5, 0.1, HALF + drop)), [0.0; 6]);
    (sys, i as usize)
}

/// The count of `attribute` in the `<Piece …>` tag of a `.vtp` text.
fn piece_count(xml: &str, attribute: &str) -> usize {
    let piece = &xml[xml.find("<Piece").unwrap()..];
    let tag = &piece[..piece.find('>').unwrap()];
    let key = format!(" {attribute}=\"");
    let start = tag.find(&key).unwrap() + key.len();
    tag[start..start + tag[start..].find('"').unwrap()].parse().unwrap()
}

/// A minimal XML well-formedness check: a declaration, comments, balanced and properly nested tags with
/// `name="value"` attributes, one root element, no stray `<`, `>` or `&` in the text.
fn assert_well_formed(xml: &str) {
    let mut rest = xml.strip_prefix("<?xml version=\"1.0\"?>").expect("an XML declaration");
    let (mut stack, mut roots) = (Vec::<&str>::new(), 0);
    while let Some(lt) = rest.find('<') {
        let text = &rest[..lt];
        assert!(!text.contains(['>', '&']), "stray text {text:?}");
        assert!(!stack.is_empty() || text.trim().is_empty(), "text outside the root: {text:?}");
        rest = &rest[lt..];
        if let Some(comment) = rest.strip_prefix("<!--") {
            let end = comment.find("-->").expect("a closed comment");
            assert!(!comment[..end].contains("--"), "'--' inside a comment");
            rest = &comment[end + 3..];
            continue;
        }
        let gt = rest.find('>').expect("a closed tag");
        let tag = &rest[1..gt];
        rest = &rest[gt + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(stack.pop(), Some(name.trim()), "closing </{name}>");
            continue;
        }
        let closed = tag.ends_with('/');
        let tag = tag.trim_end_matches('/');
        let name = tag.split_whitespace().next().unwrap();
        assert!(name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'), "tag name {name:?}");
        let mut attrs = tag[name.len()..].trim();
        while !attrs.is_empty() {
            let eq = attrs.find("=\"").unwrap_or_else(|| panic!("bad attributes in <{tag}>"));
            assert!(attrs[..eq].chars().all(|c| c.is_ascii_alphanumeric() || c == '_'), "<{tag}>");
            let value = &attrs[eq + 2..];
            let q = value.find('"').unwrap();
            assert!(!value[..q].contains(['<', '&']), "<{tag}>");
            attrs = value[q + 1..].trim_start();
        }
        roots += usize::from(stack.is_empty());
        if !closed {
            stack.push(name);
        }
    }
    assert!(rest.trim().is_empty() && stack.is_empty(), "unclosed {stack:?}");
    assert_eq!(roots, 1, "one root element");
}

/// The files two runs must share byte for byte (those present).
fn outputs(dir: &Path) -> Vec<PathBuf> {
    let names = ["series.csv", "cycles.csv", "final.json", "contacts.csv", "run.pvd", "cycle_bodies.csv"];
    let mut files: Vec<PathBuf> = names.iter().chain(&["cycle_displacements.npy"]).map(|f| dir.join(f)).collect();
    let mut vtk: Vec<PathBuf> = std::fs::read_dir(dir.join("vtk")).unwrap().map(|e| e.unwrap().path()).collect();
    vtk.sort();
    files.extend(vtk);
    files
}

/// A run of 60 steps of the walled pile: `series.csv` has a row every 7 steps and the last, the kinetic energy
/// of the bodies; `final.json` the 16 bodies with unit quaternions (the fixed ones as built); `contacts.csv` one
/// row per contact point with its z columns, each within Coulomb's cone, a fixed body always `b`; the snapshot
/// `.vtp` files parse as XML, with one polygon per face of every body and one line per contact point.
#[test]
fn a_run_writes_files_that_read_back() {
    let dir = scratch::dir("files");
    let sys = pile(1e-3, true);
    let expected_polygons: usize = sys.bodies.info.iter().map(|b| polygons_of(&b.solid)).sum();
    assert_eq!(
        expected_polygons,
        4 + 3 * 6
            + 3 * 6
            + 3 * 96
            + (3..12)
                .step_by(4)
                .map(|k| {
                    let Solid::Polyhedron(p) = &sys.bodies.info[4 + k].solid else { panic!() };
                    p.faces.len()
                })
                .sum::<usize>()
    );
    let mut plan = RunPlan::new(60, 7);
    plan.cycles = Some(CyclePlan { frequency: 50.0, body: Some(4), positions: true });
    let runner = Runner::from_system(sys.clone(), plan).unwrap();
    // Two threads asked: the run's summary says so (the split solve's threads).
    let done = runner.run(&dir, &RunOptions { vtk_every: 20, threads: 2, ..quiet() }, &mut |_| {}).unwrap();
    assert_eq!((done.status, done.step), (Status::Ended(RunEnd::Finished), 60));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["threads"], 2, "{summary}");

    let series = read_series(&dir.join("series.csv")).unwrap();
    let times: Vec<f64> = series.iter().map(|r| r.time_s).collect();
    let steps: Vec<u64> = (7..=56).step_by(7).chain([60]).collect();
    assert_eq!(times, steps.iter().map(|&k| k as f64 * 1e-3).collect::<Vec<_>>(), "exact clock, every 7 and the last");
    assert!(series.iter().all(|r| r.converged == 1 && r.contacts >= r.active_contacts && r.active_contacts > 0));
    // The bottom layer rests on the floor from the start: overlaps stay at the solver's scale (quad 1e-8), far
    // below the 1 µm of a contact closed one step late.
    assert!(series.iter().all(|r| r.max_overlap_m < 1e-6), "{series:?}");
    let cycles = read_cycles(&dir.join("cycles.csv")).unwrap();
    assert_eq!(cycles.iter().map(|c| c.cycle).collect::<Vec<_>>(), [1, 2, 3]);

    let fin = FinalState::read(&dir.join("final.json")).unwrap();
    assert_eq!((fin.engine.as_str(), fin.step, fin.time, fin.bodies.len()), ("nscd3d", 60, 0.06, 16));
    // The kinetic energy of the last row is that of the final state's velocities and spins.
    let kinetic: f64 = (4..16)
        .map(|i| {
            let (b, info) = (&fin.bodies[i], &sys.bodies.info[i]);
            let v2: f64 = b.velocity.iter().map(|v| v * v).sum();
            let q = b.orientation.unwrap();
            let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
            let ballast::engine::Spin::Spatial(w) = b.spin else { panic!("a 3D spin") };
            let w = r.inverse_transform_vector(&Vec3::from(w));
            0.5 * info.mass * v2 + 0.5 * w.dot(&info.inertia.component_mul(&w))
        })
        .sum();
    let last = series.last().unwrap().kinetic_energy_j;
    assert!((kinetic - last).abs() <= 1e-12 * last, "{kinetic} J from final.json, {last} J in series.csv");
    for (i, b) in fin.bodies.iter().enumerate() {
        let q = b.orientation.expect("an orientation");
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12, "body {i}: |q| = {norm}");
        assert_eq!(b.position.len(), 3);
        assert!(b.position.iter().chain(&b.velocity).all(|x| x.is_finite()));
        if i < 4 {
            let built = sys.bodies.pose[i].rotation.quaternion();
            assert_eq!(q, [built.w, built.i, built.j, built.k], "a wall does not turn");
        }
    }
    assert_eq!((fin.bodies[6].name.as_str(), fin.bodies[6].radius), ("ball2", Some(0.02)), "a sphere's radius");
    assert_eq!(fin.bodies[4].radius, None);

    let rows = contacts::read(&dir.join("contacts.csv")).unwrap();
    // At least the bottom layer's flat cubes and boxes (4 points each) and its ball (1) on the floor.
    assert!(rows.len() >= 17, "{} contact points", rows.len());
    for r in &rows {
        assert!(r.point_z_m.is_some() && r.normal_z.is_some() && r.f_t_z.is_some(), "{r:?}");
        let n = r.normal();
        assert!((n.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
        let f_t = [r.f_t_x, r.f_t_y, r.f_t_z.unwrap()];
        assert!(n.iter().zip(&f_t).map(|(a, b)| a * b).sum::<f64>().abs() <= 1e-9 * r.f_n.abs().max(1e-9));
        assert!(r.f_n >= 0.0, "compression only: {r:?}");
        let mu = if r.b_name.starts_with("wall") { 0.0 } else { MU };
        // Coulomb: |f_t| ≤ μ f_n, to the local solver's round-off.
        let t = f_t.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(t <= mu * r.f_n * (1.0 + 1e-9) + 1e-12, "{r:?}");
        if r.b < 4 {
            assert_eq!(r.kind, ContactKind::Wall);
            assert!(r.a >= 4, "the mobile body is a: {r:?}");
        }
        if r.b == 0 {
            assert!((n[2] - 1.0).abs() < 1e-12, "the floor pushes up: {r:?}");
        }
    }

    let vtk = dir.join("vtk");
    for step in [0, 20, 40, 60] {
        let bodies = std::fs::read_to_string(vtk.join(format!("bodies_{step:09}.vtp"))).unwrap();
        assert_well_formed(&bodies);
        assert_eq!(piece_count(&bodies, "NumberOfPolys"), expected_polygons, "step {step}");
        let contacts = std::fs::read_to_string(vtk.join(format!("contacts_{step:09}.vtp"))).unwrap();
        assert_well_formed(&contacts);
        if step == 60 {
            assert_eq!(piece_count(&contacts, "NumberOfLines"), rows.len());
        }
    }
    let pvd = std::fs::read_to_string(dir.join("run.pvd")).unwrap();
    assert_well_formed(&pvd);
    assert!(pvd.contains("file=\"vtk/bodies_000000060.vtp\"") && pvd.contains("file=\"vtk/contacts_000000060.vtp\""));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The walled pile run 60 steps straight, and stopped after 30 then resumed from its checkpoint: the same bytes
/// in every file (rows, cycles, positions, final state, contacts, snapshots); a checkpoint is refused by a run of
/// another model (the friction changed).
#[test]
fn a_run_stopped_and_resumed_writes_the_same_bytes() {
    let dir = scratch::dir("resume");
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    let plan = || {
        let mut plan = RunPlan::new(60, 4);
        plan.cycles = Some(CyclePlan { frequency: 40.0, body: Some(4), positions: true });
        plan
    };
    let runner = Runner::from_system(pile(1e-3, true), plan()).unwrap();
    let opts = RunOptions { vtk_every: 10, ..quiet() };
    let done = runner.run(&whole, &opts, &mut |_| {}).unwrap();
    assert_eq!(done.status, Status::Ended(RunEnd::Finished));
    let first = runner.run(&parts, &RunOptions { stop_after: Some(30), ..opts.clone() }, &mut |_| {}).unwrap();
    assert_eq!((first.status, first.step), (Status::Stopped, 30));
    assert!(parts.join("checkpoint.json").is_file() && !parts.join("final.json").exists());
    let mut other = pile(1e-3, true);
    other.set_law(0, 1, ContactLaw { friction: 0.3, ..ContactLaw::default() });
    let other = Runner::from_system(other, plan()).unwrap();
    let err = other.run(&parts, &RunOptions { resume: true, ..opts.clone() }, &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Checkpoint(_)), "{err}");
    let end = runner.run(&parts, &RunOptions { resume: true, ..opts }, &mut |_| {}).unwrap();
    assert_eq!((end.status, end.step), (Status::Ended(RunEnd::Finished), 60));
    let files = outputs(&whole);
    assert!(files.len() >= 7 + 2 * 7, "{files:?}");
    for f in files {
        let g = parts.join(f.strip_prefix(&whole).unwrap());
        assert_eq!(std::fs::read(&f).unwrap(), std::fs::read(&g).unwrap(), "{f:?} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The split contact solve (forced on this small pile: `split_min_rows` 8) gives the same bits on one thread
/// and on two, and two threads did use the team (joins side by side, taken back or in turn: all counted, so the
/// split path ran).
#[test]
fn the_split_solve_gives_the_same_numbers_on_one_thread_and_two() {
    let run = |threads: usize, split: usize| {
        let mut sys = pile(1e-3, true);
        sys.params.nlgs.split_min_rows = split;
        sys.set_threads(threads);
        let mut rows = 0;
        // 150 steps: the top layer has landed on the bottom one, so rows share bodies across the halves.
        for _ in 0..150 {
            rows = rows.max(sys.step().unwrap().contacts);
        }
        assert!(split == 0 || rows >= split, "the problem reaches the split's size: {rows} rows");
        (serde_json::to_string(&(&sys.bodies.pose, &sys.bodies.u)).unwrap(), sys.team_stats().joins)
    };
    let (one, _) = run(1, 8);
    let (two, joins) = run(2, 8);
    assert!(one == two, "one thread and two differ");
    assert!(joins > 0, "the team was used");
}

/// The serde form (a checkpoint's) carries the warm start: a system read back after 30 steps makes the next 30
/// bit for bit as the original does, while the same state with its warm start dropped does not — the check
/// above could fail.
#[test]
fn the_warm_start_is_part_of_the_state() {
    let mut sys = pile(1e-3, true);
    for _ in 0..30 {
        sys.step().unwrap();
    }
    assert!(!sys.warm_start().is_empty());
    let json = serde_json::to_string(&sys).unwrap();
    let mut back: System3 = serde_json::from_str(&json).unwrap();
    back.check_state().unwrap();
    back.check_same_model(&pile(1e-3, true)).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    value["memory"] = serde_json::Value::Array(Vec::new());
    let mut cold: System3 = serde_json::from_value(value).unwrap();
    for _ in 0..30 {
        sys.step().unwrap();
        back.step().unwrap();
        cold.step().unwrap();
    }
    let bits = |s: &System3| serde_json::to_string(&s.bodies).unwrap();
    assert_eq!(bits(&sys), bits(&back));
    assert_eq!(serde_json::to_string(&sys).unwrap(), serde_json::to_string(&back).unwrap());
    assert_ne!(bits(&sys), bits(&cold), "a cold start gives other round-off");
}

/// A time step of 0.5 s: the first step carries the top layer through the bottom one and the floor (nothing
/// is detected within the alert distance at its start), the second finds overlaps of a metre and stops. The
/// error names step 2 and the body, a mobile one below the floor in the state kept (step 1), whose row ends
/// `series.csv`; `summary.json` says the run diverged. A body given a NaN velocity stops the first step, named,
/// with the state unchanged, and the state check refuses it.
#[test]
fn a_diverging_run_stops_naming_the_step_and_the_body() {
    let dir = scratch::dir("diverge");
    let runner = Runner::from_system(pile(0.5, true), RunPlan::new(10, 3)).unwrap();
    let err = runner.run(&dir, &quiet(), &mut |_| {}).unwrap_err();
    let Error::Diverged { step, body, name, what } = &err else { panic!("{err}") };
    assert_eq!(*step, 2, "{err}");
    assert!(what.starts_with("runaway overlap"), "{err}");
    let fin = FinalState::read(&dir.join("final.json")).unwrap();
    assert_eq!((fin.step, fin.time), (1, 0.5));
    assert_eq!(&fin.bodies[*body].name, name);
    assert!(*body >= 4 && fin.bodies[*body].position[2] < 0.0, "{err}: {:?}", fin.bodies[*body]);
    let series = read_series(&dir.join("series.csv")).unwrap();
    assert_eq!(series.last().unwrap().time_s, 0.5, "the last good step's row");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!((report["end"].as_str(), report["steps"].as_u64()), (Some("diverged"), Some(1)));
    assert!(contacts::read(&dir.join("contacts.csv")).unwrap().iter().all(|r| r.gap_m.is_finite()));

    let mut sys = pile(1e-3, false);
    sys.bodies.u[2][2] = f64::NAN;
    let before = serde_json::to_string(&sys.bodies).unwrap();
    let err = sys.step().unwrap_err();
    assert!(matches!(&err, Error::Diverged { step: 1, body: 2, name, .. } if name == "box1"), "{err}");
    assert_eq!((sys.steps, serde_json::to_string(&sys.bodies).unwrap()), (0, before));
    let err = sys.check_state().unwrap_err().to_string();
    assert!(err.contains("body 2 ('box1')") && err.contains("velocity"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `on_stall = "stop"`: a step whose sweeps stop short of the tolerance ends the run with `Error::Stalled`
/// naming the step, the sweeps and the criterion; the state is the one before the step (bodies, springs, warm
/// start), `summary.json` says `"stalled"` and `final.json` holds the last good step. The pile's bottom layer
/// rests on the floor at the first step, so 3 sweeps cannot bring `quad` to 1e-12; under `accept` the same
/// steps go on and count as unconverged.
#[test]
fn a_stalled_step_stops_the_run_and_keeps_the_last_good_state() {
    let stalling = |on_stall| {
        let mut sys = pile(1e-3, true);
        sys.params.nlgs = NlgsSettings { max_iterations: 3, tolerance: 1e-12, on_stall, ..sys.params.nlgs };
        sys
    };
    // The engine alone: a first step solved to the pile's own tolerance, then a stalling one is refused and
    // nothing moves, the warm start included.
    let mut sys = pile(1e-3, true);
    assert!(sys.step().unwrap().nlgs.converged);
    sys.params.nlgs = stalling(OnStall::Stop).params.nlgs;
    let (before, memory) = (serde_json::to_string(&sys.bodies).unwrap(), sys.warm_start().to_vec());
    assert!(!memory.is_empty(), "the bottom layer touches the floor");
    let err = sys.step().unwrap_err();
    let Error::Stalled { step, iterations, criterion, tolerance } = err else { panic!("expected a stall: {err}") };
    assert_eq!((step, iterations, tolerance), (2, 3, 1e-12));
    assert!(criterion > tolerance && criterion.is_finite(), "{criterion}");
    assert_eq!((sys.steps, serde_json::to_string(&sys.bodies).unwrap()), (1, before));
    assert_eq!(sys.warm_start(), &memory[..]);
    // A step that converges is kept under `stop`: a lone cube in free fall has no contact to solve.
    let mut lone = System3::new(Params3 { gravity: Vec3::new(0.0, 0.0, -G), ..stalling(OnStall::Stop).params }, 1);
    let cube = BodyInfo::mobile("lone", Solid::Polyhedron(Polyhedron::cuboid([HALF; 3]).unwrap()), GRAIN, RHO);
    lone.bodies.push(cube.unwrap(), Pose::at(Vec3::new(0.0, 0.0, 1.0)), [0.0; 6]);
    assert!(lone.step().unwrap().nlgs.converged);
    // The run loop: three steps asked, the first stalls.
    let dir = scratch::dir("stall");
    let runner = Runner::from_system(stalling(OnStall::Stop), RunPlan::new(3, 1)).unwrap();
    let err = runner.run(&dir, &quiet(), &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Stalled { step: 1, iterations: 3, .. }), "{err}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!((report["end"].as_str(), report["steps"].as_u64()), (Some("stalled"), Some(0)));
    let fin = FinalState::read(&dir.join("final.json")).unwrap();
    let start = pile(1e-3, true);
    assert_eq!((fin.step, fin.time), (0, 0.0));
    for (b, pose) in fin.bodies.iter().zip(&start.bodies.pose) {
        assert_eq!(b.position, vec![pose.position.x, pose.position.y, pose.position.z], "{}", b.name);
    }
    // Accept: the same steps run on, each counted unconverged.
    let runner = Runner::from_system(stalling(OnStall::Accept), RunPlan::new(3, 1)).unwrap();
    let outcome = runner.run(&dir, &quiet(), &mut |_| {}).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!((report["end"].as_str(), report["steps"].as_u64()), (Some("finished"), Some(3)), "{outcome:?}");
    assert_eq!(report["unconverged_steps"].as_u64(), Some(3));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `System3::check_by_point`: the check pass point by point. Its norms, summed over the points, are the check
/// pass that ended the last step: on a step stopped at the cap (3 sweeps), `quad` of the sum is the step's
/// reported criterion to round-off. Before any step, and after a failed one, there is nothing to report.
#[test]
fn the_check_by_point_adds_up_to_the_steps_criterion() {
    let mut sys = pile(1e-3, true);
    assert!(sys.check_by_point().1.is_empty());
    sys.params.nlgs = NlgsSettings { max_iterations: 3, tolerance: 1e-12, ..sys.params.nlgs };
    let stats = sys.step().unwrap();
    assert!(!stats.nlgs.converged);
    let (springs, points) = sys.check_by_point();
    assert!(springs.is_empty(), "the pile has no springs");
    assert_eq!(points.len(), stats.contacts);
    let keys: Vec<_> = points.iter().map(|(k, _)| *k).collect();
    assert!(keys.windows(2).all(|w| w[0] < w[1]), "in key order");
    let sum = points.iter().fold(SweepNorms::default(), |sum, (_, n)| sum.merged(*n));
    let (quad, _) = evaluate(Policy::Quad, 1e-12, 4.0, &sum, 0.0);
    let reported = stats.nlgs.criterion;
    assert!((quad - reported).abs() <= 1e-12 * reported, "{quad} against the step's {reported}");
    // A failed step keeps nothing to diagnose.
    sys.params.nlgs.on_stall = OnStall::Stop;
    assert!(sys.step().is_err());
    assert!(sys.check_by_point().1.is_empty());
}

/// `System3::nlgs_problem`: the last step's problem with the impulses its solve found. The free velocities
/// plus `M⁻¹ H P` are the step's end velocities (to round-off: the sweeps added the same terms in another order),
/// and Gauss–Seidel on the problem from zero impulses, at the step's tolerance (`quad` 1e-8), ends at the same
/// velocities, unique where the pile's impulses are not: measured 5.6e-10 m/s apart in 9 sweeps, bounded by
/// 1e-8 m/s (the relative tolerance times the largest speed, 0.2 m/s, is 2e-9). None before a step.
#[test]
fn the_last_steps_problem_is_the_step() {
    use ballast::nscd::method::{apply_impulses, solve_nlgs};
    let mut sys = pile(1e-3, true);
    assert!(sys.nlgs_problem().is_none());
    for _ in 0..20 {
        sys.step().unwrap();
    }
    let problem = sys.nlgs_problem().unwrap();
    assert!(problem.rows.iter().any(|r| r.p[0] > 0.0), "the pile is loaded");
    let mut u = problem.u.clone();
    apply_impulses(&mut u, &problem.inv_m, &problem.rows, &problem.springs);
    let gap = |a: &[[f64; 6]], b: &[[f64; 6]]| {
        a.iter().zip(b).flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs())).fold(0.0, f64::max)
    };
    assert!(gap(&u, &sys.bodies.u) < 1e-13, "{}", gap(&u, &sys.bodies.u));
    assert!(problem.springs.is_empty(), "the pile has no springs");
    let (mut rows, mut springs) = (problem.rows.clone(), problem.springs.clone());
    for r in &mut rows {
        r.p = [0.0; 3];
    }
    let mut cold = problem.u.clone();
    let report = solve_nlgs(&sys.params.nlgs, &mut cold, &problem.inv_m, &mut rows, &mut springs);
    assert!(report.converged, "{report:?}");
    assert!(gap(&cold, &sys.bodies.u) < 1e-8, "{}", gap(&cold, &sys.bodies.u));
}

/// A cube dropped 2 cm onto the floor, followed by cycles of 50 ms (20 Hz, 50 steps of 1 ms), beside the pile.
/// Cycle 1 ends in free fall (the cube is 7.7 mm above the floor, beyond the alert distance, so no contact
/// acts): θ = ½ integrates a constant acceleration exactly, so its settlement is `½ g t²` and its mean over the
/// cycle's steps `½ g h² Σk²/50`, to round-off. From cycle 3 the cube rests on the floor: its settlement is the
/// 2 cm it fell, to the overlap a contact closed one step late leaves (< 1 µm, `tests/nscd3d.rs`), and equals the
/// fall measured from the run's start and `final.json` — exactly, the height being `z` itself under gravity
/// along `−z`.
#[test]
fn the_cycle_rows_of_a_dropped_cube_report_its_fall() {
    let dir = scratch::dir("settle");
    let drop = 0.02;
    let (sys, lone) = with_lone_cube(pile(1e-3, false), drop);
    let z0 = sys.bodies.pose[lone].position.z;
    let mut plan = RunPlan::new(200, 10);
    plan.cycles = Some(CyclePlan { frequency: 20.0, body: Some(lone), positions: true });
    let mut seen = Vec::new();
    let runner = Runner::from_system(sys, plan).unwrap();
    runner.run(&dir, &quiet(), &mut |p| seen.push(p.settlement)).unwrap();
    let cycles = read_cycles(&dir.join("cycles.csv")).unwrap();
    assert_eq!(cycles.len(), 4);
    let t: f64 = 0.05;
    let free = 0.5 * G * t * t;
    assert!((cycles[0].settlement_m - free).abs() < 1e-12, "{} m, free fall {free} m", cycles[0].settlement_m);
    let mean = 0.5 * G * 1e-6 * (50.0 * 51.0 * 101.0 / 6.0) / 50.0;
    assert!((cycles[0].settlement_mean_m - mean).abs() < 1e-12, "{} m, expected {mean} m", cycles[0].settlement_mean_m);
    let fin = FinalState::read(&dir.join("final.json")).unwrap();
    let fall = z0 - fin.bodies[lone].position[2];
    for c in &cycles[2..] {
        assert!((c.settlement_m - drop).abs() < 1e-6, "cycle {}: {} m", c.cycle, c.settlement_m);
    }
    assert_eq!(cycles[3].settlement_m, fall, "the last cycle ends the run");
    assert_eq!(*seen.last().unwrap(), Some(fall), "the progress display's settlement");
    // Cycle 1: the bottom grains press on the floor alone and the top ones fly: every grain is a rattler.
    assert_eq!(cycles[0].coordination, 0.0, "{cycles:#?}");
    // Once the top layer has landed some grains press on two neighbours or more: the coordination, a mean over
    // those grains, is at least 2, and at most the 11 other grains and the floor.
    assert!(cycles[3].coordination >= 2.0 && cycles[3].coordination <= 12.0, "{cycles:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The generalised positions: 6 per body (centroid, rotation vector), of the mobile bodies only; written back
/// they give the same poses (to round-off of the rotation vector), zero velocities and no warm start, and the
/// next step starts as a system built there; a fixed, unknown or non-finite body is refused, named, the system
/// unchanged. The potential energy is `−Σ m g · x`, and in free fall `E_k + E_p` is conserved (θ = ½ is exact for
/// a constant force). The relaxation leaves no overlap above its tolerance. The model check names what changed.
#[test]
fn configuration_energies_and_model_checks() {
    let mut sys = pile(1e-3, true);
    for _ in 0..20 {
        sys.step().unwrap();
    }
    let mobile = sys.mobile_bodies();
    assert_eq!(mobile, (4..16).collect::<Vec<_>>());
    let c = sys.configuration();
    assert_eq!((c.dof, c.q.len()), (6, 72));
    let mut back = sys.clone();
    back.set_configuration(&c).unwrap();
    for &i in &mobile {
        let (a, b) = (&sys.bodies.pose[i], &back.bodies.pose[i]);
        // The rotation vector's angle is in [0, π]: the quaternion may come back as its opposite (the same rotation).
        let (p, q) = (a.rotation.coords, b.rotation.coords);
        assert!(a.position == b.position && (p - q).norm().min((p + q).norm()) < 1e-15, "body {i}");
        assert_eq!(back.bodies.u[i], [0.0; 6]);
    }
    assert!(back.warm_start().is_empty() && back.contacts().is_empty() && back.contact_rows().is_empty());
    assert_eq!((back.steps, back.time), (20, sys.time), "the clock goes on");
    // As built there: a fresh system with these poses steps to the same numbers.
    let mut fresh = pile(1e-3, true);
    fresh.bodies.pose.clone_from(&back.bodies.pose);
    back.step().unwrap();
    fresh.step().unwrap();
    assert_eq!(serde_json::to_string(&back.bodies).unwrap(), serde_json::to_string(&fresh.bodies).unwrap());

    let mut bad = c.clone();
    bad.bodies[0] = 1;
    let e = sys.set_configuration(&bad).unwrap_err().to_string();
    assert!(e.contains("body 1 ('wall_x0') is fixed"), "{e}");
    bad = c.clone();
    bad.q[6 * 3 + 4] = f64::INFINITY;
    let e = sys.set_configuration(&bad).unwrap_err().to_string();
    assert!(e.contains("body 7") && e.contains("not finite"), "{e}");
    bad = c.clone();
    bad.bodies[2] = 99;
    assert!(sys.set_configuration(&bad).unwrap_err().to_string().contains("body 99 does not exist"));
    assert_eq!(sys.configuration(), c, "unchanged after a refusal");
    let sizes = sys.body_sizes(&[0, 4]);
    // The radius of the sphere of a cube's volume 8 a³: (6/π)^(1/3) a.
    assert!(
        sizes[0] == f64::INFINITY && (sizes[1] - (6.0 / std::f64::consts::PI).cbrt() * HALF).abs() < 1e-15,
        "{sizes:?}"
    );

    // A spinning cube alone above a floor, 100 steps of free fall (5 cm, no contact).
    let mut drop = System3::new(pile(1e-3, false).params, 1);
    let cube = BodyInfo::mobile("cube", Solid::Polyhedron(Polyhedron::cuboid([HALF; 3]).unwrap()), 0, RHO).unwrap();
    let (m, at) = (
        cube.mass,
        Pose { position: Vec3::new(0.1, 0.0, 0.5), rotation: UnitQuaternion::from_euler_angles(0.3, 0.2, 0.1) },
    );
    drop.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    drop.bodies.push(cube, at, [0.3, 0.0, 0.0, 1.0, 2.0, 0.5]);
    let total = |s: &System3, stats: &StepStats3| {
        let e = s.energies(stats, true);
        e.kinetic + e.potential
    };
    let mut stats = drop.step().unwrap();
    let e0 = total(&drop, &stats);
    let ep = m * G * drop.bodies.pose[1].position.z;
    assert!((drop.energies(&stats, true).potential - ep).abs() <= 1e-15 * ep, "−m g · x");
    assert_eq!(drop.energies(&stats, false).potential, 0.0, "not asked");
    for _ in 0..100 {
        stats = drop.step().unwrap();
    }
    // Exact in exact arithmetic (trapezoidal rule on a constant force, a cube's spin free of gyroscopic torque):
    // 101 steps of round-off on a few joules.
    let e1 = total(&drop, &stats);
    assert!(stats.contacts == 0 && (e1 - e0).abs() < 1e-12 * e0, "{e0} J, then {e1} J");

    // The relaxation (tests/nscd3d_relax.rs) leaves no overlap above its tolerance and the bodies at rest.
    let report = sys.relax(&RelaxSettings::new(1e-7)).unwrap();
    assert!(report.converged && report.max_overlap_after <= 1e-7, "{report:?}");
    assert!(sys.bodies.u.iter().zip(&sys.bodies.info).all(|(u, b)| b.fixed || *u == [0.0; 6]));

    let fresh = pile(1e-3, true);
    sys.check_same_model(&fresh).unwrap();
    let mut other = pile(1e-3, true);
    other.set_law(0, 2, ContactLaw { friction: 0.1, ..ContactLaw::default() });
    assert!(sys.check_same_model(&other).unwrap_err().to_string().contains("contact laws"));
    let mut other = pile(1e-3, true);
    other.bodies.info[9].mass *= 2.0;
    other.bodies.inv_m[9] = other.bodies.info[9].inverse_mass();
    let e = sys.check_same_model(&other).unwrap_err().to_string();
    assert!(e.contains("body 9 ('box5')"), "{e}");
}
