//! MD scene files (`engine = "md"`): round trip through `to_toml_string`, the
//! system they build (masses, laws, walls, settings), the state written back,
//! and one test per class of validation error, each checking that the one-line
//! message names the section, the entry and the field.

use ballast::md::{self, Damping, Drive, GearSet, History1, Integrator, Model, Motion, Shape, V3};
use ballast::scene::SceneFile;
use ballast::scene::{engine_of, MdScene, Scene};
use std::f64::consts::PI;

/// A small valid scene: two materials, a Hertz and a linear law, a floor, a
/// cylinder, three spheres.
const BASE: &str = r#"
[simulation]
engine = "md"
dt = 1e-6
duration = 1e-4

[[material]]
name = "glass"
density = 2500.0
young = 6e10
poisson = 0.22

[[material]]
name = "steel"
density = 7800.0
young = 2e11
poisson = 0.3

[[contact]]
between = ["glass", "glass"]
model = "hertz"
friction = 0.3
normal_damping_ratio = 0.2

[[contact]]
between = ["steel", "glass"]
model = "linear"
static_friction = 0.4
dynamic_friction = 0.3
normal_stiffness = 1e5
tangential_stiffness = 5e4
normal_damping = 0.01

[[wall]]
name = "floor"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 2.0] }

[[wall]]
name = "mould"
material = "steel"
cylinder = { axis_point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 0.01 }

[[body]]
name = "s0"
material = "glass"
sphere = 0.001
position = [0.0, 0.0, 0.0011]

[[body]]
name = "s1"
material = "glass"
sphere = 0.002
position = [0.003, 0.0, 0.0021]
velocity = [0.0, 0.1, 0.0]

[[body]]
name = "s2"
material = "glass"
sphere = 0.0015
position = [0.0, 0.004, 0.005]
spin = [1.0, 2.0, 3.0]
"#;

/// A scene with every key of the format.
const FULL: &str = r#"
[simulation]
engine = "md"
dimension = 3
dt = 1e-6
duration = 2e-5
gravity = [0.1, 0.0, -9.81]
seed = 7
equilibrium = { kinetic_energy = 1e-9, energy_ratio = 1e-6, steps = 20 }

[md]
integrator = "gear"
gear = "gear5"
skin = 2e-4
background_damping = 0.2
background_rotational_damping = 0.05
threads = 2

[output]
every = 10

[[symmetry]]
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]

[[symmetry]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 3.0, 0.0]

[[material]]
name = "diorite"
density = 2710.0
young = 46.9e9
poisson = 0.25

[[material]]
name = "steel"
density = 7850.0
young = 200e9
poisson = 0.3

[[contact]]
between = ["diorite", "diorite"]
model = "hertz"
friction = 0.5
restitution = 0.5
tangential_damping_ratio = 0.1

[[contact]]
between = ["diorite", "steel"]
model = "linear"
friction = 0.25
normal_stiffness = 2e5
tangential_stiffness = 1e5
restitution = 0.8
tangential_damping = 0.001

[[wall]]
name = "base"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

[[wall]]
name = "x_max"
material = "steel"
plane = { point = [0.03, 0.0, 0.0], normal = [-1.0, 0.0, 0.0] }

[[wall]]
name = "y_max"
material = "steel"
plane = { point = [0.0, 0.03, 0.0], normal = [0.0, -1.0, 0.0] }

[[wall]]
name = "x_min"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }

[[wall]]
name = "y_min"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] }

[[wall]]
name = "top"
material = "steel"
disc = { point = [0.0, 0.0, 0.02], normal = [0.0, 0.0, -1.0], radius = 0.05 }
servo = { mass = 2.0, viscosity = 200.0, stress = 1000.0, amplitude = 200.0, period = 10.0 }

[[wall]]
name = "press"
material = "steel"
plane = { point = [0.0, 0.0, 0.025], normal = [0.0, 0.0, -1.0] }
servo = { mass = 1.0, viscosity = 50.0, force = 3.5 }

[[wall]]
name = "pad"
material = "steel"
disc = { point = [0.0, 0.0, 0.03], normal = [0.0, 0.0, -1.0], radius = 0.01 }
servo = { mass = 1.0, viscosity = 50.0, stress = 10.0, area = 0.0003 }

