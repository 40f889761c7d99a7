//! Writing generalised positions back into an engine (`Engine::set_configuration`),
//! the operation a settlement driver makes after extrapolating cycles: on NSCD,
//! MD with velocity Verlet and MD with a Gear predictor–corrector, a system run
//! for a while (contacts, warm-start impulses, tangential springs, Gear
//! derivatives, neighbour lists all loaded), read, perturbed and written back,
//! takes the same steps, bit for bit, as a system built fresh at the written
//! positions with zero velocities. Nothing of its past may leak into them.

use ballast::engine::{Configuration, Engine};
use ballast::md::{Ghosts, MdSystem};
use ballast::scene::SceneFile;
use ballast::scene::{MdScene, Scene};

/// Pentagons and a disc on a pad held by two sublayer springs above a fixed
/// floor, between two walls (gravity only: no time-dependent load, so a system
/// built at t = 0 is comparable with one at a later time).
const NSCD: &str = r#"
[simulation]
engine = "nscd"
dt = 2.0e-4
duration = 1.0

[[material]]
name = "grain"
density = 2700.0

[[contact]]
between = ["grain", "grain"]
friction = 0.5

[[body]]
name = "floor"
material = "grain"
polygon = [[-0.2, -0.1], [0.2, -0.1], [0.2, 0.0], [-0.2, 0.0]]
position = [0.0, 0.0]
fixed = true

[[body]]
name = "left"
material = "grain"
polygon = [[-0.01, 0.0], [0.0, 0.0], [0.0, 0.3], [-0.01, 0.3]]
position = [-0.1, 0.0]
fixed = true

[[body]]
name = "right"
material = "grain"
polygon = [[0.0, 0.0], [0.01, 0.0], [0.01, 0.3], [0.0, 0.3]]
position = [0.1, 0.0]
fixed = true

[[body]]
name = "pad"
material = "grain"
polygon = [[-0.09, -0.01], [0.09, -0.01], [0.09, 0.01], [-0.09, 0.01]]
position = [0.0, 0.05]

[[body]]
name = "g1"
material = "grain"
regular = { sides = 5, radius = 0.02 }
position = [-0.05, 0.085]

[[body]]
name = "g2"
material = "grain"
regular = { sides = 5, radius = 0.025 }
position = [0.01, 0.09]
angle = 0.3

[[body]]
name = "g3"
material = "grain"
disc = 0.015
position = [0.06, 0.08]

[[body]]
name = "g4"
material = "grain"
regular = { sides = 5, radius = 0.02 }
position = [-0.02, 0.14]
angle = 0.1

[[spring]]
body = "pad"
point = [-0.08, -0.01]
anchor = [-0.08, 0.0]
k_n = 5.0e4
nu = 50.0

[[spring]]
body = "pad"
point = [0.08, -0.01]
anchor = [0.08, 0.0]
k_n = 5.0e4
nu = 50.0
"#;

/// Moves every coordinate of `c` a little: 0.3 mm and 0.01 rad, alternating in sign.
fn perturb(c: &mut Configuration) {
    for (k, x) in c.q.iter_mut().enumerate() {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        *x += sign * if k % c.dof >= c.dof / 2 && c.dof == 6 || k % c.dof == 2 && c.dof == 3 { 0.01 } else { 3e-4 };
    }
}

#[test]
fn nscd_write_back_starts_from_the_written_configuration() {
    let scene = Scene::from_toml_str(NSCD).unwrap();
    let mut sys = scene.build().unwrap();
    for _ in 0..1500 {
        sys.step().unwrap();
    }
    assert!(!sys.contacts.is_empty() && sys.springs.iter().all(|s| s.impulse != 0.0), "a loaded state");
    let mut c = sys.configuration();
    assert_eq!((c.dof, c.bodies.clone()), (3, vec![3, 4, 5, 6, 7]), "the non-fixed bodies");
    perturb(&mut c);
    sys.set_configuration(&c).unwrap();
    assert_eq!(sys.configuration(), c, "read back as written");
    assert!(sys.bodies.u.iter().all(|u| *u == [0.0; 3]));
    // Fresh: built from the scene, then placed (velocities are zero in the scene).
    let mut fresh = scene.build().unwrap();
    fresh.set_configuration(&c).unwrap();
    let step = sys.step;
    for k in 0..20 {
        let (a, b) = (sys.step().unwrap(), fresh.step().unwrap());
        assert_eq!((a.contacts, a.iterations, a.max_overlap), (b.contacts, b.iterations, b.max_overlap), "step {k}");
        assert_eq!(sys.bodies.q, fresh.bodies.q, "step {k}");
        assert_eq!(sys.bodies.u, fresh.bodies.u, "step {k}");
    }
    assert_eq!(sys.step, step + 20, "the clock goes on");
}

