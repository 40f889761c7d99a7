//! Bad MD input never panics and never runs silently: each class of hostile
//! scene is refused at load with one line naming the field or the bodies and the
//! numbers (initial overlaps with spheres, walls and symmetry images; a time step
//! above the stability limit of the contacts; an explicit background damping
//! above its stability limit; non-finite numbers), the neighbour grid saturates
//! for spheres far apart, and every scene the crate generates still passes.
//! The contact times and stability limits are checked against closed forms and
//! against the engine itself.

use crate::md_common;

use ballast::md::law::{e_star, hertz_contact_time, hertz_max_overlap, linear_contact_time, HERTZ_DURATION};
use ballast::md::neighbours::{grid, Neighbours};
use ballast::md::{Damping, GearSet, Integrator, Material, PairLaw, Particles, V3};
use ballast::scenarios::{karrech, luding, md_bed};
use ballast::scene::MdScene;
use ballast::scene::SceneFile;
use md_common::*;
use std::f64::consts::PI;
use std::fmt::Write;

const DIORITE: Material = Material { density: 2710.0, young: 46.9e9, poisson: 0.25 };
const STEEL: Material = Material { density: 7850.0, young: 200e9, poisson: 0.3 };

/// One diorite sphere (r = 3.2 mm) resting on a steel base (its bottom at z = 0),
/// Hertz without damping, velocity Verlet, dt = 1e-6 s.
const RESTING: &str = r#"
[simulation]
engine = "md"
dt = 1e-6
duration = 1e-3

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
between = ["diorite", "steel"]
model = "hertz"
friction = 0.3
normal_damping_ratio = 0.0

[[wall]]
name = "base"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

[[body]]
name = "lower"
material = "diorite"
sphere = 0.0032
position = [0.0, 0.0, 0.0032]
"#;

/// Two glass spheres of radii 1 and 2 mm side by side on a steel floor, inside a
/// steel cylinder, with a diorite sphere too (materials for every pair).
const PAIR: &str = r#"
[simulation]
engine = "md"
dt = 1e-7
duration = 1e-5

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

[[contact]]
between = ["glass", "steel"]
model = "hertz"
friction = 0.3

[[wall]]
name = "floor"
material = "steel"
plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }

[[wall]]
name = "mould"
material = "steel"
cylinder = { axis_point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 0.01 }

[[body]]
name = "s0"
material = "glass"
sphere = 0.001
position = [0.0, 0.0, 0.001]

[[body]]
name = "s1"
material = "glass"
sphere = 0.002
position = [0.003, 0.0, 0.002]
"#;

/// `text` with the first `from` replaced by `to` (which must be there).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "test bug: {from:?} not in the scene");
    text.replacen(from, to, 1)
}

/// The one-line message of an invalid scene.
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
fn expect(text: &str, parts: &[&str]) -> String {
    let m = message(text);
    for p in parts {
        assert!(m.contains(p), "message {m:?} does not contain {p:?}");
    }
    m
}

/// The number that follows `after` in `message`.
fn number_after(message: &str, after: &str) -> f64 {
    let at = message.find(after).unwrap_or_else(|| panic!("{after:?} not in {message:?}")) + after.len();
    let token: String = message[at..].chars().take_while(|c| c.is_ascii_digit() || "+-.e".contains(*c)).collect();
    token.parse().unwrap_or_else(|_| panic!("no number after {after:?} in {message:?}"))
}

// ---------------------------------------------------------------- contact times

/// The elastic Hertz impact `m* δ̈ = −(4/3) E* √R* δ^{3/2}`, `δ(0) = 0`,
/// `δ̇(0) = v`, integrated by RK4 with 200 000 steps over the contact: its
/// duration and largest overlap. The zero crossing is located by linear
/// interpolation (error O(h²) ≈ 1e-10 of the duration).
fn integrated_hertz_impact(m: f64, r: f64, e: f64, v: f64) -> (f64, f64) {
    let k = 4.0 / 3.0 * e * r.sqrt() / m;
    let acc = |d: f64| if d > 0.0 { -k * d.powf(1.5) } else { 0.0 };
    let h = hertz_contact_time(m, r, e, v) / 200_000.0;
    let (mut d, mut u, mut t, mut d_max) = (0.0f64, v, 0.0, 0.0f64);
    loop {
        let (k1d, k1u) = (u, acc(d));
        let (k2d, k2u) = (u + 0.5 * h * k1u, acc(d + 0.5 * h * k1d));
        let (k3d, k3u) = (u + 0.5 * h * k2u, acc(d + 0.5 * h * k2d));
        let (k4d, k4u) = (u + h * k3u, acc(d + h * k3d));
        let dn = d + h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
        let un = u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        if dn <= 0.0 && t > 0.0 {
            return (t + h * d / (d - dn), d_max);
        }
        (d, u, t) = (dn, un, t + h);
        d_max = d_max.max(d);
    }
}

