//! The library's constructors for systems built in code (issue 12, item 4): NSCD
//! bodies with their mass and inertia computed and their centroid returned, the
//! same system as the equivalent scene bit for bit, MD spheres, a missing MD
//! contact law refused by `MdSystem::new`, `GeometryError` converted by `?`, and
//! the engines' contact counts and body sizes (the settlement driver's bounds).

use crate::scratch;
use ballast::geometry::{ConvexPolygon, GeometryError, Shape};
use ballast::md::{
    self, Ghosts, LawTable, Material, MdSettings, MdSystem, Motion, PairLaw, Particles, SymmetryPlane, Wall, V3,
};
use ballast::nscd::{BodyInfo, Harmonic, Imposed, Load, NscdParams, System};
use ballast::scene::SceneFile;
use ballast::scene::{MdScene, Scene};
use ballast::Error;
use std::f64::consts::PI;

/// `|a − b| ≤ 1e-12 |b|`.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs()
}

#[test]
fn square_and_disc_mass_and_inertia_are_the_closed_forms() {
    let (rho, t, a) = (2700.0, 0.3, 0.2);
    // A square of side a, in world coordinates away from the origin.
    let (x0, y0) = (1.5, -2.0);
    let square = [[x0, y0], [x0 + a, y0], [x0 + a, y0 + a], [x0, y0 + a]];
    let (info, q) = BodyInfo::polygon("sq", &square, 0, rho, t).unwrap();
    assert!(close(info.mass, rho * a * a * t), "mass {} kg", info.mass);
    assert!(close(info.inertia, rho * a.powi(4) * t / 6.0), "inertia {} kg m^2", info.inertia);
    assert!((q[0] - (x0 + a / 2.0)).abs() < 1e-15 && (q[1] - (y0 + a / 2.0)).abs() < 1e-15 && q[2] == 0.0);
    assert!(!info.fixed && info.imposed.is_empty() && info.loads.is_empty() && info.name == "sq");
    // The shape is re-centred on its centroid.
    let Shape::Polygon(p) = &info.shape else { panic!("a polygon") };
    let c = p.vertices.iter().fold([0.0, 0.0], |s, v| [s[0] + v.x / 4.0, s[1] + v.y / 4.0]);
    assert!(c[0].abs() < 1e-15 && c[1].abs() < 1e-15, "{c:?}");

    // A disc of radius r: ρ t π r², ρ t π r⁴ / 2.
    let r = 0.07;
    let (info, q) = BodyInfo::disc("d", [0.3, 0.4], r, 1, rho, t).unwrap();
    assert!(close(info.mass, rho * t * PI * r * r), "mass {} kg", info.mass);
    assert!(close(info.inertia, rho * t * PI * r.powi(4) / 2.0), "inertia {} kg m^2", info.inertia);
    assert_eq!(q, [0.3, 0.4, 0.0]);
    assert_eq!(info.material, 1);

    // A square given in its body frame: the same numbers through BodyInfo::new.
    let shape = Shape::Polygon(ConvexPolygon::regular(4, a / 2f64.sqrt()).unwrap());
    let info = BodyInfo::new("sq", shape, 0, rho, t).unwrap();
    assert!(close(info.mass, rho * a * a * t) && close(info.inertia, rho * a.powi(4) * t / 6.0));

    // A compound of two unit squares side by side: a 2 × 1 rectangle,
    // J = (2·1³ + 2³·1) / 12 = 10/12.
    let parts = vec![
        vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        vec![[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]],
    ];
    let (info, q) = BodyInfo::compound("c", &parts, 0, 1.0, 1.0).unwrap();
    assert!(close(info.mass, 2.0) && close(info.inertia, 10.0 / 12.0), "{} {}", info.mass, info.inertia);
    assert!((q[0] - 1.0).abs() < 1e-15 && (q[1] - 0.5).abs() < 1e-15);
}

