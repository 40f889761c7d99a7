//! The 3D track section (`ballast::scenarios::track3d`, `ballast::studies::track3d`, `ballast track3d …`) on a
//! 24-grain sample on 12 pads, deposited once for the whole binary: the deposit comes to rest on the sublayer
//! inside the box; `sample.json` agrees with what the test computes from `sample.toml` itself (grain volumes, box,
//! weights, law (17) at the springs' saved lengths); the loaded scene validates with its sleeper on the grains
//! under the pressure it was given; two cycles settle the sleeper and write two rows; the accelerated run jumps
//! through the settlement driver; bad input is refused naming the field (the library) or the flag (the command
//! line).

use crate::scratch;
use crate::track3d_common;

use ballast::geometry::{Solid, Vec3};
use ballast::nscd::d3::overlaps::Overlaps;
use ballast::nscd::d3::rows::read_cycles;
use ballast::nscd::d3::system::System3;
use ballast::scenarios::track3d::{self, LoadingSpec, SampleReport, SampleSpec, GRAIN_PREFIX, PAD_PREFIX, SLEEPER};
use ballast::scene::{Scene3, SceneFile};
use ballast::space::detection::FaceGaps;
use ballast::studies::track3d::{self as study, SettleOptions};
use ballast::studies::{Accelerate, Quiet};
use track3d_common::{ballast, named, refused, sample, GRAINS, LOAD_DT};

const G: f64 = 9.81;

/// World vertices of polyhedron body `i`.
fn vertices(sys: &System3, i: usize) -> Vec<Vec3> {
    let Solid::Polyhedron(p) = &sys.bodies.info[i].solid else { panic!("body {i} is not a polyhedron") };
    p.vertices.iter().map(|v| sys.bodies.pose[i].point(v)).collect()
}

/// The box's inner half sizes from the walls' positions in the scene.
fn half_box(scene: &Scene3) -> (f64, f64) {
    let at = |name: &str, k: usize| scene.bodies.iter().find(|b| b.name == name).unwrap().position[k];
    ((at("wall_x1", 0) - at("wall_x0", 0)) / 2.0, (at("wall_y1", 1) - at("wall_y0", 1)) / 2.0)
}

fn density(scene: &Scene3, material: &str) -> f64 {
    scene.materials.iter().find(|m| m.name == material).unwrap().density
}

/// The deposit ended at rest, every grain inside the box and on or above the pads' top faces.
#[test]
fn the_sample_deposits_to_rest_inside_the_box_above_the_pads() {
    let (_, s) = sample();
    let r: &SampleReport = &s.report;
    assert_eq!((r.grains, r.pads), (GRAINS, 12));
    // The deposit stopped at equilibrium: E_k below 1e-10 J per grain for its last 100 steps.
    let (dir, _) = sample();
    let series = ballast::nscd::d3::rows::read_series(&dir.join("deposit/series.csv")).unwrap();
    let last = series.last().unwrap().kinetic_energy_j;
    assert!(last < 1e-10 * GRAINS as f64, "the deposit ended with E_k = {last} J");
    // The 20 measuring steps restart from the saved state without the warm start, which stirs it a little: at
    // most an rms speed √(2 E_k / M) of 1e-3 m/s (M ≈ 1 kg: E_k < 5e-7 J), i.e. 10 µm over the 20 steps of
    // 5e-4 s, a thousandth of the smallest grain. (Measured: 9e-8 J.)
    assert!(r.kinetic_energy_j < 5e-7, "kinetic energy {} J", r.kinetic_energy_j);
    let scene = Scene3::load(&s.path).unwrap();
    let sys = scene.build().unwrap();
    let (hl, hw) = half_box(&scene);
    let pads = named(&scene, PAD_PREFIX);
    let pad_top = pads.iter().flat_map(|&i| vertices(&sys, i)).map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
    // A contact may leave an overlap: the report's largest, and 1e-5 m beyond it for the 20 steps' motion.
    let slack = r.max_overlap_m + 1e-5;
    for i in named(&scene, GRAIN_PREFIX) {
        for v in vertices(&sys, i) {
            assert!(v.x.abs() <= hl + slack && v.y.abs() <= hw + slack, "grain {i} outside the box at {v:?}");
            assert!(v.z >= pad_top - slack - 1e-3, "grain {i} below the pads' tops: {v:?}");
        }
    }
    // No grain went through the pads: with smooth walls the pads carry everything, so the lowest vertex rests on
    // a pad's top face, which is at most the static sag (< 1 mm) below z = 0.
    assert!(r.lowest_grain_m > -1e-3 && r.lowest_grain_m < 0.05, "lowest grain vertex at {} m", r.lowest_grain_m);
}