#[test]
fn hertz_contact_time_is_the_classical_duration_of_an_elastic_impact() {
    // Johnson (1985) §11.4 gives 2.94 δ_max / v, i.e. 2.868 (m*²/(R* E*² v))^{1/5}.
    assert!((HERTZ_DURATION - 2.868).abs() < 5e-4, "{HERTZ_DURATION}");
    assert!((HERTZ_DURATION / (15.0f64 / 16.0).powf(0.4) - 2.9433).abs() < 1e-4);
    // Diorite on steel (r = 1.5 mm) and two glass spheres, slow and fast: the
    // integrated impact agrees to 1e-6 (the RK4 and crossing errors are ~1e-10).
    let es = e_star(&DIORITE, &STEEL);
    let glass = Material { density: 2500.0, young: 6e10, poisson: 0.22 };
    let m = sphere_mass(2710.0, 1.5e-3);
    let mg = sphere_mass(2500.0, 1e-3);
    for (m, r, e, v) in [(m, 1.5e-3, es, 1.0), (m, 1.5e-3, es, 0.01), (0.5 * mg, 0.5e-3, e_star(&glass, &glass), 30.0)]
    {
        let (t, d_max) = integrated_hertz_impact(m, r, e, v);
        let formula = 2.868_265_699_195_331_5 * (m * m / (r * e * e * v)).powf(0.2);
        assert!((hertz_contact_time(m, r, e, v) - formula).abs() <= 1e-15 * formula);
        assert!((t / formula - 1.0).abs() < 1e-6, "integrated {t} s vs {formula} s");
        let overlap = hertz_max_overlap(m, r, e, v);
        assert!((d_max / overlap - 1.0).abs() < 1e-6, "δ_max {d_max} vs {overlap}");
        assert!((overlap - (15.0 * m * v * v / (16.0 * e * r.sqrt())).powf(0.4)).abs() <= 1e-15 * overlap);
    }
    // Through the pair law: the elastic duration, whatever the damping.
    let law = PairLaw::hertz(&DIORITE, &STEEL, 0.3, 0.3, 0.5);
    assert_eq!(law.contact_time(m, 1.5e-3, 2.0), hertz_contact_time(m, 1.5e-3, es, 2.0));
    assert_eq!(law.impact_overlap(m, 1.5e-3, 2.0), hertz_max_overlap(m, 1.5e-3, es, 2.0));
}

#[test]
fn linear_contact_time_is_pi_over_omega() {
    // David et al. §2 with their numbers: k = 5000 N/m, m = 1 g (m* = 0.5 g),
    // γ₀ = 0.05 kg/s: t_c = π / √(k/m* − η₀²) ≈ 1e-3 s ("t_c = 10⁻³ s").
    let (k, m, gamma): (f64, f64, f64) = (5000.0, 0.5e-3, 0.05);
    let eta = gamma / (2.0 * m);
    let expected = PI / (k / m - eta * eta).sqrt();
    assert!((linear_contact_time(k, m, gamma) - expected).abs() <= 1e-15 * expected);
    assert!((expected - 1e-3).abs() < 0.01e-3, "{expected}");
    // Undamped: π √(m*/k), exactly.
    assert!((linear_contact_time(k, m, 0.0) - PI * (m / k).sqrt()).abs() <= 1e-18);
    // The damped oscillation δ = (v/ω) e^{−η t} sin ωt is back at 0 after π/ω,
    // when the restitution is exp(−η t_c) (r = 0.95 in the paper: 2 %).
    assert!((f64::exp(-eta * expected) - 0.95).abs() < 0.02);
    // Critical or stronger damping: no rebound, no contact time.
    assert_eq!(linear_contact_time(k, m, 2.0 * (k * m).sqrt()), f64::INFINITY);
    // Through the pair law, with a ratio: γ = 2 α √(m* k).
    let law = PairLaw::linear(k, 1000.0, Damping::Ratio(0.1), Damping::Coefficient(0.0), 0.5, 0.5);
    let omega = (k / m).sqrt() * (1.0f64 - 0.01).sqrt();
    assert!((law.contact_time(m, 1.0, 7.0) - PI / omega).abs() <= 1e-12 * PI / omega);
    assert!((law.impact_overlap(m, 1.0, 2.0) - 2.0 * (m / k).sqrt()).abs() < 1e-18);
}

// ------------------------------------------------------------- stability limits

fn all_integrators() -> [Integrator; 6] {
    [
        Integrator::Verlet,
        Integrator::Gear(GearSet::Karrech),
        Integrator::Gear(GearSet::Gear3),
        Integrator::Gear(GearSet::Gear4),
        Integrator::Gear(GearSet::Gear5),
        Integrator::Gear(GearSet::Gear6),
    ]
}

