//! Compound bodies (rigid unions of convex polygons): exact mass properties,
//! a sleeper with two bars resting on its bars, the lateral resistance a bar in a
//! groove gives, contact keys, the scene syntax `parts = [...]` and VTK output.

use crate::common;
use crate::scratch;

use ballast::geometry::{rotate, Compound, GeometryError, Shape, Vec2};
use ballast::nscd::{BodyInfo, Harmonic, Imposed, Load, System};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::Error;
use common::{floor, params, rect, run, system, G};

const DENSITY: f64 = 2000.0;

/// Adds a compound made of `parts` (vertex lists in a common frame, CCW); `origin`
/// is the world position of that frame's origin. Returns the body index and the
/// compound's centroid in the given frame.
fn compound(s: &mut System, parts: &[Vec<[f64; 2]>], origin: [f64; 2], fixed: bool) -> (usize, Vec2) {
    let (c, g) = Compound::new(parts).unwrap();
    let shape = Shape::Compound(c);
    let (area, j) = shape.area_and_polar_moment();
    let info = BodyInfo {
        name: String::new(),
        shape,
        material: 0,
        mass: DENSITY * area,
        inertia: DENSITY * j,
        fixed,
        imposed: Imposed::default(),
        loads: Vec::new(),
    };
    (s.bodies.push(info, [origin[0] + g.x, origin[1] + g.y, 0.0], [0.0; 3]), g)
}

/// Counter-clockwise rectangle `[x0, x1] × [y0, y1]`.
fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// The sleeper of the tests: a 0.1 × 0.03 m plate over two 0.01 × 0.01 m bars, in
/// a frame whose origin is under the middle of the plate, at the bars' feet.
fn sleeper_parts() -> Vec<Vec<[f64; 2]>> {
    vec![rectangle(-0.05, 0.01, 0.05, 0.04), rectangle(-0.04, 0.0, -0.03, 0.01), rectangle(0.03, 0.0, 0.04, 0.01)]
}

/// World vertices of part `k` of compound body `i`.
fn part_world(s: &System, i: usize, k: usize) -> Vec<Vec2> {
    let Shape::Compound(c) = &s.bodies.info[i].shape else { panic!("body {i} is not a compound") };
    let q = s.bodies.q[i];
    let (sin, cos) = q[2].sin_cos();
    c.parts[k].vertices.iter().map(|v| Vec2::new(q[0], q[1]) + rotate(*v, cos, sin)).collect()
}

fn min_y(v: &[Vec2]) -> f64 {
    v.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)
}

/// (a) An L made of two rectangles against the closed form. Every quantity is a
/// few sums and products of exactly representable lengths; parry's polygon
/// moments, the re-centring and the parallel-axis sum each add a few ulps, so
/// 1e-12 relative leaves a margin of about 10³ over the rounding error while
/// catching any wrong term (a missing `A d²` is a 50 % error).
#[test]
fn l_shape_mass_properties_match_the_closed_form() {
    // Foot [0, 0.1] × [0, 0.02] and stem [0, 0.02] × [0.02, 0.08], sharing part of an edge.
    let (w1, h1, c1) = (0.1, 0.02, Vec2::new(0.05, 0.01));
    let (w2, h2, c2) = (0.02, 0.06, Vec2::new(0.01, 0.05));
    let parts = vec![rectangle(0.0, 0.0, 0.1, 0.02), rectangle(0.0, 0.02, 0.02, 0.08)];
    let (c, g) = Compound::new(&parts).unwrap();
    let (a1, a2) = (w1 * h1, w2 * h2);
    let area = a1 + a2;
    let centroid = (c1 * a1 + c2 * a2) / area;
    // Rectangle about its centroid: A (w² + h²) / 12; moved by the parallel-axis theorem.
    let j = a1 * (w1 * w1 + h1 * h1) / 12.0
        + a1 * (c1 - centroid).norm_squared()
        + a2 * (w2 * w2 + h2 * h2) / 12.0
        + a2 * (c2 - centroid).norm_squared();
    // By hand: A = 0.0032 m², centroid (0.035, 0.025) m.
    assert!((area - 0.0032).abs() < 1e-15 && (centroid - Vec2::new(0.035, 0.025)).norm() < 1e-15);
    let (ca, cj) = c.area_and_polar_moment();
    let rel = |x: f64, y: f64| (x - y).abs() / y.abs();
    assert!(rel(ca, area) < 1e-12, "area {ca} vs {area}");
    assert!(rel(cj, j) < 1e-12, "polar moment {cj} vs {j}");
    assert!((g - centroid).norm() < 1e-12 * 0.1, "centroid {g:?} vs {centroid:?}");
    // Parts are stored in the body frame (union centroid at the origin), each with
    // its own inradius and a circumradius about the body centroid.
    assert!((c.parts[1].vertices[0] - (Vec2::new(0.0, 0.02) - centroid)).norm() < 1e-15);
    assert!((c.offsets[0] - (c1 - centroid)).norm() < 1e-15);
    assert!(
        rel(c.parts[0].inradius, 0.01) < 1e-12 && rel(c.parts[1].inradius, 0.01) < 1e-12,
        "{} {}",
        c.parts[0].inradius,
        c.parts[1].inradius
    );
    let far = Vec2::new(0.1, 0.0) - centroid; // the foot's outer corner is the farthest vertex
    assert!(rel(c.circumradius, far.norm()) < 1e-12);
    let shape = Shape::Compound(c);
    assert!(rel(shape.bounding_radius(), far.norm()) < 1e-12);
    assert!(rel(shape.inner_radius(), 0.01) < 1e-12);

    // A rectangle cut in two has the rectangle's mass properties.
    let (halves, g) = Compound::new(&[rectangle(0.0, 0.0, 0.3, 0.1), rectangle(0.3, 0.0, 0.5, 0.1)]).unwrap();
    let (a, j) = halves.area_and_polar_moment();
    assert!(rel(a, 0.05) < 1e-12 && rel(j, 0.05 * (0.25 + 0.01) / 12.0) < 1e-12);
    assert!((g - Vec2::new(0.25, 0.05)).norm() < 1e-15);
}

