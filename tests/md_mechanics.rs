//! Closed-form checks of MD mechanics through the public API: sliding → rolling,
//! a sphere on an incline, energy conservation, the force balance of a deposit,
//! a stress-controlled (servo) wall, and the invariance of the forces under the
//! neighbour-list skin and the number of threads.
//!
//! Scales as in `md_contact.rs`: spheres of 0.5–1 cm, density 2000 kg/m³, soft
//! materials (E = 10 MPa; k = 5000 N/m, k_t = 1000 N/m as in David et al. §3),
//! time steps of 1/50 to 1/200 of a contact time.

use crate::md_common;

use ballast::md::law::hertz_alpha_for_restitution;
use ballast::md::{
    Damping, Drive, GearSet, Ghosts, History1, Integrator, LawTable, MdSystem, Model, Motion, PairLaw, Particles,
    SymmetryPlane, Wall, V3,
};
use md_common::*;

/// Sphere radius (m) of the single-sphere tests.
const R: f64 = 0.01;
/// Young's modulus of the soft test material (Pa).
const YOUNG: f64 = 1e7;

fn hertz_law(e: f64, alpha_t: f64, mu: f64) -> PairLaw {
    let mat = material(YOUNG);
    PairLaw::hertz(&mat, &mat, hertz_alpha_for_restitution(e), alpha_t, mu)
}

fn linear_law(alpha: f64, mu: f64) -> PairLaw {
    PairLaw::linear(5000.0, 1000.0, Damping::Ratio(alpha), Damping::Ratio(alpha), mu, mu)
}

/// Overlap (m) of a sphere of mass `m` resting on a plane under a normal load `m g_n`.
fn resting_overlap(law: &PairLaw, m: f64, gn: f64) -> f64 {
    match law.model {
        Model::Hertz => (3.0 * m * gn / (4.0 * law.e_star * R.sqrt())).powf(2.0 / 3.0),
        Model::Linear => m * gn / law.kn,
    }
}

/// One sphere resting on the plane z = 0 (at its static overlap under
/// `gravity`), with velocity `v`.
fn sphere_on_plane(law: PairLaw, gravity: V3, v: V3, dt: f64) -> MdSystem {
    let rho = material(YOUNG).density;
    let m = sphere_mass(rho, R);
    let d = resting_overlap(&law, m, -gravity.z);
    let mut p = Particles::default();
    p.push("s", 0, rho, R, V3::new(0.0, 0.0, R - d), v, V3::zeros());
    let base = plane("base", 1, V3::zeros(), V3::z());
    system(settings(dt, gravity, Integrator::Verlet, 0.1 * R), p, vec![base], laws(law, law))
}