#[test]
fn fixed_imposed_and_loaded_bodies() {
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let mut sys = System::new(NscdParams::default(), 1);
    let (floor, q) = BodyInfo::polygon("floor", &square, 0, 1000.0, 1.0).unwrap();
    let floor = sys.bodies.push(floor.into_fixed(), q, [1.0, 2.0, 3.0]);
    assert_eq!(sys.bodies.u[floor], [0.0; 3]);
    assert_eq!(sys.bodies.inv_m[floor], [0.0; 3]);
    let (sleeper, q) = BodyInfo::polygon("sleeper", &square, 0, 1000.0, 1.0).unwrap();
    let zero = Some(Harmonic::constant(0.0));
    let sleeper = sleeper
        .with_imposed(Imposed::new(zero, None, zero))
        .with_load(Load::new([0.0, -2.0], Harmonic { mean: -1000.0, amplitude: -500.0, frequency: 20.0, phase: 0.0 }));
    assert_eq!(sleeper.loads[0].direction, [0.0, -1.0]);
    let i = sys.bodies.push(sleeper, [q[0], q[1] + 2.0, 0.0], [1.0, -0.5, 1.0]);
    assert_eq!(sys.bodies.u[i], [0.0, -0.5, 0.0]);
    assert_eq!(sys.bodies.inv_m[i], [0.0, 1.0 / 1000.0, 0.0]);
    assert!(sys.bodies.is_mobile(i) && !sys.bodies.is_mobile(floor));
}

#[test]
fn constructor_errors() {
    let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for (rho, t) in [(0.0, 1.0), (-1.0, 1.0), (f64::NAN, 1.0), (1.0, 0.0), (1.0, f64::INFINITY)] {
        let e = BodyInfo::polygon("b", &square, 0, rho, t).unwrap_err();
        assert!(matches!(e, Error::Scene(_)), "{e}");
        assert!(e.to_string().starts_with("body 'b': "), "{e}");
    }
    let e = BodyInfo::disc("d", [0.0, 0.0], -1.0, 0, 1.0, 1.0).unwrap_err();
    assert!(matches!(e, Error::Geometry(GeometryError::BadRadius(_))), "{e}");
    let mut p = Particles::default();
    assert!(p.add_sphere(0, 2000.0, 0.0, V3::zeros(), V3::zeros()).is_err());
    assert!(p.add_sphere(0, f64::NAN, 0.01, V3::zeros(), V3::zeros()).is_err());
    let e = p.add_sphere(0, 2000.0, 0.01, V3::new(f64::NAN, 0.0, 0.0), V3::zeros()).unwrap_err();
    assert_eq!(e.to_string(), "sphere 0: position must be finite, got [NaN, 0, 0]");
    assert!(p.is_empty(), "nothing added on an error");
}

#[test]
fn geometry_errors_convert_into_the_crate_error() {
    fn clockwise() -> ballast::Result<ConvexPolygon> {
        let (p, _) = ConvexPolygon::new(&[[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]])?;
        Ok(p)
    }
    let e = clockwise().unwrap_err();
    assert!(matches!(e, Error::Geometry(GeometryError::Clockwise)), "{e:?}");
    assert_eq!(e.to_string(), GeometryError::Clockwise.to_string());
    let e: Error = GeometryError::BadSides(2).into();
    assert_eq!(e.one_line(), "a regular polygon needs at least 3 sides, got 2");
    let e = BodyInfo::polygon("b", &[[0.0, 0.0], [1.0, 0.0]], 0, 1.0, 1.0).unwrap_err();
    assert!(matches!(e, Error::Geometry(GeometryError::TooFewVertices(2))), "{e:?}");
}