[[body]]
name = "a"
material = "diorite"
sphere = 0.0032
position = [0.004, 0.004, 0.0035]
velocity = [0.0, 0.0, -0.1]
spin = [0.0, 1.0, 0.0]

[[body]]
material = "diorite"
sphere = 0.003
position = [0.0105, 0.004, 0.0031]
"#;

/// `BASE` with the first `from` replaced by `to`.
fn edit(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "test bug: {from:?} not in the base scene");
    BASE.replacen(from, to, 1)
}

/// The validation message of `text`, which must be invalid.
fn message(text: &str) -> String {
    match MdScene::from_toml_str(text) {
        Ok(_) => panic!("scene accepted:\n{text}"),
        Err(e) => {
            let m = e.to_string();
            assert!(!m.contains('\n'), "multi-line message {m:?}");
            m
        }
    }
}

/// Asserts that `text` is refused with a message containing every part.
fn expect(text: &str, parts: &[&str]) {
    let m = message(text);
    for p in parts {
        assert!(m.contains(p), "message {m:?} does not contain {p:?}");
    }
}

#[test]
fn base_and_full_scenes_are_valid() {
    let base = MdScene::from_toml_str(BASE).unwrap();
    assert_eq!((base.steps(), base.seed(), base.output_every(), base.threads()), (100, 0, 1, None));
    let full = MdScene::from_toml_str(FULL).unwrap();
    assert_eq!((full.steps(), full.seed(), full.output_every(), full.threads()), (20, 7, 10, Some(2)));
}

#[test]
fn written_scene_reads_back_equal() {
    for text in [BASE, FULL] {
        let scene = MdScene::from_toml_str(text).unwrap();
        let written = scene.to_toml_string().unwrap();
        let again = MdScene::from_toml_str(&written).unwrap_or_else(|e| panic!("{e}\n{written}"));
        assert_eq!(again, scene, "{written}");
        assert_eq!(again.to_toml_string().unwrap(), written, "the writer is a fixed point");
    }
    // Floats keep every bit.
    let odd = edit("sphere = 0.001\n", "sphere = 0.0010000000000000002\n");
    let scene = MdScene::from_toml_str(&odd).unwrap();
    let again = MdScene::from_toml_str(&scene.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.bodies[0].sphere.to_bits(), 0.0010000000000000002f64.to_bits());
}

#[test]
fn built_system_has_the_masses_laws_and_walls_of_the_scene() {
    let scene = MdScene::from_toml_str(BASE).unwrap();
    let sys = scene.build().unwrap();
    let p = &sys.particles;
    assert_eq!(p.len(), 3);
    for (i, b) in scene.bodies.iter().enumerate() {
        let m = 4.0 / 3.0 * PI * b.sphere.powi(3) * 2500.0;
        assert!((p.m[i] - m).abs() <= 1e-14 * m, "mass of {}: {} vs {m}", b.name, p.m[i]);
        assert!((1.0 / p.inv_i[i] - 0.4 * m * b.sphere * b.sphere).abs() <= 1e-14 * m * b.sphere * b.sphere);
        assert_eq!(p.x[i], V3::from(b.position));
        assert_eq!(p.name[i], b.name);
        assert_eq!(p.material[i], 0);
    }
    assert_eq!(p.v[1], V3::new(0.0, 0.1, 0.0));
    assert_eq!(p.w[2], V3::new(1.0, 2.0, 3.0));

    // Hertz glass–glass: E* = E / (2(1 − ν²)), G* = G / (2(2 − ν)).
    let (e, nu) = (6e10, 0.22);
    let g = e / (2.0 * (1.0 + nu));
    let hertz = sys.laws.get(0, 0).unwrap();
    assert_eq!(hertz.model, Model::Hertz);
    assert!((hertz.e_star - e / (2.0 * (1.0 - nu * nu))).abs() < 1e-6 * hertz.e_star);
    assert!((hertz.g_star - g / (2.0 * (2.0 - nu))).abs() < 1e-6 * hertz.g_star);
    assert_eq!((hertz.mu_s, hertz.mu_d), (0.3, 0.3));
    assert_eq!((hertz.damping_n, hertz.damping_t), (Damping::Ratio(0.2), Damping::Ratio(0.2)), "α_t = α_n");

    // Linear steel–glass, in both orders.
    let linear = sys.laws.get(1, 0).unwrap();
    assert_eq!(sys.laws.get(0, 1), Some(linear));
    assert_eq!(linear.model, Model::Linear);
    assert_eq!((linear.kn, linear.kt, linear.mu_s, linear.mu_d), (1e5, 5e4, 0.4, 0.3));
    assert_eq!((linear.damping_n, linear.damping_t), (Damping::Coefficient(0.01), Damping::Coefficient(0.0)));
    assert!(sys.laws.get(1, 1).is_none(), "steel never touches steel");

    // Walls: normals normalised, fixed.
    assert_eq!(sys.walls.len(), 2);
    assert_eq!(sys.walls[0].shape, Shape::Plane { point: V3::zeros(), normal: V3::z() });
    assert_eq!(sys.walls[1].shape, Shape::Cylinder { axis_point: V3::zeros(), axis: V3::z(), radius: 0.01 });
    assert!(sys.walls.iter().all(|w| w.motion == Motion::Fixed && w.material == 1));
    // Defaults: Verlet, gravity −9.81 ẑ, skin 0.1 × mean diameter, no damping.
    let s = sys.settings;
    assert_eq!((s.dt, s.integrator, s.gravity), (1e-6, Integrator::Verlet, V3::new(0.0, 0.0, -9.81)));
    let mean_diameter = 2.0 * (0.001 + 0.002 + 0.0015) / 3.0;
    assert!((s.skin - 0.1 * mean_diameter).abs() < 1e-15);
    assert_eq!((s.background_damping, s.background_rotational_damping), (0.0, 0.0));
    assert!(sys.ghosts.planes.is_empty());
}

