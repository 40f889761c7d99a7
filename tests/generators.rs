//! The scene generators of `ballast::scenarios`: they build scene values that
//! round-trip through TOML, give the same numbers as the text generators they
//! replaced, and refuse impossible parameters with a one-line error naming the
//! parameter (no panic, endless loop or invalid scene).

use crate::scratch;

use ballast::md::V3;
use ballast::scenarios::karrech::{self, KarrechSpec, Loading};
use ballast::scenarios::luding::{self, LudingSpec};
use ballast::scenarios::saussine::{
    self, Guide, LoadingSpec, SampleSpec, GRAIN_PREFIX, MIN_SCALED_GRAINS, PAD_PREFIX, SLEEPER,
};
use ballast::scenarios::{pentagon_deposit, DepositSpec};
use ballast::scene::SceneFile;
use ballast::scene::{MdScene, Scene};
use std::path::Path;
use std::process::Command;

/// The error message of `r`, which must be an error.
fn message<T: std::fmt::Debug>(r: ballast::Result<T>) -> String {
    let e = r.expect_err("expected an error");
    assert!(matches!(e, ballast::Error::Scene(_)), "{e:?}");
    let m = e.to_string();
    assert!(!m.contains('\n'), "not one line: {m}");
    m
}

/// Asserts that `m` contains every one of `needles`.
fn says(m: &str, needles: &[&str]) {
    for n in needles {
        assert!(m.contains(n), "'{m}' does not say '{n}'");
    }
}

fn round_trips(scene: &Scene) {
    let text = scene.to_toml_string().unwrap();
    assert_eq!(&Scene::from_toml_str(&text).unwrap(), scene);
}

fn md_round_trips(scene: &MdScene) {
    let text = scene.to_toml_string().unwrap();
    assert_eq!(&MdScene::from_toml_str(&text).unwrap(), scene);
}

/// The scene of `tests/data/generators/NAME.toml`, written by the former text
/// generators (commit 3f65c12) for the spec in the test.
fn former(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/generators").join(format!("{name}.toml"));
    std::fs::read_to_string(path).unwrap()
}

/// Equal values, and equal texts (so equal bits: `-0.0` and `0.0` differ there).
fn same(name: &str, new: &Scene) {
    let old = Scene::from_toml_str(&former(name)).unwrap();
    assert_eq!(&old, new, "{name}");
    assert_eq!(old.to_toml_string().unwrap(), new.to_toml_string().unwrap(), "{name}");
}

fn same_md(name: &str, new: &MdScene) {
    let old = MdScene::from_toml_str(&former(name)).unwrap();
    assert_eq!(&old, new, "{name}");
    assert_eq!(old.to_toml_string().unwrap(), new.to_toml_string().unwrap(), "{name}");
}

fn small_karrech() -> KarrechSpec {
    KarrechSpec { young: 1e7, dt: 2e-6, duration: 0.6, ..KarrechSpec::table1(40, 1) }
}

fn ballast(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ballast")).args(args).output().unwrap()
}