#[test]
fn bad_compounds_are_refused_naming_the_part() {
    let dart = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 0.3], [1.0, 2.0]];
    let e = Compound::new(&[rectangle(0.0, -1.0, 1.0, 0.0), dart]).unwrap_err();
    assert!(matches!(&e, GeometryError::Part { index: 1, source } if matches!(**source, GeometryError::NonConvex(_))));
    assert!(e.to_string().starts_with("parts[1]: non-convex polygon"), "{e}");
    let e = Compound::new(&[rectangle(0.0, 0.0, 1.0, 1.0), rectangle(0.9, 0.0, 2.0, 1.0)]).unwrap_err();
    assert!(matches!(e, GeometryError::PartsOverlap(0, 1, d) if (d - 0.1).abs() < 1e-12), "{e:?}");
    assert!(e.to_string().starts_with("parts[1]: overlaps parts[0] by"), "{e}");
    assert_eq!(Compound::new(&[]).unwrap_err(), GeometryError::NoParts);
    // Touching at a corner only, or along a shared edge: accepted.
    assert!(Compound::new(&[rectangle(0.0, 0.0, 1.0, 1.0), rectangle(1.0, 1.0, 2.0, 2.0)]).is_ok());
    assert!(Compound::new(&[rectangle(0.0, 0.0, 1.0, 1.0), rectangle(0.1, 1.0, 0.3, 1.5)]).is_ok());
    // One part inside the other is an overlap, and so is a part crossing another.
    assert!(Compound::new(&[rectangle(0.0, 0.0, 1.0, 1.0), rectangle(0.2, 0.2, 0.3, 0.3)]).is_err());
    assert!(Compound::new(&[rectangle(0.0, 0.4, 1.0, 0.6), rectangle(0.4, 0.0, 0.6, 1.0)]).is_err());
}

/// (b) The sleeper dropped 2 mm onto a flat floor with friction comes to rest on
/// its two bars only: the plate's lower face stays 0.01 m above the floor (the
/// bars are rigid; what is left is the solver's overlap, well under 1e-6 m with
/// its 1e-10 tolerance), the floor carries the weight (at rest the impulse of a
/// step balances `m g h` exactly, up to the solver tolerance), and the only
/// contacts are the two ends of each bar's foot.
#[test]
fn sleeper_with_two_bars_rests_on_its_bars() {
    let mut s = system(1e-3, 0.5, 0.0);
    let fl = floor(&mut s);
    let (sl, _) = compound(&mut s, &sleeper_parts(), [0.0, 0.002], false);
    run(&mut s, 500);
    let plate = min_y(&part_world(&s, sl, 0));
    assert!((plate - 0.01).abs() < 1e-6, "plate's lower face at {plate} m");
    for k in [1, 2] {
        let foot = min_y(&part_world(&s, sl, k));
        assert!(foot.abs() < 1e-6, "bar {k} foot at {foot} m");
    }
    assert!(s.bodies.q[sl][2].abs() < 1e-9 && s.bodies.q[sl][0].abs() < 1e-9, "{:?}", s.bodies.q[sl]);
    let weight = s.bodies.info[sl].mass * G;
    let r = s.contact_resultant(sl);
    assert!((r[1] - weight).abs() < 1e-6 * weight && r[0].abs() < 1e-6 * weight, "reaction {r:?}, weight {weight}");
    let contacts: Vec<_> = s.contact_forces().collect();
    assert_eq!(contacts.len(), 4, "{contacts:?}");
    for c in &contacts {
        assert_eq!((c.candidate, c.antagonist), (fl, sl));
        let x = c.point[0].abs();
        assert!((0.03 - 1e-9..=0.04 + 1e-9).contains(&x) && c.point[1].abs() < 1e-6, "contact at {:?}", c.point);
    }
    // The four contacts are the two ends of the two feet, one each.
    let mut xs: Vec<f64> = contacts.iter().map(|c| c.point[0]).collect();
    xs.sort_by(f64::total_cmp);
    for (x, e) in xs.iter().zip([-0.04, -0.03, 0.03, 0.04]) {
        assert!((x - e).abs() < 1e-9, "{xs:?}");
    }
}

