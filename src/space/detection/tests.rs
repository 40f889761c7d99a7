//! Unit cases of the narrow phase with exact answers, as LMGC90's own PRPRx tests place two cubes face to
//! face, shifted, edge to face, vertex to face and edge across edge: unit cubes (half size 0.5), gaps of
//! ±1e-3 within an alert distance of 1e-2, and every case again under random rigid motions of the pair.

use super::narrow::{polyhedron_polyhedron_with, sphere_half_space, sphere_polyhedron, sphere_sphere};
use super::*;
use crate::geometry::{Face, Polyhedron, Pose, Vec3};
use nalgebra::{Unit, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_4};

const ALERT: f64 = 1e-2;
const GAPS: [f64; 2] = [1e-3, -1e-3];
const TOL: f64 = 1e-12;

fn cube() -> Polyhedron {
    Polyhedron::cuboid([0.5; 3]).unwrap()
}

fn about(axis: Vec3, angle: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), angle)
}

fn pose(position: Vec3, rotation: UnitQuaternion<f64>) -> Pose {
    Pose { position, rotation }
}

/// A regular tetrahedron of circumradius `r`, filled by hand.
fn tetrahedron(r: f64) -> Polyhedron {
    let s = r / 3f64.sqrt();
    let vertices: Vec<Vec3> =
        [[1., 1., 1.], [1., -1., -1.], [-1., 1., -1.], [-1., -1., 1.]].iter().map(|c| Vec3::from(*c) * s).collect();
    let faces = (0..4)
        .map(|k| {
            let normal = -vertices[k].normalize();
            let mut f: Vec<u32> = (0..4u32).filter(|&i| i as usize != k).collect();
            let (a, b, c) = (vertices[f[0] as usize], vertices[f[1] as usize], vertices[f[2] as usize]);
            if (b - a).cross(&(c - a)).dot(&normal) < 0.0 {
                f.swap(1, 2);
            }
            Face { vertices: f, normal, offset: r / 3.0 }
        })
        .collect();
    let edges = vec![[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];
    let edge = 2.0 * 2f64.sqrt() * s;
    let volume = edge.powi(3) / (6.0 * 2f64.sqrt());
    Polyhedron {
        vertices,
        faces,
        edges,
        volume,
        inertia_per_density: Vec3::repeat(volume * edge * edge / 20.0),
        radius: r,
        inradius: r / 3.0,
    }
}

/// The contact of candidate `a` at `pa` with antagonist `b` at `pb`.
fn contact(a: &Polyhedron, pa: &Pose, b: &Polyhedron, pb: &Pose, alert: f64) -> Option<Manifold> {
    contact_with(a, pa, b, pb, alert, FaceGaps::Exact)
}

/// [`contact`] under the face–face gap rule `rule`.
fn contact_with(a: &Polyhedron, pa: &Pose, b: &Polyhedron, pb: &Pose, alert: f64, rule: FaceGaps) -> Option<Manifold> {
    let (va, vb) = (PlacedPolyhedron::new(a, pa), PlacedPolyhedron::new(b, pb));
    polyhedron_polyhedron_with(&va.view(), &vb.view(), alert, None, rule)
}

fn close(a: &Vec3, b: &Vec3) -> bool {
    (a - b).norm() <= TOL
}

/// Checks the frame and that the points are `expected` (in this order) with gap `gap` each.
fn check(m: &Manifold, normal: Vec3, expected: &[Vec3], gaps: &[f64]) {
    assert!(close(&m.normal, &normal), "normal {:?}, expected {normal:?}", m.normal);
    assert!((m.t1.norm() - 1.0).abs() < TOL && m.t1.dot(&m.normal).abs() < TOL);
    assert!(close(&m.t1.cross(&m.t2), &m.normal), "right-handed frame");
    let got: Vec<_> = m.points().iter().map(|p| (p.position, p.gap)).collect();
    assert_eq!(got.len(), expected.len(), "points {got:?}, expected {expected:?}");
    for ((p, g), (e, eg)) in got.iter().zip(expected.iter().zip(gaps)) {
        assert!(close(p, e), "point {p:?}, expected {e:?} (all: {got:?})");
        assert!((g - eg).abs() <= TOL, "gap {g}, expected {eg}");
    }
}

/// The cases below, as (candidate shape, pose, antagonist shape, pose, gap).
fn cases(gap: f64) -> Vec<(&'static str, Polyhedron, Pose, Polyhedron, Pose)> {
    let id = UnitQuaternion::identity;
    let h = FRAC_1_SQRT_2;
    let down = UnitQuaternion::rotation_between(&Vec3::repeat(1.0), &-Vec3::z()).unwrap();
    vec![
        ("face-face", cube(), pose(Vec3::new(0.0, 0.0, 1.0 + gap), id()), cube(), Pose::at(Vec3::zeros())),
        ("shifted", cube(), pose(Vec3::new(0.3, 0.2, 1.0 + gap), id()), cube(), Pose::at(Vec3::zeros())),
        (
            "edge-face",
            cube(),
            pose(Vec3::new(0.3, 0.1, 0.5 + h + gap), about(Vec3::x(), FRAC_PI_4)),
            cube(),
            Pose::at(Vec3::zeros()),
        ),
        (
            "vertex-face",
            cube(),
            pose(Vec3::new(0.1, -0.2, 0.5 + 0.75f64.sqrt() + gap), down),
            cube(),
            Pose::at(Vec3::zeros()),
        ),
        (
            "crossed",
            cube(),
            pose(Vec3::new(0.1, -0.15, 2.0 * h + gap), about(Vec3::x(), FRAC_PI_4)),
            cube(),
            pose(Vec3::zeros(), about(Vec3::y(), FRAC_PI_4)),
        ),
        (
            "tilted",
            Polyhedron::cuboid([0.4; 3]).unwrap(),
            pose(Vec3::new(0.0, 0.0, 0.9 + gap), about(Vec3::x(), 2e-3)),
            cube(),
            Pose::at(Vec3::zeros()),
        ),
        (
            "octagon",
            cube(),
            pose(Vec3::new(0.0, 0.0, 1.0 + gap), about(Vec3::z(), FRAC_PI_4)),
            cube(),
            Pose::at(Vec3::zeros()),
        ),
        (
            "tetra-face",
            tetrahedron(0.45),
            pose(Vec3::new(0.05, 0.0, 0.5 + 0.15 + gap), tetra_face_down()),
            cube(),
            Pose::at(Vec3::zeros()),
        ),
    ]
}

/// Turns the tetrahedron's face opposite vertex 0 (normal −(1,1,1)/√3) to face −z.
fn tetra_face_down() -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&-Vec3::repeat(1.0), &-Vec3::z()).unwrap()
}