#[test]
fn generated_scenes_are_those_of_the_former_text_generators_bit_for_bit() {
    same("deposit_30_0.2_3", &pentagon_deposit(&DepositSpec::saussine(30, 0.2, 3)).unwrap());
    // The example scene written by `ballast deposit` (724 grains, 0.5 m, seed 1, 2 s).
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/pentagon_deposit.toml");
    let example = Scene::load(path).unwrap();
    let new = pentagon_deposit(&DepositSpec { duration: 2.0, ..DepositSpec::saussine(724, 0.5, 1) }).unwrap();
    assert_eq!(example, new);
    assert_eq!(example.to_toml_string().unwrap(), new.to_toml_string().unwrap());
    same("sample_60_1", &saussine::sample_scene(&SampleSpec::saussine(1).scaled(60)).unwrap());
    let bank = SampleSpec { bank: true, dt: 1e-4, ..SampleSpec::saussine(4) }.scaled(242);
    same("sample_242_bank_4", &saussine::sample_scene(&bank).unwrap());
    let sample = saussine::sample_scene(&SampleSpec::saussine(1).scaled(121)).unwrap();
    let f = SampleSpec::saussine(1).scaled(121).width;
    let load =
        LoadingSpec { bars: 1, guide: Some(Guide::Level), inclination_deg: 5.0, ..LoadingSpec::saussine(10).scaled(f) };
    let mut loaded = saussine::loaded_scene(&sample, &load).unwrap();
    // Added since the former generators: the loaded scenes write the grains'
    // positions at every cycle's end (what `--reference` measures E_r on).
    let cycles = loaded.output.as_mut().and_then(|o| o.cycles.as_mut()).unwrap();
    assert_eq!(cycles.positions, Some(true));
    cycles.positions = None;
    same("loaded_121_onebar_level", &loaded);
    let spec = small_karrech();
    same_md("karrech_40_1", &karrech::deposit_scene(&spec, 1000).unwrap());
    let spheres = karrech::loose_spheres(&spec).unwrap();
    let mut load = karrech::loading_scene(&spec, &spheres, Loading::PARTIAL, 10, 1000).unwrap();
    // Since the former generator, the loading scene also writes the spheres'
    // cycle positions (the settlement driver's data, eq. 22): the one difference.
    let cycles = load.output.as_mut().and_then(|o| o.cycles.as_mut()).unwrap();
    assert_eq!(cycles.positions.take(), Some(true));
    same_md("karrech_40_1_load_partial", &load);
    let spec = LudingSpec::paper(10, 0.0, 3);
    same_md("luding_10_3", &luding::compression_scene(&spec, 1.0, 1).unwrap());
    let spheres: Vec<(f64, V3)> = luding::radii(&spec)
        .iter()
        .enumerate()
        .map(|(i, &r)| (r, V3::new(0.012 * i as f64 + 0.008, 0.02, 0.03)))
        .collect();
    let (lo, hi) = (V3::new(-0.001, 0.0, 0.0005), V3::new(0.3, 0.05, 0.06));
    same_md("luding_10_3_cycle", &luding::cyclic_scene(&spec, &spheres, lo, hi, 3, 100).unwrap());
}

#[test]
fn every_generated_scene_round_trips_through_toml() {
    round_trips(&pentagon_deposit(&DepositSpec::saussine(50, 0.3, 7)).unwrap());
    let sample = saussine::sample_scene(&SampleSpec::saussine(2).scaled(60)).unwrap();
    round_trips(&sample);
    let bank = saussine::sample_scene(&SampleSpec { bank: true, ..SampleSpec::saussine(3) }.scaled(60)).unwrap();
    round_trips(&bank);
    round_trips(&saussine::open_bank(&bank).unwrap());
    for guide in [Guide::Vertical, Guide::Level, Guide::Free] {
        for bars in [0, 1, 2] {
            let spec = LoadingSpec { guide: Some(guide), bars, inclination_deg: 3.0, ..LoadingSpec::saussine(3) }
                .scaled(60.0 / 724.0);
            round_trips(&saussine::loaded_scene(&sample, &spec).unwrap());
        }
    }
    let spec = small_karrech();
    md_round_trips(&karrech::deposit_scene(&spec, 100).unwrap());
    let spheres = karrech::loose_spheres(&spec).unwrap();
    for loading in [Loading::FULL, Loading::PARTIAL] {
        md_round_trips(&karrech::loading_scene(&spec, &spheres, loading, 2, 10).unwrap());
    }
    let spec = LudingSpec::paper(27, 0.2, 5);
    let compressed = luding::compression_scene(&spec, 2.0, 100).unwrap();
    md_round_trips(&compressed);
    let spheres: Vec<(f64, V3)> = compressed.bodies.iter().map(|b| (b.sphere, V3::from(b.position))).collect();
    md_round_trips(&luding::cyclic_scene(&spec, &spheres, V3::zeros(), V3::repeat(0.04), 2, 100).unwrap());
}

