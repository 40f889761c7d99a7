//! The detector's results on the bench's two piles (`benches/detection3d.rs`: 2028 cuboid grains jammed in a
//! lattice, or of random shapes and orientations, in a box of five walls) against hashes recorded with the
//! detector of commit ceec2b1, before it was made faster: every bit of every contact (key, position, normal,
//! tangents, gap) the same, on a cold detector and a warm one (the per-pair memory filled by a first call),
//! on one thread and on two.

use super::*;
use crate::geometry::{Face, Polyhedron, Pose, Solid, Vec3};
use nalgebra::{Matrix3, Unit, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const ALERT: f64 = 1e-2;
const N: [usize; 3] = [13, 13, 12];

fn turn(rng: &mut ChaCha8Rng, max: f64) -> UnitQuaternion<f64> {
    let axis = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), rng.random_range(-max..max))
}

/// The bench's pile (the same generator, the same seeds).
pub(super) fn pile(jammed: bool) -> (Vec<Solid>, Vec<Pose>, Vec<bool>) {
    let mut rng = ChaCha8Rng::seed_from_u64(if jammed { 1 } else { 2 });
    let (mut solids, mut poses, mut mobile) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..N[2] {
        for j in 0..N[1] {
            for i in 0..N[0] {
                let reach = 0.5 + rng.random_range(0.0..2e-3);
                let (rotation, half) = if jammed {
                    let r = turn(&mut rng, 0.02);
                    let m: Matrix3<f64> = r.to_rotation_matrix().matrix().abs();
                    let h = m.try_inverse().unwrap() * Vec3::repeat(reach);
                    (r, [h.x, h.y, h.z])
                } else {
                    let r = turn(&mut rng, std::f64::consts::PI);
                    let h = Vec3::from_fn(|_, _| rng.random_range(0.25..0.5));
                    let m = r.to_rotation_matrix().matrix().abs();
                    let s = reach / (m * h).max();
                    (r, [h.x * s, h.y * s, h.z * s])
                };
                solids.push(Solid::Polyhedron(Polyhedron::cuboid(half).unwrap()));
                poses.push(Pose { position: Vec3::new(i as f64, j as f64, k as f64), rotation });
                mobile.push(true);
            }
        }
    }
    let wall = |point: Vec3, normal: Vec3| Pose {
        position: point,
        rotation: UnitQuaternion::rotation_between(&Vec3::z(), &normal)
            .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vec3::x_axis(), std::f64::consts::PI)),
    };
    let (x1, y1) = (N[0] as f64 - 0.5, N[1] as f64 - 0.5);
    for (p, n) in [
        (Vec3::new(0.0, 0.0, -0.5), Vec3::z()),
        (Vec3::new(-0.5, 0.0, 0.0), Vec3::x()),
        (Vec3::new(x1, 0.0, 0.0), -Vec3::x()),
        (Vec3::new(0.0, -0.5, 0.0), Vec3::y()),
        (Vec3::new(0.0, y1, 0.0), -Vec3::y()),
    ] {
        solids.push(Solid::HalfSpace);
        poses.push(wall(p, n));
        mobile.push(false);
    }
    (solids, poses, mobile)
}

/// A convex hull of `n` random points on an ellipsoid of semi-axes in `0.45..0.62`, made here (every
/// triple of points with all the others below its plane is a face: the points are in general position), so
/// that the reference does not depend on [`Polyhedron::from_points`]; its vertices about their mean.
fn hull(rng: &mut ChaCha8Rng, n: usize) -> Polyhedron {
    let axes = Vec3::from_fn(|_, _| rng.random_range(0.45..0.62));
    let mut v: Vec<Vec3> = (0..n)
        .map(|_| loop {
            let d = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            if (0.1..1.0).contains(&d.norm()) {
                break d.normalize().component_mul(&axes);
            }
        })
        .collect();
    let mean = v.iter().sum::<Vec3>() / n as f64;
    v.iter_mut().for_each(|x| *x -= mean);
    let mut faces = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let normal = (v[j] - v[i]).cross(&(v[k] - v[i])).normalize();
                let offset = normal.dot(&v[i]);
                let side =
                    |s: f64| (0..n).all(|m| m == i || m == j || m == k || s * (normal.dot(&v[m]) - offset) < 0.0);
                if side(1.0) {
                    faces.push(Face { vertices: vec![i as u32, j as u32, k as u32], normal, offset });
                } else if side(-1.0) {
                    faces.push(Face { vertices: vec![i as u32, k as u32, j as u32], normal: -normal, offset: -offset });
                }
            }
        }
    }
    let mut edges: Vec<[u32; 2]> = faces
        .iter()
        .flat_map(|f| (0..3).map(|k| (f.vertices[k], f.vertices[(k + 1) % 3])).map(|(a, b)| [a.min(b), a.max(b)]))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let radius = v.iter().map(|x| x.norm()).fold(0.0, f64::max);
    let inradius = faces.iter().map(|f| f.offset).fold(f64::INFINITY, f64::min);
    Polyhedron { vertices: v, faces, edges, volume: 1.0, inertia_per_density: Vec3::repeat(1.0), radius, inradius }
}