#[test]
fn face_face_four_corners() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(0);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        let z = 0.5 + 0.5 * g;
        // The candidate's bottom vertices 0..3, in index order.
        let corners = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)].map(|(x, y)| Vec3::new(x, y, z));
        check(&m, Vec3::z(), &corners, &[g; 4]);
        assert_eq!(m.normal, Vec3::z(), "the face normal exactly");
    }
}

#[test]
fn shifted_face_face_overlap_rectangle() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(1);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        let z = 0.5 + 0.5 * g;
        // Vertex 0 of the candidate, vertex 7 of the antagonist, then the two edge crossings.
        let expected = [(-0.2, -0.3), (0.5, 0.5), (0.5, -0.3), (-0.2, 0.5)].map(|(x, y)| Vec3::new(x, y, z));
        check(&m, Vec3::z(), &expected, &[g; 4]);
    }
}

#[test]
fn edge_face_two_points_clipped() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(2);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        let z = 0.5 + 0.5 * g;
        // The bottom edge runs over x in [-0.2, 0.8] at y = 0.1: clipped to the face at x = 0.5.
        check(&m, Vec3::z(), &[Vec3::new(-0.2, 0.1, z), Vec3::new(0.5, 0.1, z)], &[g; 2]);
    }
    // Centred: the edge's ends are on the face's boundary.
    let a = cube();
    let pa = pose(Vec3::new(0.0, 0.0, 0.5 + FRAC_1_SQRT_2 + 1e-3), about(Vec3::x(), FRAC_PI_4));
    let m = contact(&a, &pa, &cube(), &Pose::at(Vec3::zeros()), ALERT).unwrap();
    let z = 0.5 + 0.5e-3;
    check(&m, Vec3::z(), &[Vec3::new(-0.5, 0.0, z), Vec3::new(0.5, 0.0, z)], &[1e-3; 2]);
}