#[test]
fn verlet_stability_limit_is_the_closed_form() {
    // Verlet on ẍ = −ω² x − 2ζω ẋ (dashpot on the half-step velocity): the step
    // matrix has det 1 − 2ζh and trace 2 − h² − 2ζh (h = ω Δt); it is stable for
    // h < 2(√(1 + ζ²) − ζ) (Jury), and for a pure damping c Δt < 2. The computed
    // limit allows a spectral radius of 1 + 1e-3 (STABILITY_TOLERANCE): 1e-3 relative.
    let omega = 1234.5;
    for zeta in [0.0, 0.1, 0.44, 1.0, 3.0] {
        let dt = Integrator::Verlet.stability_limit(omega * omega, 2.0 * zeta * omega);
        let exact = 2.0 * ((1.0 + zeta * zeta).sqrt() - zeta) / omega;
        assert!((dt / exact - 1.0).abs() < 1e-3, "ζ = {zeta}: {dt} vs {exact}");
        assert!(dt >= exact * (1.0 - 1e-9), "never below the exact limit");
    }
    let c = 50.0;
    let dt = Integrator::Verlet.stability_limit(0.0, c);
    assert!((dt * c - 2.0).abs() < 2e-3, "{}", dt * c);
    assert_eq!(Integrator::Verlet.stability_limit(0.0, 0.0), f64::INFINITY);
}

/// A sphere resting on a plane through a linear contact (k = 1e4 N/m, damping
/// ratio ζ) under gravity oscillates about its rest overlap as `ẍ = −(k/m) x −
/// (γ/m) ẋ`: the engine's own step. Started 2e-6 m above rest (a quarter of the
/// rest overlap), run `steps` steps of `dt`; returns the largest distance from
/// rest over the last half of the run (m), infinite if the run diverged.
fn resting_oscillation(integrator: Integrator, zeta: f64, dt: f64, steps: usize) -> f64 {
    let (r, k) = (0.01, 1e4);
    let rho = 2000.0;
    let m = sphere_mass(rho, r);
    let rest = r - m * G / k;
    let law = PairLaw::linear(k, k, Damping::Ratio(zeta), Damping::Coefficient(0.0), 0.5, 0.5);
    let mut p = Particles::default();
    p.push("s", 0, rho, r, V3::new(0.0, 0.0, rest + 2e-6), V3::zeros(), V3::zeros());
    let floor = plane("floor", 1, V3::zeros(), V3::z());
    let mut sys = system(settings(dt, V3::new(0.0, 0.0, -G), integrator, 1e-3), p, vec![floor], laws(law, law));
    let mut worst = 0.0f64;
    for n in 0..steps {
        if sys.step().is_err() {
            return f64::INFINITY;
        }
        if n >= steps / 2 {
            worst = worst.max((sys.particles.x[0][2] - rest).abs());
        }
    }
    worst
}

#[test]
fn stability_limits_are_where_the_engine_goes_unstable() {
    // For every integrator and two damping ratios: 10 % below the computed limit
    // the engine's oscillation about rest does not grow (it stays below its 2e-6
    // m start: 1.5 × for margin); 10 % above, it grows past 3 × in 20 000 steps,
    // while still in contact (the rest overlap is 8.2e-6 m; beyond, the sphere
    // bounces, which bounds the growth of the slowest, Gear 'karrech' at ζ = 0.2,
    // at 7 ×; the others diverge).
    let m = sphere_mass(2000.0, 0.01);
    let omega2 = 1e4 / m;
    for integrator in all_integrators() {
        for zeta in [0.2, 0.6] {
            let limit = integrator.stability_limit(omega2, 2.0 * zeta * omega2.sqrt());
            let below = resting_oscillation(integrator, zeta, 0.9 * limit, 20_000);
            let above = resting_oscillation(integrator, zeta, 1.1 * limit, 20_000);
            assert!(below < 3e-6, "{integrator:?} ζ = {zeta}: {below} m at 0.9 × {limit} s");
            assert!(above > 6e-6, "{integrator:?} ζ = {zeta}: {above} m at 1.1 × {limit} s");
        }
    }
}

// ------------------------------------------------------------------- time step

/// The stability limit the validator computes for `RESTING`'s contact
/// (diorite sphere of radius `r`, mass `m`, on steel, undamped Hertz, velocity
/// Verlet) at impact speed `v`: the contact linearised at the largest overlap of
/// an impact at `v`, `k = 2 E* √(r δ_max)`, doubled for a sphere between two such
/// contacts (`ω² = 2k/m`), and Verlet's `ω Δt < 2`: `Δt = √2 √(m/k)`.
fn resting_limit(r: f64, v: f64) -> (f64, f64) {
    let m = sphere_mass(2710.0, r);
    let es = e_star(&DIORITE, &STEEL);
    let k = 2.0 * es * (r * hertz_max_overlap(m, r, es, v)).sqrt();
    (2.0f64.sqrt() * (m / k).sqrt(), hertz_contact_time(m, r, es, v))
}

