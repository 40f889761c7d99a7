//! 3D NSCD scenes (`ballast::scene::d3::Scene3`, `engine = "nscd"` with `dimension = 3`): the example parses,
//! validates and builds (bodies, masses against ρV, where a polyhedron's centroid goes, orientations), writes
//! back to the same scene and system, its cubes come to rest on the floor; and every class of error is one line
//! naming the key.

use crate::scratch;
use ballast::geometry::{Polyhedron, Solid, Vec3};
use ballast::nscd::d3::overlaps::Overlaps;
use ballast::nscd::d3::system::System3;
use ballast::scene::{d3::Scene3, Scene, SceneFile, SceneKind};
use ballast::space::detection::FaceGaps;
use ballast::Error;
use nalgebra::{Quaternion, UnitQuaternion};

const EXAMPLE: &str = include_str!("../examples/cubes3d.toml");
const RHO: f64 = 2700.0;

fn example() -> Scene3 {
    Scene3::from_toml_str(EXAMPLE).unwrap()
}

/// `EXAMPLE` with the first occurrence of `from` replaced by `to` (which must exist).
fn edit(from: &str, to: &str) -> String {
    assert!(EXAMPLE.contains(from), "test bug: {from:?} not in the example");
    EXAMPLE.replacen(from, to, 1)
}

/// The scene error of `text`, checked to be one line.
fn message(text: &str) -> String {
    let m = match Scene3::from_toml_str(text) {
        Err(Error::Scene(m)) => m,
        Err(e) => panic!("expected a scene error, got {e:?}"),
        Ok(_) => panic!("expected a scene error, the scene was accepted"),
    };
    assert!(!m.contains('\n') && !m.is_empty(), "not one line: {m:?}");
    eprintln!("{m}");
    m
}

/// Asserts that the message of `text` contains every one of `parts`.
fn expect(text: &str, parts: &[&str]) {
    let m = message(text);
    for p in parts {
        assert!(m.contains(p), "message {m:?} does not contain {p:?}");
    }
}

/// The index of the body named `name`.
fn index(sys: &System3, name: &str) -> usize {
    sys.bodies.info.iter().position(|b| b.name == name).unwrap()
}

/// The vertices of the rock as the example gives them.
fn rock_vertices(scene: &Scene3) -> Vec<[f64; 3]> {
    scene.bodies[4].polyhedron.as_ref().unwrap().vertices.clone()
}

#[test]
fn the_example_parses_validates_and_builds() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cubes3d.toml");
    let scene = Scene3::load(path).unwrap();
    assert_eq!(scene, example());
    assert!(SceneKind::is_nscd3(EXAMPLE, "cubes3d.toml").unwrap());
    assert_eq!(scene.steps(), 500);
    assert_eq!(scene.output_every(), 10);
    let sys = scene.build().unwrap();
    assert_eq!(sys.bodies.len(), 5);
    assert_eq!(sys.params.dt, 1e-3);
    assert_eq!(sys.params.alert_distance, 1e-3);
    assert_eq!(sys.params.gravity, Vec3::new(0.0, 0.0, -9.81));
    assert_eq!(sys.params.nlgs.tolerance, 1e-6);
    assert_eq!(sys.params.nlgs.max_iterations, 2000);

    // The floor: a fixed half-space at the origin, its outward normal (the frame's +z) up.
    let floor = &sys.bodies.info[0];
    assert!(floor.fixed && matches!(floor.solid, Solid::HalfSpace));
    assert!((sys.bodies.pose[0].rotation * Vec3::z() - Vec3::z()).norm() < 1e-15);

    // Masses: ρ V of each hull; the cubes' exactly (8 vertices or a box).
    for (name, side) in [("a", 0.1), ("b", 0.08), ("c", 0.06)] {
        let m = sys.bodies.info[index(&sys, name)].mass;
        let expected = RHO * side * side * side;
        assert!((m - expected).abs() < 1e-12 * expected, "{name}: {m} kg, expected {expected} kg");
    }
    let (rock, _) = Polyhedron::from_points(&rock_vertices(&scene), Polyhedron::MERGE_ANGLE).unwrap();
    assert_eq!(sys.bodies.info[4].mass, RHO * rock.volume);
    assert_eq!(sys.bodies.info[4].inertia, rock.inertia_per_density * RHO);

    // Cube "b" is given by its vertices with a corner at its frame's origin: its centroid is at
    // position + R (0.04, 0.04, 0.04), R the 30° turn about z, and its principal frame is R (three equal moments).
    let b = index(&sys, "b");
    let r = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::PI / 6.0);
    let centroid = Vec3::new(0.25, 0.0, 0.003) + r * Vec3::repeat(0.04);
    assert!((sys.bodies.pose[b].position - centroid).norm() < 1e-15, "{:?}", sys.bodies.pose[b].position);
    assert!(sys.bodies.pose[b].rotation.angle_to(&r) < 1e-15);

    // The rock: every vertex of the built body is the rotation-vector turn of an input vertex, moved by position
    // (the vertices are in the body's own frame; position and orientation place that frame).
    let r = UnitQuaternion::from_scaled_axis(Vec3::new(0.2, 0.1, 0.0));
    let placed: Vec<Vec3> =
        rock_vertices(&scene).iter().map(|v| Vec3::new(0.0, 0.3, 0.02) + r * Vec3::from(*v)).collect();
    let Solid::Polyhedron(built) = &sys.bodies.info[4].solid else { panic!("the rock is a polyhedron") };
    for v in &built.vertices {
        let world = sys.bodies.pose[4].point(v);
        assert!(placed.iter().any(|p| (p - world).norm() < 1e-14), "vertex {world:?} is not an input vertex placed");
    }
    let (_, frame) = Polyhedron::from_points(&rock_vertices(&scene), Polyhedron::MERGE_ANGLE).unwrap();
    let centroid = Vec3::new(0.0, 0.3, 0.02) + r * frame.position;
    assert!((sys.bodies.pose[4].position - centroid).norm() < 1e-15);

    // Everything starts at rest.
    assert!(sys.bodies.u.iter().all(|u| u.iter().all(|&x| x == 0.0)));
}