#[test]
fn vertex_face_one_point() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(3);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        check(&m, Vec3::z(), &[Vec3::new(0.1, -0.2, 0.5 + 0.5 * g)], &[g]);
    }
}

#[test]
fn crossed_edges_one_point() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(4);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        // Edges along x (candidate, at y = -0.15) and y (antagonist, at x = 0), both at height 1/√2.
        check(&m, Vec3::z(), &[Vec3::new(0.0, -0.15, FRAC_1_SQRT_2 + 0.5 * g)], &[g]);
    }
}

#[test]
fn tilted_face_has_a_gap_per_point() {
    let g = -1e-3;
    let (_, a, pa, b, pb) = cases(g).swap_remove(5);
    let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
    let expected: Vec<Vec3> = a.vertices[..4].iter().map(|v| pa.point(v)).collect();
    let gaps: Vec<f64> = expected.iter().map(|v| v.z - 0.5).collect();
    let mid: Vec<Vec3> = expected.iter().map(|v| Vec3::new(v.x, v.y, 0.5 * (v.z + 0.5))).collect();
    check(&m, Vec3::z(), &mid, &gaps);
    assert!((gaps[0] - gaps[2]).abs() > 1.5e-3, "the two sides differ: {gaps:?}");
}

/// LMGC90's face–face rule ([`FaceGaps::CommonPlane`]) on a 0.4 cube on a unit cube, tilted about x by `tilt`
/// (rad): the band is 10 % of the smaller centroid-to-plane distance, 0.1 × 0.4 = 0.04, and the tilted bottom face
/// spans 0.8 sin(tilt) along the normal. Below 0.05 rad its four corners are within the band: the four points of
/// the exact rule, each with the exact rule's smallest gap. Above, only the low edge is: the exact rule's points
/// and gaps, as LMGC90's edge–face case.
#[test]
fn common_plane_gaps_flatten_only_face_face_contacts() {
    let top = Polyhedron::cuboid([0.4; 3]).unwrap();
    for (tilt, face_face) in [(2e-3, true), (0.03, true), (0.08, false), (0.2, false)] {
        for g in GAPS {
            let r = about(Vec3::x(), tilt);
            // The lowest corner at gap g above the unit cube's top face (z = 0.5).
            let low = (0..8).map(|k| (r * top.vertices[k]).z).fold(f64::INFINITY, f64::min);
            let pa = pose(Vec3::new(0.0, 0.0, 0.5 + g - low), r);
            let (bottom, pb) = (cube(), Pose::at(Vec3::zeros()));
            let exact = contact_with(&top, &pa, &bottom, &pb, ALERT, FaceGaps::Exact).unwrap();
            let common = contact_with(&top, &pa, &bottom, &pb, ALERT, FaceGaps::CommonPlane).unwrap();
            assert!((exact.points().iter().map(|p| p.gap).fold(f64::INFINITY, f64::min) - g).abs() < TOL);
            if face_face {
                // The four corners, as the exact rule gives them with an alert distance that reaches the far
                // side (0.05 m: beyond the 0.024 m spread, short of the top face 0.8 m up).
                let all = contact_with(&top, &pa, &bottom, &pb, 0.05, FaceGaps::Exact).unwrap();
                let pts: Vec<Vec3> = all.points().iter().map(|p| p.position).collect();
                check(&common, exact.normal, &pts, &[g; 4]);
                let spread = all.points().iter().map(|p| p.gap).fold(f64::NEG_INFINITY, f64::max) - g;
                assert!((spread - 0.8 * tilt.sin()).abs() < 1e-9, "tilt {tilt}: exact gaps spread {spread}");
            } else {
                assert_eq!(common, exact, "tilt {tilt}: an edge on a face keeps its exact gaps");
                assert_eq!(exact.len, 2, "tilt {tilt}: the low edge");
            }
        }
    }
}