/// `sample.json` against the test's own numbers from `sample.toml`: the solid fraction from the grains' volumes,
/// the box's area and the reported height; the weights from volumes and densities; the sublayer's reaction
/// against the weight, both as the engine's impulses and as the springs' static compression.
#[test]
fn sample_json_agrees_with_an_independent_computation() {
    let (dir, s) = sample();
    let r: SampleReport = serde_json::from_str(&std::fs::read_to_string(dir.join("sample.json")).unwrap()).unwrap();
    let scene = Scene3::load(&s.path).unwrap();
    let sys = scene.build().unwrap();
    let grains = named(&scene, GRAIN_PREFIX);
    let pads = named(&scene, PAD_PREFIX);
    let volume_of = |i: usize| sys.bodies.info[i].solid.mass_properties().0;
    let volume: f64 = grains.iter().map(|&i| volume_of(i)).sum();
    let (hl, hw) = half_box(&scene);
    let area = 4.0 * hl * hw;
    assert!((r.grain_volume_m3 - volume).abs() <= 1e-12 * volume);
    let phi = volume / (area * r.layer_height_m);
    assert!((r.solid_fraction - phi).abs() < 1e-9, "solid fraction {} vs {phi}", r.solid_fraction);
    // The whole layer's fraction: a gravity deposit of angular grains lies below the random close packing of
    // spheres (0.64); a layer two grains deep in a box three grains wide, its surface taken at each bin's highest
    // vertex, has as much void at the walls and the surface as inside, so well below a bulk's 0.55–0.6, but a
    // layer below 0.2 would be grains standing on their tips.
    assert!((0.2..0.64).contains(&phi), "solid fraction {phi}");
    // The layer's mean surface is below the highest vertex and at most one longest grain (75 mm) under it. The
    // report measures it after its steps of measurement and the test takes the vertex at the sample's state:
    // 1e-5 m of slack for the motion in between, as above (a deposit of this file's seed measured 3.7e-7 m).
    let top = grains.iter().flat_map(|&i| vertices(&sys, i)).map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
    let surface_gap = top - r.surface_m;
    assert!((-1e-5..=0.075).contains(&surface_gap), "surface {} m, top vertex {top} m", r.surface_m);

    // Weights: ρ V g of the grains, and of the pads (boxes of the scene's half sizes).
    let grain_weight = density(&scene, "ballast") * volume * G;
    let pad_volume: f64 =
        pads.iter().map(|&i| scene.bodies[i].cuboid.unwrap().half.iter().product::<f64>() * 8.0).sum();
    let weight = grain_weight + density(&scene, "elastomer") * pad_volume * G;
    assert!((r.grain_weight_n - grain_weight).abs() < 1e-9 * grain_weight);
    assert!((r.weight_n - weight).abs() < 1e-9 * weight);
    // The pads carry the weight. The reaction is the springs' impulses over 20 steps / (20 h); the momentum
    // balance of those steps makes reaction − weight = ΔP_z / (20 h), and at rest (|P_z| ≤ √(2 M E_k),
    // E_k < 5e-7 J, M ≈ 1 kg: 1e-3 N·s at most, over 20 h = 10 ms: 0.1 N of 8.6 N) that is within 1.2 %.
    // The walls are smooth and vertical: they carry nothing vertically.
    assert!(r.balance_error.abs() < 1.2e-2, "balance error {}", r.balance_error);
    assert!(((r.sublayer_reaction_n - weight) / weight).abs() < 1.2e-2, "{} N vs {weight} N", r.sublayer_reaction_n);
    assert!(r.wall_reaction_n.abs() < 1e-6 * weight, "walls carry {} N", r.wall_reaction_n);
    // The same from the saved state alone: law (17) at each pad, R = k_N (L0 − L)/L0 − ν L̇/L0, L from the pad's
    // saved position to its anchor, L̇ its saved vertical velocity. Against the weight it differs only by the
    // bodies' vertical accelerations at the deposit's calm end (E_k < 2.4e-9 J: speeds below 1e-4 m/s; were
    // they to change by as much in a step, m a / W ≤ 1e-4 / (g h) = 2 %; measured 8e-5); the springs also carry
    // the pads' weight. 1 % asks for a balance, not for the crude bound.
    let mut law_17 = 0.0;
    for spring in &scene.springs {
        let pad = scene.bodies.iter().find(|b| b.name == spring.body).unwrap();
        let bottom = pad.position[2] + spring.point.unwrap()[2];
        let length = bottom - spring.anchor.unwrap()[2];
        let l0 = spring.rest_length.unwrap();
        let rate = pad.velocity.unwrap_or([0.0; 3])[2];
        law_17 += (spring.k_n * (l0 - length) / l0 - spring.nu.unwrap() * rate / l0).max(0.0);
    }
    assert!(((law_17 - weight) / weight).abs() < 1e-2, "springs' force {law_17} N, weight {weight} N");
    // Coordination: a grain resting in a pile presses on at least two bodies; a mean above 8 would be a pile
    // jammed far past a frictional packing (isostatic 4–6 in 3D, wall and pad contacts counted).
    assert!((2.0..8.0).contains(&r.coordination), "coordination {}", r.coordination);
    assert!((0.0..1.0).contains(&r.rattler_fraction));
}