/// Vertices written in world coordinates with `position = [0, 0, 0]` stay where they are.
#[test]
fn vertices_at_the_origin_frame_stay_where_they_are() {
    let text = edit(
        "position = [0.0, 0.3, 0.02]\norientation = { rotation_vector = [0.2, 0.1, 0.0] }\n",
        "position = [0.0, 0.0, 0.0]\n",
    );
    let scene = Scene3::from_toml_str(&text).unwrap();
    let sys = scene.build().unwrap();
    let (_, frame) = Polyhedron::from_points(&rock_vertices(&scene), Polyhedron::MERGE_ANGLE).unwrap();
    assert_eq!(sys.bodies.pose[4].position, frame.position);
    let Solid::Polyhedron(built) = &sys.bodies.info[4].solid else { panic!("the rock is a polyhedron") };
    for v in &built.vertices {
        let world = sys.bodies.pose[4].point(v);
        assert!(rock_vertices(&scene).iter().any(|p| (Vec3::from(*p) - world).norm() < 1e-15), "{world:?}");
    }
}

/// The same rotation as a quaternion and as a rotation vector gives the same pose; velocity and spin set the
/// centroid's velocity (`velocity + spin × R c`) and the spin in the principal frame.
#[test]
fn quaternion_and_rotation_vector_give_the_same_pose() {
    let axis = nalgebra::Unit::new_normalize(Vec3::new(1.0, 2.0, 3.0));
    let angle = 0.7;
    let q = UnitQuaternion::from_axis_angle(&axis, angle);
    let (w, x, y, z) = (q.w, q.i, q.j, q.k);
    let rv = axis.into_inner() * angle;
    let from = "orientation = { rotation_vector = [0.2, 0.1, 0.0] }";
    let with_q = edit(from, &format!("orientation = {{ quaternion = [{w:?}, {x:?}, {y:?}, {z:?}] }}"));
    let with_rv = edit(from, &format!("orientation = {{ rotation_vector = [{:?}, {:?}, {:?}] }}", rv.x, rv.y, rv.z));
    let a = Scene3::from_toml_str(&with_q).unwrap().build().unwrap();
    let b = Scene3::from_toml_str(&with_rv).unwrap().build().unwrap();
    assert!((a.bodies.pose[4].position - b.bodies.pose[4].position).norm() < 1e-16);
    assert!(a.bodies.pose[4].rotation.angle_to(&b.bodies.pose[4].rotation) < 1e-15);

    // A moving start: the centroid's velocity and the spin in the principal frame.
    let moving = edit(from, &format!("{from}\nvelocity = [0.1, -0.2, 0.3]\nspin = [1.0, 2.0, -3.0]"));
    let scene = Scene3::from_toml_str(&moving).unwrap();
    let sys = scene.build().unwrap();
    let r = UnitQuaternion::from_scaled_axis(Vec3::new(0.2, 0.1, 0.0));
    let (_, frame) = Polyhedron::from_points(&rock_vertices(&scene), Polyhedron::MERGE_ANGLE).unwrap();
    let spin = Vec3::new(1.0, 2.0, -3.0);
    let (v, w) = sys.bodies.world_velocity(4);
    assert!((v - (Vec3::new(0.1, -0.2, 0.3) + spin.cross(&(r * frame.position)))).norm() < 1e-15);
    assert!((w - spin).norm() < 1e-14, "{w:?}");
}