#[test]
fn a_time_step_above_the_stability_limit_is_refused_with_both_numbers() {
    // The review's case: dt = 1e-3 s for a diorite sphere resting on a base (it
    // bounced to 456 m and the run exited 0).
    let at_rest = MdScene::from_toml_str(RESTING).unwrap();
    assert_eq!(at_rest.steps(), 1000);
    let m = expect(&edit(RESTING, "dt = 1e-6", "dt = 1e-3"), &[
        "simulation.dt: 0.001 s is above the stability limit ",
        " s of velocity Verlet for the 'diorite'–'steel' contacts (the smallest sphere, body[0] 'lower', on wall[0] \
         'base'): Hertz contact time ",
        " s at 1 m/s",
    ]);
    // At rest the fastest impact is the reference 1 m/s (a fall from 3.2 mm is
    // 0.25 m/s). Numbers printed to 3 digits: 0.5 %; the limit's tolerance 1e-3.
    let (limit, t_c) = resting_limit(0.0032, 1.0);
    let shown = number_after(&m, "stability limit ");
    assert!((shown / limit - 1.0).abs() < 0.007, "{shown} vs {limit}");
    let shown = number_after(&m, "Hertz contact time ");
    assert!((shown / t_c - 1.0).abs() < 0.007, "{shown} vs {t_c}");
    // The limit itself: 10 % below passes, 10 % above is refused.
    MdScene::from_toml_str(&edit(RESTING, "dt = 1e-6", &format!("dt = {:?}", 0.9 * limit))).unwrap();
    expect(&edit(RESTING, "dt = 1e-6", &format!("dt = {:?}", 1.1 * limit)), &["simulation.dt: "]);
}

#[test]
fn falls_initial_speeds_and_damping_tighten_the_limit() {
    let dt_of = |text: &str| number_after(&message(&edit(text, "dt = 1e-6", "dt = 1.0")), "stability limit ");
    let duration = |text: &str| edit(text, "duration = 1e-3", "duration = 10.0");
    // Dropped from 20 m above the base: it lands at √(2 g (20 − r)) m/s.
    let high = duration(&edit(RESTING, "position = [0.0, 0.0, 0.0032]", "position = [0.0, 0.0, 20.0032]"));
    let v = (2.0 * 9.81 * 20.0f64).sqrt();
    let m = message(&edit(&high, "dt = 1e-6", "dt = 1.0"));
    assert!((number_after(&m, " s at ") / v - 1.0).abs() < 0.007, "{m}");
    assert!((dt_of(&high) / resting_limit(0.0032, v).0 - 1.0).abs() < 0.007);
    // Thrown down at 50 m/s from rest height: 2 × 50 m/s + the fall from 3.2 mm.
    let thrown = duration(&edit(
        RESTING,
        "position = [0.0, 0.0, 0.0032]",
        "position = [0.0, 0.0, 0.0032]\nvelocity = [0.0, 0.0, -50.0]",
    ));
    let v = 100.0 + (2.0 * 9.81 * 0.0032f64).sqrt();
    assert!((dt_of(&thrown) / resting_limit(0.0032, v).0 - 1.0).abs() < 0.007);
    // A damping ratio of 0.44 (Karrech et al.): doubled with the contact, Verlet's
    // limit 2(√(1 + ζ'²) − ζ')/ω' with ζ' = √2 × 0.44 is 0.70 of the undamped one.
    let damped = duration(&edit(RESTING, "normal_damping_ratio = 0.0", "normal_damping_ratio = 0.44"));
    let z = 2.0f64.sqrt() * 0.44;
    let ratio = (1.0 + z * z).sqrt() - z;
    assert!((dt_of(&damped) / (resting_limit(0.0032, 1.0).0 * ratio) - 1.0).abs() < 0.007);
    // Gear 6 is far less stable than Verlet with that damping (0.178 against
    // 1.305 in ω Δt for ζ = 0.44 on one contact).
    let gear6 = edit(&damped, "[[material]]", "[md]\nintegrator = \"gear\"\ngear = \"gear6\"\n\n[[material]]");
    let m = message(&edit(&gear6, "dt = 1e-6", "dt = 1.0"));
    assert!(m.contains("of Gear 'gear6' for"), "{m}");
    assert!(number_after(&m, "stability limit ") < 0.25 * dt_of(&damped));
}

#[test]
fn linear_contacts_are_limited_by_pi_sqrt_m_over_k() {
    // David et al.'s law (k = 5000 N/m, undamped here) on a 5 mm sphere of
    // 2000 kg/m³ against a wall: t_c = π √(m/k), limit √2 √(m/k) with Verlet.
    let text = edit(
        &edit(
            RESTING,
            "model = \"hertz\"\nfriction = 0.3\nnormal_damping_ratio = 0.0",
            "model = \"linear\"\nfriction = 0.3\nnormal_stiffness = 5000.0\ntangential_stiffness = 1000.0",
        ),
        "sphere = 0.0032\nposition = [0.0, 0.0, 0.0032]",
        "sphere = 0.005\nposition = [0.0, 0.0, 0.005]",
    );
    let text = edit(&edit(&text, "density = 2710.0", "density = 2000.0"), "dt = 1e-6", "dt = 1e-3");
    let m = expect(&text, &["simulation.dt: 0.001 s is above the stability limit", "linear contact time "]);
    let mass = sphere_mass(2000.0, 0.005);
    let t_c = PI * (mass / 5000.0).sqrt();
    assert!((number_after(&m, "linear contact time ") / t_c - 1.0).abs() < 0.007, "{m}");
    let limit = 2.0f64.sqrt() * (mass / 5000.0).sqrt();
    assert!((number_after(&m, "stability limit ") / limit - 1.0).abs() < 0.007, "{m}");
}

