//! Scene validation: every class of error gives one `Error::Scene` line naming
//! the field and the body or section; valid scenes build, and `with_state`
//! round-trips the state.

use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::Error;

/// A valid scene with a floor, a block, a pentagon with an imposed velocity and
/// a load, a disc, and two springs.
const BASE: &str = r#"
[simulation]
engine = "nscd"
dt = 1.0e-3
duration = 0.01
gravity = [0.0, -9.81]
thickness = 1.0
seed = 7

[nscd]
theta = 0.5
criterion = "quad"
tolerance = 1.0e-4
min_iterations = 1
max_iterations = 1000
max_factor = 16.0

[output]
every = 2

[[material]]
name = "grain"
density = 2367.0

[[material]]
name = "steel"
density = 7800.0

[[contact]]
between = ["grain", "grain"]
friction = 0.5
restitution = 0.0
tangential_restitution = 0.0

[[contact]]
between = ["grain", "steel"]
friction = 0.3

[[body]]
name = "floor"
material = "steel"
polygon = [[-1.0, -0.1], [1.0, -0.1], [1.0, 0.0], [-1.0, 0.0]]
position = [0.0, 0.0]
fixed = true

[[body]]
name = "block"
material = "grain"
polygon = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]
position = [0.2, 0.001]
angle = 0.3
velocity = [0.1, -0.2]
spin = 1.5

[[body]]
name = "pad0"
material = "grain"
regular = { sides = 5, radius = 0.05 }
position = [-0.3, 0.2]
imposed = { vx = 0.0, spin = { mean = 0.0, amplitude = 0.1, frequency = 5.0, phase = 0.5 } }
load = { direction = [0.0, 2.0], mean = -1000.0, amplitude = -500.0, frequency = 20.0, phase = -3.141592653589793 }

[[body]]
material = "grain"
disc = 0.02
position = [0.5, 0.3]

[[spring]]
body = "pad0"
point = [0.01, 0.0]
anchor = [-0.3, 0.1]
k_n = 4100.0
nu = 80.0

[[spring]]
body = "block"
point = [0.05, 0.05]
other = "pad0"
other_point = [0.0, 0.0]
k_n = 100.0
rest_length = 0.5
prestrain = 0.01
compression_only = false
"#;

/// `BASE` with the first occurrence of `from` replaced by `to` (which must exist).
fn edit(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "test bug: {from:?} not in the base scene");
    BASE.replacen(from, to, 1)
}