#[test]
fn octagon_reduced_to_four_points() {
    let g = 1e-3;
    let (_, a, pa, b, pb) = cases(g).swap_remove(6);
    let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
    assert_eq!(m.len, 4);
    // The octagon's vertices are at distance 0.5 / cos(22.5°) from the axis, at the mid-plane.
    let r = 0.5 / (std::f64::consts::PI / 8.0).cos();
    let mut xy = Vec::new();
    for p in m.points() {
        assert!((p.gap - g).abs() < TOL && (p.position.z - 0.5 - 0.5 * g).abs() < TOL);
        assert!((p.position.xy().norm() - r).abs() < 1e-12, "an octagon vertex: {:?}", p.position);
        xy.push(p.position.xy());
    }
    // Spread out: the quadrilateral spans at least half the octagon's area (2.0 × 0.414…).
    let area = |p: &[nalgebra::Vector2<f64>]| {
        let mut hull = p.to_vec();
        let c = hull.iter().sum::<nalgebra::Vector2<f64>>() / 4.0;
        hull.sort_by(|u, v| (u.y - c.y).atan2(u.x - c.x).total_cmp(&(v.y - c.y).atan2(v.x - c.x)));
        (0..4).map(|k| crate::geometry::cross(hull[k], hull[(k + 1) % 4])).sum::<f64>() * 0.5
    };
    assert!(area(&xy) > 0.5, "area {}", area(&xy));
}

#[test]
fn hand_made_tetrahedron_face_on_a_cube() {
    for g in GAPS {
        let (_, a, pa, b, pb) = cases(g).swap_remove(7);
        let m = contact(&a, &pa, &b, &pb, ALERT).unwrap();
        // The face opposite vertex 0: vertices 1, 2, 3, all inside the cube's top face.
        let expected: Vec<Vec3> = (1..4).map(|k| pa.point(&a.vertices[k]) - Vec3::z() * 0.5 * g).collect();
        check(&m, Vec3::z(), &expected, &[g; 3]);
    }
}

#[test]
fn apart_beyond_the_alert_distance_is_no_contact() {
    for (name, a, pa, b, pb) in cases(0.02) {
        assert!(contact(&a, &pa, &b, &pb, ALERT).is_none(), "{name}");
        if name == "tilted" {
            continue; // its lowest corner is 1e-3 nearer
        }
        // Within a larger alert distance they are found, at that gap.
        let m = contact(&a, &pa, &b, &pb, 0.05).unwrap_or_else(|| panic!("{name}"));
        let min = m.points().iter().map(|p| p.gap).fold(f64::INFINITY, f64::min);
        assert!((min - 0.02).abs() < 1e-9, "{name}: {min}");
    }
}

/// A random rigid motion: rotation and translation.
fn motion(rng: &mut ChaCha8Rng) -> (UnitQuaternion<f64>, Vec3) {
    let axis = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    let r = about(axis, rng.random_range(-3.0..3.0));
    (r, Vec3::from_fn(|_, _| rng.random_range(-5.0..5.0)))
}

fn moved(p: &Pose, (r, t): &(UnitQuaternion<f64>, Vec3)) -> Pose {
    Pose { position: r * p.position + t, rotation: r * p.rotation }
}

/// Every case, under both face–face gap rules, moved with its pair by 20 random rigid motions: the same normal,
/// points and gaps, moved.
#[test]
fn invariant_under_a_rigid_motion_of_the_pair() {
    let mut rng = ChaCha8Rng::seed_from_u64(36);
    for (g, rule) in GAPS.into_iter().flat_map(|g| [(g, FaceGaps::Exact), (g, FaceGaps::CommonPlane)]) {
        for (name, a, pa, b, pb) in cases(g) {
            let m0 = contact_with(&a, &pa, &b, &pb, ALERT, rule).unwrap();
            for _ in 0..20 {
                let mv = motion(&mut rng);
                let m = contact_with(&a, &moved(&pa, &mv), &b, &moved(&pb, &mv), ALERT, rule).unwrap();
                assert!((mv.0 * m0.normal - m.normal).norm() < TOL, "{name}: normal");
                assert_eq!(m.len, m0.len, "{name}: count");
                for (p0, p) in m0.points().iter().zip(m.points()) {
                    assert!((mv.0 * p0.position + mv.1 - p.position).norm() < TOL, "{name}: point");
                    assert!((p0.gap - p.gap).abs() < TOL, "{name}: gap {} vs {}", p0.gap, p.gap);
                }
            }
        }
    }
}