/// `to_toml_string` reads back to the same scene and the same system; a state written back after some steps
/// (`with_state`) reads back to the system's poses and velocities.
#[test]
fn scenes_and_states_round_trip() {
    let scene = example();
    let text = scene.to_toml_string().unwrap();
    let again = Scene3::from_toml_str(&text).unwrap();
    assert_eq!(again, scene);
    assert_eq!(again.build().unwrap().bodies, scene.build().unwrap().bodies);

    let mut sys = scene.build().unwrap();
    for _ in 0..40 {
        sys.step().unwrap();
    }
    let saved = scene.with_state(&sys);
    let restarted = Scene3::from_toml_str(&saved.to_toml_string().unwrap()).unwrap().build().unwrap();
    for i in 0..sys.bodies.len() {
        let (p, q) = (&sys.bodies.pose[i], &restarted.bodies.pose[i]);
        assert!((p.position - q.position).norm() < 1e-15, "body {i}: {p:?} vs {q:?}");
        assert!(p.rotation.angle_to(&q.rotation) < 1e-14, "body {i}");
        for k in 0..6 {
            assert!((sys.bodies.u[i][k] - restarted.bodies.u[i][k]).abs() < 1e-14, "body {i} dof {k}");
        }
    }
    // Fixed bodies are left as given; mobile ones get a quaternion with w ≥ 0.
    assert_eq!(saved.bodies[0], scene.bodies[0]);
    let q = saved.bodies[4].orientation.unwrap().quaternion.unwrap();
    assert!(q[0] >= 0.0);
    assert!((Quaternion::new(q[0], q[1], q[2], q[3]).norm() - 1.0).abs() < 1e-15);
}

/// Physics, not only parsing: after 200 steps (0.2 s) every cube rests flat on the floor, its centroid at its
/// half height to 1 µm (measured: 1e-11 m; the landings are plastic and the solve tight, quad 1e-6) and its turn
/// about z the one it was given; the rock, which lands on an edge, rests on a face, not sunk into the floor.
#[test]
fn the_cubes_come_to_rest_on_the_floor() {
    let mut sys = example().build().unwrap();
    let start: Vec<_> = sys.bodies.pose.clone();
    for _ in 0..200 {
        sys.step().unwrap();
    }
    for (name, half) in [("a", 0.05), ("b", 0.04), ("c", 0.03)] {
        let i = index(&sys, name);
        let z = sys.bodies.pose[i].position.z;
        assert!((z - half).abs() < 1e-6, "cube {name}: centroid at {z} m, half height {half} m");
        assert!(sys.bodies.pose[i].rotation.angle_to(&start[i].rotation) < 1e-6, "cube {name} turned");
        assert!((sys.bodies.pose[i].position.xy() - start[i].position.xy()).norm() < 1e-6, "cube {name} slid");
        let (v, w) = sys.bodies.world_velocity(i);
        assert!(v.norm() < 1e-9 && w.norm() < 1e-9, "cube {name} still moves: {v:?} m/s, {w:?} rad/s");
    }
    let Solid::Polyhedron(rock) = &sys.bodies.info[4].solid else { panic!("the rock is a polyhedron") };
    let heights: Vec<f64> = rock.vertices.iter().map(|v| sys.bodies.pose[4].point(v).z).collect();
    let lowest = heights.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(lowest > -1e-6, "the rock sank {lowest} m into the floor");
    assert!(heights.iter().filter(|&&z| z < 1e-6).count() >= 3, "the rock is not on a face: {heights:?}");
    assert!(sys.bodies.kinetic_energy() < 1e-12, "still moving: {} J", sys.bodies.kinetic_energy());
}

/// The example with the rock's `polyhedron` table replaced by `table`.
fn with_rock(table: &str) -> String {
    let start = EXAMPLE.rfind("polyhedron = { vertices = [").unwrap();
    let end = start + EXAMPLE[start..].find("] }\n").unwrap() + 4;
    format!("{}polyhedron = {table}\n{}", &EXAMPLE[..start], &EXAMPLE[end..])
}

#[test]
fn a_degenerate_hull_is_refused() {
    let coplanar =
        "{ vertices = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.05, 0.05, 0.0], [0.02, 0.03, 0.0]] }";
    expect(&with_rock(coplanar), &["body[4] 'rock': polyhedron.vertices: degenerate polyhedron"]);
    let three = "{ vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }";
    expect(&with_rock(three), &["body[4] 'rock': polyhedron.vertices: a polyhedron needs at least 4 vertices, got 3"]);
    let flat = "{ vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 2.0]] }";
    expect(&with_rock(flat), &["invalid length 4", "vertices"]);
    let angle =
        "{ vertices = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]], merge_angle = 0.5 }";
    expect(
        &with_rock(angle),
        &["body[4] 'rock': polyhedron.merge_angle: merge_angle must be finite and in [0, 0.1] rad"],
    );
    // A tetrahedron given by its corners builds, with the volume a b c / 6.
    let tet = "{ vertices = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]], merge_angle = 0.01 }";
    let sys = Scene3::from_toml_str(&with_rock(tet)).unwrap().build().unwrap();
    let expected = RHO * 1e-3 / 6.0;
    assert!((sys.bodies.info[4].mass - expected).abs() < 1e-12 * expected);
}