/// Check 4: a sphere launched sliding at `v0` without spin on a plane with
/// friction μ = 0.3 decelerates at `μ g` while its spin grows, and rolls after
/// `t_s = 2 v0 / (7 μ g)` at `5/7 v0`. The angular momentum about a point of the
/// plane is conserved (friction acts in the plane), so with the lever arm
/// `a = r − δ` the engine uses (the contact point is on the plane), the final speed
/// is exactly `v0 / (1 + I/(m a²))`, which is `5/7 v0 (1 − 0.57 δ/r)`
/// (δ/r = 2.4e-3 for Hertz, 1.6e-3 for linear here).
///
/// Tolerances: final speed vs `v0 / (1 + I/(m a²))` 1e-4 relative: the
/// tangential spring's oscillation at the stick transition is damped
/// (α_t = 0.3 at ω_t ≈ 1300 rad/s: e^{-60} over the run) and momentum is only
/// perturbed by the vertical force fluctuations (N ≠ m g) while sliding, which the
/// normal damping keeps ≪ 1e-4 m g; vs `5/7 v0`: that plus the lever-arm
/// correction `0.6 δ/r`. Sliding phase: at `t_s/2`, `v = v0 − μ g t`. Hertz
/// keeps the tangential force at `μ F_n` (exact up to round-off; tolerance 1e-6
/// relative to `μ g t`). The linear law (David et al. eqs. 3–4 with μ_s = μ_d)
/// goes back to sticking whenever the test force `−k_t ξ − γ_t v_t`, with ξ
/// set from the previous step's slip velocity, falls below `μ f_n`, which happens
/// on steps where the slip decelerates (here at `3.5 μ g`): the force is then
/// short of `μ f_n` by `γ_t Δv_t = 3.5 γ_t μ g Δt`, a relative deficit of
/// `3.5 γ_t Δt / m` (1.4 %, O(Δt)) on at most every step; tolerance that
/// fraction of `μ g t`.
#[test]
fn sliding_sphere_ends_rolling_at_five_sevenths() {
    let (v0, mu) = (0.5, 0.3);
    let m = sphere_mass(material(YOUNG).density, R);
    for law in [hertz_law(0.5, 0.3, mu), linear_law(0.3, mu)] {
        let dt = 2e-5;
        let mut s = sphere_on_plane(law, V3::new(0.0, 0.0, -G), V3::new(v0, 0.0, 0.0), dt);
        let t_s = 2.0 * v0 / (7.0 * mu * G);
        let half = (0.5 * t_s / dt).round() as usize;
        for _ in 0..half {
            s.step().unwrap();
        }
        let (t_mid, v_mid) = (s.time, s.particles.v[0].x);
        let v_mid_theory = v0 - mu * G * t_mid;
        while s.time < 0.25 {
            s.step().unwrap();
        }
        let d = resting_overlap(&law, m, G);
        let a = R - d;
        let v_end = s.particles.v[0].x;
        let slip = v_end - a * s.particles.w[0].y;
        let v_exact = v0 / (1.0 + 0.4 * R * R / (a * a));
        eprintln!(
            "{:?}: v(t_s/2) = {v_mid:.7} (v0 − μ g t = {v_mid_theory:.7}); final v = {v_end:.8}, exact {v_exact:.8}, 5/7 v0 = {:.8}, slip {slip:.2e}",
            law.model,
            5.0 / 7.0 * v0
        );
        let deficit = match law.model {
            Model::Hertz => 1e-6,
            Model::Linear => 3.5 * law.damping_t.gamma(m, law.kt) * dt / m,
        };
        assert!((v_mid - v_mid_theory).abs() <= deficit * mu * G * t_mid, "sliding: v {v_mid} vs {v_mid_theory}");
        assert!(rel(v_end, v_exact) < 1e-4, "rolling: v {v_end} vs {v_exact}");
        assert!(rel(v_end, 5.0 / 7.0 * v0) < 0.6 * d / R + 1e-4, "rolling: v {v_end} vs 5/7 v0");
        assert!(slip.abs() < 1e-4 * v0, "not rolling: slip {slip}");
    }
}