#[test]
fn restitution_servo_walls_symmetry_and_settings_reach_the_engine() {
    let scene = MdScene::from_toml_str(FULL).unwrap();
    let sys = scene.build().unwrap();
    let (diorite, steel) = (
        md::Material { density: 2710.0, young: 46.9e9, poisson: 0.25 },
        md::Material { density: 7850.0, young: 200e9, poisson: 0.3 },
    );
    // Hertz with a restitution: α_n from the model's exact mapping, α_t given.
    let hertz = sys.laws.get(0, 0).unwrap();
    let alpha = md::law::hertz_alpha_for_restitution(0.5);
    assert_eq!(*hertz, md::PairLaw::hertz(&diorite, &diorite, alpha, 0.1, 0.5));
    assert!((md::law::hertz_restitution(alpha) - 0.5).abs() < 1e-6);
    // Linear with a restitution: the exact ratio of a linear spring–dashpot.
    let linear = sys.laws.get(0, 1).unwrap();
    let ratio = md::law::linear_alpha_for_restitution(0.8);
    assert_eq!(linear.damping_n, Damping::Ratio(ratio));
    assert_eq!(linear.damping_t, Damping::Coefficient(0.001));
    assert_eq!((linear.mu_s, linear.mu_d), (0.25, 0.25));
    // E* and G* of two materials.
    let e_star = 1.0 / ((1.0 - 0.25f64.powi(2)) / 46.9e9 + (1.0 - 0.3f64.powi(2)) / 200e9);
    let g = |m: &md::Material| m.young / (2.0 * (1.0 + m.poisson));
    let g_star = 1.0 / ((2.0 - 0.25) / g(&diorite) + (2.0 - 0.3) / g(&steel));
    assert!((md::law::e_star(&diorite, &steel) - e_star).abs() < 1e-6 * e_star);
    assert!((md::law::g_star(&diorite, &steel) - g_star).abs() < 1e-6 * g_star);

    let s = sys.settings;
    assert_eq!(s.integrator, Integrator::Gear(GearSet::Gear5));
    assert_eq!((s.skin, s.background_damping, s.background_rotational_damping), (2e-4, 0.2, 0.05));
    assert_eq!(s.gravity, V3::new(0.1, 0.0, -9.81));
    assert_eq!(sys.threads(), 2);
    let normals: Vec<V3> = sys.ghosts.planes.iter().map(|p| p.normal).collect();
    assert_eq!(normals, [V3::x(), V3::y()], "normalised");

    let motion = |name: &str| sys.walls.iter().find(|w| w.name == name).unwrap().motion;
    let history = |base, amplitude, period| History1 { base, amplitude, period };
    assert_eq!(
        motion("top"),
        Motion::Servo { mass: 2.0, viscosity: 200.0, drive: Drive::Stress(history(1000.0, 200.0, 10.0), None) }
    );
    assert_eq!(
        motion("press"),
        Motion::Servo { mass: 1.0, viscosity: 50.0, drive: Drive::Force(history(3.5, 0.0, 0.0)) }
    );
    assert_eq!(
        motion("pad"),
        Motion::Servo { mass: 1.0, viscosity: 50.0, drive: Drive::Stress(history(10.0, 0.0, 0.0), Some(3e-4)) }
    );
    assert_eq!(motion("base"), Motion::Fixed);
    // The box of the top wall: 3 cm × 3 cm.
    assert!((md::walls::box_area(&sys.walls, 2) - 9e-4).abs() < 1e-15);
}