#[test]
fn orientations_are_checked() {
    let q = "orientation = { quaternion = [0.9659258262890683, 0.0, 0.0, 0.25881904510252074] }";
    expect(
        &edit(q, "orientation = { quaternion = [1.0, 0.0, 0.0, 1.0] }"),
        &["body[2] 'b': orientation.quaternion: must be a unit quaternion [w, x, y, z]", "got |q| = 1.414"],
    );
    // Seven significant digits pass (and are normalised).
    Scene3::from_toml_str(&edit(q, "orientation = { quaternion = [0.9659258, 0.0, 0.0, 0.2588190] }")).unwrap();
    expect(&edit(q, "orientation = { quaternion = [1.0, 0.0, 0.0] }"), &["invalid length 3", "quaternion"]);
    expect(
        &edit(q, "orientation = { quaternion = [1.0, 0.0, 0.0, 0.0], rotation_vector = [0.0, 0.0, 1.0] }"),
        &["body[2] 'b': orientation: give one of quaternion, rotation_vector, not both"],
    );
    expect(
        &edit(q, "orientation = {}"),
        &["body[2] 'b': orientation: give quaternion = [w, x, y, z] or rotation_vector"],
    );
    expect(
        &edit("rotation_vector = [0.0, 0.0, 0.4]", "rotation_vector = [0.0, nan, 0.4]"),
        &["body[3] 'c': orientation.rotation_vector: must be finite"],
    );
    expect(
        &edit("fixed = true", "fixed = true\norientation = { rotation_vector = [0.1, 0.0, 0.0] }"),
        &["body[0] 'floor': orientation: a plane is oriented by its normal"],
    );
}

#[test]
fn shapes_and_sizes_are_checked() {
    let a = "box = { half = [0.05, 0.05, 0.05] }";
    expect(
        &edit(a, "sphere = { radius = -0.01 }"),
        &["body[1] 'a': sphere.radius: must be positive and finite, got -0.01"],
    );
    expect(
        &edit(a, "box = { half = [0.05, 0.0, 0.05] }"),
        &["body[1] 'a': box.half: size must be positive and finite, got 0"],
    );
    expect(&edit(a, "box = { half = [0.05, 0.05] }"), &["invalid length 2", "half"]);
    expect(&edit(a, ""), &["body[1] 'a': shape: missing, give exactly one of polyhedron, box, sphere, plane"]);
    expect(&edit(a, &format!("{a}\nsphere = {{ radius = 0.05 }}")), &["body[1] 'a': shape: give exactly one of"]);
    expect(
        &edit("normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 0.0]"),
        &["body[0] 'floor': plane.normal: must be a finite non-zero vector, got [0, 0, 0]"],
    );
    expect(&edit(a, "box = { half = [1e-12, 1e-12, 1e-12] }"), &["body[1] 'a': shape: the body's size"]);
    expect(&edit("position = [0.0, 0.0, 0.052]", "position = [0.0, 0.0]"), &["invalid length 2", "position"]);
    expect(
        &edit("position = [0.0, 0.0, 0.052]", "position = [0.0, 0.0, 1e10]"),
        &["body[1] 'a': position: coordinates must be within"],
    );
    // A sphere builds.
    let sys = Scene3::from_toml_str(&edit(a, "sphere = { radius = 0.05 }")).unwrap().build().unwrap();
    let expected = RHO * 4.0 / 3.0 * std::f64::consts::PI * 0.05f64.powi(3);
    assert!((sys.bodies.info[1].mass - expected).abs() < 1e-12 * expected);
}