/// `saussine sample --grains 1` wrote pads of negative width (a clockwise
/// polygon), `--grains 2` a box narrower than a grain (the deposit diverged at
/// step 1): the scaled width is `n / 724` m and must hold the largest grain.
#[test]
fn samples_scaled_below_the_minimum_are_refused() {
    for n in [1, 2, MIN_SCALED_GRAINS - 1] {
        let m = message(saussine::sample_scene(&SampleSpec::saussine(1).scaled(n)));
        says(&m, &["sample: width", "cannot hold the largest grain", "0.022", "fewer than 16 grains"]);
    }
    // The smallest accepted sample deposits without diverging, every pad counter-clockwise.
    let scene = saussine::sample_scene(&SampleSpec::saussine(1).scaled(MIN_SCALED_GRAINS)).unwrap();
    assert_eq!(scene.bodies.iter().filter(|b| b.name.starts_with(GRAIN_PREFIX)).count(), 16);
    for pad in scene.bodies.iter().filter(|b| b.name.starts_with(PAD_PREFIX)) {
        let p = pad.polygon.as_ref().unwrap();
        assert!(p[1][0] > p[0][0] && p[2][1] > p[1][1], "{}: {p:?}", pad.name);
    }
    let mut sys = scene.build().unwrap();
    for _ in 0..2000 {
        sys.step().unwrap();
    }
    // Other impossible samples.
    let spec = SampleSpec::saussine(1);
    says(&message(saussine::sample_scene(&SampleSpec { dt: f64::NAN, ..spec.clone() })), &["sample: dt (s)", "NaN"]);
    says(
        &message(saussine::sample_scene(&SampleSpec { grading: vec![(0.0, 3)], ..spec.clone() })),
        &["sample: grading[0] radius (m) must be positive"],
    );
    says(
        &message(saussine::sample_scene(&SampleSpec { grading: vec![(0.01, 0)], ..spec.clone() })),
        &["sample: grading: the grading has no grain"],
    );
    says(&message(saussine::sample_scene(&SampleSpec { pad_gap: 0.01, ..spec.clone() })), &["pad_gap"]);
    says(&message(saussine::sample_scene(&SampleSpec { pad_width: 2.0, ..spec.clone() })), &["cannot hold one pad"]);
    says(
        &message(saussine::sample_scene(&SampleSpec { bank: true, grading: vec![(0.001, 50)], ..spec.clone() })),
        &["pass under the mould"],
    );
    says(&message(saussine::sample_scene(&SampleSpec { k_n: -1.0, ..spec })), &["sample: k_n (N)"]);
}