/// Check 5: a sphere released on an incline of angle α (gravity tilted, plane
/// z = 0), μ = 0.3, so the threshold is `tan α = 3.5 μ` (α = 46.4°). Below, it
/// rolls: `a = g sin α / (1 + I/(m a_c²)) = 5/7 g sin α (1 − 0.57 δ/r)` with the
/// lever arm `a_c = r − δ`; above, it slides: `a = g (sin α − μ cos α)`.
///
/// The acceleration is measured as `(v(0.3 s) − v(0.15 s)) / 0.15 s`, after the
/// tangential spring's start-up oscillation has died out (α_t = 0.3:
/// e^{-50} by 0.15 s), so the only errors are the remaining velocity
/// fluctuations (≪ 1e-6 m/s against Δv ≈ 0.4–1 m/s). Tolerance 1e-4 relative
/// against the expressions above (the rolling one with the lever-arm correction,
/// and also 5/7 g sin α within that correction).
#[test]
fn sphere_on_incline_rolls_or_slides() {
    let mu = 0.3;
    let m = sphere_mass(material(YOUNG).density, R);
    for law in [hertz_law(0.5, 0.3, mu), linear_law(0.3, mu)] {
        for deg in [20.0f64, 40.0, 50.0, 60.0] {
            let alpha = deg.to_radians();
            let rolls = alpha.tan() < 3.5 * mu;
            let g = V3::new(G * alpha.sin(), 0.0, -G * alpha.cos());
            let dt = 2e-5;
            let mut s = sphere_on_plane(law, g, V3::zeros(), dt);
            let (t1, t2) = (0.15, 0.3);
            let mut v1 = None;
            while s.time < t2 - 0.5 * dt {
                s.step().unwrap();
                if v1.is_none() && s.time >= t1 - 0.5 * dt {
                    v1 = Some((s.time, s.particles.v[0].x));
                }
            }
            let (t1, v1) = v1.unwrap();
            let acc = (s.particles.v[0].x - v1) / (s.time - t1);
            let d = resting_overlap(&law, m, G * alpha.cos());
            let a = R - d;
            let slip = s.particles.v[0].x - a * s.particles.w[0].y;
            let expected = if rolls {
                G * alpha.sin() / (1.0 + 0.4 * R * R / (a * a))
            } else {
                G * (alpha.sin() - mu * alpha.cos())
            };
            eprintln!(
                "{:?} α = {deg}°: acceleration {acc:.6} m/s², expected {expected:.6} ({}), 5/7 g sin α = {:.6}, slip {slip:.2e} m/s",
                law.model,
                if rolls { "rolling" } else { "sliding" },
                5.0 / 7.0 * G * alpha.sin()
            );
            assert!(rel(acc, expected) < 1e-4, "α = {deg}°: {acc} vs {expected}");
            if rolls {
                assert!(rel(acc, 5.0 / 7.0 * G * alpha.sin()) < 0.6 * d / R + 1e-4);
                assert!(slip.abs() < 1e-5, "α = {deg}°: rolling expected, slip {slip}");
            } else {
                assert!(slip > 0.1, "α = {deg}°: sliding expected, slip {slip}");
            }
        }
    }
}

/// A tiny deterministic generator (numbers in [0, 1)), so the tests need no seed handling.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The six planes of the box `[0, l]³` (sphere–wall material 1), named
/// `base`, `top`, `x0`, `x1`, `y0`, `y1`.
fn box_walls(l: V3) -> Vec<Wall> {
    vec![
        plane("base", 1, V3::zeros(), V3::z()),
        plane("top", 1, V3::new(0.0, 0.0, l.z), -V3::z()),
        plane("x0", 1, V3::zeros(), V3::x()),
        plane("x1", 1, V3::new(l.x, 0.0, 0.0), -V3::x()),
        plane("y0", 1, V3::zeros(), V3::y()),
        plane("y1", 1, V3::new(0.0, l.y, 0.0), -V3::y()),
    ]
}

