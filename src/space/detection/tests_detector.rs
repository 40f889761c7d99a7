//! Tests of [`Detector`]: sorted unique keys, the candidate/antagonist rule, bit-identical repeated calls,
//! no dependence on the previous calls, pairs of fixed bodies skipped, a pair moved apart vanishing, and
//! agreement with the narrow-phase functions called on every pair of a random cloud (the broad phase misses
//! nothing).

use super::narrow::polyhedron_polyhedron;
use super::*;
use crate::geometry::{Polyhedron, Pose, Solid, Vec3};
use nalgebra::{Unit, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const ALERT: f64 = 1e-2;

fn cube(half: f64) -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid([half; 3]).unwrap())
}

/// A floor, two stacked cubes, a sphere against the lower cube and the floor, a sphere against it, a
/// turned cube against the lower cube, and a fixed cube on the floor.
fn pile() -> (Vec<Solid>, Vec<Pose>, Vec<bool>) {
    let turned = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::FRAC_PI_4);
    let bodies = vec![
        (cube(0.5), Pose::at(Vec3::new(0.0, 0.0, 0.5 - 1e-3)), true),
        (Solid::HalfSpace, Pose::at(Vec3::zeros()), false),
        (cube(0.5), Pose::at(Vec3::new(0.0, 0.0, 1.5 - 2e-3)), true),
        (Solid::Sphere { radius: 0.3 }, Pose::at(Vec3::new(0.8 + 5e-4, 0.0, 0.3)), true),
        (Solid::Sphere { radius: 0.3 }, Pose::at(Vec3::new(1.4 + 2e-3, 0.1, 0.3)), true),
        (cube(0.4), Pose { position: Vec3::new(-0.503 - 0.4 * 2f64.sqrt(), 0.0, 0.4 + 1e-3), rotation: turned }, true),
        (cube(0.5), Pose::at(Vec3::new(3.0, 0.0, 0.5 - 1e-3)), false),
    ];
    let mut s = (Vec::new(), Vec::new(), Vec::new());
    for (solid, pose, mobile) in bodies {
        s.0.push(solid);
        s.1.push(pose);
        s.2.push(mobile);
    }
    s
}

fn bits(f: &Found) -> [u64; 13] {
    let v = |x: &Vec3| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()];
    let [a, b, c] = v(&f.position);
    let [d, e, g] = v(&f.normal);
    let [h, i, j] = v(&f.t1);
    let [k, l, m] = v(&f.t2);
    [a, b, c, d, e, g, h, i, j, k, l, m, f.gap.to_bits()]
}

fn same(x: &[Found], y: &[Found]) -> bool {
    x.len() == y.len() && x.iter().zip(y).all(|(a, b)| a.key == b.key && bits(a) == bits(b))
}

fn pairs(found: &[Found]) -> Vec<(u32, u32)> {
    let mut p: Vec<_> = found.iter().map(|f| (f.key.0, f.key.1)).collect();
    p.dedup();
    p
}

#[test]
fn pile_keys_sorted_unique_and_repeatable() {
    let (solids, mut poses, mobile) = pile();
    let mut det = Detector::default();
    det.run(&solids, &poses, &mobile, ALERT);
    let first = det.found.clone();
    assert!(first.windows(2).all(|w| w[0].key < w[1].key), "sorted, no duplicate");
    assert_eq!(pairs(&first), vec![(0, 1), (0, 2), (0, 3), (0, 5), (3, 1), (3, 4), (4, 1), (5, 1)]);
    for f in &first {
        let (c, a) = (f.key.0 as usize, f.key.1 as usize);
        assert!(!matches!(solids[c], Solid::HalfSpace), "a half-space is never the candidate");
        assert!(c < a || matches!(solids[a], Solid::HalfSpace));
        assert!((f.normal.norm() - 1.0).abs() < 1e-12 && (f.t1.cross(&f.t2) - f.normal).norm() < 1e-12);
    }
    // Cube on the floor and cube on cube: four points each, the normal from the antagonist to the candidate.
    let of = |c, a| first.iter().filter(move |f| (f.key.0, f.key.1) == (c, a));
    assert_eq!(of(0, 1).count(), 4);
    assert!(of(0, 1).all(|f| f.normal == Vec3::z() && (f.gap + 1e-3).abs() < 1e-12));
    assert_eq!(of(0, 2).count(), 4);
    assert!(of(0, 2).all(|f| (f.normal + Vec3::z()).norm() < 1e-12 && (f.gap + 1e-3).abs() < 1e-12));
    let side = of(0, 3).next().unwrap();
    assert!((side.normal + Vec3::x()).norm() < 1e-12 && (side.gap - 5e-4).abs() < 1e-12);
    // The fixed cube on the floor (6, 1) is not looked at.
    // The same call again, and a fresh detector: bit-identical.
    det.run(&solids, &poses, &mobile, ALERT);
    assert!(same(&det.found, &first));
    let mut fresh = Detector::default();
    fresh.run(&solids, &poses, &mobile, ALERT);
    assert!(same(&fresh.found, &first));
    // The top cube lifted away: its pair vanishes; put back, everything as before.
    poses[2].position.z += 0.5;
    det.run(&solids, &poses, &mobile, ALERT);
    assert!(det.found.iter().all(|f| f.key.0 != 2 && f.key.1 != 2));
    assert_eq!(det.found.len(), first.len() - 4);
    poses[2].position.z -= 0.5;
    det.run(&solids, &poses, &mobile, ALERT);
    assert!(same(&det.found, &first));
    // References to shapes are accepted as well.
    let refs: Vec<&Solid> = solids.iter().collect();
    det.run(&refs, &poses, &mobile, ALERT);
    assert!(same(&det.found, &first));
}