// --------------------------------------------------------------- initial overlaps

#[test]
fn sphere_pairs_overlapping_deeper_than_a_tenth_of_the_smaller_radius_are_refused() {
    MdScene::from_toml_str(PAIR).unwrap();
    // s1 (r = 2 mm) 2.8 mm from s0 (r = 1 mm): 0.2 mm into it, 20 % of 1 mm.
    let dx = (0.0028f64.powi(2) - 0.001f64.powi(2)).sqrt();
    let deep = edit(PAIR, "position = [0.003, 0.0, 0.002]", &format!("position = [{dx:?}, 0.0, 0.002]"));
    expect(&deep, &["body[0] 's0' and body[1] 's1': initial overlap 2e-4 m is 20.0 % of the smaller radius (at most 10 % allowed)"]);
    // 5 % passes, and so do the static overlaps of a deposited sample (1e-6 m).
    for into in [5e-5, 1e-6] {
        let dx = ((0.003 - into) * (0.003 - into) - 0.001f64.powi(2)).sqrt();
        MdScene::from_toml_str(&edit(
            PAIR,
            "position = [0.003, 0.0, 0.002]",
            &format!("position = [{dx:?}, 0.0, 0.002]"),
        ))
        .unwrap();
    }
    // One sphere inside the other.
    let inside = edit(PAIR, "position = [0.003, 0.0, 0.002]", "position = [0.0, 0.0, 0.002]");
    expect(&inside, &["body[0] 's0' and body[1] 's1': initial overlap 0.002 m is 200.0 % of the smaller radius"]);
}

#[test]
fn spheres_behind_outside_or_deep_in_walls_are_refused() {
    // Plane: the centre behind it is refused whatever the depth.
    let behind = edit(PAIR, "position = [0.0, 0.0, 0.001]", "position = [0.0, 0.0, -0.0005]");
    expect(&behind, &["body[0] 's0' and wall[0] 'floor': the centre is 5e-4 m behind the wall (its normal points to the free side)"]);
    let on = edit(PAIR, "position = [0.0, 0.0, 0.001]", "position = [0.0, 0.0, 0.0]");
    expect(&on, &["body[0] 's0' and wall[0] 'floor': the centre is 0 m behind the wall"]);
    // 0.42 mm into the floor: 42 %.
    let deep = edit(PAIR, "position = [0.0, 0.0, 0.001]", "position = [0.0, 0.0, 0.00058]");
    expect(
        &deep,
        &["body[0] 's0' and wall[0] 'floor': initial overlap 4.2e-4 m is 42.0 % of the radius (at most 10 % allowed)"],
    );
    MdScene::from_toml_str(&edit(PAIR, "position = [0.0, 0.0, 0.001]", "position = [0.0, 0.0, 0.00095]")).unwrap();
    // Cylinder: the centre outside, a sphere wider than it, a sphere deep in it.
    let out = edit(PAIR, "position = [0.003, 0.0, 0.002]", "position = [0.011, 0.0, 0.002]");
    expect(&out, &["body[1] 's1' and wall[1] 'mould': the centre is 0.001 m outside the cylinder"]);
    let wide =
        edit(PAIR, "sphere = 0.002\nposition = [0.003, 0.0, 0.002]", "sphere = 0.011\nposition = [0.0, 0.0, 0.011]");
    expect(&wide, &["body[1] 's1' and wall[1] 'mould': the sphere's radius 0.011 m does not fit in the cylinder of radius 0.01 m"]);
    let into = edit(PAIR, "position = [0.003, 0.0, 0.002]", "position = [0.0085, 0.0, 0.002]");
    expect(&into, &["body[1] 's1' and wall[1] 'mould': initial overlap 5e-4 m is 25.0 % of the radius"]);
    // Disc: behind it within its radius is refused, behind it but beside it is not.
    let disc = |at: &str| {
        let lid = "[[wall]]\nname = \"lid\"\nmaterial = \"steel\"\n\
                   disc = { point = [0.0, 0.0, 0.01], normal = [0.0, 0.0, -1.0], radius = 0.005 }\n\n[[body]]";
        edit(&edit(PAIR, "[[body]]", lid), "position = [0.003, 0.0, 0.002]", at)
    };
    expect(
        &disc("position = [0.003, 0.0, 0.012]"),
        &["body[1] 's1' and wall[2] 'lid': the centre is 0.002 m behind the wall"],
    );
    MdScene::from_toml_str(&disc("position = [0.0075, 0.0, 0.012]")).unwrap();
}