#[test]
fn state_written_back_restarts_from_where_the_run_stopped() {
    let scene = MdScene::from_toml_str(FULL).unwrap();
    let mut sys = scene.build().unwrap();
    for _ in 0..scene.steps() {
        sys.step().unwrap();
    }
    let top = sys.walls.iter().position(|w| w.name == "top").unwrap();
    assert!(sys.walls[top].s != 0.0, "the servo wall moved");
    let saved = scene.with_state(&sys);
    let again = MdScene::from_toml_str(&saved.to_toml_string().unwrap()).unwrap();
    assert_eq!(again, saved);
    let p = &sys.particles;
    for (i, b) in again.bodies.iter().enumerate() {
        assert_eq!((V3::from(b.position), V3::from(b.velocity()), V3::from(b.spin())), (p.x[i], p.v[i], p.w[i]));
    }
    let disc = again.walls[top].disc.unwrap();
    assert_eq!(disc.point[2], 0.02 - sys.walls[top].s, "moved along its normal (−z)");
    assert_eq!(again.walls[0], scene.walls[0], "fixed walls unchanged");
    let restarted = again.build().unwrap();
    assert_eq!(restarted.walls[top].point(), sys.walls[top].point());
}

#[test]
fn engine_of_tells_the_formats_apart() {
    assert_eq!(engine_of(BASE).unwrap(), "md");
    let nscd = "[simulation]\nengine = \"nscd\"\ndt = 1e-3\nduration = 1.0\n";
    assert_eq!(engine_of(nscd).unwrap(), "nscd");
    let e = engine_of(&BASE.replace("engine = \"md\"", "engine = \"dem\"")).unwrap_err().to_string();
    assert_eq!(e, "simulation.engine: unknown engine 'dem', expected 'nscd', 'md2d' or 'md'");
    let e = engine_of(&BASE.replace("engine = \"md\"\n", "")).unwrap_err().to_string();
    assert!(e.starts_with("scene.toml line 2: missing field `engine`"), "{e}");
    let e = engine_of("[simulation\n").unwrap_err().to_string();
    assert!(e.starts_with("scene.toml line 1:"), "{e}");
    // Each scene type refuses the other engine.
    expect(&BASE.replace("engine = \"md\"", "engine = \"nscd\""), &["simulation.engine: expected 'md'", "Scene"]);
    let e = Scene::from_toml_str(&nscd.replace("\"nscd\"", "\"md\"")).unwrap_err().to_string();
    assert!(e.contains("simulation.engine") && e.contains("MdScene"), "{e}");
}

