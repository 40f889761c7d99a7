//! The contact list of the MD engine (`MdSystem::contact_forces`): the forces of
//! a sphere's contacts add up to the contact force and torque the step applied
//! to it, the walls' to the force on each wall, for a pile of frictional
//! Hertz–Mindlin spheres falling into a box (velocity Verlet, background
//! damping) and for a quarter sample with symmetry planes under a servo plate
//! (Gear, whose corrector moves the spheres after the evaluation).
//!
//! Tolerance of the sums: the list holds, per contact, the very force vector the
//! step applied, split into normal and tangential parts along the step's own
//! unit normal and put back together (`f_n n + f_t`): one rounding per
//! component, 1e-16 of the contact force; the sums run over at most a dozen
//! contacts per sphere in another order than the engine's. Their differences are
//! therefore round-off, a few 1e-16 of the largest contact force; 1e-12 of it
//! leaves a margin of three and a half orders of magnitude, while any missing,
//! doubled or misplaced contact (or a point off by the smallest overlap) shows
//! at 1e-4 or more.

use crate::md_common;

use ballast::md::law::hertz_alpha_for_restitution;
use ballast::md::{
    Drive, GearSet, Ghosts, History1, Integrator, MdContactKind, MdSystem, Motion, PairLaw, Particles, Shape,
    SymmetryPlane, Wall, V3,
};
use md_common::*;

/// Sphere radius (m) and Young's modulus of the soft test material (Pa).
const R: f64 = 0.01;
const YOUNG: f64 = 1e7;
/// Time step (s): about a hundredth of the Hertz contact time of two spheres
/// meeting at 1 m/s (1.9 ms).
const DT: f64 = 2e-5;

fn hertz(mu: f64) -> PairLaw {
    let mat = material(YOUNG);
    PairLaw::hertz(&mat, &mat, hertz_alpha_for_restitution(0.5), 0.3, mu)
}

/// `n` spheres on a loose grid of `nx × nx` per layer, 1 mm apart, shifted by
/// up to ±0.4 mm (a fixed pseudo-random pattern) so that they do not stack
/// exactly, above `z0` (m), from `x0` (m) along x and y; moving down at 0.2 m/s
/// with a sideways drift of up to 0.4 mm/s.
fn spheres(n: usize, nx: usize, x0: f64, z0: f64) -> Particles {
    let rho = material(YOUNG).density;
    let mut p = Particles::default();
    let pitch = 2.0 * R + 1e-3;
    for k in 0..n {
        let (ix, iy, iz) = (k % nx, (k / nx) % nx, k / (nx * nx));
        let jitter = |s: usize| 4e-4 * (((k * 7919 + s * 104_729) % 1000) as f64 / 500.0 - 1.0);
        let x = V3::new(
            x0 + R + 5e-4 + pitch * ix as f64 + jitter(1),
            x0 + R + 5e-4 + pitch * iy as f64 + jitter(2),
            z0 + R + 5e-4 + pitch * iz as f64,
        );
        let v = V3::new(jitter(3), jitter(4), -0.2);
        p.push(&format!("s{k}"), 0, rho, R, x, v, V3::zeros());
    }
    p
}

/// What a check compares.
struct Sums {
    /// Largest |difference| of a sphere's force (N) and torque (N·m).
    force: f64,
    torque: f64,
    /// Largest |difference| of a wall's force (N).
    wall: f64,
    /// Largest contact force (N), the scale of the tolerance.
    scale: f64,
    pairs: usize,
    images: usize,
    walls: usize,
}

