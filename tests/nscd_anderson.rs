//! Anderson acceleration of the NLGS sweeps (`[nscd] anderson`, `ballast::nscd::method::anderson`), on the
//! problem of one step of the loaded 536-pentagon pile (a 10 kg sleeper on 0.1–0.3 kg grains: the ill-conditioned
//! problem of the settlement runs) and on runs of it: the mixed sweeps meet the same stopping rule in a fraction
//! of the sweeps, leave the velocities those of the impulses, give the same bits on one thread or two, and the
//! scene key is checked. The 3D column of cubes under the mixing is in `tests/nscd3d.rs`.

use ballast::nscd::method::anderson::{solve_nlgs_anderson, AndersonWorkspace};
use ballast::nscd::nlgs::{remove_impulses, solve_nlgs, NlgsProblem, NlgsReport, NlgsSettings};
use ballast::nscd::{Policy, System};
use ballast::scenarios::saussine::{loaded_scene, LoadingSpec};
use ballast::scene::{Scene, SceneFile};
use std::sync::OnceLock;

/// The loaded 536 pile (one cycle's scene) and the same after 200 steps (40 ms) under the sleeper (the default solver).
fn loaded() -> &'static (System, System) {
    static LOADED: OnceLock<(System, System)> = OnceLock::new();
    LOADED.get_or_init(|| {
        let pile = include_str!("../data/pentagon_pile_536.toml").replace("\"grain\"", "\"ballast\"");
        let pile = Scene::from_toml_str(&pile).unwrap();
        let start = loaded_scene(&pile, &LoadingSpec::saussine(1)).unwrap().build().unwrap();
        let mut sys = start.clone();
        for _ in 0..200 {
            sys.step().unwrap();
        }
        (start, sys)
    })
}

/// `quad` at `tolerance`, measured by the check pass, unsplit, a cap far above what either method needs.
fn settings(tolerance: f64, anderson: usize) -> NlgsSettings {
    NlgsSettings {
        policy: Policy::Quad,
        tolerance,
        max_iterations: 40_000,
        split_min_rows: 0,
        anderson,
        ..NlgsSettings::default()
    }
}

/// The step's problem solved from zero impulses, plain (`anderson` 0) or mixed.
fn solve(p: &NlgsProblem, tolerance: f64, anderson: usize) -> (NlgsProblem, NlgsReport) {
    let mut q = p.clone();
    let s = settings(tolerance, anderson);
    let r = if anderson == 0 {
        solve_nlgs(&s, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs)
    } else {
        solve_nlgs_anderson(&s, &mut AndersonWorkspace::default(), &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs)
    };
    (q, r)
}

/// The largest component of `u − M⁻¹ H P − u_free` (m/s or rad/s): zero when the velocities are those of the
/// impulses.
fn inconsistency(solved: &NlgsProblem, free: &NlgsProblem) -> f64 {
    let mut back = solved.u.clone();
    remove_impulses(&mut back, &solved.inv_m, &solved.rows, &solved.springs);
    back.iter().zip(&free.u).flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs())).fold(0.0, f64::max)
}

/// The same stopping rule (LMGC90's check pass at `quad` 1e-4 and 1e-5) is met in a fraction of the sweeps:
/// measured 605 mixed against 3 011 plain at 1e-4 (0.20), 719 against 5 533 at 1e-5 (0.13). The bound 0.4
/// leaves about twice the measured ratio; a mixing that did nothing would give 1, one that broke the fixed point
/// would not converge. The mixed velocities are those of the impulses: the mixing's round-off (up to 3e-10 m/s
/// on the pile's 21st step before the final `u = u_free + M⁻¹ H P`) is gone, as with plain sweeps (1e-14 m/s).
#[test]
fn mixed_sweeps_meet_the_stopping_rule_in_a_fraction_of_the_plain_sweeps() {
    let (_, sys) = loaded();
    let p = sys.nlgs_problem();
    assert!(p.rows.len() > 1000, "{} rows", p.rows.len());
    for (tolerance, bound) in [(1e-4, 0.4), (1e-5, 0.4)] {
        let (plain, rp) = solve(&p, tolerance, 0);
        let (mixed, rm) = solve(&p, tolerance, 5);
        assert!(rp.converged && rm.converged, "{tolerance:e}: plain {rp:?}, mixed {rm:?}");
        let ratio = rm.iterations as f64 / rp.iterations as f64;
        eprintln!("quad {tolerance:e}: {} sweeps mixed, {} plain ({ratio:.2})", rm.iterations, rp.iterations);
        assert!(ratio < bound, "quad {tolerance:e}: {} sweeps mixed, {} plain", rm.iterations, rp.iterations);
        for (name, q) in [("plain", &plain), ("mixed", &mixed)] {
            let off = inconsistency(q, &p);
            assert!(off < 1e-12, "quad {tolerance:e}, {name}: velocities {off:e} from those of the impulses");
        }
    }
}