/// The scene error message of `text`, checked to be a single line.
fn message(text: &str) -> String {
    let m = match Scene::from_toml_str(text) {
        Err(Error::Scene(m)) => {
            assert!(!m.contains('\n'), "multi-line message: {m:?}");
            assert!(!m.is_empty());
            m
        }
        Err(e) => panic!("expected a scene error, got {e:?}"),
        Ok(_) => panic!("expected a scene error, the scene was accepted"),
    };
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

#[test]
fn base_scene_is_valid_and_builds() {
    let scene = Scene::from_toml_str(BASE).unwrap();
    assert_eq!(scene.steps(), 10);
    assert_eq!(scene.seed(), 7);
    assert_eq!(scene.output_every(), 2);
    let sys = scene.build().unwrap();
    assert_eq!(sys.bodies.len(), 4);
    assert_eq!(sys.springs.len(), 2);
    assert_eq!(sys.materials, 2);
    assert_eq!(sys.bodies.info[1].name, "block");
    // Block: mass = density * area * thickness, centre of mass at origin + R c.
    let b = &sys.bodies.info[1];
    assert!((b.mass - 2367.0 * 0.01).abs() < 1e-9);
    assert!((b.inertia - 2367.0 * 0.01 * 0.01 / 6.0).abs() < 1e-12);
    let (s, c) = 0.3f64.sin_cos();
    let rc = [c * 0.05 - s * 0.05, s * 0.05 + c * 0.05];
    let q = sys.bodies.q[1];
    assert!((q[0] - (0.2 + rc[0])).abs() < 1e-15 && (q[1] - (0.001 + rc[1])).abs() < 1e-15);
    // Velocity of the centre of mass = v + spin × (R c).
    let u = sys.bodies.u[1];
    assert!((u[0] - (0.1 - 1.5 * rc[1])).abs() < 1e-15);
    assert!((u[1] - (-0.2 + 1.5 * rc[0])).abs() < 1e-15);
    // Load direction is normalised; the imposed vx and spin have zero inverse mass.
    let pad = &sys.bodies.info[2];
    assert_eq!(pad.loads[0].direction, [0.0, 1.0]);
    assert_eq!(sys.bodies.inv_m[2][0], 0.0);
    assert!(sys.bodies.inv_m[2][1] > 0.0);
    assert_eq!(sys.bodies.inv_m[2][2], 0.0);
    // Default alert distance: 1% of the smallest inner radius of the mobile bodies
    // (the square's 0.05 m, the pentagon's 0.05 cos 36°, the disc's 0.02 m).
    assert!((sys.params.alert_distance - 0.01 * 0.02).abs() < 1e-15);
    // Spring rest length defaults to the initial length.
    let pad_point = [-0.3 + 0.01, 0.2];
    assert!((sys.springs[0].rest_length - (pad_point[1] - 0.1_f64).hypot(pad_point[0] + 0.3)).abs() < 1e-12);
    let p = sys.springs[1].point_a; // the block's centroid
    assert!(p[0].abs() < 1e-15 && p[1].abs() < 1e-15);
    // Friction between the materials.
    assert_eq!(sys.laws[1].friction, 0.3);
    assert_eq!(sys.laws[2].friction, 0.3);
    assert_eq!(sys.laws[0].friction, 0.5);
    assert_eq!(sys.laws[3].friction, 0.0);
}

#[test]
fn with_state_round_trips_positions() {
    let scene = Scene::from_toml_str(BASE).unwrap();
    let sys = scene.build().unwrap();
    let again = scene.with_state(&sys).build().unwrap();
    for i in 0..sys.bodies.len() {
        for d in 0..3 {
            assert!((sys.bodies.q[i][d] - again.bodies.q[i][d]).abs() < 1e-12, "q[{i}][{d}]");
            assert!((sys.bodies.u[i][d] - again.bodies.u[i][d]).abs() < 1e-12, "u[{i}][{d}]");
        }
    }
    for (a, b) in sys.springs.iter().zip(&again.springs) {
        assert!((a.rest_length - b.rest_length).abs() < 1e-12);
    }
}

#[test]
fn with_state_after_steps_round_trips_through_toml() {
    let scene = Scene::from_toml_str(BASE).unwrap();
    let mut sys = scene.build().unwrap();
    for _ in 0..scene.steps() {
        sys.step().unwrap();
    }
    let saved = scene.with_state(&sys);
    let text = saved.to_toml_string().unwrap();
    let reread = Scene::from_toml_str(&text).unwrap();
    assert_eq!(reread, saved);
    let restarted = reread.build().unwrap();
    for i in 0..sys.bodies.len() {
        for d in 0..3 {
            assert!((sys.bodies.q[i][d] - restarted.bodies.q[i][d]).abs() < 1e-12, "q[{i}][{d}]");
        }
    }
    // The springs keep the rest length they had.
    let original = scene.build().unwrap();
    assert_eq!(restarted.springs[0].rest_length, original.springs[0].rest_length);
}

#[test]
fn examples_parse_build_and_round_trip() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    for name in ["block_on_floor", "sleeper_load", "imposed_velocity", "sublayer_spring"] {
        let scene = Scene::load(format!("{dir}/{name}.toml")).unwrap_or_else(|e| panic!("{name}: {e}"));
        scene.build().unwrap();
        let again = Scene::from_toml_str(&scene.to_toml_string().unwrap()).unwrap();
        assert_eq!(again, scene, "{name}");
    }
}

#[test]
fn unknown_key() {
    expect(&edit("seed = 7", "seed = 7\nfoo = 1"), &["line 9", "unknown field `foo`"]);
    expect(&edit("disc = 0.02", "disc = 0.02\ncolour = 1"), &["unknown field `colour`", "colour = 1"]);
    expect(&edit("vx = 0.0,", "vz = 0.0,"), &["unknown field `vz`"]);
    expect(&edit("[output]", "[outputs]"), &["unknown field `outputs`"]);
    expect(&edit("mean = 0.0, amplitude", "mean = 0.0, amp = 1, amplitude"), &["unknown field `amp`"]);
}

#[test]
fn syntax_error() {
    expect(&edit("dt = 1.0e-3", "dt = 1.0e-3 3"), &["scene.toml line 4"]);
    expect(&edit("[simulation]", "[simulation"), &["scene.toml line 2"]);
}