/// `deposit --dt nan` wrote `dt = NaN` (not TOML) and then reported an error in
/// a `scene.toml` the user never wrote.
#[test]
fn deposit_with_a_bad_dt_or_width_is_a_clear_error() {
    let spec = DepositSpec::saussine(30, 0.2, 3);
    let m = message(pentagon_deposit(&DepositSpec { dt: f64::NAN, ..spec.clone() }));
    assert_eq!(m, "deposit: dt (s) must be positive and finite, got NaN");
    says(&message(pentagon_deposit(&DepositSpec { duration: -1.0, ..spec.clone() })), &["deposit: duration (s)"]);
    says(&message(pentagon_deposit(&DepositSpec { width: 0.01, ..spec.clone() })), &["deposit: width 0.01 m", "0.022"]);
    says(
        &message(pentagon_deposit(&DepositSpec::saussine(0, 0.2, 3))),
        &["deposit: grading: the grading has no grain"],
    );
    says(
        &message(pentagon_deposit(&DepositSpec { grading: vec![(-0.005, 3)], ..spec.clone() })),
        &["deposit: grading[0] radius"],
    );
    says(&message(pentagon_deposit(&DepositSpec { friction: f64::INFINITY, ..spec })), &["deposit: friction"]);

    let dir = scratch::dir("deposit");
    let out = dir.join("d.toml");
    let o = ballast(&["deposit", "--dt", "nan", "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("deposit: dt (s) must be positive and finite, got NaN") && !err.contains("scene.toml"),
        "{err}"
    );
    assert!(!out.exists());
    let o = ballast(&["deposit", "--grains", "20", "--width", "0.2", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.starts_with("# Loose pentagon deposit: 20 grains, seed 1.\n"), "{text}");
    let spec = DepositSpec { duration: 2.0, ..DepositSpec::saussine(20, 0.2, 1) };
    assert_eq!(Scene::from_toml_str(&text).unwrap(), pentagon_deposit(&spec).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `saussine load` on a 60-grain sample failed with the default options: the
/// sleeper was scaled with the sample (20.7 mm) but not its two 10 mm bars,
/// which need 40 mm. The bars now narrow with a sleeper too narrow for them.
#[test]
fn small_samples_are_loaded_by_a_scaled_sleeper() {
    let sample = saussine::sample_scene(&SampleSpec::saussine(1).scaled(60)).unwrap();
    let f = 60.0 / 724.0;
    let spec = LoadingSpec::saussine(100).scaled(f);
    assert_eq!(spec.sleeper_width, Some(0.25 * f));
    assert_eq!(spec.bar_size, 0.25 * f / 5.0);
    let loaded = saussine::loaded_scene(&sample, &spec).unwrap();
    let sleeper = loaded.bodies.iter().find(|b| b.name == SLEEPER).unwrap();
    let parts = sleeper.parts.as_ref().unwrap();
    assert_eq!(parts.len(), 3);
    // Bars one bar width from the ends and from each other.
    let b = spec.bar_size;
    let (w, x0, x1) = (spec.width(), parts[1][0][0], parts[2][0][0]);
    assert!((x0 - (-w / 2.0 + b)).abs() < 1e-15 && (x1 - (x0 + 2.0 * b)).abs() < 1e-15, "{parts:?}");
    // A sample that holds the 10 mm bars keeps them (the 121-grain sample: 41.8 mm).
    assert_eq!(LoadingSpec::saussine(1).scaled(121.0 / 724.0).bar_size, 0.01);
    // A sleeper given too narrow for its bars is still refused.
    let narrow = LoadingSpec { sleeper_width: Some(0.03), ..LoadingSpec::saussine(1) };
    says(&message(saussine::loaded_scene(&sample, &narrow)), &["too narrow for 2 bars of 0.01 m", "use fewer bars"]);

    // Through the CLI, with the default options.
    let dir = scratch::dir("load");
    let (sample_path, out) = (dir.join("sample.toml"), dir.join("loaded.toml"));
    std::fs::write(&sample_path, sample.to_toml_string().unwrap()).unwrap();
    let o = ballast(&["saussine", "load", "--sample", sample_path.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = Scene::load(&out).unwrap();
    let sleeper = written.bodies.iter().find(|b| b.name == SLEEPER).unwrap();
    assert_eq!(sleeper.load.unwrap().mean, -1000.0 * f);
    // With --sleeper-width, the sleeper keeps its 10 mm bars.
    let o = ballast(&[
        "saussine",
        "load",
        "--sample",
        sample_path.to_str().unwrap(),
        "--sleeper-width",
        "0.05",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = Scene::load(&out).unwrap();
    let parts = written.bodies.iter().find(|b| b.name == SLEEPER).unwrap().parts.clone().unwrap();
    assert!((parts[1][1][0] - parts[1][0][0] - 0.01).abs() < 1e-12, "{parts:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_loading_parameters_are_named() {
    let sample = saussine::sample_scene(&SampleSpec::saussine(1).scaled(121)).unwrap();
    let base = LoadingSpec::saussine(10).scaled(121.0 / 724.0);
    for (spec, needle) in [
        (LoadingSpec { frequency: 0.0, ..base.clone() }, "frequency: the loading frequency (Hz) must be positive"),
        (LoadingSpec { cycles: 0, ..base.clone() }, "cycles: must be at least 1"),
        (LoadingSpec { dt: f64::NAN, ..base.clone() }, "dt: the time step (s) must be positive"),
        (LoadingSpec { criterion: "fast".into(), ..base.clone() }, "criterion: 'fast' is not one of"),
        (LoadingSpec { inclination_deg: 90.0, ..base.clone() }, "inclination_deg: must be in (-90, 90)"),
        (
            LoadingSpec { sleeper_width: Some(0.0), ..base.clone() },
            "sleeper_width: the sleeper's width (m) must be positive",
        ),
        (LoadingSpec { bar_size: -0.01, ..base.clone() }, "bar_size: the bars' side (m) must be positive"),
        (LoadingSpec { mean: f64::INFINITY, ..base.clone() }, "mean: the load's mean A (N) must be finite"),
        (LoadingSpec { max_iterations: 0, ..base.clone() }, "min_iterations: must be at least 1"),
    ] {
        says(&message(saussine::loaded_scene(&sample, &spec)), &[needle]);
    }
}

/// A zero spread of the radii, a container smaller than a sphere or a packing
/// fraction too dense to place at random made `loose_spheres` loop forever.
#[test]
fn impossible_karrech_samples_are_errors_not_endless_loops() {
    let spec = small_karrech();
    for (bad, needle) in [
        (KarrechSpec { radius_sd: 0.0, ..spec.clone() }, "karrech: radius_sd (m) must be positive"),
        (KarrechSpec { radius_mean: -1e-3, ..spec.clone() }, "karrech: radius_mean (m)"),
        (KarrechSpec { container_radius: 0.005, ..spec.clone() }, "karrech: container_radius 0.005 m is too small"),
        (KarrechSpec { spheres: 0, ..spec.clone() }, "karrech: spheres must be at least 1"),
        (KarrechSpec { spheres: 3, ..spec.clone() }, "karrech: spheres: the loose layer of 3 spheres"),
        (KarrechSpec { loose_fraction: 1.5, ..spec.clone() }, "karrech: loose_fraction must be in (0, 1)"),
        (KarrechSpec { dt: f64::NAN, ..spec.clone() }, "karrech: dt (s)"),
        (KarrechSpec { poisson: 0.5, ..spec.clone() }, "karrech: poisson"),
        (KarrechSpec { energy_ratio: 0.0, ..spec.clone() }, "karrech: energy_ratio"),
    ] {
        says(&message(karrech::deposit_scene(&bad, 100)), &[needle]);
    }
    // Denser than random placement reaches: refused after a bounded number of draws.
    let dense = KarrechSpec { spheres: 400, loose_fraction: 0.45, ..spec.clone() };
    says(&message(karrech::loose_spheres(&dense)), &["karrech: loose_fraction 0.45: no free place for sphere"]);
    says(&message(karrech::deposit_scene(&spec, 0)), &["karrech: every"]);
    let spheres = karrech::loose_spheres(&spec).unwrap();
    let half = Loading { coverage: 0.0, ..Loading::FULL };
    says(&message(karrech::loading_scene(&spec, &spheres, half, 2, 10)), &["karrech: loading coverage"]);
    says(&message(karrech::loading_scene(&spec, &spheres, Loading::FULL, 0, 10)), &["karrech: cycles"]);
    says(&message(karrech::loading_scene(&spec, &[], Loading::FULL, 1, 10)), &["no sphere"]);
}

#[test]
fn impossible_luding_boxes_are_errors() {
    let spec = LudingSpec::paper(27, 0.1, 1);
    says(
        &message(luding::compression_scene(&LudingSpec { spheres: 0, ..spec.clone() }, 1.0, 10)),
        &["luding: spheres"],
    );
    says(&message(luding::compression_scene(&spec, f64::NAN, 10)), &["luding: duration (s)"]);
    says(&message(luding::compression_scene(&LudingSpec { dt: 0.0, ..spec.clone() }, 1.0, 10)), &["luding: dt (s)"]);
    says(&message(luding::compression_scene(&LudingSpec { friction: -0.1, ..spec.clone() }, 1.0, 10)), &["friction"]);
    let spheres = vec![(0.005, V3::repeat(0.02))];
    says(
        &message(luding::cyclic_scene(&spec, &spheres, V3::repeat(0.04), V3::zeros(), 1, 10)),
        &["luding: box corners"],
    );
    says(&message(luding::cyclic_scene(&spec, &spheres, V3::zeros(), V3::repeat(0.04), 0, 10)), &["luding: cycles"]);
    says(
        &message(luding::cyclic_scene(
            &LudingSpec { period: 0.0, ..spec },
            &spheres,
            V3::zeros(),
            V3::repeat(0.04),
            1,
            10,
        )),
        &["luding: period (s)"],
    );
}

/// `saussine sample --grains 1` is refused before any run, with the minimum.
#[test]
fn cli_refuses_a_sample_below_the_minimum() {
    let dir = scratch::dir("grains");
    let out = dir.join("s");
    let o = ballast(&["saussine", "sample", "--grains", "1", "--quiet", "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("fewer than 16 grains"), "{err}");
    assert!(!out.join("deposit.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn impossible_md_beds_are_errors() {
    use ballast::scenarios::md_bed::{bed_spheres, bed_system, BedSpec, MIN_SIDE};
    says(&message(bed_spheres(&BedSpec { n: 0, ..BedSpec::peers(10, 1) })), &["md_bed: n (spheres)"]);
    for side in [0.01, f64::NAN] {
        says(&message(bed_system(&BedSpec { side, ..BedSpec::peers(10, 1) })), &["md_bed: side must be at least"]);
    }
    assert_eq!(bed_spheres(&BedSpec { side: MIN_SIDE, ..BedSpec::peers(3, 1) }).unwrap().len(), 3);
    assert_eq!(bed_system(&BedSpec::peers(2000, 12345)).unwrap().particles.len(), 2000);
}