#[test]
fn materials_contacts_and_fixed_bodies() {
    expect(
        &edit("name = \"a\"\nmaterial = \"grain\"", "name = \"a\"\nmaterial = \"sand\""),
        &["body[1] 'a': material: unknown material 'sand'"],
    );
    expect(&edit("density = 2400.0", "density = -1.0"), &["material[1] 'concrete': density: must be positive"]);
    expect(
        &edit("between = [\"grain\", \"grain\"]", "between = [\"grain\", \"sand\"]"),
        &["contact[1].between: unknown material 'sand'"],
    );
    expect(
        &edit("between = [\"grain\", \"grain\"]", "between = [\"grain\", \"probe\"]"),
        &["contact[1].between: unknown material 'probe'"],
    );
    expect(&edit("friction = 0.5", "friction = -0.5"), &["contact[0].friction: must be non-negative"]);
    // A pair without a law is frictionless and plastic, as in 2D: the scene builds.
    let no_law = edit("[[contact]]\nbetween = [\"grain\", \"grain\"]\nfriction = 0.5\n", "");
    Scene3::from_toml_str(&no_law).unwrap().build().unwrap();
    // A half-space must be fixed; fixed bodies do not move.
    expect(
        &edit("fixed = true\n", ""),
        &["body[0] 'floor': plane: a half-space can only be a fixed body, add fixed = true"],
    );
    expect(
        &edit("fixed = true", "fixed = true\nvelocity = [0.0, 0.0, 1.0]"),
        &["body[0] 'floor': velocity: a fixed body does not move (give a moving wall fixed = false and imposed velocities)"],
    );
    expect(
        &edit("fixed = true", "fixed = true\nspin = [0.0, 0.0, 1.0]"),
        &["body[0] 'floor': spin: a fixed body does not turn"],
    );
    expect(&edit("name = \"c\"", "name = \"a\""), &["body[3] 'a': name: duplicate body name (also body[1])"]);
    // A fixed box is a wall.
    let wall = edit("position = [0.0, 0.0, 0.052]", "position = [0.0, 0.0, 0.052]\nfixed = true");
    let sys = Scene3::from_toml_str(&wall).unwrap().build().unwrap();
    assert!(sys.bodies.info[1].fixed && sys.bodies.inv_m[1] == [0.0; 6]);
}

/// The example with body "a" guided along z (imposed `vx`, `vy`, spin) under a harmonic force and a moment, and
/// body "b" (given by its vertices, a corner at its frame's origin, turned 30° about z) on a spring from the
/// middle of its bottom face to a world anchor 0.1 m below it.
fn driven() -> String {
    let a = "position = [0.0, 0.0, 0.052]";
    let drives = "imposed = { vx = 0.0, vy = { mean = 0.0 }, spin = [0.0, 0.0, 0.0] }\n\
                  load = { direction = [0.0, 0.0, -2.0], mean = -10.0, amplitude = -5.0, frequency = 20.0 }\n\
                  torque = { direction = [1.0, 0.0, 0.0], mean = 0.5 }";
    let spring =
        "[[spring]]\nbody = \"b\"\npoint = [0.04, 0.04, 0.0]\nanchor = [0.25, 0.0, -0.097]\nk_n = 1000.0\nnu = 2.0\n";
    format!("{}\n{spring}", edit(a, &format!("{a}\n{drives}")))
}

/// Where the example puts the middle of body "b"'s bottom face: its frame's corner at `position`, turned 30°
/// about z.
fn bottom_of_b() -> Vec3 {
    let turn = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::PI / 6.0);
    Vec3::new(0.25, 0.0, 0.003) + turn * Vec3::new(0.04, 0.04, 0.0)
}