/// Horizontal constant force `f` (N) on body `i`.
fn push(s: &mut System, i: usize, f: f64) {
    s.bodies.info[i].loads.push(Load { direction: [1.0, 0.0], force: Harmonic::constant(f) });
}

/// A fixed floor (top at y = 0) with two fixed blocks on it, `[−0.5, −0.005]` and
/// `[0.005, 0.5]` × `[0, 0.01]`: a groove 0.01 m wide and deep at x = 0.
fn grooved_floor(s: &mut System) {
    floor(s);
    rect(s, 0.495, 0.01, -0.2525, 0.005, 0.0, true);
    rect(s, 0.495, 0.01, 0.2525, 0.005, 0.0, true);
}

/// (c) A plate with one 0.01 m bar sitting in a groove of the same width does
/// not move under a horizontal force of 1.5 × its weight, five times the friction
/// limit μ W (μ = 0.3): the groove's side bears it. The force is below the
/// bearing capacity: the body can only leave by tipping about the plate's far
/// bottom corner (0.05, 0.01), which needs `F (y_G − 0.01) > W · 0.05`, i.e.
/// F > 3.48 W. The same plate without the bar, on the same floor, slides with
/// the closed-form acceleration `(F − μ W)/m = 1.2 g` (θ = ½ integrates a
/// constant force exactly, so `x = ½ a t²` up to the solver tolerance).
#[test]
fn a_bar_in_a_groove_holds_a_lateral_force_that_slides_the_flat_plate() {
    let (mu, ratio) = (0.3, 1.5);
    // With the bar.
    let mut s = system(1e-3, mu, 0.0);
    grooved_floor(&mut s);
    let parts = vec![rectangle(-0.05, 0.01, 0.05, 0.04), rectangle(-0.005, 0.0, 0.005, 0.01)];
    let (sl, g) = compound(&mut s, &parts, [0.0, 0.0], false);
    let weight = s.bodies.info[sl].mass * G;
    let y_g = g.y;
    let capacity = weight * 0.05 / (y_g - 0.01);
    assert!((capacity / weight - 3.483).abs() < 1e-3, "tipping capacity {capacity} N for a weight {weight} N");
    push(&mut s, sl, ratio * weight);
    let q0 = s.bodies.q[sl];
    run(&mut s, 200);
    let q = s.bodies.q[sl];
    let moved = (q[0] - q0[0]).hypot(q[1] - q0[1]);
    assert!(moved < 1e-7 && q[2].abs() < 1e-6, "the sleeper moved by {moved} m, turned by {} rad", q[2]);
    let r = s.contact_resultant(sl);
    assert!((r[0] + ratio * weight).abs() < 1e-6 * weight && (r[1] - weight).abs() < 1e-6 * weight, "{r:?}");

    // The flat plate.
    let mut s = system(1e-3, mu, 0.0);
    grooved_floor(&mut s);
    let pl = rect(&mut s, 0.1, 0.03, 0.0, 0.025, 0.0, false);
    let weight = s.bodies.info[pl].mass * G;
    push(&mut s, pl, ratio * weight);
    let steps = 50;
    run(&mut s, steps);
    let t = steps as f64 * 1e-3;
    let expected = 0.5 * (ratio - mu) * G * t * t;
    let x = s.bodies.q[pl][0];
    assert!((x - expected).abs() < 1e-6 * expected, "plate slid {x} m, expected {expected} m");
    assert!((s.bodies.q[pl][1] - 0.025).abs() < 1e-6);
}