/// The loaded scene validates, its sleeper spans the requested footprint, rests just above the grains under it,
/// is guided along z and carries the pressure times its area.
#[test]
fn the_loaded_scene_puts_the_sleeper_on_the_grains() {
    let (dir, s) = sample();
    let out = dir.join("loaded_test.toml");
    let spec = LoadingSpec { cycles: 3, ..LoadingSpec::default() };
    study::load(&s.path, &spec, &out).unwrap();
    let scene = Scene3::load(&out).unwrap();
    scene.validate().unwrap();
    assert_eq!(scene.steps(), 750); // 3 cycles of 1/20 s at 2e-4 s
    let cycles = scene.output.as_ref().unwrap().cycles.as_ref().unwrap();
    assert_eq!((cycles.frequency, cycles.body.as_deref()), (20.0, Some(SLEEPER)));
    let sys = scene.build().unwrap();
    let k = scene.bodies.iter().position(|b| b.name == SLEEPER).unwrap();
    let sleeper = vertices(&sys, k);
    let lo = sleeper.iter().fold(Vec3::repeat(f64::INFINITY), |a, v| a.inf(v));
    let hi = sleeper.iter().fold(Vec3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v));
    let (hl, hw) = half_box(&scene);
    let (w, l) = (hi.x - lo.x, hi.y - lo.y);
    assert!((w - hl).abs() < 1e-9, "width {w}: half the box's length {}", 2.0 * hl);
    assert!((l - (2.0 * hw - 2.0 * track3d::SLEEPER_GAP)).abs() < 1e-9, "length {l}");
    // Above every grain vertex under its footprint; and the generator's drop (0.5 mm) above the highest vertex of
    // the grains that reach under it (a grain partly under it counts whole: its part under the sleeper is lower).
    let grains: Vec<Vec<Vec3>> = named(&scene, GRAIN_PREFIX).into_iter().map(|i| vertices(&sys, i)).collect();
    let inside = |v: &Vec3| v.x.abs() <= w / 2.0 && v.y.abs() <= l / 2.0;
    let under = grains.iter().flatten().filter(|v| inside(v)).map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
    assert!(lo.z > under, "sleeper bottom {} m, grain vertices under it up to {under} m", lo.z);
    let reaching = grains
        .iter()
        .filter(|g| {
            let (a, b) = (
                g.iter().fold(Vec3::repeat(f64::INFINITY), |a, v| a.inf(v)),
                g.iter().fold(Vec3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v)),
            );
            b.x >= -w / 2.0 && a.x <= w / 2.0 && b.y >= -l / 2.0 && a.y <= l / 2.0
        })
        .flatten()
        .map(|v| v.z)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (lo.z - reaching - 5e-4).abs() < 1e-9,
        "sleeper bottom {} m, grains reaching under it up to {reaching} m",
        lo.z
    );
    let body = &scene.bodies[k];
    let load = body.load.unwrap();
    assert!(
        (load.mean - spec.mean_pressure * w * l).abs() < 1e-9
            && (load.amplitude - spec.amplitude_pressure * w * l).abs() < 1e-9
    );
    assert_eq!((load.frequency, load.phase, load.direction), (20.0, -std::f64::consts::PI, [0.0, 0.0, 1.0]));
    let imposed = body.imposed.unwrap();
    assert!(imposed.vx.is_some() && imposed.vy.is_some() && imposed.vz.is_none() && imposed.spin.is_some());
    // The face–face gap rule: exact unless asked, LMGC90's common plane when asked.
    assert_eq!(sys.params.face_gaps, FaceGaps::Exact);
    let common = LoadingSpec { face_gaps: "common_plane".into(), ..spec };
    study::load(&s.path, &common, &out).unwrap();
    assert_eq!(Scene3::load(&out).unwrap().build().unwrap().params.face_gaps, FaceGaps::CommonPlane);
    // The overlap law: the velocity-level law unless asked, held when asked.
    assert_eq!(sys.params.overlaps, Overlaps::Kept);
    let held = LoadingSpec { overlaps: "held".into(), ..common };
    study::load(&s.path, &held, &out).unwrap();
    assert_eq!(Scene3::load(&out).unwrap().build().unwrap().params.overlaps, Overlaps::Held);
}