/// Check 6: eight spheres bouncing in a box of planes under gravity, Hertz
/// without damping or friction, 1e5 Verlet steps of 1e-5 s (about 200 steps per
/// contact at the impact speeds here, ~1 m/s).
///
/// Energy = kinetic + elastic (the step's `MdStepStats`) + gravitational
/// (`gravitational_energy()`, from the fixed base plane: `Σ m g z`), i.e.
/// `kinetic_energy + potential_energy()`.
///
/// Bound: Verlet conserves a shadow energy, so there is no secular drift from the
/// smooth part of the motion; the energy seen at the steps differs from it by
/// `O((ωΔt)²)` of the elastic energy during contacts, and each impact loses
/// `O((Δt/t_c)^{5/2})` of its energy because the Hertz force switches on within a
/// step (check 1 measured 2(1 − e) = 2.5e-6 at 200 steps per contact), an
/// impact carrying at most ~1/4 of the total energy (eight spheres, one or two
/// in each impact). With the ~300 impacts of the 1 s run this is ≲ 2e-4 of the
/// total; tolerance 2e-4 relative on the largest deviation from the initial
/// energy (the shadow-energy fluctuation, `(ωΔt)²/8 ≈ 3e-5` of the elastic
/// energy in contacts, is smaller).
#[test]
fn energy_is_conserved_without_dissipation() {
    let mat = material(YOUNG);
    let law = PairLaw::hertz(&mat, &mat, 0.0, 0.0, 0.0);
    let l = V3::new(0.08, 0.08, 0.08);
    let mut rng = Lcg(7);
    let mut p = Particles::default();
    for k in 0..8 {
        let (i, j, h) = ((k % 2) as f64, ((k / 2) % 2) as f64, (k / 4) as f64);
        let x = V3::new(0.02 + 0.04 * i, 0.02 + 0.04 * j, 0.02 + 0.04 * h);
        let v = V3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
        p.push("s", 0, mat.density, R, x, v, V3::zeros());
    }
    let mut s =
        system(settings(1e-5, V3::new(0.0, 0.0, -G), Integrator::Verlet, 0.2 * R), p, box_walls(l), laws(law, law));
    assert_eq!(s.gravity_reference, 0.0, "the base plane z = 0 is the zero of the gravitational energy");
    let energy = |s: &MdSystem| s.last.kinetic_energy + s.potential_energy();
    let e0 = energy(&s);
    let mut worst = 0.0f64;
    let mut impacts = 0;
    let mut touching = 0;
    for _ in 0..100_000 {
        let st = s.step().unwrap();
        let now = st.contacts as usize + st.wall_contacts;
        if now > touching {
            impacts += now - touching;
        }
        touching = now;
        worst = worst.max((energy(&s) - e0).abs());
    }
    eprintln!("E0 = {e0:.6e} J, worst |E − E0| / E0 = {:.3e} over {impacts} impacts", worst / e0);
    assert!(impacts > 50, "the spheres should collide: {impacts} impacts");
    assert!(worst < 2e-4 * e0, "energy drift {:.3e} of E0", worst / e0);
}

/// Check 8: 45 polydisperse spheres (r = 4–6 mm) dropped into a 45 mm square box
/// with friction (μ = 0.5 between spheres, 0.3 on the walls), with the linear law
/// of David et al. (k = 5000 N/m, k_t = 1000 N/m, damping ratio 0.3) and with
/// Hertz (E = 10 MPa, e = 0.3), a little background damping, left to rest
/// (1.2 s, 40 000 steps of 3e-5 s). Force balance of the whole deposit (contact
/// forces between spheres cancel): `base + Σ_sides F_z − W = M a_cm`. The side
/// walls carry at most `μ_w Σ|N_side|` vertically (Coulomb), so
/// `|base − W| ≤ μ_w Σ|N_side| + M|a_cm|`, with `M a_cm = Σ f_i + M g` computed
/// from the forces of the last step (the dynamic tolerance; it is also checked to
/// be a small correction, < 1e-3 W). Also checked: the deposit is at rest
/// (kinetic energy < 1e-8 of `W` × 1 cm, i.e. velocities ~1e-5 m/s against ~1 m/s
/// while falling) and the base carries most of the weight (> 50 %).
#[test]
fn deposit_base_reaction_equals_weight_within_wall_friction() {
    let mu_wall = 0.3;
    let cases =
        [(linear_law(0.3, 0.5), linear_law(0.3, mu_wall)), (hertz_law(0.3, 0.3, 0.5), hertz_law(0.3, 0.3, mu_wall))];
    for (sphere, wall) in cases {
        let l = V3::new(0.045, 0.045, 0.2);
        let mut rng = Lcg(11);
        let mut p = Particles::default();
        for k in 0..45 {
            let (i, j, h) = ((k % 3) as f64, ((k / 3) % 3) as f64, (k / 9) as f64);
            let r = 0.004 + 0.002 * rng.next();
            let jitter = V3::new(rng.next() - 0.5, rng.next() - 0.5, 0.0) * 0.002;
            let x = V3::new(0.0075 + 0.015 * i, 0.0075 + 0.015 * j, 0.008 + 0.014 * h) + jitter;
            p.push("s", 0, 2000.0, r, x, V3::zeros(), V3::zeros());
        }
        let mut set = settings(3e-5, V3::new(0.0, 0.0, -G), Integrator::Verlet, 0.002);
        set.background_damping = 0.005;
        // Torque −γ_br r² ω: 1e-3 kg/s relaxes spins in about 2/5 m/γ_br ≈ 0.2 s.
        set.background_rotational_damping = 1e-3;
        let mut walls = box_walls(l);
        walls.retain(|w| w.name != "top");
        let mut s = system(set, p, walls, laws(sphere, wall));
        for _ in 0..40_000 {
            s.step().unwrap();
        }
        let p = &s.particles;
        let mass: f64 = p.m.iter().sum();
        let weight = s.weight();
        let m_acm = (p.f.iter().sum::<V3>() + s.settings.gravity * mass).norm();
        let base = s.wall_load("base").unwrap();
        let sides: f64 = ["x0", "x1", "y0", "y1"].iter().map(|n| s.wall_load(n).unwrap().abs()).sum();
        let ke = s.last.kinetic_energy;
        eprintln!(
            "{:?}: base {base:.6e} N, weight {weight:.6e} N, |base − W| = {:.3e} N, μ_w Σ|N_side| = {:.3e} N, M|a_cm| = {m_acm:.2e} N, KE = {ke:.2e} J",
            sphere.model,
            (base - weight).abs(),
            mu_wall * sides
        );
        assert!(ke < 1e-8 * weight * 0.01, "not at rest: kinetic energy {ke}");
        assert!(m_acm < 1e-3 * weight, "not in equilibrium: M a_cm = {m_acm}");
        assert!(base > 0.5 * weight, "base load {base} vs weight {weight}");
        assert!(
            (base - weight).abs() <= mu_wall * sides + m_acm,
            "|base − W| {} > wall friction share",
            (base - weight).abs()
        );
    }
}