/// Keys of a compound resting on a compound (a floor of two halves) with a disc
/// and a pentagon on top are unique, sorted, and the same from step to step at
/// rest (so the warm start finds every contact); contacts are split per part.
#[test]
fn compound_contact_keys_are_unique_and_stable() {
    let mut s = system(1e-3, 0.5, 0.0);
    let (fl, _) =
        compound(&mut s, &[rectangle(-0.2, -0.02, 0.0, 0.0), rectangle(0.0, -0.02, 0.2, 0.0)], [0.0, 0.0], true);
    let (sl, _) = compound(&mut s, &sleeper_parts(), [0.0, 0.001], false);
    let d = common::disc(&mut s, 0.005, -0.02, 0.0455, false);
    let p = common::regular(&mut s, 5, 0.006, 0.02, 0.048, 0.1);
    let mut previous: Vec<(u32, u32, u32)> = Vec::new();
    for step in 0..600 {
        s.step().unwrap();
        let keys: Vec<_> = s.contacts.iter().map(|c| c.key).collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "step {step}: keys not strictly sorted: {keys:?}");
        if step >= 590 {
            assert_eq!(keys, previous, "step {step}: keys changed at rest");
        }
        previous = keys;
    }
    let pairs: Vec<(u32, u32)> = previous.iter().map(|k| (k.0, k.1)).collect();
    let count = |a: usize, b: usize| pairs.iter().filter(|&&x| x == (a as u32, b as u32)).count();
    // Each foot on its own half of the floor (edge to edge: two points each).
    assert_eq!(count(fl, sl), 4, "{previous:?}");
    assert!(count(sl, d) >= 1 && count(sl, p) >= 1, "{previous:?}");
    // The left foot touches part 0 of the floor, the right foot part 1: the
    // candidate's part index is in bits 20..28 of the feature id.
    for c in s.contacts.iter().filter(|c| c.key.0 == fl as u32) {
        let part = (c.key.2 >> 20) & 0xff;
        assert_eq!(part, u32::from(c.point.x > 0.0), "{c:?}");
    }
    let plate = min_y(&part_world(&s, sl, 0));
    assert!((plate - 0.01).abs() < 1e-6, "plate's lower face at {plate} m");
}

/// The three-part sleeper in free flight falls like a point mass (θ = ½
/// integrates gravity exactly) and finds no contact with itself.
#[test]
fn compound_free_fall_is_exact() {
    let mut s = System::new(params(1e-3), 1);
    let (i, _) = compound(&mut s, &sleeper_parts(), [0.0, 1.0], false);
    let y0 = s.bodies.q[i][1];
    run(&mut s, 100);
    let t = 0.1;
    assert!((s.bodies.q[i][1] - (y0 - 0.5 * G * t * t)).abs() < 1e-12);
    assert_eq!(s.contacts.len(), 0);
}

/// A scene with a sleeper made of a plate and two bars, on a floor (the
/// example of `docs/scene-format.md`, turned and moved).
const SCENE: &str = r#"
[simulation]
engine = "nscd"
dt = 1.0e-3
duration = 0.01
thickness = 0.5

[[material]]
name = "concrete"
density = 2400.0

[[body]]
name = "floor"
material = "concrete"
polygon = [[-0.5, -0.1], [0.5, -0.1], [0.5, 0.0], [-0.5, 0.0]]
position = [0.0, 0.0]
fixed = true

[[body]]
name = "sleeper"
material = "concrete"
parts = [
  [[-0.05, 0.01], [0.05, 0.01], [0.05, 0.04], [-0.05, 0.04]],   # the plate
  [[-0.04, 0.0], [-0.03, 0.0], [-0.03, 0.01], [-0.04, 0.01]],   # left bar
  [[0.03, 0.0], [0.04, 0.0], [0.04, 0.01], [0.03, 0.01]],       # right bar
]
position = [0.1, 0.0]
angle = 0.2
"#;

fn scene_error(text: &str) -> String {
    match Scene::from_toml_str(text) {
        Err(Error::Scene(m)) => {
            assert!(!m.contains('\n'), "multi-line message: {m:?}");
            m
        }
        Err(e) => panic!("expected a scene error, got {e:?}"),
        Ok(_) => panic!("expected a scene error, the scene was accepted"),
    }
}