/// A random cloud of cubes of random sizes and spheres above a tilted wall.
fn cloud(rng: &mut ChaCha8Rng, n: usize) -> (Vec<Solid>, Vec<Pose>, Vec<bool>) {
    let (mut solids, mut poses, mut mobile) = (Vec::new(), Vec::new(), Vec::new());
    let wall = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vec3::new(1.0, 1.0, 0.0)), 0.2);
    solids.push(Solid::HalfSpace);
    poses.push(Pose { position: Vec3::new(0.0, 0.0, -0.1), rotation: wall });
    mobile.push(false);
    for k in 0..n {
        let solid = if k % 4 == 3 {
            Solid::Sphere { radius: rng.random_range(0.1..0.3) }
        } else {
            let half = [0.0; 3].map(|_: f64| rng.random_range(0.1..0.3));
            Solid::Polyhedron(Polyhedron::cuboid(half).unwrap())
        };
        let axis = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let rotation = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), rng.random_range(-3.0..3.0));
        let position = Vec3::from_fn(|_, _| rng.random_range(0.0..2.0));
        solids.push(solid);
        poses.push(Pose { position, rotation });
        mobile.push(k % 7 != 0);
    }
    (solids, poses, mobile)
}

/// The narrow phase called directly on one pair, in the detector's orientation.
fn direct(solids: &[Solid], poses: &[Pose], c: usize, a: usize) -> Option<Manifold> {
    let view = |k: usize| match &solids[k] {
        Solid::Polyhedron(p) => Some(PlacedPolyhedron::new(p, &poses[k])),
        _ => None,
    };
    let (pc, pa) = (view(c), view(a));
    let centre = |k: usize| poses[k].position;
    match (&solids[c], &solids[a]) {
        (Solid::Polyhedron(_), Solid::Polyhedron(_)) => {
            polyhedron_polyhedron(&pc.unwrap().view(), &pa.unwrap().view(), ALERT, None)
        }
        (Solid::Polyhedron(_), Solid::Sphere { radius }) => {
            polyhedron_sphere(&pc.unwrap().view(), &centre(a), *radius, ALERT)
        }
        (Solid::Sphere { radius }, Solid::Polyhedron(_)) => {
            sphere_polyhedron(&centre(c), *radius, &pa.unwrap().view(), ALERT)
        }
        (Solid::Sphere { radius: rc }, Solid::Sphere { radius: ra }) => {
            sphere_sphere(&centre(c), *rc, &centre(a), *ra, ALERT)
        }
        (Solid::Polyhedron(_), Solid::HalfSpace) => {
            polyhedron_half_space(&pc.unwrap().view(), &Plane::from_pose(&poses[a]), ALERT)
        }
        (Solid::Sphere { radius }, Solid::HalfSpace) => {
            sphere_half_space(&centre(c), *radius, &Plane::from_pose(&poses[a]), ALERT)
        }
        _ => None,
    }
}

#[test]
fn random_cloud_matches_every_pair_tested_directly() {
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let (solids, poses, mobile) = cloud(&mut rng, 120);
    let mut det = Detector::default();
    det.run(&solids, &poses, &mobile, ALERT);
    let mut expected = Vec::new();
    for i in 0..solids.len() {
        for j in i + 1..solids.len() {
            if !mobile[i] && !mobile[j] {
                continue;
            }
            let (c, a) = if matches!(solids[i], Solid::HalfSpace) { (j, i) } else { (i, j) };
            if let Some(m) = direct(&solids, &poses, c, a) {
                for (k, p) in m.points().iter().enumerate() {
                    expected.push(((c as u32, a as u32, k as u32), p.position, m.normal, p.gap));
                }
            }
        }
    }
    expected.sort_by_key(|e| e.0);
    assert!(expected.len() > 100, "a dense enough cloud: {} points", expected.len());
    assert_eq!(det.found.len(), expected.len());
    for (f, e) in det.found.iter().zip(&expected) {
        assert_eq!(f.key, e.0);
        assert!(f.position == e.1 && f.normal == e.2 && f.gap == e.3, "{f:?} vs {e:?}");
    }
    // The previous normals (a warm detector) change nothing.
    let first = det.found.clone();
    det.run(&solids, &poses, &mobile, ALERT);
    assert!(same(&det.found, &first));
}