#[test]
fn spheres_must_be_on_the_sample_side_of_symmetry_planes() {
    // The images assume every sphere on the side the normal points to: a sphere
    // on the other side would meet its image pushing it away from the sample.
    // The plane x = −d, normal +x: s0 (r = 1 mm, at the origin) is d from it.
    let plane = |d: f64| {
        let sym = format!("[[symmetry]]\npoint = [{:?}, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n\n[[material]]", -d);
        edit(PAIR, "[[material]]", &sym)
    };
    expect(&plane(-0.002), &["body[0] 's0' and symmetry[0]: the centre is 0.002 m on the wrong side of the plane (its normal [1, 0, 0] points into the sample)"]);
    expect(&plane(0.0), &["body[0] 's0' and symmetry[0]: the centre is 0 m on the wrong side"]);
    // 0.9 mm from the plane: 0.2 mm into its image, 20 % of the radius.
    expect(
        &plane(0.0009),
        &["body[0] 's0' and its image across symmetry[0]: initial overlap 2e-4 m is 20.0 % of the radius"],
    );
    // Touching its image by 1e-6 m (a deposited sample against the plane) is fine.
    MdScene::from_toml_str(&plane(0.0009995)).unwrap();
    MdScene::from_toml_str(&plane(0.005)).unwrap();
}

#[test]
fn ten_thousand_spheres_are_checked_through_the_cell_grid() {
    // A 22 × 22 × 21 lattice of 1 mm glass spheres (gaps 0.1 mm) on the floor,
    // its last sphere pushed 0.3 mm towards the one before: 0.2 mm into it, found
    // by the grid among 10 164 spheres (all pairs would be 5e7 tests).
    let head = &PAIR[..PAIR.find("[[wall]]\nname = \"mould\"").unwrap()];
    let lattice = |push: f64| {
        let mut text = head.to_string();
        let mut n = 0;
        for k in 0..21 {
            for j in 0..22 {
                for i in 0..22 {
                    let mut x = V3::new(0.0021 * i as f64, 0.0021 * j as f64, 0.00105 + 0.0021 * k as f64);
                    if n == 10_163 {
                        x[0] -= push;
                    }
                    let _ = writeln!(
                        text,
                        "\n[[body]]\nname = \"g{n}\"\nmaterial = \"glass\"\nsphere = 0.001\nposition = [{:?}, {:?}, {:?}]",
                        x[0], x[1], x[2]
                    );
                    n += 1;
                }
            }
        }
        text
    };
    let t0 = std::time::Instant::now();
    MdScene::from_toml_str(&lattice(0.0)).unwrap();
    let valid = t0.elapsed();
    expect(
        &lattice(0.0003),
        &["body[10162] 'g10162' and body[10163] 'g10163': initial overlap 2e-4 m is 20.0 % of the smaller radius"],
    );
    println!("10 164 spheres validated in {valid:?}");
}

// ----------------------------------------------------------- background damping

#[test]
fn explicit_background_damping_on_light_spheres_is_refused() {
    // One 1 µm glass sphere, no wall: γ_b = 0.2 kg/s with dt = 2e-5 s is
    // γ_b Δt / m = 4.8e8 on m = 1.05e-14 kg, far above Verlet's 2 (each step
    // multiplies the velocity by 1 − γ_b Δt / m).
    let one = r#"
[simulation]
engine = "md"
dt = 2e-5
duration = 1e-3

[md]
background_damping = 0.2

[[material]]
name = "glass"
density = 2500.0
young = 6e10
poisson = 0.22

[[body]]
name = "dust"
material = "glass"
sphere = 1e-6
position = [0.0, 0.0, 0.0]
"#;
    let m = sphere_mass(2500.0, 1e-6);
    let b = 0.2 * 2e-5 / m;
    let msg = expect(one, &[
        "md.background_damping: γ_b Δt / m = ",
        " for the lightest sphere, body[0] 'dust' (m = 1.05e-14 kg), is above the explicit stability limit 2 of velocity Verlet",
    ]);
    assert!((number_after(&msg, "γ_b Δt / m = ") / b - 1.0).abs() < 0.007, "{msg}");
    assert!((number_after(&msg, "needs dt ≤ ") / (2.0 * m / 0.2) - 1.0).abs() < 0.007, "{msg}");
    // The rotational damping: τ = −γ_br r² ω on I = 2/5 m r², i.e. 2.5 γ_br / m.
    let rot = edit(one, "background_damping = 0.2", "background_rotational_damping = 0.05");
    let msg = expect(&rot, &["md.background_rotational_damping: γ_br r² Δt / I = 2.5 γ_br Δt / m = "]);
    assert!((number_after(&msg, "2.5 γ_br Δt / m = ") / (2.5 * 0.05 * 2e-5 / m) - 1.0).abs() < 0.007);
    // David et al.'s values on their 1 g spheres pass (γ_b Δt / m = 4e-3).
    let luding = edit(&edit(one, "sphere = 1e-6", "sphere = 0.005"), "density = 2500.0", "density = 2000.0");
    MdScene::from_toml_str(&edit(
        &luding,
        "background_damping = 0.2",
        "background_damping = 0.2\nbackground_rotational_damping = 0.05",
    ))
    .unwrap();
    // Gear 6 damps explicitly far worse: γ_b Δt / m = 0.5 passes with Verlet, not with it.
    let half = edit(
        &luding,
        "background_damping = 0.2",
        &format!("background_damping = {:?}", 0.5 * sphere_mass(2000.0, 0.005) / 2e-5),
    );
    MdScene::from_toml_str(&half).unwrap();
    let gear6 = edit(&half, "[md]", "[md]\nintegrator = \"gear\"\ngear = \"gear6\"");
    expect(&gear6, &["md.background_damping: γ_b Δt / m = 0.5 ", "of Gear 'gear6'"]);
}