/// Two cycles: two rows of cycles.csv, the sleeper went down (it landed and pressed the layer and the sublayer),
/// by less than the layer's height.
#[test]
fn settle_two_cycles_writes_two_rows_of_positive_settlement() {
    let (dir, s) = sample();
    let out = dir.join("settle");
    let spec = LoadingSpec { cycles: 2, dt: LOAD_DT, ..LoadingSpec::default() };
    let opts = SettleOptions { snapshot_every: 0, checkpoint_every_s: 0.0, resume: false };
    study::settle(&s.path, &spec, &out, &opts, &Quiet).unwrap();
    let rows = read_cycles(&out.join("cycles.csv")).unwrap();
    assert_eq!(rows.len(), 2);
    for r in &rows {
        assert!(r.settlement_m > 0.0 && r.settlement_m < s.report.layer_height_m, "settlement {} m", r.settlement_m);
    }
    assert!(out.join("loaded.toml").exists() && out.join("summary.json").exists());
}

/// A settle run killed mid-way (a checkpoint left at step 60 of 100) and continued with `resume` writes the
/// cycles of the run made straight, byte for byte.
#[test]
fn a_stopped_settle_resumes_to_the_same_cycles() {
    let (dir, s) = sample();
    let spec = LoadingSpec { cycles: 2, dt: LOAD_DT, ..LoadingSpec::default() };
    let opts = SettleOptions { snapshot_every: 0, checkpoint_every_s: 0.0, resume: false };
    let straight = dir.join("straight");
    study::settle(&s.path, &spec, &straight, &opts, &Quiet).unwrap();
    let resumed = dir.join("resumed");
    std::fs::create_dir_all(&resumed).unwrap();
    study::load(&s.path, &spec, &resumed.join("loaded.toml")).unwrap();
    let stop = ballast::run::RunOptions { stop_after: Some(60), checkpoint_every_s: 0.0, ..Default::default() };
    let loaded = ballast::open::open(&resumed.join("loaded.toml"), &stop).unwrap();
    loaded.run(&resumed, &stop, &mut |_| {}).unwrap();
    assert!(resumed.join("checkpoint.json").exists());
    study::settle(&s.path, &spec, &resumed, &SettleOptions { resume: true, ..opts }, &Quiet).unwrap();
    let cycles = |d: &std::path::Path| std::fs::read(d.join("cycles.csv")).unwrap();
    assert_eq!(cycles(&straight), cycles(&resumed));
}

fn accelerate() -> Accelerate {
    Accelerate {
        cycles: [1, 2, 2],
        law: "shenton".into(),
        growth: 1.0,
        relax_tolerance: None,
        extrapolation_limit: None,
        smoothing_length: None,
        settle_cycles: None,
        settle_rate: None,
        rollback_rate: None,
        relax_stage: None,
        hold_anchored: true,
        reference: None,
    }
}

/// `--accelerate`: the loaded scene with a `[settlement]` table on the sleeper goes through the settlement
/// driver, whose jumps land through the 3D engine's relaxation: 6 cycles reached with fewer computed, and the
/// sleeper settled.
#[test]
fn settle_accelerated_jumps_with_the_settlement_driver() {
    let (dir, s) = sample();
    let out = dir.join("accelerated");
    let spec = LoadingSpec { cycles: 6, dt: LOAD_DT, ..LoadingSpec::default() };
    let summary =
        study::settle_accelerated(&s.path, &spec, &accelerate(), &out, &SettleOptions::default(), &mut |_| {}).unwrap();
    let loaded = Scene3::load(out.join("loaded.toml")).unwrap();
    assert_eq!(loaded.settlement.expect("a [settlement] table").settlement_body.as_deref(), Some(SLEEPER));
    assert_eq!(summary.total_cycles, 6);
    assert!(summary.jumps >= 1 && summary.computed_cycles < 6, "{summary:?}");
    assert!(summary.settlement_m > 0.0, "{summary:?}");
}