/// Check 9b: a stress-controlled wall. A layer of 3 × 3 spheres (r = 1 cm) in
/// a 6 cm square box, under gravity, loaded by a top plane driven by
/// `σ = 100 Pa` over the box area (`Drive::Stress(σ, None)`: 3.6e-3 m², so
/// σA = 0.36 N ≈ 4.4 × the layer's weight), wall mass 0.05 kg, viscosity
/// 50 kg/s (near-critical on the layer's stiffness 9 k/2). At equilibrium
/// `m_w s̈ = σA + F_c − γ_w ṡ = 0` gives a reaction of the spheres `−F_c = σA`;
/// the base then carries `W + σA` and each top contact `σA/9` (overlap
/// `σA/(9k)`). All modes are damped (contact damping ratio 0.3, wall near
/// critical) over ≥ 20 relaxation times (0.4 s), so the residual is far below the
/// 1e-6 relative tolerance.
#[test]
fn servo_wall_reaches_stress_equilibrium() {
    let sigma = 100.0;
    let law = linear_law(0.3, 0.3);
    let l = V3::new(0.06, 0.06, 2.0 * R);
    let mut p = Particles::default();
    for k in 0..9 {
        let x = V3::new(R + 2.0 * R * (k % 3) as f64, R + 2.0 * R * (k / 3) as f64, R);
        p.push("s", 0, 2000.0, R, x, V3::zeros(), V3::zeros());
    }
    let mut walls = box_walls(l);
    let top = walls.iter_mut().find(|w| w.name == "top").unwrap();
    top.motion = Motion::Servo {
        mass: 0.05,
        viscosity: 50.0,
        drive: Drive::Stress(History1 { base: sigma, amplitude: 0.0, period: 0.0 }, None),
    };
    let mut s = system(settings(2e-5, V3::new(0.0, 0.0, -G), Integrator::Verlet, 0.1 * R), p, walls, laws(law, law));
    while s.time < 0.4 {
        s.step().unwrap();
    }
    let area = l.x * l.y;
    let load = s.wall_load("top").unwrap();
    let stress = s.wall_stress("top", None).unwrap();
    let base = s.wall_load("base").unwrap();
    let top = s.walls.iter().find(|w| w.name == "top").unwrap();
    eprintln!(
        "top load {load:.9e} N (σA = {:.9e}), stress {stress:.9e} Pa, base {base:.9e} N (W + σA = {:.9e}), wall s = {:.3e} m, ṡ = {:.1e} m/s, max overlap {:.6e} ((mg + σA/9)/k = {:.6e})",
        sigma * area,
        s.weight() + sigma * area,
        top.s,
        top.s_dot,
        s.last.max_overlap,
        (s.particles.m[0] * G + sigma * area / 9.0) / law.kn,
    );
    assert!(rel(load, sigma * area) < 1e-6, "reaction {load} vs σA {}", sigma * area);
    assert!(rel(stress, sigma) < 1e-6, "wall stress {stress} vs {sigma}");
    assert!(rel(base, s.weight() + sigma * area) < 1e-6, "base {base}");
    // The largest overlap is at the base: (m g + σA/9) / k.
    let d_base = (s.particles.m[0] * G + sigma * area / 9.0) / law.kn;
    assert!(rel(s.last.max_overlap, d_base) < 1e-6, "base overlap {} vs {d_base}", s.last.max_overlap);
    // The wall went down by the two overlaps of a column.
    let d_top = sigma * area / 9.0 / law.kn;
    assert!(rel(top.s, d_base + d_top) < 1e-6, "wall travel {} vs {}", top.s, d_base + d_top);
    // The top wall has moved down onto the layer (its normal is −z).
    assert!(top.s > 0.0, "the servo wall should have advanced: s = {}", top.s);
}