#[test]
fn missing_field() {
    expect(&edit("duration = 0.01\n", ""), &["missing field `duration`"]);
    expect(&edit("density = 7800.0\n", ""), &["missing field `density`"]);
    expect(&edit("material = \"grain\"\ndisc", "disc"), &["missing field `material`"]);
    expect(&edit("k_n = 100.0\n", ""), &["missing field `k_n`"]);
    expect(&edit("[simulation]", "[simulations]"), &["unknown field `simulations`"]);
    let no_simulation = BASE.split("[nscd]").nth(1).map(|rest| format!("[nscd]{rest}")).unwrap();
    expect(&no_simulation, &["scene.toml: missing field `simulation`"]);
}

#[test]
fn wrong_type_or_length() {
    expect(&edit("dt = 1.0e-3", "dt = \"fast\""), &["line 4", "invalid type", "dt = \"fast\""]);
    expect(&edit("position = [0.5, 0.3]", "position = [0.5, 0.3, 0.0]"), &["invalid length 3", "position"]);
    expect(&edit("between = [\"grain\", \"steel\"]", "between = [\"grain\"]"), &["invalid length 1", "between"]);
    expect(&edit("seed = 7", "seed = -7"), &["seed = -7"]);
}

#[test]
fn bad_polygon() {
    let nonconvex = "polygon = [[0.0, 0.0], [0.1, 0.0], [0.05, 0.02], [0.1, 0.1], [0.0, 0.1]]";
    expect(
        &edit("polygon = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]", nonconvex),
        &["body[1] 'block': polygon: non-convex polygon: the turn at vertex"],
    );
    let clockwise = "polygon = [[0.0, 0.0], [0.0, 0.1], [0.1, 0.1], [0.1, 0.0]]";
    expect(
        &edit("polygon = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]", clockwise),
        &["body[1] 'block': polygon:", "counter-clockwise"],
    );
    let degenerate = "polygon = [[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]]";
    expect(
        &edit("polygon = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]", degenerate),
        &["body[1] 'block': polygon: degenerate polygon"],
    );
    let two = "polygon = [[0.0, 0.0], [0.1, 0.0]]";
    expect(&edit("polygon = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]", two), &["body[1] 'block': polygon:"]);
    expect(&edit("sides = 5", "sides = 2"), &["body[2] 'pad0': regular:"]);
    expect(&edit("disc = 0.02", "disc = -0.02"), &["body[3]: disc:"]);
}

#[test]
fn non_positive_quantities() {
    expect(&edit("dt = 1.0e-3", "dt = -0.001"), &["simulation.dt: must be positive and finite, got -0.001"]);
    expect(&edit("dt = 1.0e-3", "dt = 0.0"), &["simulation.dt:"]);
    expect(&edit("duration = 0.01", "duration = 0"), &["simulation.duration:"]);
    expect(&edit("duration = 0.01", "duration = 1e-5"), &["simulation.duration:", "half a time step"]);
    expect(&edit("thickness = 1.0", "thickness = -1.0"), &["simulation.thickness:"]);
    expect(&edit("density = 2367.0", "density = 0.0"), &["material[0] 'grain': density"]);
    expect(&edit("k_n = 4100.0", "k_n = -1.0"), &["spring[0].k_n"]);
    expect(&edit("nu = 80.0", "nu = -1.0"), &["spring[0].nu"]);
    expect(&edit("rest_length = 0.5", "rest_length = 0.0"), &["spring[1].rest_length"]);
}

#[test]
fn non_finite_numbers() {
    expect(&edit("dt = 1.0e-3", "dt = nan"), &["simulation.dt:"]);
    expect(&edit("gravity = [0.0, -9.81]", "gravity = [0.0, -inf]"), &["simulation.gravity[1]: must be finite"]);
    expect(&edit("position = [0.2, 0.001]", "position = [0.2, nan]"), &["body[1] 'block': position"]);
    expect(&edit("angle = 0.3", "angle = inf"), &["body[1] 'block': angle: must be finite"]);
    expect(&edit("velocity = [0.1, -0.2]", "velocity = [inf, -0.2]"), &["body[1] 'block': velocity"]);
    expect(&edit("spin = 1.5", "spin = nan"), &["body[1] 'block': spin"]);
    expect(&edit("amplitude = 0.1", "amplitude = nan"), &["body[2] 'pad0': imposed.spin.amplitude"]);
    expect(&edit("vx = 0.0", "vx = inf"), &["body[2] 'pad0': imposed.vx"]);
    expect(&edit("mean = -1000.0", "mean = nan"), &["body[2] 'pad0': load.mean"]);
    expect(&edit("[0.1, 0.0], [0.1, 0.1]", "[0.1, 0.0], [0.1, inf]"), &["body[1] 'block': polygon:", "not finite"]);
    expect(&edit("prestrain = 0.01", "prestrain = nan"), &["spring[1].prestrain"]);
    expect(&edit("anchor = [-0.3, 0.1]", "anchor = [nan, 0.1]"), &["spring[0].anchor"]);
    expect(&edit("friction = 0.5", "friction = inf"), &["contact[0].friction"]);
    expect(&edit("position = [0.2, 0.001]", "position = [0.2, 1e300]"), &["body[1] 'block': position"]);
}

