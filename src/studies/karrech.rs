//! The MD test of Karrech et al. (2007) (`ballast karrech …`), on the sample
//! of [`crate::scenarios::karrech`]:
//!
//! - [`deposit`] (Table 1, §2.3): the sample deposited under gravity until
//!   `E_c/E_p ≤ 10⁻⁶` (scene `deposit.toml`, run in the stage's folder), then
//!   the Fig. 3 figures from `series.csv`: apparent weight, coordination
//!   number, packing fraction, kinetic and potential energy;
//! - [`load`] (§4): the deposited sample under the cyclic plate (`load.toml`),
//!   then the residual displacement per cycle (from `cycles.csv`) and the
//!   plate's motion as figures. A loading run may start from a perturbed copy
//!   of the deposit ([`Start`]: replica `r ≥ 1` moves every sphere by at most
//!   1e-9 m, [`crate::studies::replicas::perturb_md_scene`]), the noise floor of
//!   a settlement comparison.

use super::md_stage::{chart, columns, curve, final_state, spheres_of, Stage, StageOutcome, TestSpec};
use super::replicas::{perturb_md_scene, REPLICA_FILE};
use super::RunDisplay;
use crate::error::{Error, Result};
use crate::scenarios::karrech::{self, KarrechSpec, Loading};
use crate::scene::SceneFile;
use std::path::Path;

/// The deposit: the Table 1 sample of `spheres` spheres (850: the paper's
/// 13.6 N sample, a quarter of it), its seed, time step (s), longest deposit
/// (s) and Young's modulus (Pa).
#[derive(Debug, Clone, PartialEq)]
pub struct Deposit {
    /// Number of spheres in the quarter sample (850 for the paper's).
    pub spheres: usize,
    /// Seed of the random radii and loose positions.
    pub seed: u64,
    /// Time step (s).
    pub dt: f64,
    /// Longest deposit (s): it ends earlier at `E_c / E_p ≤ 10⁻⁶`.
    pub duration: f64,
    /// Young's modulus `E` of the spheres (Pa); Table 1's is 46.9 GPa.
    pub young: f64,
}

impl Default for Deposit {
    /// The paper's: 850 spheres, seed 1, dt = 1e-7 s, 2 s (at Table 1's
    /// stiffness the full sample reaches E_c/E_p = 1.9e-6 at 1 s), E = 46.9 GPa.
    fn default() -> Self {
        Self { spheres: karrech::PAPER_SPHERES, seed: 1, dt: 1e-7, duration: 2.0, young: 46.9e9 }
    }
}

/// Deposits the sample of `spec` in `stage.out` (`deposit.toml`, `spec.json`,
/// the run's outputs) and draws the figures `fig3a_apparent_weight`,
/// `fig3b_coordination`, `fig3c_packing_fraction`, `fig3d_energies`.
///
/// # Errors
/// [`Error::Scene`] naming the parameters if a count or a value is not
/// positive, or for an invalid scene or checkpoint; else as
/// [`crate::run::Runner::run`], or an output that cannot be written or read back.
pub fn deposit(spec: &Deposit, stage: &Stage, display: &dyn RunDisplay) -> Result<StageOutcome> {
    crate::io::figures::require()?; // the stage ends with its figures
    let Deposit { spheres, seed, dt, duration, young } = *spec;
    if spheres == 0 || !(dt > 0.0 && duration > 0.0 && young > 0.0) {
        return Err(Error::Scene(format!(
            "karrech deposit: need spheres > 0, dt > 0, duration > 0, young > 0; got {spheres}, {dt}, {duration}, {young}"
        )));
    }
    let sample = KarrechSpec { dt, duration, young, ..KarrechSpec::table1(spheres, seed) };
    let (scene, written) = stage.write_scene("deposit.toml", || karrech::deposit_scene(&sample, stage.every))?;
    if written {
        TestSpec { spheres, seed, dt: Some(dt), young: Some(young), ..TestSpec::default() }.write(&stage.out)?;
    }
    let run = stage.run(&scene, display, "karrech deposit")?;
    Ok(StageOutcome { run, written: deposit_figures(&stage.out)? })
}

/// The start of a loading run ([`super::replicas::Start`]): here replica
/// `r ≥ 1` is the deposit with every sphere moved by [`perturb_md_scene`].
pub use super::replicas::Start;

/// The loading scene of the sample deposited in `from`, from `start`, written
/// as `load.toml` in `stage.out` (with `[settlement]` from `settlement` if
/// given, else a plain run) unless a resumed stage has it already.
fn write_load_scene(
    from: &Path,
    loading: Loading,
    cycles: u32,
    start: &Start,
    stage: &Stage,
    settlement: Option<crate::scene::common::SettlementSection>,
) -> Result<std::path::PathBuf> {
    let (sys, spec) = deposited(from)?;
    start.perturbation.check()?;
    let mut record = None;
    let (path, written) = stage.write_scene("load.toml", || {
        let mut scene = karrech::loading_scene(&spec, &spheres_of(&sys), loading, cycles, stage.every)?;
        record = Some(perturb_md_scene(&mut scene, &start.perturbation, start.replica)?);
        scene.settlement = settlement;
        scene.validate()?;
        Ok(scene)
    })?;
    if let (true, Some(record)) = (written, record) {
        if record.replica > 0 {
            crate::io::write_json(&stage.out.join(REPLICA_FILE), &record)?;
        }
    }
    Ok(path)
}