/// A dense, frictional, shaken sample for the bookkeeping checks: `nx × ny × nz`
/// spheres (r = 5.1 mm, 2 % overlap on a 1 cm lattice) in a box with `room` (m)
/// to spare along each axis and a symmetry plane at x = 0 instead of a wall,
/// random velocities and spins, Hertz with friction, under gravity; time step
/// 1e-5 s (1/100 of a contact at 0.5 m/s).
fn dense_sample(nx: usize, ny: usize, nz: usize, room: f64, skin: f64) -> MdSystem {
    let mat = material(YOUNG);
    let law = PairLaw::hertz(&mat, &mat, hertz_alpha_for_restitution(0.7), 0.3, 0.5);
    let mut rng = Lcg(3);
    let mut p = Particles::default();
    let r = 0.0051;
    for h in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let x = V3::new(0.005 + 0.01 * i as f64, 0.005 + 0.01 * j as f64, 0.005 + 0.01 * h as f64);
                let v = V3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 0.5;
                let w = V3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * 50.0;
                p.push("s", 0, 2000.0, r, x, v, w);
            }
        }
    }
    let mut walls = box_walls(V3::new(0.01 * nx as f64, 0.01 * ny as f64, 0.01 * nz as f64) + V3::repeat(room));
    walls.retain(|w| w.name != "x0");
    let mut table = LawTable::new(2);
    table.set(0, 0, law);
    table.set(0, 1, law);
    let ghosts = Ghosts::new(vec![SymmetryPlane { point: V3::zeros(), normal: V3::x() }]);
    MdSystem::new(settings(1e-5, V3::new(0.0, 0.0, -G), Integrator::Verlet, skin), p, walls, table, ghosts).unwrap()
}