/// (d) `parts` loads and builds; the body is placed by its frame origin and the
/// engine gets the centre of mass; the scene writes back unchanged.
#[test]
fn scene_with_parts_loads_builds_and_round_trips() {
    let scene = Scene::from_toml_str(SCENE).unwrap();
    let sys = scene.build().unwrap();
    let b = &sys.bodies.info[1];
    let Shape::Compound(c) = &b.shape else { panic!("not a compound: {:?}", b.shape) };
    assert_eq!(c.parts.len(), 3);
    let area = 0.003 + 2.0 * 0.0001;
    assert!((b.mass - 2400.0 * 0.5 * area).abs() < 1e-12 * b.mass);
    // Centroid in the scene frame: (0, (0.003·0.025 + 0.0002·0.005)/0.0032) = (0, 0.02375).
    let (sin, cos) = 0.2f64.sin_cos();
    let rc = rotate(Vec2::new(0.0, 0.02375), cos, sin);
    let q = sys.bodies.q[1];
    assert!((q[0] - (0.1 + rc.x)).abs() < 1e-12 && (q[1] - rc.y).abs() < 1e-12 && q[2] == 0.2, "{q:?}");
    let text = scene.to_toml_string().unwrap();
    assert!(text.contains("parts = [[["), "{text}");
    assert_eq!(Scene::from_toml_str(&text).unwrap(), scene);
    // The default alert distance uses the smallest part inradius (a bar's, 0.005 m).
    assert!((sys.params.alert_distance - 0.01 * 0.005).abs() < 1e-15, "{}", sys.params.alert_distance);
}

#[test]
fn bad_parts_give_one_line_errors() {
    let nonconvex = SCENE.replace(
        "[[-0.04, 0.0], [-0.03, 0.0], [-0.03, 0.01], [-0.04, 0.01]]",
        "[[-0.04, 0.0], [-0.03, 0.0], [-0.035, 0.002], [-0.03, 0.01], [-0.04, 0.01]]",
    );
    let m = scene_error(&nonconvex);
    assert!(m.starts_with("body[1] 'sleeper': parts[1]: non-convex polygon: the turn at vertex"), "{m}");
    let overlap = SCENE.replace(
        "[[0.03, 0.0], [0.04, 0.0], [0.04, 0.01], [0.03, 0.01]]",
        "[[0.03, 0.0], [0.04, 0.0], [0.04, 0.02], [0.03, 0.02]]",
    );
    let m = scene_error(&overlap);
    assert_eq!(m, "body[1] 'sleeper': parts[2]: overlaps parts[0] by 1e-2 m (parts may share edges but not overlap)");
    let clockwise = SCENE.replace(
        "[[0.03, 0.0], [0.04, 0.0], [0.04, 0.01], [0.03, 0.01]]",
        "[[0.03, 0.0], [0.03, 0.01], [0.04, 0.01], [0.04, 0.0]]",
    );
    let m = scene_error(&clockwise);
    assert!(m.starts_with("body[1] 'sleeper': parts[2]: polygon vertices must be given counter-clockwise"), "{m}");
    let m = scene_error(&SCENE.replace("angle = 0.2", "angle = 0.2\ndisc = 0.1"));
    assert_eq!(m, "body[1] 'sleeper': shape: give exactly one of polygon, regular, disc, parts, not several");
    let body = SCENE.find("parts = [").unwrap();
    let empty = format!("{}parts = []\nposition = [0.0, 0.0]\n", &SCENE[..body]);
    let m = scene_error(&empty);
    assert_eq!(m, "body[1] 'sleeper': parts: a compound needs at least one part");
    let m = scene_error(&SCENE.replace("[[0.03, 0.0], [0.04, 0.0]", "[[0.03, 0.0, 1.0], [0.04, 0.0]"));
    assert!(m.contains("array of exactly 2 elements"), "{m}");
}

/// A compound is written as one VTK polygon cell per part, with every cell
/// array repeating the body's value for each of its parts.
#[test]
fn vtk_writes_one_cell_per_part() {
    let sys = Scene::from_toml_str(SCENE).unwrap().build().unwrap();
    let dir = scratch::dir("vtk");
    let path = dir.join("bodies.vtk");
    ballast::plane::vtk::write_bodies(&path, &sys).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let mut lines = text.lines();
    let polygons = lines.by_ref().find(|l| l.starts_with("POLYGONS")).unwrap();
    assert_eq!(polygons, "POLYGONS 4 20", "floor + 3 parts, 4 vertices each");
    assert!(text.contains("CELL_DATA 4"));
    let ids: Vec<&str> = text.lines().skip_while(|l| !l.starts_with("SCALARS body_id")).skip(2).take(4).collect();
    assert_eq!(ids, ["0", "1", "1", "1"]);
    let radius: Vec<f64> = text
        .lines()
        .skip_while(|l| !l.starts_with("SCALARS radius"))
        .skip(2)
        .take(4)
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(radius[1], radius[3]);
    assert_eq!(radius[1], sys.bodies.info[1].shape.bounding_radius());
}