// ------------------------------------------------------------------- the grid

#[test]
fn the_neighbour_grid_saturates_for_far_and_non_finite_positions() {
    // Spheres at opposite corners of the ±1e9 m validator box: 1e18 cells of
    // 2e-9 m per axis, 1e54 in all (the product overflowed usize), now capped.
    let (size, dims) = grid(&V3::repeat(2e9), 2e-9, 8 * 2 + 27);
    assert!(dims.iter().product::<usize>() <= 43 && size >= 2e-9, "{dims:?} {size}");
    let (size, dims) = grid(&V3::new(f64::INFINITY, 0.0, 0.0), 1e-3, 100);
    assert_eq!((size, dims), (f64::INFINITY, [1, 1, 1]));
    // Two touching spheres at each far corner, and one gone to infinity and one
    // to NaN (what the engine may meet after a divergence): the pairs are found.
    let x = [
        V3::repeat(1e9),
        V3::repeat(1e9) + V3::new(1.5e-9, 0.0, 0.0),
        V3::repeat(-1e9),
        V3::repeat(-1e9) + V3::new(0.0, 0.0, 1.5e-9),
        V3::new(f64::INFINITY, 0.0, f64::NEG_INFINITY),
        V3::new(f64::NAN, 0.0, 0.0),
    ];
    let r = [1e-9; 6];
    let mut nb = Neighbours::new(0.0);
    nb.build(&x, &r, x.len(), &[]);
    assert_eq!(nb.pairs(), 2);
    assert_eq!((nb.j[nb.start[0] as usize], nb.j[nb.start[2] as usize]), (1, 3));
    // A system of two spheres 2e9 m apart (valid scene coordinates) builds and steps.
    let open = PAIR.replace(
        "[[wall]]\nname = \"mould\"\nmaterial = \"steel\"\ncylinder = { axis_point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = 0.01 }\n",
        "",
    );
    let far = edit(&open, "position = [0.003, 0.0, 0.002]", "position = [1e9, -1e9, 0.002]");
    let mut sys = MdScene::from_toml_str(&far).unwrap().build().unwrap();
    sys.step().unwrap();
}

// ------------------------------------------------------------- non-finite input

/// Every number of the FULL-like scene `text` replaced in turn by `nan`, `inf`
/// and `-inf`: refused with one line that names the key, never a panic.
#[test]
fn every_non_finite_number_is_refused_with_one_line_naming_its_key() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/md_two_spheres.toml")).unwrap();
    let text = text
        + "\n[[wall]]\nname = \"lid\"\nmaterial = \"steel\"\n\
        disc = { point = [0.0, 0.0, 0.03], normal = [0.0, 0.0, -1.0], radius = 0.0075 }\n\
        servo = { mass = 0.01, viscosity = 1.0, stress = 10.0, amplitude = 1.0, period = 0.1, area = 1e-4 }\n\n\
        [[symmetry]]\npoint = [-0.1, 0.0, 0.0]\nnormal = [1.0, 0.0, 0.0]\n";
    let text = edit(&text, "seed = 1", "seed = 1\nequilibrium = { kinetic_energy = 1e-8, energy_ratio = 1e-6 }");
    let text = edit(
        &text,
        "skin = 3.0e-4",
        "skin = 3.0e-4\nbackground_damping = 0.001\nbackground_rotational_damping = 0.001",
    );
    let text = edit(&text, "every = 500", "every = 500\ncycles = { frequency = 10.0 }");
    let text = edit(&text, "name = \"upper\"", "name = \"upper\"\nvelocity = [0.0, 0.0, 0.0]\nspin = [0.0, 0.0, 0.0]");
    MdScene::from_toml_str(&text).unwrap();
    // Numbers: after '=', '[', or ', ', made of digits, '.', 'e', '-', '+'.
    let bytes = text.as_bytes();
    let mut tested = 0;
    let mut at = 0;
    while at < bytes.len() {
        let starts = (bytes[at].is_ascii_digit() || bytes[at] == b'-')
            && at >= 2
            && (text[..at].ends_with("= ") || text[..at].ends_with('[') || text[..at].ends_with(", "));
        if !starts {
            at += 1;
            continue;
        }
        let end = at + text[at..].find(|c: char| !(c.is_ascii_digit() || "+-.e".contains(c))).unwrap();
        let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
        // The key: the last `name =` before the number on its line.
        let key_end = text[line_start..at].rfind(" =").map(|i| line_start + i).unwrap();
        let key_start = text[..key_end].rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap() + 1;
        let key = &text[key_start..key_end];
        for bad in ["nan", "inf", "-inf"] {
            let changed = format!("{}{bad}{}", &text[..at], &text[end..]);
            let result = std::panic::catch_unwind(|| MdScene::from_toml_str(&changed).map(|_| ()));
            let m = match result {
                Ok(Err(e)) => e.to_string(),
                Ok(Ok(())) => panic!("{key} = {bad} accepted"),
                Err(_) => panic!("{key} = {bad}: panic"),
            };
            assert!(!m.contains('\n') && m.contains(key), "{key} = {bad}: {m:?}");
        }
        tested += 1;
        at = end;
    }
    assert!(tested > 40, "{tested} numbers");
}