/// Check 10a: the neighbour list is an optimisation only. With a skin of 1e-9 m
/// the list (and the symmetry images) are rebuilt at every step; with 1 mm (a
/// fifth of a radius) every few tens of steps. The 64 spheres, given 2 mm of
/// room, push apart, collide and settle, with tens of contacts at a time.
/// Contacts are found from the same rows in the same key order either way (pairs
/// listed but apart contribute nothing) and the contact memory is carried over at
/// each rebuild, so over 2000 steps the forces and positions must agree up to
/// the order of floating-point sums: the engine splits the pair list into chunks
/// balanced by the number of listed pairs, which depends on the skin, and adds
/// the chunks' force buffers: differences of a few ulps (3e-16 N on forces of
/// ~1 N), which the dynamics then amplifies (a position difference δx changes a
/// contact force by `k_n δx`, k_n ~ 1e4 N/m). Tolerances: 1e-12 of the largest
/// force over the first 500 steps, 1e-10 over the 2000 (measured 1.4e-12:
/// Δx ≈ 2e-16 m by then), positions to 1e-12 of the box size.
#[test]
fn forces_do_not_depend_on_the_skin() {
    let mut tight = dense_sample(4, 4, 4, 0.002, 1e-9);
    let mut loose = dense_sample(4, 4, 4, 0.002, 1e-3);
    let (mut df_early, mut df_all, mut f_max, mut contacts) = (0.0f64, 0.0f64, 0.0f64, 0.0);
    for step in 0..2000 {
        contacts += tight.step().unwrap().contacts / 2000.0;
        loose.step().unwrap();
        let (a, b) = (&tight.particles, &loose.particles);
        for i in 0..a.len() {
            f_max = f_max.max(a.f[i].norm());
            let d = (a.f[i] - b.f[i]).norm().max((a.t[i] - b.t[i]).norm() / a.r[i]);
            df_all = df_all.max(d);
            if step < 500 {
                df_early = df_early.max(d);
            }
        }
    }
    let dx =
        (0..tight.particles.len()).map(|i| (tight.particles.x[i] - loose.particles.x[i]).norm()).fold(0.0, f64::max);
    eprintln!(
        "builds: {} (tight) vs {} (loose); mean contacts {contacts:.1}; max |Δf| {df_early:.2e} N over 500 steps, {df_all:.2e} N over 2000 (|f| up to {f_max:.2e}), max |Δx| {dx:.2e} m",
        tight.neighbours.builds, loose.neighbours.builds
    );
    assert!(tight.neighbours.builds >= 2000, "the tight list should be rebuilt every step");
    assert!((5..200).contains(&loose.neighbours.builds), "the loose list should be kept for many steps");
    assert!(contacts > 20.0, "the sample should be dense: {contacts} contacts on average");
    assert!(df_early <= 1e-12 * f_max, "forces differ by {df_early} over the first 500 steps");
    assert!(df_all <= 1e-10 * f_max, "forces differ by {df_all}");
    assert!(dx <= 1e-12 * 0.04, "positions differ by {dx}");
}

/// Check 10b: the engine cuts every phase of a step (predictor, pair forces,
/// sums + walls + corrector) into the same two chunks whatever the threads, and
/// adds the chunks' results in chunk order, so one thread and two give the same
/// numbers bit for bit; on two threads the second chunk of each phase runs on the
/// team's helper thread. The sample has 11 × 11 × 9 = 1089 spheres (enough for
/// two threads: the engine stays on one below 256 spheres per chunk), five walls
/// and a symmetry plane, so every kind of force is in both chunks. A race (both
/// chunks writing one sphere) or a sum in another order would show as a
/// difference of at least an ulp, which 200 steps of a dense frictional sample
/// amplify far above zero.
#[test]
fn threads_give_the_same_numbers() {
    let mut one = dense_sample(11, 11, 9, 0.0, 0.001);
    let mut two = one.clone();
    one.set_threads(1);
    two.set_threads(2);
    assert_eq!(two.threads(), 2);
    for _ in 0..200 {
        let a = one.step().unwrap();
        let b = two.step().unwrap();
        assert_eq!(a, b);
    }
    let p = (&one.particles, &two.particles);
    assert!(one.last.contacts > 1000.0 && one.last.wall_contacts > 100, "{:?}", one.last);
    assert_eq!(p.0.x, p.1.x);
    assert_eq!(p.0.v, p.1.v);
    assert_eq!(p.0.w, p.1.w);
    assert_eq!(p.0.f, p.1.f);
    assert_eq!(p.0.t, p.1.t);
    for (a, b) in one.walls.iter().zip(&two.walls) {
        assert_eq!(a.force, b.force, "wall {}", a.name);
    }
}