#[test]
fn syntax_errors_unknown_keys_missing_keys_and_vector_lengths() {
    expect(
        &edit("poisson = 0.22\n", "poisson = 0.22\nhardness = 3.0\n"),
        &["scene.toml line 12: unknown field `hardness`"],
    );
    expect(&edit("young = 6e10\n", ""), &["missing field `young`", "[[material]]"]);
    expect(&edit("[[wall]]\nname = \"floor\"", "[[wall]]\nname = \"floor\"\nheight = 1"), &["unknown field `height`"]);
    expect(
        &edit("position = [0.0, 0.0, 0.0011]", "position = [0.0, 0.0]"),
        &["line 48", "invalid length 2, expected an array of exactly 3 elements"],
    );
    expect(&edit("normal = [0.0, 0.0, 2.0] }", "normal = [0.0, 0.0, 2.0, 1.0] }"), &["exactly 3 elements"]);
    expect(&edit("[simulation]", "[simulation"), &["scene.toml line 2:"]);
    expect(&edit("dt = 1e-6\n", ""), &["missing field `dt`"]);
    expect(&edit("duration = 1e-4\n", "duration = 1e-4\n\n[output]\ncycle = 3\n"), &["unknown field `cycle`"]);
    expect(
        &edit("duration = 1e-4\n", "duration = 1e-4\n\n[output]\ncycles = 3\n"),
        &["line", "expected struct CyclesSpec"],
    );
    expect(
        &edit("duration = 1e-4\n", "duration = 1e-4\n\n[output]\ncycles = { frequency = -1.0 }\n"),
        &["output.cycles.frequency: must be positive and finite, got -1"],
    );
}

#[test]
fn sphere_radius_density_and_young_must_be_positive() {
    expect(
        &edit("sphere = 0.002", "sphere = -0.001"),
        &["body[1] 's1': sphere: must be positive and finite, got -0.001"],
    );
    expect(&edit("sphere = 0.001", "sphere = 0.0"), &["body[0] 's0': sphere: must be positive"]);
    expect(&edit("density = 2500.0", "density = 0.0"), &["material[0] 'glass': density: must be positive"]);
    expect(&edit("young = 2e11", "young = -2e11"), &["material[1] 'steel': young: must be positive"]);
    expect(&edit("young = 6e10", "young = inf"), &["material[0] 'glass': young: must be positive and finite"]);
}

#[test]
fn poisson_must_be_in_minus_one_half() {
    for bad in ["0.5", "-1.0", "0.7", "nan"] {
        expect(
            &edit("poisson = 0.22", &format!("poisson = {bad}")),
            &["material[0] 'glass': poisson: must be in (-1, 0.5)"],
        );
    }
    MdScene::from_toml_str(&edit("poisson = 0.22", "poisson = -0.5")).unwrap();
}

#[test]
fn time_step_duration_and_skin_ranges() {
    expect(&edit("dt = 1e-6", "dt = 0.0"), &["simulation.dt: must be positive and finite, got 0"]);
    expect(&edit("dt = 1e-6", "dt = -1e-6"), &["simulation.dt: must be positive"]);
    expect(&edit("duration = 1e-4", "duration = -1.0"), &["simulation.duration: must be positive"]);
    expect(&edit("duration = 1e-4", "duration = 1e-7"), &["simulation.duration", "shorter than half a time step"]);
    let md = |skin: &str| edit("[[material]]", &format!("[md]\nskin = {skin}\n\n[[material]]"));
    expect(&md("0.0"), &["md.skin: must be positive and finite, got 0"]);
    expect(&md("-1e-3"), &["md.skin: must be positive"]);
    expect(&md("1e12"), &["md.skin: must be at most"]);
    expect(&edit("[[material]]", "[md]\nbackground_damping = -1.0\n\n[[material]]"), &["md.background_damping"]);
    expect(&edit("[[material]]", "[md]\nthreads = 0\n\n[[material]]"), &["md.threads: must be at least 1"]);
    expect(
        &edit("[[material]]", "[md]\nintegrator = \"euler\"\n\n[[material]]"),
        &["md.integrator: unknown integrator 'euler'"],
    );
    expect(
        &edit("[[material]]", "[md]\ngear = \"gear4\"\n\n[[material]]"),
        &["md.gear: only with integrator = \"gear\""],
    );
    expect(
        &edit("[[material]]", "[md]\nintegrator = \"gear\"\ngear = \"gear9\"\n\n[[material]]"),
        &["md.gear: unknown set 'gear9'"],
    );
    expect(
        &edit("duration = 1e-4", "duration = 1e-4\ngravity = [0.0, nan, 0.0]"),
        &["simulation.gravity[1]: must be finite"],
    );
}