/// Adds up the contact list of `sys` per sphere and per wall and compares with
/// the engine: `expected_force(i)` and `expected_torque(i)` are sphere `i`'s
/// contact force and torque. The torque arm is `point − centre` with
/// `centre(i)`, or with `None` the evaluation's `−(r − δ/2) n` (pairs) and
/// `−(r − δ) n` (walls).
fn sums(
    sys: &MdSystem,
    expected_force: impl Fn(usize) -> V3,
    expected_torque: impl Fn(usize) -> V3,
    centre: Option<&dyn Fn(usize) -> V3>,
) -> Sums {
    let p = &sys.particles;
    let n = p.len();
    let mut f = vec![V3::zeros(); n];
    let mut t = vec![V3::zeros(); n];
    let mut on_wall = vec![V3::zeros(); sys.walls.len()];
    let mut s = Sums { force: 0.0, torque: 0.0, wall: 0.0, scale: 0.0, pairs: 0, images: 0, walls: 0 };
    for c in sys.contact_forces() {
        let nrm = V3::from(c.normal);
        let force = V3::from(c.force());
        let ft = V3::from(c.f_t);
        assert!((nrm.norm() - 1.0).abs() < 1e-15, "unit normal {nrm:?}");
        assert!(c.overlap > 0.0 && c.overlap < 0.2 * R, "overlap {}", c.overlap);
        // Hertz–Mindlin: compressive normal force, tangential force within Coulomb's cone.
        assert!(c.f_n >= 0.0, "{c:?}");
        assert!(ft.norm() <= 0.5 * c.f_n * (1.0 + 1e-12) + 1e-300, "{c:?}");
        assert!(ft.dot(&nrm).abs() <= 1e-15 * ft.norm().max(c.f_n), "{c:?}");
        s.scale = s.scale.max(force.norm());
        let i = c.sphere;
        let wall = matches!(c.kind, MdContactKind::Wall { .. });
        let arm = match centre {
            Some(x) => V3::from(c.point) - x(i),
            None => -nrm * (p.r[i] - if wall { c.overlap } else { 0.5 * c.overlap }),
        };
        f[i] += force;
        t[i] += arm.cross(&force);
        match c.kind {
            MdContactKind::Pair { j } => {
                assert!(j > i && j < n);
                f[j] -= force;
                let arm_j = match centre {
                    Some(x) => V3::from(c.point) - x(j),
                    None => nrm * (p.r[j] - 0.5 * c.overlap),
                };
                t[j] -= arm_j.cross(&force);
                s.pairs += 1;
            }
            MdContactKind::Image { origin, planes } => {
                assert!(origin < n && planes != 0);
                s.images += 1;
            }
            MdContactKind::Wall { wall } => {
                on_wall[wall] -= force;
                s.walls += 1;
            }
        }
    }
    for i in 0..n {
        s.force = s.force.max((f[i] - expected_force(i)).norm());
        s.torque = s.torque.max((t[i] - expected_torque(i)).norm());
    }
    for (w, sum) in sys.walls.iter().zip(&on_wall) {
        s.wall = s.wall.max((w.force - sum).norm());
    }
    s
}

/// 36 spheres dropped into a 7 cm square box (floor and four sides, friction
/// 0.5 between spheres, 0.3 on the walls), with translational and rotational
/// background damping, velocity Verlet: checked on the way down and at rest.
#[test]
fn verlet_pile_contact_forces_add_up_per_sphere() {
    let mat = 1;
    let box_w = 3.0 * (2.0 * R + 1e-3) + 1e-3;
    let walls = vec![
        plane("floor", mat, V3::zeros(), V3::z()),
        plane("x0", mat, V3::zeros(), V3::x()),
        plane("x1", mat, V3::new(box_w, 0.0, 0.0), -V3::x()),
        plane("y0", mat, V3::zeros(), V3::y()),
        plane("y1", mat, V3::new(0.0, box_w, 0.0), -V3::y()),
    ];
    let mut set = settings(DT, V3::new(0.0, 0.0, -G), Integrator::Verlet, 0.1 * R);
    set.background_damping = 0.02;
    set.background_rotational_damping = 0.01;
    let mut sys = system(set, spheres(36, 3, 0.0, 0.0), walls, laws(hertz(0.5), hertz(0.3)));
    let (gb, gr) = (set.background_damping, set.background_rotational_damping);
    let mut checked = 0;
    for step in 1..=6000 {
        let stats = sys.step().unwrap();
        if step % 500 != 0 {
            continue;
        }
        let p = &sys.particles;
        // Velocity Verlet evaluates the forces (and the damping) at the velocity
        // of the first half kick: v_eval = v − (f/m + g) h/2, ω_eval = ω − t/I h/2.
        let v_eval = |i: usize| p.v[i] - (p.f[i] * p.inv_m[i] + set.gravity) * (0.5 * DT);
        let w_eval = |i: usize| p.w[i] - p.t[i] * (p.inv_i[i] * 0.5 * DT);
        let force = |i: usize| p.f[i] + v_eval(i) * gb;
        let torque = |i: usize| p.t[i] + w_eval(i) * (gr * p.r[i] * p.r[i]);
        // Verlet's centres do not move after the evaluation.
        let centre = |i: usize| p.x[i];
        let s = sums(&sys, force, torque, Some(&centre));
        eprintln!(
            "step {step}: {} pairs, {} wall contacts; largest contact force {:.3e} N; sums off by {:.1e} N, \
             {:.1e} N·m, walls {:.1e} N",
            s.pairs, s.walls, s.scale, s.force, s.torque, s.wall
        );
        assert_eq!(s.pairs as f64, stats.contacts);
        assert_eq!(s.walls, stats.wall_contacts);
        assert!(s.force <= 1e-12 * s.scale, "force sums off by {:e} N", s.force);
        assert!(s.torque <= 1e-12 * s.scale * R, "torque sums off by {:e} N·m", s.torque);
        assert!(s.wall <= 1e-12 * s.scale * 36.0, "wall sums off by {:e} N", s.wall);
        if s.pairs > 20 && s.walls > 9 {
            checked += 1;
        }
    }
    let weight: f64 = sys.particles.m.iter().sum::<f64>() * G;
    let floor = sys.walls[0].normal_force();
    eprintln!("at rest: floor pressed with {:.4} N, weight {weight:.4} N", -floor);
    assert!(checked >= 5, "the pile must be in contact on most checks");
}