/// The bodies of both systems: name, shape, material, mass, inertia, fixed,
/// imposed, loads, and q, u, inverse masses, bit for bit.
fn assert_same_bodies(a: &System, b: &System) {
    let json = |x: &dyn erased::Ser| x.json();
    assert_eq!(a.bodies.len(), b.bodies.len());
    for i in 0..a.bodies.len() {
        let (x, y) = (&a.bodies.info[i], &b.bodies.info[i]);
        assert_eq!(x.name, y.name);
        assert_eq!(json(&x.shape), json(&y.shape), "body {i}: shape");
        assert_eq!(x.material, y.material);
        assert_eq!(x.mass.to_bits(), y.mass.to_bits(), "body {i}: mass {} and {}", x.mass, y.mass);
        assert_eq!(x.inertia.to_bits(), y.inertia.to_bits(), "body {i}: inertia");
        assert_eq!((x.fixed, x.imposed, &x.loads), (y.fixed, y.imposed, &y.loads), "body {i}");
        let bits = |v: &[f64; 3]| v.map(f64::to_bits);
        assert_eq!(bits(&a.bodies.q[i]), bits(&b.bodies.q[i]), "body {i}: q");
        assert_eq!(bits(&a.bodies.u[i]), bits(&b.bodies.u[i]), "body {i}: u");
        assert_eq!(bits(&a.bodies.inv_m[i]), bits(&b.bodies.inv_m[i]), "body {i}: 1/m");
    }
}

/// Serde values of the shapes (which have no `PartialEq`).
mod erased {
    pub trait Ser {
        fn json(&self) -> serde_json::Value;
    }
    impl<T: serde::Serialize> Ser for T {
        fn json(&self) -> serde_json::Value {
            serde_json::to_value(self).unwrap()
        }
    }
}

#[test]
fn constructed_system_is_the_scene_system_bit_for_bit() {
    // Vertices away from the origin and not symmetric, so the centroid is a
    // computed value; a 0.3 m thickness; a pentagon, a disc, a compound, a
    // fixed floor, an imposed and loaded body.
    let pentagon = [[0.31, 0.17], [0.52, 0.21], [0.57, 0.39], [0.41, 0.52], [0.27, 0.36]];
    let floor = [[-1.0, -0.2], [1.3, -0.2], [1.3, 0.0], [-1.0, 0.0]];
    let parts =
        [vec![[0.7, 0.05], [0.9, 0.05], [0.9, 0.15], [0.7, 0.15]], vec![[0.9, 0.05], [1.0, 0.05], [0.95, 0.12]]];
    let points = |v: &[[f64; 2]]| v.iter().map(|p| format!("[{}, {}]", p[0], p[1])).collect::<Vec<_>>().join(", ");
    let toml = format!(
        r#"
[simulation]
engine = "nscd"
dt = 1e-4
duration = 1e-3
thickness = 0.3
[[material]]
name = "granite"
density = 2650.0
[[material]]
name = "steel"
density = 7850.0
[[contact]]
between = ["granite", "granite"]
friction = 0.8
[[body]]
name = "floor"
material = "steel"
polygon = [{floor}]
position = [0.0, 0.0]
fixed = true
[[body]]
name = "grain"
material = "granite"
polygon = [{pentagon}]
position = [0.0, 0.0]
velocity = [0.1, -0.2]
[[body]]
name = "pebble"
material = "granite"
disc = 0.05
position = [-0.4, 0.3]
[[body]]
name = "sleeper"
material = "steel"
parts = [[{p0}], [{p1}]]
position = [0.0, 0.0]
imposed = {{ vx = 0.0, spin = 0.0 }}
load = {{ direction = [0.0, -3.0], mean = -1000.0, amplitude = -500.0, frequency = 20.0, phase = -3.141592653589793 }}
"#,
        floor = points(&floor),
        pentagon = points(&pentagon),
        p0 = points(&parts[0]),
        p1 = points(&parts[1]),
    );
    let from_scene = Scene::from_toml_str(&toml).unwrap().build().unwrap();

    let t = 0.3;
    let params = NscdParams { dt: 1e-4, ..NscdParams::default() };
    let mut sys = System::new(params, 2);
    sys.set_law(0, 0, ballast::nscd::ContactLaw { friction: 0.8, ..Default::default() });
    let (info, q) = BodyInfo::polygon("floor", &floor, 1, 7850.0, t).unwrap();
    sys.bodies.push(info.into_fixed(), q, [0.0; 3]);
    let (info, q) = BodyInfo::polygon("grain", &pentagon, 0, 2650.0, t).unwrap();
    sys.bodies.push(info, q, [0.1, -0.2, 0.0]);
    let (info, q) = BodyInfo::disc("pebble", [-0.4, 0.3], 0.05, 0, 2650.0, t).unwrap();
    sys.bodies.push(info, q, [0.0; 3]);
    let (info, q) = BodyInfo::compound("sleeper", &parts, 1, 7850.0, t).unwrap();
    let zero = Some(Harmonic::constant(0.0));
    let load = Harmonic { mean: -1000.0, amplitude: -500.0, frequency: 20.0, phase: -PI };
    let info = info.with_imposed(Imposed::new(zero, None, zero)).with_load(Load::new([0.0, -3.0], load));
    sys.bodies.push(info, q, [0.0; 3]);
    sys.params.alert_distance = sys.bodies.default_alert_distance();

    assert_same_bodies(&sys, &from_scene);
    assert_eq!(sys.params, from_scene.params, "the parameters, alert distance included");
    assert_eq!(sys.laws, from_scene.laws);
    sys.check_same_model(&from_scene).unwrap();
    // And they step alike.
    let mut from_scene = from_scene;
    for _ in 0..5 {
        sys.step().unwrap();
        from_scene.step().unwrap();
    }
    assert_same_bodies(&sys, &from_scene);
}