/// Mixed and plain sweeps stop near the same solution: at `quad` 1e-5 the sleeper's vertical velocity of either
/// is within the distance between the plain solutions at 1e-4 and 1e-5 of the other (the stopping rule's own
/// error, 3.4e-4 m/s of −0.198 m/s; measured 6e-7 m/s between mixed and plain), not a different state.
#[test]
fn mixed_and_plain_sweeps_stop_at_the_same_solution() {
    let (_, sys) = loaded();
    let sleeper = sys.bodies.info.iter().position(|b| b.name == "sleeper").unwrap();
    let p = sys.nlgs_problem();
    let v = |q: &NlgsProblem| q.u[sleeper][1];
    let loose = v(&solve(&p, 1e-4, 0).0);
    let plain = v(&solve(&p, 1e-5, 0).0);
    let mixed = v(&solve(&p, 1e-5, 5).0);
    let scale = (loose - plain).abs();
    eprintln!("sleeper: plain 1e-4 {loose}, plain 1e-5 {plain}, mixed 1e-5 {mixed} m/s");
    assert!(scale > 0.0, "the two tolerances gave the same sleeper velocity {plain} m/s");
    assert!((mixed - plain).abs() <= scale, "mixed {mixed}, plain {plain} m/s, tolerance's effect {scale:e}");
}

/// Runs of the loaded pile with the mixing, split in two halves (≈ 1 200 rows, above the split threshold): the
/// same bits on one thread and two, and not those of plain sweeps (the key is in effect).
#[test]
fn mixed_split_sweeps_give_the_same_bits_on_one_or_two_threads() {
    let (start, _) = loaded();
    let run = |threads: usize, anderson: usize| {
        let mut s = start.clone();
        s.params.nlgs.anderson = anderson;
        s.set_threads(threads);
        for _ in 0..10 {
            s.step().unwrap();
        }
        s
    };
    let one = run(1, 5);
    let two = run(2, 5);
    assert_eq!(one.bodies.q, two.bodies.q);
    assert_eq!(one.bodies.u, two.bodies.u);
    assert_ne!(one.bodies.q, run(1, 0).bodies.q, "the mixing changed nothing");
}

/// `nscd.anderson` is a depth of 0 to 8 that mixes Gauss–Seidel sweeps: other values, or another solver, are
/// refused on one line naming the key; a valid depth is read into the settings.
#[test]
fn the_scene_key_is_checked() {
    let pile = include_str!("../data/pentagon_pile_536.toml");
    let with = |extra: &str| pile.replacen("[nscd]", &format!("[nscd]\n{extra}"), 1);
    assert!(pile.contains("[nscd]"));
    let sys = Scene::from_toml_str(&with("anderson = 5")).unwrap().build().unwrap();
    assert_eq!(sys.params.nlgs.anderson, 5);
    for (extra, words) in
        [("anderson = 9", "0 to 8, got 9"), ("anderson = 5\nsolver = \"apgd\"", "not solver = 'apgd'")]
    {
        let err = Scene::from_toml_str(&with(extra)).and_then(|s| s.build()).map(|_| ()).unwrap_err().to_string();
        assert!(err.contains("nscd.anderson") && err.contains(words) && !err.contains('\n'), "{extra}: {err}");
    }
}