/// A quarter sample (symmetry planes x = 0 and y = 0) of 27 spheres on a floor
/// under a servo plate pressing with 5 N, 5-value Gear, no background damping:
/// its corrector moves the spheres after the evaluation, so the list must use
/// the evaluation's centres (the torques use the evaluation's arms;
/// the sums hold to round-off only if every normal, overlap and force is the
/// step's). A system read back from its serde form gives the same list.
#[test]
fn gear_quarter_sample_with_images_and_servo_plate() {
    let mat = 1;
    let top = 4.0 * (2.0 * R + 1e-3);
    let plate = Wall::new(
        "plate",
        mat,
        Shape::Plane { point: V3::new(0.0, 0.0, top), normal: -V3::z() },
        Motion::Servo {
            mass: 0.05,
            viscosity: 2.0,
            drive: Drive::Force(History1 { base: 5.0, amplitude: 0.0, period: 0.0 }),
        },
    );
    let walls = vec![plane("floor", mat, V3::zeros(), V3::z()), plate];
    let set = settings(DT, V3::new(0.0, 0.0, -G), Integrator::Gear(GearSet::Gear5), 0.1 * R);
    let planes = vec![
        SymmetryPlane { point: V3::zeros(), normal: V3::x() },
        SymmetryPlane { point: V3::zeros(), normal: V3::y() },
    ];
    // The first row and column within ±0.4 mm of touching their images.
    let particles = spheres(27, 3, -5e-4, 0.0);
    let mut sys = MdSystem::new(set, particles, walls, laws(hertz(0.5), hertz(0.3)), Ghosts::new(planes)).unwrap();
    let (mut images, mut corrected) = (0, 0.0f64);
    for step in 1..=5000 {
        let stats = sys.step().unwrap();
        if step % 500 != 0 {
            continue;
        }
        let p = &sys.particles;
        let s = sums(&sys, |i| p.f[i], |i| p.t[i], None);
        eprintln!(
            "step {step}: {} pairs, {} image and {} wall contacts; plate at {:.3e} m pressed with {:.3} N; sums off \
             by {:.1e} N, {:.1e} N·m, walls {:.1e} N",
            s.pairs,
            s.images,
            s.walls,
            sys.walls[1].s,
            -sys.walls[1].normal_force(),
            s.force,
            s.torque,
            s.wall
        );
        assert_eq!(s.pairs as f64 + 0.5 * s.images as f64, stats.contacts);
        assert_eq!(s.walls, stats.wall_contacts);
        assert!(s.force <= 1e-12 * s.scale, "force sums off by {:e} N", s.force);
        assert!(s.torque <= 1e-12 * s.scale * R, "torque sums off by {:e} N·m", s.torque);
        assert!(s.wall <= 1e-12 * s.scale * 27.0, "wall sums off by {:e} N", s.wall);
        images = images.max(s.images);
        // The geometry is the evaluation's: each overlap is that of the centres
        // the forces were evaluated at, and each point sits between them; the
        // corrector has moved the spheres since.
        let x = sys.force_positions();
        let moved = x.iter().zip(&p.x).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        let mut off = 0.0f64;
        for c in sys.contact_forces() {
            let (i, nrm, point) = (c.sphere, V3::from(c.normal), V3::from(c.point));
            if let MdContactKind::Pair { j } = c.kind {
                off = off.max((2.0 * R - (x[i] - x[j]).norm() - c.overlap).abs());
                off = off.max((x[j] + nrm * (R - 0.5 * c.overlap) - point).norm());
            }
            let a = if matches!(c.kind, MdContactKind::Wall { .. }) { R - c.overlap } else { R - 0.5 * c.overlap };
            off = off.max((x[i] - nrm * a - point).norm());
        }
        eprintln!("  centres moved by the corrector up to {moved:.1e} m; geometry off by {off:.1e} m");
        // Round-off of a few operations on coordinates of 0.05 m (ulp 7e-18 m).
        assert!(off <= 1e-15, "the contact geometry is not the evaluation's: {off:e} m");
        corrected = corrected.max(moved);
    }
    assert!(
        corrected > 1e-12,
        "the corrector must move the spheres (by {corrected:e} m) for the check to mean anything"
    );
    assert!(images > 0, "spheres must touch their images");
    assert!(-sys.walls[1].normal_force() > 0.0, "the plate must be pressing");
    let back: MdSystem = serde_json::from_str(&serde_json::to_string(&sys).unwrap()).unwrap();
    assert_eq!(back.contact_forces(), sys.contact_forces());
}