#[test]
fn friction_and_restitution_ranges() {
    expect(&edit("friction = 0.5", "friction = -0.1"), &["contact[0].friction"]);
    expect(&edit("restitution = 0.0", "restitution = 1.5"), &["contact[0].restitution: must be in [0, 1]"]);
    expect(
        &edit("tangential_restitution = 0.0", "tangential_restitution = -0.5"),
        &["contact[0].tangential_restitution"],
    );
}

#[test]
fn nscd_settings() {
    expect(&edit("theta = 0.5", "theta = 0.3"), &["nscd.theta: must be in [0.5, 1], got 0.3"]);
    expect(&edit("theta = 0.5", "theta = 1.1"), &["nscd.theta"]);
    expect(&edit("tolerance = 1.0e-4", "tolerance = 0.0"), &["nscd.tolerance"]);
    expect(&edit("tolerance = 1.0e-4", "tolerance = 1.0"), &["nscd.tolerance"]);
    expect(&edit("min_iterations = 1", "min_iterations = 0"), &["nscd.min_iterations"]);
    expect(&edit("max_iterations = 1000", "max_iterations = 0"), &["nscd.max_iterations"]);
    expect(&edit("min_iterations = 1", "min_iterations = 2000"), &["nscd.max_iterations"]);
    expect(&edit("max_factor = 16.0", "max_factor = 0.5"), &["nscd.max_factor"]);
    expect(&edit("criterion = \"quad\"", "criterion = \"fast\""), &["nscd.criterion: unknown criterion 'fast'"]);
    expect(&edit("max_factor = 16.0", "max_factor = 16.0\nalert_distance = -1.0"), &["nscd.alert_distance"]);
    expect(
        &edit("max_factor = 16.0", "max_factor = 16.0\nface_gaps = \"exact\""),
        &["nscd.face_gaps: the gap rule of two polyhedra's face–face contacts is a 3D setting"],
    );
    expect(
        &edit("max_factor = 16.0", "max_factor = 16.0\noverlaps = \"held\""),
        &["nscd.overlaps: the held-overlap law is a 3D setting"],
    );
    expect(&edit("every = 2", "every = 0"), &["output.every"]);
}

#[test]
fn engine() {
    expect(
        &edit("engine = \"nscd\"", "engine = \"md\""),
        &["simulation.engine: expected 'nscd', got 'md' (read it with scene::MdScene)"],
    );
    expect(&edit("engine = \"nscd\"", "engine = \"dem\""), &["simulation.engine: unknown engine 'dem'"]);
}

#[test]
fn unknown_material() {
    expect(
        &edit("between = [\"grain\", \"steel\"]", "between = [\"grain\", \"rock\"]"),
        &["contact[1].between: unknown material 'rock'"],
    );
    expect(
        &edit("material = \"steel\"\npolygon", "material = \"rock\"\npolygon"),
        &["body[0] 'floor': material: unknown material 'rock'"],
    );
}

#[test]
fn shapes_count() {
    expect(
        &edit("disc = 0.02", "disc = 0.02\nregular = { sides = 4, radius = 0.02 }"),
        &["body[3]: shape:", "exactly one"],
    );
    expect(&edit("disc = 0.02\n", ""), &["body[3]: shape:", "exactly one"]);
}

#[test]
fn duplicate_names() {
    expect(&edit("name = \"steel\"", "name = \"grain\""), &["material[1].name: duplicate material 'grain'"]);
    expect(&edit("name = \"pad0\"", "name = \"block\""), &["body[2] 'block': name: duplicate"]);
    expect(
        &edit("between = [\"grain\", \"steel\"]", "between = [\"grain\", \"grain\"]"),
        &["contact[1].between: duplicate"],
    );
}