/// Apart vertex to vertex and vertex over an edge: no face or edge-pair axis gives the distance, GJK does.
#[test]
fn vertex_vertex_and_vertex_edge_apart_by_gjk() {
    let g = 1e-3;
    let down = UnitQuaternion::rotation_between(&Vec3::repeat(1.0), &-Vec3::z()).unwrap();
    let up = UnitQuaternion::rotation_between(&Vec3::repeat(1.0), &Vec3::z()).unwrap();
    let (c, h) = (0.75f64.sqrt(), FRAC_1_SQRT_2);
    let cases = [
        (pose(Vec3::new(0.0, 0.0, 2.0 * c + g), down), pose(Vec3::zeros(), up), Vec3::new(0.0, 0.0, c + 0.5 * g)),
        (
            pose(Vec3::new(0.1, 0.0, h + c + g), down),
            pose(Vec3::zeros(), about(Vec3::x(), FRAC_PI_4)),
            Vec3::new(0.1, 0.0, h + 0.5 * g),
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (pa, pb, point) in cases {
        // The separating-axis search alone bounds the distance from below, and says so.
        let (va, vb) = (PlacedPolyhedron::new(&cube(), &pa), PlacedPolyhedron::new(&cube(), &pb));
        let axis::Search::Plane(plane) = axis::common_plane(&va.view(), &vb.view(), ALERT, None) else { panic!() };
        assert!(plane.separation < g - 1e-4 && !axis::is_exact(&va.view(), &vb.view(), &plane), "{plane:?}");
        let m = contact(&cube(), &pa, &cube(), &pb, ALERT).unwrap();
        assert_eq!(m.len, 1);
        assert!((m.normal - Vec3::z()).norm() < 1e-9, "{:?}", m.normal);
        assert!((m.points[0].position - point).norm() < 1e-9 && (m.points[0].gap - g).abs() < 1e-9, "{m:?}");
        for _ in 0..10 {
            let mv = motion(&mut rng);
            let n = contact(&cube(), &moved(&pa, &mv), &cube(), &moved(&pb, &mv), ALERT).unwrap();
            assert_eq!(n.len, 1);
            assert!((n.normal - mv.0 * Vec3::z()).norm() < 1e-9);
            assert!((n.points[0].position - (mv.0 * point + mv.1)).norm() < 1e-9 && (n.points[0].gap - g).abs() < 1e-9);
        }
        // Beyond the alert distance: none.
        let far = Pose { position: pa.position + Vec3::new(0.0, 0.0, 0.02), ..pa };
        assert!(contact(&cube(), &far, &cube(), &pb, ALERT).is_none());
    }
}

#[test]
fn polyhedron_on_a_wall_face_edge_vertex() {
    let floor = Plane { point: Vec3::new(0.0, 0.0, -0.5), normal: Vec3::z() };
    let down = UnitQuaternion::rotation_between(&Vec3::repeat(1.0), &-Vec3::z()).unwrap();
    let h = FRAC_1_SQRT_2;
    for g in GAPS {
        let face = PlacedPolyhedron::new(&cube(), &Pose::at(Vec3::new(0.2, 0.0, g)));
        let m = polyhedron_half_space(&face.view(), &floor, ALERT).unwrap();
        let z = -0.5 + 0.5 * g;
        let corners = [(-0.3, -0.5), (0.7, -0.5), (-0.3, 0.5), (0.7, 0.5)].map(|(x, y)| Vec3::new(x, y, z));
        check(&m, Vec3::z(), &corners, &[g; 4]);
        let edge = PlacedPolyhedron::new(&cube(), &pose(Vec3::new(0.0, 0.0, h - 0.5 + g), about(Vec3::x(), FRAC_PI_4)));
        let m = polyhedron_half_space(&edge.view(), &floor, ALERT).unwrap();
        check(&m, Vec3::z(), &[Vec3::new(-0.5, 0.0, z), Vec3::new(0.5, 0.0, z)], &[g; 2]);
        let vertex = PlacedPolyhedron::new(&cube(), &pose(Vec3::new(0.0, 0.0, 0.75f64.sqrt() - 0.5 + g), down));
        let m = polyhedron_half_space(&vertex.view(), &floor, ALERT).unwrap();
        check(&m, Vec3::z(), &[Vec3::new(0.0, 0.0, z)], &[g]);
    }
    let far = PlacedPolyhedron::new(&cube(), &Pose::at(Vec3::new(0.0, 0.0, 0.02)));
    assert!(polyhedron_half_space(&far.view(), &floor, ALERT).is_none());
    // A tilted wall: the cube turned with it.
    let r = about(Vec3::new(1.0, 2.0, 0.5), 0.7);
    let wall = Plane { point: Vec3::new(1.0, -2.0, 3.0), normal: r * Vec3::z() };
    let cube_pose = pose(wall.point + r * Vec3::new(0.1, 0.0, 0.5 - 1e-3), r);
    let m = polyhedron_half_space(&PlacedPolyhedron::new(&cube(), &cube_pose).view(), &wall, ALERT).unwrap();
    assert_eq!(m.len, 4);
    assert!(m.points().iter().all(|p| (p.gap + 1e-3).abs() < TOL));
    assert!(close(&m.normal, &wall.normal));
}

#[test]
fn spheres_against_closed_forms() {
    let (ra, rb) = (0.3, 0.5);
    for g in GAPS {
        let dir = Vec3::new(1.0, -2.0, 0.5).normalize();
        let cb = Vec3::new(1.0, 2.0, 3.0);
        let ca = cb + dir * (ra + rb + g);
        let m = sphere_sphere(&ca, ra, &cb, rb, ALERT).unwrap();
        check(&m, dir, &[cb + dir * (rb + 0.5 * g)], &[g]);
        let wall = Plane { point: cb, normal: dir };
        let m = sphere_half_space(&ca, ra + rb, &wall, ALERT).unwrap();
        check(&m, dir, &[cb + dir * (0.5 * g)], &[g]);
        // A sphere on the cube's top face, over an edge and over a vertex.
        let b = PlacedPolyhedron::new(&cube(), &Pose::at(Vec3::zeros()));
        let on = |foot: Vec3, n: Vec3| {
            let m = sphere_polyhedron(&(foot + n * (ra + g)), ra, &b.view(), ALERT).unwrap();
            check(&m, n, &[foot + n * (0.5 * g)], &[g]);
            let r = polyhedron_sphere(&b.view(), &(foot + n * (ra + g)), ra, ALERT).unwrap();
            check(&r, -n, &[foot + n * (0.5 * g)], &[g]);
        };
        on(Vec3::new(0.1, 0.2, 0.5), Vec3::z());
        on(Vec3::new(0.5, 0.1, 0.5), Vec3::new(1.0, 0.0, 1.0).normalize());
        on(Vec3::new(0.5, 0.5, 0.5), Vec3::repeat(1.0).normalize());
    }
    // Apart beyond the alert distance.
    assert!(sphere_sphere(&Vec3::new(0.0, 0.0, 1.0), 0.4, &Vec3::zeros(), 0.5, ALERT).is_none());
    let b = PlacedPolyhedron::new(&cube(), &Pose::at(Vec3::zeros()));
    assert!(sphere_polyhedron(&Vec3::new(0.8, 0.8, 0.8), 0.3, &b.view(), ALERT).is_none());
    // The centre inside: the face of least penetration (the top, 0.1 away).
    let m = sphere_polyhedron(&Vec3::new(0.1, 0.0, 0.4), 0.2, &b.view(), ALERT).unwrap();
    check(&m, Vec3::z(), &[Vec3::new(0.1, 0.0, 0.35)], &[-0.3]);
}

#[test]
fn tangent_frame_is_right_handed() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for k in 0..200 {
        let n = if k < 6 {
            let mut e = Vec3::zeros();
            e[k % 3] = if k < 3 { 1.0 } else { -1.0 };
            e
        } else {
            Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize()
        };
        let (t1, t2) = tangent_frame(&n);
        assert!((t1.norm() - 1.0).abs() < TOL && t1.dot(&n).abs() < TOL && t2.dot(&t1).abs() < TOL);
        assert!(close(&t1.cross(&t2), &n));
    }
    assert_eq!(tangent_frame(&Vec3::z()), (Vec3::x(), Vec3::y()));
}

/// Random pairs of boxes and tetrahedra near contact: the deepest point's gap is parry's signed distance
/// (GJK when apart, exactly; EPA when overlapping, to its precision), and every manifold is well formed.
#[test]
fn deepest_gap_is_the_signed_distance() {
    use parry3d_f64::math::{Pose as PPose, Vector as PVec};
    use parry3d_f64::shape::ConvexPolyhedron;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut apart, mut overlapping) = (0, 0);
    for k in 0..400 {
        let shape = |rng: &mut ChaCha8Rng, k: usize| {
            if k.is_multiple_of(3) {
                tetrahedron(rng.random_range(0.3..0.6))
            } else {
                Polyhedron::cuboid([0.0; 3].map(|_: f64| rng.random_range(0.15..0.5))).unwrap()
            }
        };
        let (a, b) = (shape(&mut rng, k), shape(&mut rng, k / 2));
        let (ra, rb) = (motion(&mut rng).0, motion(&mut rng).0);
        let (pa, pb) = (pose(Vec3::zeros(), ra), pose(Vec3::zeros(), rb));
        let hull = |v: &PlacedPolyhedron| {
            let pts: Vec<PVec> = v.view().vertices.iter().map(|x| PVec::new(x.x, x.y, x.z)).collect();
            ConvexPolyhedron::from_convex_hull(&pts).unwrap()
        };
        let id = PPose::IDENTITY;
        // Along a random direction: apart along it, brought back until touching (each step by the distance,
        // which cannot overshoot), then moved by a small gap.
        let dir = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
        let (va, vb) = (PlacedPolyhedron::new(&a, &pa), PlacedPolyhedron::new(&b, &pb));
        let hb = hull(&vb);
        let mut t = va.view().extent(&-dir, &Vec3::zeros()).1 + vb.view().extent(&dir, &Vec3::zeros()).1;
        for _ in 0..30 {
            let ha = hull(&PlacedPolyhedron::new(&a, &pose(dir * t, ra)));
            t -= parry3d_f64::query::distance(&id, &ha, &id, &hb).unwrap().distance;
        }
        let pa = pose(dir * (t + rng.random_range(-0.02..0.008)), ra);
        let va = PlacedPolyhedron::new(&a, &pa);
        let ha = hull(&va);
        let Some(m) = polyhedron_polyhedron(&va.view(), &vb.view(), ALERT, None) else {
            let d = parry3d_f64::query::distance(&id, &ha, &id, &hb).unwrap().distance;
            assert!(d > ALERT - 1e-9, "pair {k}: no contact but distance {d}");
            continue;
        };
        assert!((1..=4).contains(&m.len) && (m.normal.norm() - 1.0).abs() < TOL);
        assert!(close(&m.t1.cross(&m.t2), &m.normal));
        let min = m.points().iter().map(|p| p.gap).fold(f64::INFINITY, f64::min);
        assert!(m.points().iter().all(|p| p.gap <= ALERT && p.gap.is_finite()));
        if min > 0.0 {
            let d = parry3d_f64::query::distance(&id, &ha, &id, &hb).unwrap().distance;
            assert!((min - d).abs() < 1e-9, "pair {k}: gap {min}, distance {d}");
            apart += 1;
        } else if let Ok(Some(c)) = parry3d_f64::query::contact(&id, &ha, &id, &hb, 0.0) {
            assert!((min - c.dist).abs() < 1e-6, "pair {k}: gap {min}, parry {}", c.dist);
            overlapping += 1;
        }
    }
    assert!(apart > 50 && overlapping > 100, "{apart} apart, {overlapping} overlapping");
}