/// The library names the spec field of a bad value.
#[test]
fn bad_specs_name_their_field() {
    let bad_sample = |spec: SampleSpec, field: &str| {
        let e = track3d::sample_scene(&spec).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{field}:")), "{e}");
    };
    bad_sample(SampleSpec { grains: 0, ..SampleSpec::track(1) }, "grains");
    bad_sample(SampleSpec { dt: -1.0, ..SampleSpec::track(1).scaled(10) }, "dt");
    bad_sample(SampleSpec { width: 0.05, ..SampleSpec::track(1).scaled(10) }, "width");
    bad_sample(SampleSpec { pad_gap: 0.03, ..SampleSpec::track(1).scaled(10) }, "pad_gap");
    bad_sample(SampleSpec { friction: f64::NAN, ..SampleSpec::track(1).scaled(10) }, "friction");
    bad_sample(SampleSpec { tolerance: 0.0, ..SampleSpec::track(1).scaled(10) }, "tolerance");
    bad_sample(SampleSpec { theta: 0.4, ..SampleSpec::track(1).scaled(10) }, "theta");
    bad_sample(SampleSpec { theta: f64::NAN, ..SampleSpec::track(1).scaled(10) }, "theta");
    // The deposit's θ is the scene's (default 1); the loaded scene has the loading's (default the paper's ½),
    // not the sample's.
    for theta in [0.5, 1.0] {
        let scene = track3d::sample_scene(&SampleSpec { theta, ..SampleSpec::track(1).scaled(10) }).unwrap();
        assert_eq!(scene.nscd.as_ref().and_then(|n| n.theta), Some(theta));
    }
    assert_eq!(SampleSpec::track(1).theta, 1.0);
    let (_, s) = sample();
    let sample_scene = Scene3::load(&s.path).unwrap();
    assert_eq!(sample_scene.nscd.as_ref().and_then(|n| n.theta), Some(1.0));
    for theta in [0.5, 0.75] {
        let loaded = track3d::loaded_scene(&sample_scene, &LoadingSpec { theta, ..LoadingSpec::default() }).unwrap();
        assert_eq!(loaded.nscd.as_ref().and_then(|n| n.theta), Some(theta));
    }
    assert_eq!(LoadingSpec::default().theta, 0.5);
    let bad_loading = |spec: LoadingSpec, field: &str| {
        let e = track3d::loaded_scene(&sample_scene, &spec).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{field}:")), "{e}");
    };
    let d = LoadingSpec::default();
    bad_loading(LoadingSpec { cycles: 0, ..d.clone() }, "cycles");
    bad_loading(LoadingSpec { sleeper_width: Some(5.0), ..d.clone() }, "sleeper_width");
    bad_loading(LoadingSpec { sleeper_length: Some(-1.0), ..d.clone() }, "sleeper_length");
    bad_loading(LoadingSpec { criterion: "fast".into(), ..d.clone() }, "criterion");
    bad_loading(LoadingSpec { tolerance: 2.0, ..d.clone() }, "tolerance");
    bad_loading(LoadingSpec { theta: 1.5, ..d.clone() }, "theta");
    bad_loading(LoadingSpec { face_gaps: "flat".into(), ..d.clone() }, "face_gaps");
    bad_loading(LoadingSpec { overlaps: "gap".into(), ..d.clone() }, "overlaps");
    bad_loading(LoadingSpec { mean_pressure: f64::INFINITY, ..d.clone() }, "mean_pressure");
    bad_loading(LoadingSpec { dt: 0.0, ..d }, "dt");
}

/// The command line refuses bad input on one line naming the flag, exit code 2.
#[test]
fn bad_flags_are_named_on_one_line() {
    let (_, s) = sample();
    let dir = scratch::dir("cli");
    let sample = s.path.to_str().unwrap();
    let out = dir.join("x.toml");
    let out = out.to_str().unwrap();
    let cases: [(&[&str], &str); 9] = [
        (&["track3d", "sample", "--grains", "0", "--out", out], "--grains:"),
        (&["track3d", "sample", "--grains", "10", "--tolerance", "2", "--out", out], "--tolerance:"),
        (&["track3d", "sample", "--grains", "10", "--dt=-1", "--out", out], "--dt:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--cycles", "0"], "--cycles:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--sleeper-width", "3"], "--sleeper-width:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--mean-pressure", "inf"], "--mean-pressure:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--face-gaps", "flat"], "--face-gaps:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--overlaps", "gap"], "--overlaps:"),
        (&["track3d", "load", "--sample", sample, "--out", out, "--anderson", "9"], "--anderson:"),
    ];
    for (args, flag) in cases {
        refused(args, flag);
    }
    let (code, err) = ballast(&["track3d", "load", "--sample", "/nonexistent/sample.toml", "--out", out]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("sample.toml"), "{err}");
}