/// A step that fails leaves the whole state of the last good step: the last
/// backup (every 100 steps) is restored and the steps after it made again.
/// Two soft spheres fly at each other at 20 m/s each (Δt = 10 µs: 0.4 mm closer
/// per step, contact at step ≈ 150, and a 1 MPa Hertz contact cannot stop them
/// before the overlap passes half a radius), while a third, pushed at 1 mm/s on
/// the floor, rocks on its tangential contact spring (sticking: peak force ≈
/// v₀√(k_t m) ≈ 1 mN < μ m g ≈ 5 mN), so that the wall contact memory changes at
/// every step. After the error the system must equal a copy taken after the last
/// good step, bit for bit, in every serialized part (spheres, Gear derivatives,
/// forces, pair and wall contact memory, neighbour list, walls, clock), and the
/// error names the step being made.
#[test]
fn a_failed_step_leaves_the_last_good_state() {
    let mat = material(1e6);
    let steel = material(210e9);
    let law = PairLaw::hertz(&mat, &mat, 0.3, 0.3, 0.5);
    let wall_law = PairLaw::hertz(&mat, &steel, 0.3, 0.3, 0.5);
    let r = 0.005;
    let mut p = Particles::default();
    let m = sphere_mass(2000.0, r);
    let delta0 = (m * G / ((4.0 / 3.0) * (1e6 / (2.0 * (1.0 - 0.25 * 0.25))) * r.sqrt())).powf(2.0 / 3.0);
    p.push("slider", 0, 2000.0, r, V3::new(0.0, 0.0, r - delta0), V3::new(0.001, 0.0, 0.0), V3::zeros());
    p.push("left", 0, 2000.0, r, V3::new(-0.035, 0.0, 0.1), V3::new(20.0, 0.0, 0.0), V3::zeros());
    p.push("right", 0, 2000.0, r, V3::new(0.035, 0.0, 0.1), V3::new(-20.0, 0.0, 0.0), V3::zeros());
    let floor = plane("floor", 1, V3::zeros(), V3::z());
    let mut sys = system(
        settings(1e-5, V3::new(0.0, 0.0, -G), Integrator::Gear(GearSet::Gear5), 0.001),
        p,
        vec![floor],
        laws(law, wall_law),
    );
    let (err, mut last_good) = loop {
        let before = sys.clone();
        match sys.step() {
            Ok(_) => assert!(sys.step < 1000, "no divergence"),
            Err(e) => break (e, before),
        }
    };
    let msg = err.to_string();
    assert!(msg.contains("runaway overlap") && (msg.contains("left") || msg.contains("right")), "{msg}");
    assert!(last_good.step > 100 && !last_good.step.is_multiple_of(100), "the test needs a replay: {}", last_good.step);
    assert!(msg.starts_with(&format!("step {}:", last_good.step + 1)), "{msg}");
    assert_eq!(sys.step, last_good.step, "held at the last good step");
    assert_eq!(serde_json::to_value(&sys).unwrap(), serde_json::to_value(&last_good).unwrap());
    assert!(sys.walls[0].contacts == 1, "the slider is on the floor");
    // The same next step, and the same failure, from both.
    assert_eq!(sys.step().unwrap_err().to_string(), last_good.step().unwrap_err().to_string());
    assert_eq!(serde_json::to_value(&sys).unwrap(), serde_json::to_value(&last_good).unwrap());
}

/// A sphere carried beyond the bounds of a scene (±1e9 m, `MAX_LENGTH`) ends the
/// run with a divergence naming it, so that the state can always be written back
/// as a valid scene: 0.5 mm inside the bound at 1 m/s, Δt = 1 ms, it crosses it
/// in the first step (x = 1e9 + 0.5 mm), and the system holds the start.
#[test]
fn a_sphere_beyond_the_scene_bounds_diverges() {
    let x0 = ballast::geometry::MAX_LENGTH - 5e-4;
    let mut p = Particles::default();
    p.push("runaway", 0, 2000.0, 0.01, V3::new(x0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0), V3::zeros());
    let law = PairLaw::hertz(&material(1e8), &material(1e8), 0.3, 0.3, 0.5);
    let mut sys = system(settings(1e-3, V3::zeros(), Integrator::Verlet, 0.001), p, vec![], laws(law, law));
    let err = sys.step().unwrap_err().to_string();
    assert!(err.starts_with("step 1: body 0 ('runaway')") && err.contains("beyond"), "{err}");
    assert_eq!((sys.step, sys.particles.x[0][0]), (0, x0), "held at the start");
}