#[test]
fn loads_imposed_velocities_and_springs_build() {
    let scene = Scene3::from_toml_str(&driven()).unwrap();
    let sys = scene.build().unwrap();
    let a = &sys.bodies.info[1];
    // vx, vy and the spin imposed: only v_z is free.
    assert_eq!(sys.bodies.inv_m[1][..2], [0.0, 0.0]);
    assert_eq!(sys.bodies.inv_m[1][3..], [0.0, 0.0, 0.0]);
    assert!((sys.bodies.inv_m[1][2] - 1.0 / a.mass).abs() < 1e-15 / a.mass);
    assert_eq!(a.loads.len(), 2);
    // The force: −10 − 5 cos(2π 20 t) along −z, normalised; the moment 0.5 N·m about x.
    assert!((a.loads[0].at(0.0) - Vec3::new(0.0, 0.0, 15.0)).norm() < 1e-12);
    assert!((a.loads[1].at(0.3) - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
    // The spring: its first end where the scene put it, the anchor where given, the rest length the initial one.
    let s = &sys.springs[0];
    let b = index(&sys, "b");
    let pose = &sys.bodies.pose[b];
    let end = pose.position + pose.rotation * s.point_a;
    assert!((end - bottom_of_b()).norm() < 1e-12, "{end:?} vs {:?}", bottom_of_b());
    assert_eq!((s.a, s.b, s.point_b), (b, None, Vec3::new(0.25, 0.0, -0.097)));
    assert!((s.rest_length - (bottom_of_b() - s.point_b).norm()).abs() < 1e-15);
    assert_eq!((s.k_n, s.nu, s.compression_only), (1000.0, 2.0, false));
    // Written and read back: the same scene, the same system; a state written back names the rest length.
    let text = scene.to_toml_string().unwrap();
    let again = Scene3::from_toml_str(&text).unwrap();
    assert_eq!(again, scene);
    assert_eq!(again.build().unwrap().springs, sys.springs);
    let saved = scene.with_state(&sys);
    assert_eq!(saved.springs[0].rest_length, Some(s.rest_length));
}

#[test]
fn loads_imposed_velocities_and_springs_are_checked() {
    let text = driven();
    let bad = |from: &str, to: &str| {
        assert!(text.contains(from), "test bug: {from:?}");
        text.replacen(from, to, 1)
    };
    let load = "direction = [0.0, 0.0, -2.0]";
    expect(
        &bad(load, "direction = [0.0, 0.0, 0.0]"),
        &["body[1] 'a': load.direction: must be a finite non-zero vector"],
    );
    expect(&bad("mean = 0.5", "mean = nan"), &["body[1] 'a': torque.mean: must be finite"]);
    expect(&bad("vy = { mean = 0.0 }", "vy = { mean = 0.0, amplitude = inf }"), &["body[1] 'a': imposed.vy.amplitude"]);
    expect(&bad("spin = [0.0, 0.0, 0.0]", "spin = [0.0, nan, 0.0]"), &["body[1] 'a': imposed.spin[1]"]);
    expect(&bad("spin = [0.0, 0.0, 0.0]", "spin = [0.0, 0.0]"), &["spin"]);
    expect(&bad("spin = [0.0, 0.0, 0.0]", "wz = 0.0"), &["wz"]);
    let on_floor = |key: &str| text.replacen("fixed = true", &format!("fixed = true\n{key}"), 1);
    expect(
        &on_floor("imposed = { vz = 1.0 }"),
        &["body[0] 'floor': imposed: a fixed body cannot have imposed velocities"],
    );
    let push = "{ direction = [0.0, 0.0, 1.0], mean = 1.0 }";
    expect(&on_floor(&format!("load = {push}")), &["body[0] 'floor': load: a fixed body cannot carry a load"]);
    expect(&on_floor(&format!("torque = {push}")), &["body[0] 'floor': torque: a fixed body cannot carry a torque"]);
    let anchor = "anchor = [0.25, 0.0, -0.097]";
    expect(&bad("body = \"b\"", "body = \"z\""), &["spring[0].body: unknown body 'z'"]);
    expect(
        &bad(anchor, &format!("{anchor}\nother = \"a\"")),
        &["spring[0].anchor: give either anchor or other, not both"],
    );
    expect(&bad(anchor, ""), &["spring[0].anchor: missing, give either anchor or other"]);
    expect(&bad(anchor, "other = \"b\""), &["spring[0].other: the spring joins body 'b' to itself"]);
    expect(
        &bad(anchor, &format!("{anchor}\nother_point = [0.0, 0.0, 0.0]")),
        &["spring[0].other_point: only allowed with other"],
    );
    expect(&bad("k_n = 1000.0", "k_n = -1.0"), &["spring[0].k_n: must be non-negative"]);
    expect(&bad("nu = 2.0", "nu = -2.0"), &["spring[0].nu: must be non-negative"]);
    expect(&bad(anchor, "anchor = [0.25, 0.0, nan]"), &["spring[0].anchor[2]: must be finite"]);
    // The anchor at the attachment: no initial length, so the rest length must be given.
    let at = bottom_of_b();
    let zero = bad(anchor, &format!("anchor = [{:?}, {:?}, {:?}]", at.x, at.y, at.z));
    let m = message(&zero);
    assert!(
        m.starts_with("spring[0].rest_length: the initial length is") && m.ends_with("give a positive rest_length")
    );
    Scene3::from_toml_str(&format!("{zero}rest_length = 0.1\n")).unwrap().build().unwrap();
}

#[test]
fn simulation_and_nscd_sections() {
    expect(&edit("dimension = 3\n", ""), &["simulation.dimension: a 3D NSCD scene says dimension = 3"]);
    expect(
        &edit("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, -9.81]"),
        &["simulation.gravity: a 3D scene needs 3 components, got 2"],
    );
    expect(&edit("dt = 1.0e-3", "dt = 1.0e-3\nthickness = 1.0"), &["simulation.thickness: only for 2D scenes"]);
    expect(&edit("engine = \"nscd\"", "engine = \"md\""), &["simulation.engine: expected 'nscd', got 'md'"]);
    expect(&edit("tolerance = 1.0e-6", "tolerance = 2.0"), &["nscd.tolerance: must be in (0, 1), got 2"]);
    expect(
        &edit("criterion = \"quad\"", "criterion = \"quadratic\""),
        &["nscd.criterion: unknown criterion 'quadratic'"],
    );
    expect(&edit("[nscd]", "[nscd]\ntheta = 0.2"), &["nscd.theta: must be in [0.5, 1], got 0.2"]);
    expect(
        &edit("[nscd]", "[nscd]\nsolver = \"interior_point\""),
        &["nscd.solver: 'interior_point' solves the step as a linear complementarity problem"],
    );
    let accelerated = edit("[nscd]", "[nscd]\nsolver = \"apgd\"");
    let sys = Scene3::from_toml_str(&accelerated).unwrap().build().unwrap();
    assert_eq!(sys.params.nlgs.solver, ballast::nscd::method::Solver::Apgd, "apgd is taken in 3D");
    let stopping = edit("[nscd]", "[nscd]\non_stall = \"stop\"");
    let sys = Scene3::from_toml_str(&stopping).unwrap().build().unwrap();
    assert_eq!(sys.params.nlgs.on_stall, ballast::nscd::method::OnStall::Stop, "on_stall = stop is taken in 3D");
    expect(&edit("alert_distance = 1.0e-3", "alert_distance = -1.0"), &["nscd.alert_distance: must be non-negative"]);
    // The face–face gap rule: exact by default, LMGC90's common plane on request, kept through a round trip.
    assert_eq!(example().build().unwrap().params.face_gaps, FaceGaps::Exact);
    let common = Scene3::from_toml_str(&edit("[nscd]", "[nscd]\nface_gaps = \"common_plane\"")).unwrap();
    assert_eq!(common.build().unwrap().params.face_gaps, FaceGaps::CommonPlane);
    let again = Scene3::from_toml_str(&common.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.build().unwrap().params.face_gaps, FaceGaps::CommonPlane);
    expect(
        &edit("[nscd]", "[nscd]\nface_gaps = \"flat\""),
        &["nscd.face_gaps: unknown rule 'flat', expected 'exact' or 'common_plane'"],
    );
    // The overlap law: kept by default, held on request, kept through a round trip.
    assert_eq!(example().build().unwrap().params.overlaps, Overlaps::Kept);
    let held = Scene3::from_toml_str(&edit("[nscd]", "[nscd]\noverlaps = \"held\"")).unwrap();
    assert_eq!(held.build().unwrap().params.overlaps, Overlaps::Held);
    let again = Scene3::from_toml_str(&held.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.build().unwrap().params.overlaps, Overlaps::Held);
    expect(
        &edit("[nscd]", "[nscd]\noverlaps = \"gap\""),
        &["nscd.overlaps: unknown rule 'gap', expected 'kept' or 'held'"],
    );
    // The settings that apply are taken as given.
    let tuned = edit(
        "[nscd]",
        "[nscd]\ntheta = 0.6\nsymmetric = true\nrelaxation = 1.2\non_stall = \"extend\"\nstall_max_iterations = 5000",
    );
    let sys = Scene3::from_toml_str(&tuned).unwrap().build().unwrap();
    assert_eq!(sys.params.theta, 0.6);
    assert!(
        sys.params.nlgs.symmetric && sys.params.nlgs.relaxation == 1.2 && sys.params.nlgs.stall_max_iterations == 5000
    );
    // Without [nscd] the defaults of 2D scenes, and the alert distance from the smallest inner radius.
    let start = EXAMPLE.find("[nscd]").unwrap();
    let end = EXAMPLE.find("[output]").unwrap();
    let plain = format!("{}{}", &EXAMPLE[..start], &EXAMPLE[end..]);
    let sys = Scene3::from_toml_str(&plain).unwrap().build().unwrap();
    assert_eq!(sys.params.nlgs, ballast::nscd::NlgsSettings::default());
    let inner = sys.bodies.info[1..]
        .iter()
        .map(|b| match &b.solid {
            Solid::Polyhedron(p) => p.inradius,
            _ => f64::INFINITY,
        })
        .fold(f64::INFINITY, f64::min);
    assert_eq!(sys.params.alert_distance, ballast::nscd::system::DEFAULT_ALERT_FRACTION * inner);
}

#[test]
fn outputs_and_settlement_name_bodies() {
    let cycles = edit("every = 10", "every = 10\ncycles = { frequency = 10.0, body = \"a\", positions = true }");
    let scene = Scene3::from_toml_str(&cycles).unwrap();
    assert_eq!(scene.plan().unwrap().cycles.unwrap().body, Some(1));
    expect(
        &edit("every = 10", "every = 10\ncycles = { frequency = 10.0, body = \"z\" }"),
        &["output.cycles.body: unknown body 'z'"],
    );
    let settle = format!("{cycles}\n[settlement]\ninitial_cycles = 1\ncomputed_cycles = 2\nextrapolated_cycles = 2\n");
    let scene = Scene3::from_toml_str(&settle).unwrap();
    assert_eq!(scene.acceleration().unwrap().unwrap().cycles, 5);
    let fixed = format!("{settle}settlement_body = \"floor\"\n");
    expect(&fixed, &["settlement.settlement_body: body 'floor' is fixed"]);
    let again = Scene3::from_toml_str(&scene.to_toml_string().unwrap()).unwrap();
    assert_eq!(again, scene);
}

#[test]
fn unknown_keys_and_syntax() {
    expect(&edit("name = \"rock\"", "name = \"rock\"\ncolour = 1"), &["unknown field `colour`", "colour = 1"]);
    expect(&edit("[output]", "[soft]\nmodel = \"linear\"\n[output]"), &["unknown field `soft`"]);
    expect(&edit("box = { half", "box = { size = [0.1, 0.1, 0.1], half"), &["unknown field `size`"]);
    expect(&edit("dt = 1.0e-3", "dt = 1.0e-3 3"), &["scene.toml line"]);
}

/// Which format a file is: the 2D scene refuses a 3D one and names the 3D type; the `engine` override of a
/// run cannot put a 3D NSCD scene on an MD engine.
#[test]
fn the_kind_of_a_scene() {
    // A 2D scene given dimension = 3 is told where 3D NSCD scenes are read.
    let block = include_str!("../examples/block_on_floor.toml");
    let lifted = block.replacen("engine = \"nscd\"", "engine = \"nscd\"\ndimension = 3", 1);
    match Scene::from_toml_str(&lifted) {
        Err(Error::Scene(m)) => {
            assert!(m.contains("simulation.dimension: must be 2 for the nscd engine, got 3"), "{m}");
            assert!(m.contains("scene::Scene3"), "{m}");
        }
        other => panic!("a 3D scene read as 2D: {other:?}"),
    }
    match ballast::scene::scene_on(EXAMPLE, "cubes3d.toml", SceneKind::Nscd, false) {
        Err(Error::Scene(m)) => assert!(m.contains("is read with scene::Scene3"), "{m}"),
        other => panic!("a 3D scene set on the 2D engine: {other:?}"),
    }
    assert!(!SceneKind::is_nscd3(block, "block.toml").unwrap());
    assert!(!SceneKind::is_nscd3(include_str!("../examples/md_two_spheres.toml"), "md.toml").unwrap());
    for engine in ["md", "md2d"] {
        match SceneKind::of(EXAMPLE, "cubes3d.toml", Some(engine)) {
            Err(Error::Scene(m)) => assert!(m.contains("does not run 3D NSCD scenes"), "{m}"),
            other => panic!("{engine}: {other:?}"),
        }
    }
    assert_eq!(SceneKind::of(block, "block.toml", Some("md2d")).unwrap(), SceneKind::PlanarMd);
}

/// The scene file opens on the 3D NSCD engine through the one registration point (`open::open`: `SceneKind::Nscd3`)
/// and runs through the run loop: `final.json` says `nscd3d` and holds the cubes at rest on the floor, the
/// same state as the system stepped here directly (the run loop adds nothing to the mechanics); an engine
/// override for 2D is refused by name.
#[test]
fn the_scene_file_opens_and_runs_on_the_3d_engine() {
    use ballast::engine::final_state::FinalState;
    use ballast::open::{open, Loaded};
    use ballast::run::RunOptions;
    let dir = scratch::dir("open");
    let path = dir.join("cubes3d.toml");
    std::fs::write(&path, EXAMPLE).unwrap();
    assert_eq!(SceneKind::of(EXAMPLE, "cubes3d.toml", None).unwrap(), SceneKind::Nscd3);
    let quiet = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let loaded = open(&path, &quiet).unwrap();
    assert!(matches!(loaded, Loaded::Nscd3(_)));
    let out = dir.join("run");
    loaded.run(&out, &quiet, &mut |_| {}).unwrap();
    let fin = FinalState::read(&out.join("final.json")).unwrap();
    assert_eq!(fin.engine, "nscd3d");
    let mut sys = example().build().unwrap();
    while sys.steps < fin.step {
        sys.step().unwrap();
    }
    for (i, b) in fin.bodies.iter().enumerate() {
        let p = sys.bodies.pose[i].position;
        assert_eq!(b.position, vec![p.x, p.y, p.z], "body {i} '{}'", b.name);
    }
    let a = &fin.bodies[index(&sys, "a")];
    assert!((a.position[2] - 0.05).abs() < 1e-6, "cube a rests at z = {} m", a.position[2]);
    let refused = open(&path, &RunOptions { engine: Some("md2d".into()), ..quiet.clone() });
    assert!(matches!(refused, Err(Error::Scene(m)) if m.starts_with("engine:")));
    std::fs::remove_dir_all(&dir).unwrap();
}