#[test]
fn nscd_write_back_refuses_bad_configurations_and_changes_nothing() {
    let scene = Scene::from_toml_str(NSCD).unwrap();
    let mut sys = scene.build().unwrap();
    sys.step().unwrap();
    let before = serde_json::to_value(&sys).unwrap();
    let good = sys.configuration();
    let fixed = Configuration { bodies: vec![0], q: vec![0.0; 3], ..good.clone() };
    let nan = Configuration { q: good.q.iter().map(|_| f64::NAN).collect(), ..good.clone() };
    let short = Configuration { q: good.q[1..].to_vec(), ..good.clone() };
    let unknown = Configuration { bodies: vec![99], q: vec![0.0; 3], ..good.clone() };
    let dof = Configuration { dof: 6, ..good.clone() };
    for (c, expected) in [
        (fixed, "body 0 ('floor') is fixed"),
        (nan, "not finite"),
        (short, "coordinates for 5 bodies"),
        (unknown, "body 99 does not exist"),
        (dof, "6 coordinates per body"),
    ] {
        let e = sys.set_configuration(&c).unwrap_err().to_string();
        assert!(e.starts_with("configuration: ") && e.contains(expected), "{e}");
    }
    assert_eq!(serde_json::to_value(&sys).unwrap(), before, "unchanged");
}

/// Nine Hertz spheres (r = 4 mm) settling in a 17 × 17 mm box with friction
/// (tangential springs in the contact memory) and a symmetry plane (images),
/// with the integrator of `md`.
fn md_scene(md: &str) -> MdScene {
    let mut text = format!(
        "[simulation]\nengine = \"md\"\ndt = 2e-6\nduration = 0.1\n\n[md]\n{md}\nskin = 0.0005\n\n\
         [[symmetry]]\npoint = [0.0, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n\n\
         [[material]]\nname = \"rock\"\ndensity = 2700.0\nyoung = 1e8\npoisson = 0.25\n\n\
         [[contact]]\nbetween = [\"rock\", \"rock\"]\nmodel = \"hertz\"\nfriction = 0.5\nrestitution = 0.5\n\n"
    );
    for (name, p, n) in [
        ("floor", [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ("far", [0.017, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ("front", [0.0, -0.0085, 0.0], [0.0, 1.0, 0.0]),
        ("back", [0.0, 0.0085, 0.0], [0.0, -1.0, 0.0]),
    ] {
        text += &format!(
            "[[wall]]\nname = \"{name}\"\nmaterial = \"rock\"\nplane = {{ point = {p:?}, normal = {n:?} }}\n\n"
        );
    }
    for i in 0..9 {
        // A staggered column that topples into a heap of two or three layers.
        let (x, y, z) = (0.0045 + 0.004 * (i % 3) as f64, -0.004 + 0.004 * (i / 3) as f64, 0.0045 + 0.0085 * i as f64);
        text +=
            &format!("[[body]]\nname = \"s{i}\"\nmaterial = \"rock\"\nsphere = 0.004\nposition = [{x}, {y}, {z}]\n\n");
    }
    MdScene::from_toml_str(&text).unwrap()
}

/// The system built from `scene` with the spheres of `sys` placed at `c`
/// (velocities zero) and the walls where they are in `sys`.
fn fresh_md(scene: &MdScene, sys: &MdSystem, c: &Configuration) -> MdSystem {
    let built = scene.build().unwrap();
    let mut particles = sys.particles.clone();
    for (k, &i) in c.bodies.iter().enumerate() {
        let q = c.body(k);
        particles.x[i] = [q[0], q[1], q[2]].into();
        particles.q[i] = nalgebra::UnitQuaternion::from_scaled_axis(nalgebra::Vector3::new(q[3], q[4], q[5]));
    }
    for v in particles.v.iter_mut().chain(particles.w.iter_mut()) {
        *v = nalgebra::Vector3::zeros();
    }
    let mut walls = sys.walls.clone();
    for w in &mut walls {
        w.s_dot = 0.0;
    }
    MdSystem::new(built.settings, particles, walls, built.laws, Ghosts::new(built.ghosts.planes)).unwrap()
}

fn md_write_back(md: &str) {
    let scene = md_scene(md);
    let mut sys = scene.build().unwrap();
    for _ in 0..60000 {
        sys.step().unwrap();
    }
    assert!(sys.last.contacts >= 3.0 && sys.last.wall_contacts >= 3, "a loaded state: {:?}", sys.last);
    assert!(!sys.ghosts.is_empty(), "images of the spheres near the symmetry plane");
    let mut c = sys.configuration();
    assert_eq!((c.dof, c.bodies.len()), (6, 9));
    perturb(&mut c);
    sys.set_configuration(&c).unwrap();
    let back = sys.configuration();
    for (a, b) in back.q.iter().zip(&c.q) {
        // Positions exactly; the rotation vector through a unit quaternion to round-off.
        assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0), "{a} vs {b}");
    }
    let mut fresh = fresh_md(&scene, &sys, &c);
    assert_eq!(sys.particles.f, fresh.particles.f, "forces evaluated at the written configuration");
    let step = sys.step;
    for k in 0..300 {
        let (a, b) = (sys.step().unwrap(), fresh.step().unwrap());
        assert_eq!((a.contacts, a.max_overlap, a.kinetic_energy), (b.contacts, b.max_overlap, b.kinetic_energy), "{k}");
        assert_eq!(sys.particles.x, fresh.particles.x, "step {k}");
        assert_eq!(sys.particles.v, fresh.particles.v, "step {k}");
        assert_eq!(sys.particles.w, fresh.particles.w, "step {k}");
    }
    assert_eq!(sys.step, step + 300, "the clock goes on");
}

#[test]
fn md_verlet_write_back_starts_from_the_written_configuration() {
    md_write_back("integrator = \"verlet\"");
}

#[test]
fn md_gear_write_back_starts_from_the_written_configuration() {
    md_write_back("integrator = \"gear\"\ngear = \"gear5\"");
}
