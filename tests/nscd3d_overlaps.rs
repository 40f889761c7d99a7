//! The held-overlap law of the 3D engine (`nscd.overlaps = "held"`, `ballast::nscd::d3::overlaps`) against the
//! velocity-level law it amends: a loaded column of cubes solved loosely sinks step after step under the
//! velocity-level law (its overlaps creep) and keeps its height under the held law; an overlap a cube starts with
//! is not pushed out; and under a tight solve the held law is the velocity-level law (a block sliding on an
//! incline at `g (sin α − μ cos α)`).

use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::overlaps::Overlaps;
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::method::{NlgsSettings, Policy};
use ballast::space::bodies::BodyInfo;
use ballast::space::loads::{Harmonic, Load3};

const G: f64 = 9.81;
const RHO: f64 = 2700.0;
const HALF: f64 = 0.05;

fn system(overlaps: Overlaps, tolerance: f64, max_iterations: usize, dt: f64) -> System3 {
    let nlgs = NlgsSettings { policy: Policy::Quad, tolerance, max_iterations, ..NlgsSettings::default() };
    let params =
        Params3 { dt, gravity: Vec3::new(0.0, 0.0, -G), alert_distance: 1e-3, overlaps, nlgs, ..Params3::default() };
    let mut sys = System3::new(params, 1);
    sys.set_law(0, 0, ContactLaw { friction: 0.5, ..ContactLaw::default() });
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    sys
}

fn cube() -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid([HALF; 3]).expect("a valid box"))
}

/// A column of 5 cubes, the top one pushed down by `A + B cos(2π f t − φ)` (10 and 5 times the column's weight
/// at 20 Hz), solved at `quad` 1e-3 (every step reaching it); the system after `steps` steps of 1 ms and the top
/// cube's sink below the rigid column's height, `9 HALF − z`, at the load's minimum of every cycle.
fn loaded_column(overlaps: Overlaps, steps: usize) -> (System3, Vec<f64>) {
    let mut sys = system(overlaps, 1e-3, 20_000, 1e-3);
    let n = 5;
    let weight = n as f64 * BodyInfo::mobile("c", cube(), 0, RHO).unwrap().mass * G;
    for k in 0..n {
        let mut body = BodyInfo::mobile(&format!("cube{k}"), cube(), 0, RHO).unwrap();
        if k == n - 1 {
            let load = Harmonic { mean: -10.0 * weight, amplitude: 5.0 * weight, frequency: 20.0, phase: 0.0 };
            body = body.with_load(Load3::force(Vec3::z(), load));
        }
        sys.bodies.push(body, Pose::at(Vec3::new(0.0, 0.0, HALF * (2 * k + 1) as f64)), [0.0; 6]);
    }
    let mut sink = Vec::new();
    for step in 1..=steps {
        assert!(sys.step().unwrap().nlgs.converged, "{overlaps:?}: step {step} stopped at the cap");
        if step % 50 == 0 {
            sink.push(9.0 * HALF - sys.bodies.pose[n].position.z);
        }
    }
    (sys, sink)
}

/// Rigid cubes do not compress: the loaded column's exact height is `9 HALF` at every instant. Solved to
/// `quad` 1e-3, the velocity-level law leaves the closed contacts approaching by a little every step and the
/// column sinks cycle after cycle (measured 29 µm after 2 cycles, 155 µm after 10: a creep of 16 µm per cycle).
/// Under the held law each step's growth is pushed back out by the next one, so the column stays within one
/// step's growth of its height (measured ≤ 0.6 µm over the 10 cycles; bound 2 µm, 1/60 of the kept law's
/// creep over cycles 2–10).
#[test]
fn a_loaded_column_creeps_under_kept_overlaps_and_keeps_its_height_under_held_ones() {
    let (_, kept) = loaded_column(Overlaps::Kept, 500);
    let (_, held) = loaded_column(Overlaps::Held, 500);
    assert!(kept[9] - kept[1] > 50e-6, "kept overlaps: the column sank {:?} m at the load minima", kept);
    assert!(held.iter().all(|s| s.abs() < 2e-6), "held overlaps: the column sank {held:?} m at the load minima");
}

/// A cube placed 0.1 mm into the floor under the held law: the overlap it starts with is its points' reference,
/// so it is not pushed out; the cube rests where it is (at rest within round-off, its height unchanged to 1 nm).
#[test]
fn an_overlap_a_body_starts_with_is_not_pushed_out() {
    let mut sys = system(Overlaps::Held, 1e-8, 20_000, 1e-3);
    let z0 = HALF - 1e-4;
    sys.bodies.push(BodyInfo::mobile("cube", cube(), 0, RHO).unwrap(), Pose::at(Vec3::new(0.0, 0.0, z0)), [0.0; 6]);
    for _ in 0..200 {
        let stats = sys.step().unwrap();
        assert_eq!(stats.contacts, 4, "a face on the floor: 4 points");
    }
    let z = sys.bodies.pose[1].position.z;
    assert!((z - z0).abs() < 1e-9, "the cube moved from {z0} to {z} m");
    assert!(sys.bodies.kinetic_energy() < 1e-12, "still moving: {} J", sys.bodies.kinetic_energy());
}

/// Under a tight solve the held law is the velocity-level law: a block sliding down an incline with
/// `tan α = 0.7 > μ = 0.5` accelerates at `g (sin α − μ cos α)` (to 1e-8 relative, as under the kept law in
/// `tests/nscd3d.rs`); its points slide along the floor 0.4 mm per step at the end, within the alert distance,
/// so they carry their references on.
#[test]
fn a_block_slides_down_an_incline_at_the_analytic_acceleration_under_held_overlaps() {
    let (mu, alpha) = (0.5, 0.7f64.atan());
    let mut sys = system(Overlaps::Held, 1e-8, 20_000, 1e-3);
    sys.params.gravity = G * Vec3::new(alpha.sin(), 0.0, -alpha.cos());
    sys.set_law(0, 0, ContactLaw { friction: mu, ..ContactLaw::default() });
    let half = [0.1, 0.05, 0.02];
    let block = BodyInfo::mobile("block", Solid::Polyhedron(Polyhedron::cuboid(half).unwrap()), 0, RHO).unwrap();
    sys.bodies.push(block, Pose::at(Vec3::new(0.0, 0.0, half[2])), [0.0; 6]);
    for _ in 0..500 {
        assert!(sys.step().unwrap().nlgs.converged, "every step meets the tolerance");
    }
    let (v, expected) = (sys.bodies.u[1][0], G * (alpha.sin() - mu * alpha.cos()) * 0.5);
    assert!((v - expected).abs() < 1e-8 * expected, "sliding block at {v} m/s, expected {expected} m/s");
}

/// The points' references are part of the system's serde form (a checkpoint): the loaded column written after
/// 120 steps and read back steps on to the same numbers, bit for bit, as the run that went straight on. Without
/// the references the read-back system would take every point as new and push nothing back.
#[test]
fn the_references_go_through_a_checkpoint() {
    let (mut straight, _) = loaded_column(Overlaps::Held, 120);
    let text = serde_json::to_string(&straight).unwrap();
    assert!(text.contains("\"held\":["), "the serde form carries the references");
    let mut resumed: System3 = serde_json::from_str(&text).unwrap();
    resumed.check_state().unwrap();
    for _ in 0..80 {
        straight.step().unwrap();
        resumed.step().unwrap();
    }
    for (a, b) in straight.bodies.pose.iter().zip(&resumed.bodies.pose) {
        assert_eq!(a.position, b.position);
        assert_eq!(a.rotation, b.rotation);
    }
}
