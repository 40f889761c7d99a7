//! Builders shared by the physics tests: systems assembled through the library API.
#![allow(dead_code)]

use ballast::geometry::{ConvexPolygon, Shape};
use ballast::nscd::{BodyInfo, ContactLaw, Imposed, NlgsSettings, NscdParams, Policy, System};

pub const G: f64 = 9.81;

/// Parameters with a tight solver so tests compare physics, not solver error.
pub fn params(dt: f64) -> NscdParams {
    NscdParams {
        dt,
        theta: 0.5,
        gravity: [0.0, -G],
        alert_distance: 1e-4,
        nlgs: NlgsSettings {
            policy: Policy::QuadMax,
            tolerance: 1e-10,
            min_iterations: 1,
            max_iterations: 5000,
            max_factor: 4.0,
            symmetric: false,
            split_min_rows: ballast::nscd::nlgs::DEFAULT_SPLIT_MIN_ROWS,
            ..NlgsSettings::default()
        },
    }
}

/// A system with one material (index 0) and the given contact law.
pub fn system(dt: f64, friction: f64, restitution: f64) -> System {
    let mut s = System::new(params(dt), 1);
    s.set_law(0, 0, ContactLaw { friction, restitution_n: restitution, restitution_t: 0.0 });
    s
}

fn info(shape: Shape, density: f64, fixed: bool) -> BodyInfo {
    let (area, j) = shape.area_and_polar_moment();
    BodyInfo {
        name: String::new(),
        shape,
        material: 0,
        mass: density * area,
        inertia: density * j,
        fixed,
        imposed: Imposed::default(),
        loads: Vec::new(),
    }
}

/// A rectangle `w × h` (m) centred at `(x, y)`, rotated by `angle`; returns its index.
pub fn rect(s: &mut System, w: f64, h: f64, x: f64, y: f64, angle: f64, fixed: bool) -> usize {
    let v = [[-w / 2.0, -h / 2.0], [w / 2.0, -h / 2.0], [w / 2.0, h / 2.0], [-w / 2.0, h / 2.0]];
    let (p, _) = ConvexPolygon::new(&v).unwrap();
    s.bodies.push(info(Shape::Polygon(p), 2000.0, fixed), [x, y, angle], [0.0; 3])
}

/// A regular polygon of circumradius `r` (m) centred at `(x, y)`.
pub fn regular(s: &mut System, sides: usize, r: f64, x: f64, y: f64, angle: f64) -> usize {
    let p = ConvexPolygon::regular(sides, r).unwrap();
    s.bodies.push(info(Shape::Polygon(p), 2000.0, false), [x, y, angle], [0.0; 3])
}

/// A disc of radius `r` (m) centred at `(x, y)`.
pub fn disc(s: &mut System, r: f64, x: f64, y: f64, fixed: bool) -> usize {
    s.bodies.push(info(Shape::disc(r).unwrap(), 2000.0, fixed), [x, y, 0.0], [0.0; 3])
}

/// A fixed floor whose top face is at `y = 0`, spanning `x ∈ [-1, 1]`.
pub fn floor(s: &mut System) -> usize {
    rect(s, 2.0, 0.2, 0.0, -0.1, 0.0, true)
}

/// Runs `n` steps, panicking with the error if one fails.
pub fn run(s: &mut System, n: usize) {
    for _ in 0..n {
        s.step().unwrap();
    }
}