/// A rock-like material (kg/m³, Pa).
const ROCK: Material = Material { density: 2000.0, young: 1e7, poisson: 0.25 };
const STEEL: Material = Material { density: 7850.0, young: 2e11, poisson: 0.3 };

fn settings() -> MdSettings {
    MdSettings { dt: 1e-5, skin: 1e-3, ..MdSettings::default() }
}

fn floor(material: u32) -> Wall {
    Wall::new("floor", material, md::Shape::Plane { point: V3::zeros(), normal: V3::z() }, Motion::Fixed)
}

#[test]
fn md_sphere_constructor_and_scene_agree() {
    let (r, x, v) = (0.004, V3::new(0.01, -0.02, 0.005), V3::new(0.1, 0.0, -0.3));
    let mut p = Particles::default();
    let i = p.add_sphere(0, ROCK.density, r, x, v).unwrap();
    let m = ROCK.density * 4.0 / 3.0 * PI * r.powi(3);
    assert!(close(p.m[i], m) && close(p.inv_m[i], 1.0 / m));
    assert!(close(p.inv_i[i], 1.0 / (0.4 * m * r * r)), "I = 2/5 m r^2");
    assert_eq!((p.x[i], p.v[i], p.w[i], p.material[i]), (x, v, V3::zeros(), 0));
    assert_eq!(md::sphere_mass(ROCK.density, r).to_bits(), p.m[i].to_bits());

    let scene = MdScene::from_toml_str(
        r#"
[simulation]
engine = "md"
dt = 1e-5
duration = 1e-4
[[material]]
name = "rock"
density = 2000.0
young = 1e7
poisson = 0.25
[[contact]]
between = ["rock", "rock"]
model = "hertz"
friction = 0.5
normal_damping_ratio = 0.5
[[wall]]
name = "floor"
material = "rock"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
[[body]]
material = "rock"
sphere = 0.004
position = [0.01, -0.02, 0.005]
velocity = [0.1, 0.0, -0.3]
"#,
    )
    .unwrap()
    .build()
    .unwrap();
    let q = &scene.particles;
    assert_eq!(
        (q.m[0].to_bits(), q.inv_m[0].to_bits(), q.inv_i[0].to_bits()),
        (p.m[i].to_bits(), p.inv_m[i].to_bits(), p.inv_i[i].to_bits())
    );
    assert_eq!((q.x[0], q.v[0], q.r[0]), (x, v, r));
    assert_eq!(scene.laws.names, vec!["rock".to_string()], "scenes name their materials");
}