/// A 10 × 10 × 5 lattice (unit spacing) of convex hulls of 8 to 24 vertices and, one in five, spheres, at
/// random orientations and moved by up to 0.05, on a floor: vertex, edge and face contacts of many-sided
/// shapes, and many pairs apart.
pub(super) fn hulls() -> (Vec<Solid>, Vec<Pose>, Vec<bool>) {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (mut solids, mut poses, mut mobile) =
        (vec![Solid::HalfSpace], vec![Pose::at(Vec3::new(0.0, 0.0, -0.5))], vec![false]);
    for k in 0..5 {
        for j in 0..10 {
            for i in 0..10 {
                let solid = if rng.random_range(0..5) == 0 {
                    Solid::Sphere { radius: rng.random_range(0.45..0.52) }
                } else {
                    let n = rng.random_range(8..25);
                    Solid::Polyhedron(hull(&mut rng, n))
                };
                let jitter = Vec3::from_fn(|_, _| rng.random_range(-0.05..0.05));
                solids.push(solid);
                poses.push(Pose {
                    position: Vec3::new(i as f64, j as f64, k as f64) + jitter,
                    rotation: turn(&mut rng, std::f64::consts::PI),
                });
                mobile.push(true);
            }
        }
    }
    (solids, poses, mobile)
}

/// FNV-1a over every bit of the contacts, in order.
pub(super) fn hash(found: &[Found]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for f in found {
        eat(u64::from(f.key.0));
        eat(u64::from(f.key.1));
        eat(u64::from(f.key.2));
        for v in [&f.position, &f.normal, &f.t1, &f.t2] {
            for x in v.iter() {
                eat(x.to_bits());
            }
        }
        eat(f.gap.to_bits());
    }
    h
}

/// The count and hash of the contacts of a cold call, a warm call on the same poses, then five calls on the
/// pile shaken (see [`moved`]), recorded with the detector of commit ceec2b1.
type Record = ((usize, u64), (usize, u64), [(usize, u64); 5]);

const JAMMED: Record = (
    (27766, 12653942401900275285),
    (27766, 12653942401900275285),
    [
        (27500, 7874856190672407307),
        (27198, 4749843101351790985),
        (26847, 15763630719163670780),
        (26618, 4848674860751191433),
        (26474, 15228492266759393502),
    ],
);

const RANDOM: Record = (
    (377, 5402657671136178054),
    (377, 5402657671136178054),
    [
        (380, 5879249856100670647),
        (385, 5271087809037609963),
        (385, 2651775093332704411),
        (388, 300723006750441395),
        (387, 4261050835006999048),
    ],
);

const HULLS: Record = (
    (438, 16237400825788943636),
    (438, 16237400825788943636),
    [
        (440, 6603672202383860724),
        (440, 9828598852369846999),
        (437, 14041884166756095834),
        (445, 13406353087439194954),
        (442, 12969160114896870827),
    ],
);

fn check(name: &str, (solids, poses, mobile): (Vec<Solid>, Vec<Pose>, Vec<bool>), expected: &Record) {
    for threads in [1, 2] {
        let mut det = Detector::with_threads(threads);
        det.run(&solids, &poses, &mobile, ALERT);
        assert_eq!((det.found.len(), hash(&det.found)), expected.0, "{name}, {threads} threads, cold");
        det.run(&solids, &poses, &mobile, ALERT);
        assert_eq!((det.found.len(), hash(&det.found)), expected.1, "{name}, {threads} threads, warm");
        let steps = moved(&mut det, &solids, poses.clone(), &mobile);
        assert_eq!(steps[..], expected.2[..], "{name}, {threads} threads, moved");
    }
}

#[test]
fn jammed_pile_as_before() {
    check("jammed", pile(true), &JAMMED);
}

#[test]
fn random_pile_as_before() {
    check("random", pile(false), &RANDOM);
}

#[test]
fn hull_pile_as_before() {
    check("hulls", hulls(), &HULLS);
}

/// Five calls on the pile shaken a little more each time (every grain moved and turned by a few
/// thousandths, from a seeded generator): the warm detector's memory holds normals and separating axes of
/// the previous call. The count and hash of each call.
pub(super) fn moved(det: &mut Detector, solids: &[Solid], mut poses: Vec<Pose>, mobile: &[bool]) -> Vec<(usize, u64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut out = Vec::new();
    for _ in 0..5 {
        for (p, &m) in poses.iter_mut().zip(mobile) {
            if m {
                p.position += Vec3::from_fn(|_, _| rng.random_range(-3e-3..3e-3));
                p.rotation = turn(&mut rng, 3e-3) * p.rotation;
            }
        }
        det.run(solids, &poses, mobile, ALERT);
        out.push((det.found.len(), hash(&det.found)));
    }
    out
}