#[test]
fn zero_normals_are_refused() {
    expect(
        &edit("normal = [0.0, 0.0, 2.0]", "normal = [0.0, 0.0, 0.0]"),
        &["wall[0] 'floor': plane.normal: must be a non-zero vector, got [0, 0, 0]"],
    );
    expect(
        &edit("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 0.0]"),
        &["wall[1] 'mould': cylinder.axis: must be a non-zero"],
    );
    let symmetry =
        edit("[[material]]", "[[symmetry]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]\n\n[[material]]");
    expect(&symmetry, &["symmetry[0].normal: must be a non-zero vector"]);
    let disc = edit(
        "plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 2.0] }",
        "disc = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 0.0], radius = 0.1 }",
    );
    expect(&disc, &["wall[0] 'floor': disc.normal: must be a non-zero vector"]);
}

#[test]
fn unknown_material_names_are_refused() {
    expect(
        &edit("material = \"glass\"\nsphere = 0.002", "material = \"rock\"\nsphere = 0.002"),
        &["body[1] 's1': material: unknown material 'rock'"],
    );
    expect(
        &edit("name = \"floor\"\nmaterial = \"steel\"", "name = \"floor\"\nmaterial = \"iron\""),
        &["wall[0] 'floor': material: unknown material 'iron'"],
    );
    expect(
        &edit("between = [\"steel\", \"glass\"]", "between = [\"steel\", \"gass\"]"),
        &["contact[1].between: unknown material 'gass'"],
    );
    expect(&edit("name = \"steel\"", "name = \"glass\""), &["material[1].name: duplicate material 'glass'"]);
}

#[test]
fn every_pair_that_can_touch_needs_a_law() {
    // Sphere–wall.
    let no_wall_law =
        edit("[[contact]]\nbetween = [\"steel\", \"glass\"]", "[[contact]]\nbetween = [\"steel\", \"steel\"]");
    expect(&no_wall_law, &[
        "contact: no [[contact]] between materials 'glass' and 'steel', which can touch (body[0] 's0' and wall[0] 'floor')",
    ]);
    // Sphere–sphere.
    let no_sphere_law = edit("between = [\"glass\", \"glass\"]", "between = [\"steel\", \"steel\"]");
    expect(
        &no_sphere_law,
        &["contact: no [[contact]] between materials 'glass' and 'glass'", "body[0] 's0' and body[1] 's1'"],
    );
    // One sphere of its material touches only its symmetry image.
    let alone = no_sphere_law
        .replace("material = \"glass\"\nsphere = 0.002", "material = \"steel\"\nsphere = 0.002")
        .replace("material = \"glass\"\nsphere = 0.0015", "material = \"steel\"\nsphere = 0.0015");
    MdScene::from_toml_str(&alone).unwrap();
    let mirrored = alone.replacen(
        "[[material]]",
        "[[symmetry]]\npoint = [0.0, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n\n[[material]]",
        1,
    );
    expect(&mirrored, &["materials 'glass' and 'glass'", "body[0] 's0' and its symmetry image"]);
    // A pair nothing uses needs no law; a duplicate law is refused.
    let dup = edit(
        "[[wall]]",
        "[[contact]]\nbetween = [\"glass\", \"glass\"]\nmodel = \"hertz\"\nfriction = 0.1\n\n[[wall]]",
    );
    expect(&dup, &["contact[2].between: duplicate law for materials 'glass' and 'glass' (also contact[0])"]);
}