#[test]
fn md_system_refuses_a_missing_law_naming_both_materials() {
    let law = PairLaw::hertz(&ROCK, &STEEL, 0.3, 0.3, 0.5);
    let two_rocks = || {
        let mut p = Particles::default();
        p.add_sphere(0, ROCK.density, 0.01, V3::new(0.0, 0.0, 0.01), V3::zeros()).unwrap();
        p.push("top", 0, ROCK.density, 0.01, V3::new(0.0, 0.0, 0.05), V3::zeros(), V3::zeros());
        p
    };
    let none = || Ghosts::new(Vec::new());

    // Sphere–wall: rock on steel without a law.
    let mut laws = LawTable::named(&["rock", "steel"]);
    laws.set(0, 0, law);
    let e = MdSystem::new(settings(), two_rocks(), vec![floor(1)], laws.clone(), none()).unwrap_err();
    assert!(matches!(e, Error::Scene(_)));
    assert_eq!(
        e.to_string(),
        "no contact law between materials 'rock' and 'steel', which can touch (sphere 0 and wall 0 'floor')"
    );
    // With the law, it builds.
    laws.set(0, 1, law);
    MdSystem::new(settings(), two_rocks(), vec![floor(1)], laws, none()).unwrap();

    // Sphere–sphere: two rocks, only rock–steel given; the materials unnamed.
    let mut laws = LawTable::new(2);
    laws.set(0, 1, law);
    let e = MdSystem::new(settings(), two_rocks(), vec![floor(1)], laws.clone(), none()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no contact law between materials material 0 and material 0, which can touch (sphere 0 and sphere 1 'top')"
    );
    // One rock alone meets no rock but its image by a symmetry plane.
    let mut one = Particles::default();
    one.add_sphere(0, ROCK.density, 0.01, V3::new(0.02, 0.0, 0.01), V3::zeros()).unwrap();
    MdSystem::new(settings(), one.clone(), vec![floor(1)], laws.clone(), none()).unwrap();
    let mirror = Ghosts::new(vec![SymmetryPlane { point: V3::zeros(), normal: V3::x() }]);
    let e = MdSystem::new(settings(), one, vec![floor(1)], laws.clone(), mirror).unwrap_err();
    assert!(e.to_string().ends_with("(sphere 0 and its symmetry image)"), "{e}");

    // Two materials of spheres: rock and steel spheres need rock–steel.
    let mut laws = LawTable::named(&["rock", "steel"]);
    laws.set(0, 0, law);
    laws.set(1, 1, law);
    let mut p = two_rocks();
    p.add_sphere(1, STEEL.density, 0.01, V3::new(0.1, 0.0, 0.01), V3::zeros()).unwrap();
    let e = MdSystem::new(settings(), p, vec![], laws, none()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no contact law between materials 'rock' and 'steel', which can touch (sphere 0 and sphere 2)"
    );

    // A material index out of the table.
    let mut laws = LawTable::new(1);
    laws.set(0, 0, law);
    let e = MdSystem::new(settings(), two_rocks(), vec![floor(3)], laws, none()).unwrap_err();
    assert_eq!(e.to_string(), "wall 0 'floor': material 3 of 1");
}

#[test]
fn md_scene_missing_law_message_is_unchanged() {
    // The scene check and MdSystem::new go through the same search
    // (md::law::first_uncovered); the scene words it in its own terms.
    let e = MdScene::from_toml_str(
        r#"
[simulation]
engine = "md"
dt = 1e-6
duration = 1e-5
[[material]]
name = "glass"
density = 2500.0
young = 6e10
poisson = 0.22
[[material]]
name = "steel"
density = 7850.0
young = 2e11
poisson = 0.3
[[contact]]
between = ["glass", "glass"]
model = "hertz"
friction = 0.3
[[wall]]
name = "floor"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
[[body]]
name = "s0"
material = "glass"
sphere = 0.001
position = [0.0, 0.0, 0.002]
"#,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "contact: no [[contact]] between materials 'glass' and 'steel', which can touch (body[0] 's0' and wall[0] 'floor')"
    );
}

/// An NSCD system (dt 1 ms, friction 0.5) with a fixed 1 m × 0.1 m floor whose top is y = 0.
fn system_on_floor() -> System {
    let mut sys = System::new(NscdParams { dt: 1e-3, ..NscdParams::default() }, 1);
    sys.set_law(0, 0, ballast::nscd::ContactLaw { friction: 0.5, ..Default::default() });
    let (floor, q) =
        BodyInfo::polygon("floor", &[[-0.5, -0.1], [0.5, -0.1], [0.5, 0.0], [-0.5, 0.0]], 0, 2700.0, 1.0).unwrap();
    sys.bodies.push(floor.into_fixed(), q, [0.0; 3]);
    sys
}