#[test]
fn springs() {
    expect(&edit("body = \"pad0\"", "body = \"pad9\""), &["spring[0].body: unknown body 'pad9'"]);
    expect(&edit("other = \"pad0\"", "other = \"nobody\""), &["spring[1].other: unknown body 'nobody'"]);
    expect(&edit("other = \"pad0\"", "other = \"block\""), &["spring[1].other"]);
    expect(&edit("anchor = [-0.3, 0.1]", "anchor = [-0.3, 0.1]\nother = \"block\""), &["spring[0].anchor", "not both"]);
    expect(&edit("anchor = [-0.3, 0.1]\n", ""), &["spring[0].anchor", "missing"]);
    // The anchor at the attachment point: zero initial length, no rest_length.
    expect(&edit("anchor = [-0.3, 0.1]", "anchor = [-0.29, 0.2]"), &["spring[0].rest_length", "initial length"]);
}

#[test]
fn load_and_fixed_bodies() {
    expect(
        &edit("direction = [0.0, 2.0]", "direction = [0.0, 0.0]"),
        &["body[2] 'pad0': load.direction: must be a non-zero"],
    );
    expect(&edit("fixed = true", "fixed = true\nimposed = { vx = 1.0 }"), &["body[0] 'floor': imposed"]);
    expect(
        &edit("fixed = true", "fixed = true\nload = { direction = [1.0, 0.0], mean = 1.0 }"),
        &["body[0] 'floor': load"],
    );
}

#[test]
fn no_bodies() {
    let text = r#"
[simulation]
engine = "nscd"
dt = 1.0e-3
duration = 0.01
"#;
    expect(text, &["body"]);
}

#[test]
fn garbage_never_panics() {
    let inputs = [
        "",
        "\u{0}\u{1}",
        "[[[",
        "x = ",
        "[simulation]\nengine = 3",
        "[simulation]\nengine = \"nscd\"\ndt = 1e-3\nduration = 1e300",
        "[simulation]\nengine = \"nscd\"\ndt = 1e-300\nduration = 1",
        "[[body]]\nmaterial = 'a'\nregular = { sides = 1000000000000, radius = 1 }\nposition = [0, 0]",
        "é = 1\n[simulation]\nfoo = \"ü\"",
    ];
    for text in inputs {
        let _ = message(text);
    }
    // Every truncation of the base scene is either valid or a one-line error.
    for cut in (0..BASE.len()).filter(|&c| BASE.is_char_boundary(c)).step_by(7) {
        if let Err(Error::Scene(m)) = Scene::from_toml_str(&BASE[..cut]) {
            assert!(!m.contains('\n'));
        }
    }
}

#[test]
fn equilibrium_criterion_is_validated_and_round_trips() {
    let with = |eq: &str| edit("seed = 7\n", &format!("seed = 7\nequilibrium = {eq}\n"));
    expect(&with("{ kinetic_energy = 0.0 }"), &["simulation.equilibrium.kinetic_energy", "positive"]);
    expect(&with("{ kinetic_energy = 1e-9, steps = 0 }"), &["simulation.equilibrium.steps", "at least 1"]);
    expect(&with("{ kinetic_energy = 1e-9, window = 3 }"), &["unknown field `window`"]);
    let scene = Scene::from_toml_str(&with("{ kinetic_energy = 1e-9, steps = 30 }")).unwrap();
    let eq = scene.simulation.equilibrium.unwrap();
    assert_eq!((eq.kinetic_energy, eq.steps()), (Some(1e-9), 30));
    let again = Scene::from_toml_str(&scene.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.simulation.equilibrium, scene.simulation.equilibrium);
}

#[test]
fn cycle_output_is_validated_and_round_trips() {
    let with = |c: &str| edit("every = 2\n", &format!("every = 2\ncycles = {c}\n"));
    expect(&with("{ frequency = 20.0, body = \"nobody\" }"), &["output.cycles.body", "unknown body 'nobody'"]);
    expect(&with("{ frequency = -1.0, body = \"block\" }"), &["output.cycles.frequency", "positive"]);
    expect(&with("{ frequency = 20.0 }"), &["output.cycles.body", "name the followed body"]);
    let scene = Scene::from_toml_str(&with("{ frequency = 20.0, body = \"block\", positions = true }")).unwrap();
    let plan = ballast::run::CyclePlan { frequency: 20.0, body: Some(1), positions: true };
    assert_eq!(scene.plan().unwrap().cycles, Some(plan));
    let again = Scene::from_toml_str(&scene.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.plan().unwrap().cycles, Some(plan));
}