// ------------------------------------------------------- what the crate generates

/// The peers' bed (`scenarios::md_bed`, built as a system there) as a scene.
fn bed_scene(n: usize) -> String {
    let spec = md_bed::BedSpec::peers(n, 12345);
    let mut out = format!(
        "[simulation]\nengine = \"md\"\ndt = {:?}\nduration = 0.001\n\n[md]\nskin = {:?}\n\n",
        md_bed::DT,
        md_bed::SKIN
    );
    let m = md_bed::MATERIAL;
    let _ = writeln!(
        out,
        "[[material]]\nname = \"grain\"\ndensity = {:?}\nyoung = {:?}\npoisson = {:?}\n",
        m.density, m.young, m.poisson
    );
    let _ = writeln!(
        out,
        "[[contact]]\nbetween = [\"grain\", \"grain\"]\nmodel = \"hertz\"\nfriction = {:?}\nrestitution = {:?}\n",
        md_bed::FRICTION,
        md_bed::RESTITUTION
    );
    let v = |x: V3| format!("[{:?}, {:?}, {:?}]", x[0], x[1], x[2]);
    for (name, shape) in md_bed::bed_walls(spec.side) {
        if let ballast::md::Shape::Plane { point, normal } = shape {
            let _ = writeln!(
                out,
                "[[wall]]\nname = \"{name}\"\nmaterial = \"grain\"\nplane = {{ point = {}, normal = {} }}\n",
                v(point),
                v(normal)
            );
        }
    }
    for (k, s) in md_bed::bed_spheres(&spec).unwrap().iter().enumerate() {
        let _ = writeln!(
            out,
            "[[body]]\nname = \"s{k}\"\nmaterial = \"grain\"\nsphere = {:?}\nposition = {}\nvelocity = {}\n",
            s.radius,
            v(s.position),
            v(s.velocity)
        );
    }
    out
}

/// A generated scene, written and read back as a file is.
fn check(scene: ballast::Result<MdScene>) -> MdScene {
    MdScene::from_toml_str(&scene.unwrap().to_toml_string().unwrap()).unwrap()
}

#[test]
fn every_generated_scene_and_the_example_pass() {
    let example =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/md_two_spheres.toml")).unwrap();
    MdScene::from_toml_str(&example).unwrap();
    // Karrech Table 1 (dt = 1e-7 s; limit 6.9e-7 s, the cylinder on the smallest
    // sphere at the 3.3 m/s of a fall through the loose sample), its load on the
    // loose spheres, and the softened sample of tests/md_ready_tests.rs.
    let spec = karrech::KarrechSpec::table1(karrech::PAPER_SPHERES, 1);
    check(karrech::deposit_scene(&spec, 1000));
    let loose = karrech::loose_spheres(&spec).unwrap();
    for loading in [karrech::Loading::FULL, karrech::Loading::PARTIAL] {
        check(karrech::loading_scene(&spec, &loose, loading, 2, 100));
    }
    let soft = karrech::KarrechSpec { dt: 2e-6, young: 1e7, ..karrech::KarrechSpec::table1(40, 1) };
    check(karrech::deposit_scene(&soft, 1000));
    // David et al.'s box (dt = 2e-5 s; limit 2.5e-4 s) and its cyclic test.
    let l = luding::LudingSpec::paper(343, 0.1, 1);
    let compression = check(luding::compression_scene(&l, 1.0, 100));
    let spheres: Vec<(f64, V3)> = compression.bodies.iter().map(|b| (b.sphere, V3::from(b.position))).collect();
    let hi = V3::repeat(spheres.iter().map(|(r, x)| x.max() + r).fold(0.0, f64::max));
    check(luding::cyclic_scene(&l, &spheres, V3::zeros(), hi, 2, 100));
    // The peers' bed (dt = 5e-6 s; limit 6.1e-5 s).
    MdScene::from_toml_str(&bed_scene(2000)).unwrap();
}