#[test]
fn nscd_block_on_floor_carries_its_weight() {
    // The crate's doc example, with the numbers printed.
    let mut sys = system_on_floor();
    let (block, q) =
        BodyInfo::polygon("block", &[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]], 0, 2700.0, 1.0).unwrap();
    let weight = block.mass * 9.81;
    let block = sys.bodies.push(block, q, [0.0; 3]);
    sys.params.alert_distance = sys.bodies.default_alert_distance();
    assert!((sys.params.alert_distance - 0.01 * 0.05).abs() < 1e-15, "1 % of the block's inradius");
    for _ in 0..100 {
        sys.step().unwrap();
    }
    let carried: f64 =
        sys.contact_forces().filter(|c| c.candidate == block || c.antagonist == block).map(|c| c.r_n).sum();
    eprintln!("carried {carried} N, weight {weight} N, relative {:e}", (carried - weight) / weight);
    assert!((carried - weight).abs() < 1e-3 * weight);
}

#[test]
fn md_sphere_on_plane_rests_at_the_hertz_overlap() {
    let r = 0.01;
    let mut spheres = Particles::default();
    let s = spheres.add_sphere(0, ROCK.density, r, V3::new(0.0, 0.0, r), V3::zeros()).unwrap();
    let mut laws = LawTable::named(&["rock"]);
    laws.set(0, 0, PairLaw::hertz(&ROCK, &ROCK, 0.5, 0.5, 0.5));
    let settings = MdSettings { dt: 1e-5, skin: 0.1 * r, ..MdSettings::default() };
    let mut sys = MdSystem::new(settings, spheres, vec![floor(0)], laws, Ghosts::new(Vec::new())).unwrap();
    for _ in 0..5000 {
        sys.step().unwrap();
    }
    let m = sys.particles.m[s];
    let expected = (m * 9.81 / (4.0 / 3.0 * md::law::e_star(&ROCK, &ROCK) * r.sqrt())).powf(2.0 / 3.0);
    let overlap = r - sys.particles.x[s].z;
    eprintln!(
        "overlap {overlap:e} m, Hertz {expected:e} m, relative {:e}; E_k {:e} J",
        (overlap - expected) / expected,
        sys.particles.kinetic_energy()
    );
    assert!((overlap - expected).abs() < 1e-3 * expected);
}

#[test]
fn engines_count_the_force_carrying_contacts_and_size_the_bodies() {
    use ballast::engine::Engine;
    // NSCD: two 10 cm blocks stacked on a floor, at rest after 100 steps: the
    // lower one touches the floor and the upper one (2), the upper one the
    // lower one (1). Size: the radius of the disc of the same area, √(0.01/π).
    let mut sys = system_on_floor();
    for (name, y) in [("lower", 0.0), ("upper", 0.1)] {
        let (block, q) =
            BodyInfo::polygon(name, &[[0.0, y], [0.1, y], [0.1, y + 0.1], [0.0, y + 0.1]], 0, 2700.0, 1.0).unwrap();
        sys.bodies.push(block, q, [0.0; 3]);
    }
    sys.params.alert_distance = sys.bodies.default_alert_distance();
    for _ in 0..100 {
        sys.step().unwrap();
    }
    let mobile = sys.mobile_bodies();
    assert_eq!(mobile, vec![1, 2]);
    assert_eq!(sys.contact_counts(&mobile), vec![2, 1]);
    for size in sys.body_sizes(&mobile) {
        assert!(close(size, (0.01 / PI).sqrt()), "{size}");
    }

    // MD: two spheres stacked on a plane (the same, by the half pair list).
    let r = 0.01;
    let mut spheres = Particles::default();
    spheres.add_sphere(0, ROCK.density, r, V3::new(0.0, 0.0, r), V3::zeros()).unwrap();
    spheres.add_sphere(0, ROCK.density, 0.5 * r, V3::new(0.0, 0.0, 2.5 * r), V3::zeros()).unwrap();
    let mut laws = LawTable::named(&["rock"]);
    laws.set(0, 0, PairLaw::hertz(&ROCK, &ROCK, 0.5, 0.5, 0.5));
    let settings = MdSettings { dt: 1e-5, skin: 0.1 * r, ..MdSettings::default() };
    let mut sys = MdSystem::new(settings, spheres, vec![floor(0)], laws, Ghosts::new(Vec::new())).unwrap();
    for _ in 0..2000 {
        sys.step().unwrap();
    }
    let mobile = sys.mobile_bodies();
    assert_eq!(sys.contact_counts(&mobile), vec![2, 1]);
    assert_eq!(sys.body_sizes(&mobile), vec![r, 0.5 * r]);
}