#[test]
fn contradictory_contact_keys_are_refused() {
    expect(
        &edit("static_friction = 0.4", "friction = 0.2\nstatic_friction = 0.4"),
        &["contact[1].static_friction: give either friction or static_friction and dynamic_friction, not both"],
    );
    expect(
        &edit("normal_damping = 0.01", "normal_damping = 0.01\nrestitution = 0.5"),
        &["contact[1].normal_damping: give either restitution or normal_damping, not both"],
    );
    expect(
        &edit("normal_damping_ratio = 0.2", "normal_damping_ratio = 0.2\nrestitution = 0.5"),
        &["contact[0].normal_damping_ratio: give either restitution or normal_damping_ratio, not both"],
    );
    // Keys of the other model.
    expect(
        &edit("normal_damping_ratio = 0.2", "normal_damping_ratio = 0.2\nnormal_stiffness = 1e5"),
        &["contact[0].normal_stiffness: not a key of model 'hertz' (only of 'linear')"],
    );
    expect(
        &edit("friction = 0.3", "static_friction = 0.3\ndynamic_friction = 0.2"),
        &["contact[0].static_friction: not a key of model 'hertz'"],
    );
    expect(
        &edit("normal_damping = 0.01", "normal_damping = 0.01\ntangential_damping_ratio = 0.1"),
        &["contact[1].tangential_damping_ratio: not a key of model 'linear' (only of 'hertz')"],
    );
    // Incomplete or out-of-range laws.
    expect(
        &edit("dynamic_friction = 0.3", "dynamic_friction = 0.5"),
        &["contact[1].dynamic_friction: must not exceed static_friction = 0.4, got 0.5"],
    );
    expect(&edit("dynamic_friction = 0.3\n", ""), &["contact[1].dynamic_friction: missing"]);
    expect(&edit("friction = 0.3\n", ""), &["contact[0].friction: missing"]);
    expect(&edit("friction = 0.3", "friction = -0.3"), &["contact[0].friction: must be non-negative"]);
    expect(
        &edit("tangential_stiffness = 5e4\n", ""),
        &["contact[1].tangential_stiffness: missing, required by model 'linear'"],
    );
    expect(
        &edit("normal_stiffness = 1e5", "normal_stiffness = 0.0"),
        &["contact[1].normal_stiffness: must be positive"],
    );
    expect(
        &edit("normal_damping_ratio = 0.2", "restitution = 0.0"),
        &["contact[0].restitution: must be in (0, 1], got 0"],
    );
    expect(&edit("normal_damping_ratio = 0.2", "restitution = 1.5"), &["contact[0].restitution: must be in (0, 1]"]);
    expect(&edit("model = \"hertz\"", "model = \"hooke\""), &["contact[0].model: unknown model 'hooke'"]);
}

#[test]
fn dimension_must_be_3() {
    expect(
        &edit("dt = 1e-6", "dimension = 2\ndt = 1e-6"),
        &["simulation.dimension: must be 3 for the md engine, got 2"],
    );
    MdScene::from_toml_str(&edit("dt = 1e-6", "dimension = 3\ndt = 1e-6")).unwrap();
}

#[test]
fn at_most_two_perpendicular_symmetry_planes() {
    // Through (−5, −5, 0) mm: every sphere on the side the normals point to.
    let plane = |n: &str| format!("[[symmetry]]\npoint = [-0.005, -0.005, 0.0]\nnormal = {n}\n\n");
    let with = |normals: &[&str]| {
        let planes: String = normals.iter().map(|n| plane(n)).collect();
        edit("[[material]]", &format!("{planes}[[material]]"))
    };
    MdScene::from_toml_str(&with(&["[1.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]"])).unwrap();
    expect(
        &with(&["[1.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]", "[0.0, 0.0, 1.0]"]),
        &["symmetry: at most 2 symmetry planes, got 3"],
    );
    expect(
        &with(&["[1.0, 0.0, 0.0]", "[1.0, 1.0, 0.0]"]),
        &["symmetry[1].normal: two symmetry planes must be perpendicular", "0.7071"],
    );
}