/// Loads the sample deposited in `from` (its `final_scene.toml` and
/// `spec.json`), from `start`, cyclically by the plate of `loading`
/// ([`Loading::FULL`] or [`Loading::PARTIAL`]) for `cycles` cycles in
/// `stage.out` (`load.toml`), then draws `residual_displacement` and `plate`.
///
/// # Errors
/// [`Error::Scene`] if `from` holds no finished deposit, or for an invalid
/// scene or checkpoint; else as [`deposit`].
pub fn load(
    from: &Path,
    loading: Loading,
    cycles: u32,
    start: &Start,
    stage: &Stage,
    display: &dyn RunDisplay,
) -> Result<StageOutcome> {
    crate::io::figures::require()?; // the stage ends with its figures
    let scene = write_load_scene(from, loading, cycles, start, stage, None)?;
    let run = stage.run(&scene, display, "karrech load")?;
    Ok(StageOutcome { run, written: load_figures(&stage.out)? })
}

/// [`load`] accelerated (Karrech et al. 2007, Fig. 10), from `start`: the loading scene with
/// its `[settlement]` table (the plate's displacement is the settlement; the
/// relaxation tolerance by default 1 % of the smallest radius) written as
/// `load.toml` and run through [`crate::open::settle_file`]: `settlement.csv`,
/// `jumps.csv`, `summary.json`, the figures; with a reference (a full run through
/// the driver), `errors.csv` ([`crate::report::settlement`]).
///
/// # Errors
/// As [`load`], and for invalid acceleration settings.
pub fn load_accelerated(
    from: &Path,
    loading: Loading,
    cycles: u32,
    accelerate: &super::Accelerate,
    start: &Start,
    stage: &Stage,
    progress: &mut dyn FnMut(&crate::settlement::AccelerationProgress),
) -> Result<crate::settlement::AccelerationSummary> {
    crate::io::figures::require()?;
    let section = accelerate.section(Some("plate".into()), None);
    let path = write_load_scene(from, loading, cycles, start, stage, Some(section))?;
    let opts = crate::run::RunOptions { figures: true, ..stage.run.clone() };
    accelerate.run_scene(&path, &stage.out, &opts, progress)
}

/// The sample deposited in `from` (its final state) and the specification it
/// was made with (`spec.json`; the paper's time step and modulus where it has none).
fn deposited(from: &Path) -> Result<(crate::md::MdSystem, KarrechSpec)> {
    let sys = final_state(from)?;
    let v = TestSpec::read(from)?;
    let paper = Deposit::default();
    let spec = KarrechSpec {
        dt: v.dt.unwrap_or(paper.dt),
        young: v.young.unwrap_or(paper.young),
        ..KarrechSpec::table1(sys.particles.len(), v.seed)
    };
    Ok((sys, spec))
}

/// Karrech et al. Fig. 3 from a deposit's `series.csv`.
fn deposit_figures(dir: &Path) -> Result<Vec<String>> {
    let c = columns(
        &dir.join("series.csv"),
        &["time_s", "base_force_N", "coordination", "packing_fraction", "kinetic_energy_J", "potential_energy_J"],
    )?;
    let weight = final_state(dir)?.weight();
    let t = &c[0];
    let flat: Vec<f64> = t.iter().map(|_| weight).collect();
    let stems = ["fig3a_apparent_weight", "fig3b_coordination", "fig3c_packing_fraction", "fig3d_energies"];
    chart(
        dir,
        stems[0],
        "Apparent weight on the base",
        "time (s)",
        "force (N)",
        false,
        vec![curve("apparent weight", t, &c[1]), curve("weight of the spheres", t, &flat)],
    )?;
    chart(dir, stems[1], "Coordination number", "time (s)", "z", false, vec![curve("z", t, &c[2])])?;
    chart(dir, stems[2], "Packing fraction", "time (s)", "φ", false, vec![curve("φ", t, &c[3])])?;
    let ek: Vec<f64> = c[4].iter().map(|v| v.max(1e-30)).collect();
    let ep: Vec<f64> = c[5].iter().map(|v| v.max(1e-30)).collect();
    chart(
        dir,
        stems[3],
        "Kinetic and potential energy",
        "time (s)",
        "energy (J)",
        true,
        vec![curve("kinetic E_c", t, &ek), curve("potential E_p", t, &ep)],
    )?;
    Ok(stems.map(String::from).to_vec())
}

/// Residual displacement per cycle and the plate's motion.
fn load_figures(dir: &Path) -> Result<Vec<String>> {
    let c = columns(&dir.join("cycles.csv"), &["cycle", "mean_displacement_z_m", "max_displacement_m"])?;
    let down: Vec<f64> = c[1].iter().map(|v| -v).collect();
    chart(
        dir,
        "residual_displacement",
        "Residual displacement at the end of each cycle",
        "cycle",
        "displacement (m)",
        false,
        vec![curve("mean settlement of the spheres (−u_z)", &c[0], &down), curve("largest displacement", &c[0], &c[2])],
    )?;
    let s = columns(&dir.join("series.csv"), &["time_s", "plate_position_m", "plate_force_N"])?;
    chart(
        dir,
        "plate",
        "Loading plate",
        "time (s)",
        "displacement (m)",
        false,
        vec![curve("plate displacement (down)", &s[0], &s[1])],
    )?;
    Ok(vec!["residual_displacement".into(), "plate".into()])
}