/// The kinds of error a caller can tell apart: a missing scene file is `Error::File` with the operating
/// system's kind, a refused option names the argument (`Error::Scene`), a missing checkpoint to resume from is
/// `Error::Checkpoint`.
#[test]
fn error_kinds_tell_a_file_an_argument_and_a_checkpoint_apart() {
    use ballast::run::RunOptions;
    let missing = std::path::Path::new("examples/no_such_scene.toml");
    let out = scratch::path("kinds");
    match ballast::open::run_file(missing, &out, &RunOptions::default(), &mut |_| {}) {
        Err(e @ Error::File { .. }) => {
            assert!(e.is_input());
            let Error::File { path, source, .. } = e else { unreachable!() };
            assert_eq!((path.as_path(), source.kind()), (missing, std::io::ErrorKind::NotFound));
        }
        other => panic!("expected Error::File, got {:?}", other.map(|o| o.step)),
    }
    let scene = std::path::Path::new("examples/block_on_floor.toml");
    let e = ballast::open::run_file(scene, &out, &RunOptions { threads: 0, ..RunOptions::default() }, &mut |_| {})
        .unwrap_err();
    assert!(matches!(&e, Error::Scene(m) if m.starts_with("threads:")) && e.is_input(), "{e}");
    assert_eq!(e.key().as_deref(), Some("threads"));
    let _ = std::fs::remove_dir_all(&out);
    let e = ballast::open::run_file(scene, &out, &RunOptions { resume: true, ..RunOptions::default() }, &mut |_| {})
        .unwrap_err();
    assert!(matches!(&e, Error::Checkpoint(m) if m.starts_with("resume: no checkpoint.json")) && e.is_input(), "{e}");
    assert_eq!(e.key(), None, "a checkpoint's refusal names a file, not a key");
    let _ = std::fs::remove_dir_all(&out);
    // A scene's bad value names its key; a syntax error names the file and line, not a key.
    let text = std::fs::read_to_string(scene).unwrap();
    let bad = Scene::from_toml_str(&text.replace("dt = 1.0e-3", "dt = -1.0e-3")).unwrap_err();
    assert_eq!(bad.key().as_deref(), Some("simulation.dt"), "{bad}");
    let bad =
        Scene::from_toml_str(&text.replace("[simulation]", "[nscd]\ntolerance = 2.0\n\n[simulation]")).unwrap_err();
    assert_eq!(bad.key().as_deref(), Some("nscd.tolerance"), "{bad}");
    let clockwise = "polygon = [[-0.05, -0.05], [-0.05, 0.05], [0.05, 0.05], [0.05, -0.05]]";
    let bad = Scene::from_toml_str(
        &text.replace("polygon = [[-0.05, -0.05], [0.05, -0.05], [0.05, 0.05], [-0.05, 0.05]]", clockwise),
    )
    .unwrap_err();
    assert_eq!(bad.key().as_deref(), Some("body[1].polygon"), "{bad}");
    let syntax = Scene::from_toml_str(&text.replace("dt = 1.0e-3", "dt = = 1")).unwrap_err();
    assert_eq!(syntax.key(), None, "{syntax}");
}