#[test]
fn servo_walls() {
    let servo = |table: &str| edit("radius = 0.01 }", &format!("radius = 0.01 }}\nservo = {table}"));
    expect(
        &servo("{ mass = 1.0, viscosity = 1.0, force = 1.0 }"),
        &["wall[1] 'mould': servo: only plane and disc walls can be servo walls, not a cylinder"],
    );
    let on_floor =
        |table: &str| edit("normal = [0.0, 0.0, 2.0] }", &format!("normal = [0.0, 0.0, 2.0] }}\nservo = {table}"));
    expect(
        &on_floor("{ mass = 1.0, viscosity = 1.0, stress = 1.0, force = 1.0, area = 1.0 }"),
        &["wall[0] 'floor': servo: give either stress or force, not both"],
    );
    expect(&on_floor("{ mass = 1.0, viscosity = 1.0 }"), &["wall[0] 'floor': servo: missing stress or force"]);
    expect(
        &on_floor("{ mass = 0.0, viscosity = 1.0, force = 1.0 }"),
        &["wall[0] 'floor': servo.mass: must be positive"],
    );
    expect(&on_floor("{ mass = 1.0, viscosity = -1.0, force = 1.0 }"), &["servo.viscosity: must be non-negative"]);
    expect(
        &on_floor("{ mass = 1.0, viscosity = 1.0, force = 1.0, area = 1.0 }"),
        &["wall[0] 'floor': servo.area: only with stress"],
    );
    expect(
        &on_floor("{ mass = 1.0, viscosity = 1.0, force = 1.0, period = -1.0 }"),
        &["servo.period: must be non-negative"],
    );
    expect(&on_floor("{ mass = 1.0, viscosity = 1.0, mass2 = 1.0 }"), &["unknown field `mass2`"]);
    // A stress without an area needs the box of the other walls.
    expect(&on_floor("{ mass = 1.0, viscosity = 1.0, stress = 1.0 }"), &[
        "wall[0] 'floor': servo.area: omitted, but no plane or disc walls with normals ±x and ±y close a box around the z axis",
    ]);
    MdScene::from_toml_str(&on_floor("{ mass = 1.0, viscosity = 1.0, stress = 1.0, area = 1e-4 }")).unwrap();
}

#[test]
fn overlapping_spheres_are_allowed() {
    // s1 (r = 2 mm) 2.95 mm from s0 (r = 1 mm): 0.05 mm into it, 5 % of the
    // smaller radius (at most 10 % allowed: tests/md_safety.rs). Released, the
    // pair separates at 41 m/s: the Hertz contacts need dt below 8e-7 s then.
    let dx = (0.00295f64.powi(2) - 0.001f64.powi(2)).sqrt();
    let text = edit("position = [0.003, 0.0, 0.0021]", &format!("position = [{dx:?}, 0.0, 0.0021]"))
        .replace("dt = 1e-6", "dt = 5e-7");
    let scene = MdScene::from_toml_str(&text).unwrap();
    let sys = scene.build().unwrap();
    assert!((sys.last.max_overlap - 5e-5).abs() < 1e-9, "overlap {}", sys.last.max_overlap);
}

#[test]
fn other_body_and_wall_errors_name_the_entry() {
    expect(&edit("name = \"s1\"", "name = \"s0\""), &["body[1] 's0': name: duplicate body name (also body[0])"]);
    expect(&edit("name = \"mould\"", "name = \"floor\""), &["wall[1].name: duplicate wall 'floor' (also wall[0])"]);
    expect(&edit("name = \"mould\"", "name = \"\""), &["wall[1].name: must not be empty"]);
    expect(
        &edit("position = [0.0, 0.004, 0.005]", "position = [0.0, nan, 0.005]"),
        &["body[2] 's2': position: must be finite"],
    );
    expect(
        &edit("velocity = [0.0, 0.1, 0.0]", "velocity = [0.0, inf, 0.0]"),
        &["body[1] 's1': velocity: must be finite"],
    );
    expect(&edit("radius = 0.01 }", "radius = 0.0 }"), &["wall[1] 'mould': cylinder.radius: must be positive"]);
    let two = edit("cylinder = {", "plane = { point = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }\ncylinder = {");
    expect(&two, &["wall[1] 'mould': shape: give exactly one of plane, disc, cylinder, not several"]);
    let none = edit("cylinder = { axis_point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 0.01 }\n", "");
    expect(&none, &["wall[1] 'mould': shape: missing"]);
    let nobody = BASE[..BASE.find("[[body]]").unwrap()].to_string();
    expect(&nobody, &["body: the scene has no [[body]]"]);
    expect(&edit("[[material]]", "[output]\nevery = 0\n\n[[material]]"), &["output.every: must be at least 1, got 0"]);
    let eq = |table: &str| edit("duration = 1e-4", &format!("duration = 1e-4\nequilibrium = {table}"));
    expect(&eq("{ steps = 10 }"), &["simulation.equilibrium: give kinetic_energy (J), energy_ratio (E_k/E_p) or both"]);
    expect(&eq("{ kinetic_energy = 0.0 }"), &["simulation.equilibrium.kinetic_energy: must be positive"]);
    expect(&eq("{ energy_ratio = 1e-3, steps = 0 }"), &["simulation.equilibrium.steps: must be at least 1"]);
}
