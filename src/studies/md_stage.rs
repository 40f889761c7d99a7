//! What the ready-made MD tests ([`super::karrech`], after Karrech et al.
//! 2007, and [`super::luding`], after David, García-Rojo, Herrmann & Luding)
//! share: each is two stages, a first one (deposit, compression) whose
//! finished state a second one (cyclic load) starts from. A stage is a scene
//! written into its output folder and run there like `ballast run`
//! ([`Stage`]: progress, checkpoints, `--resume`, `--vtk-every`); the first
//! stage leaves `spec.json` ([`TestSpec`]) for the stages after it. Then the
//! stage's tables and figures are computed from the run's outputs.

use super::{axes, output_error, run_scene, write_file, RunDisplay};
use crate::error::{Error, Result};
use crate::io::figures::{line_chart, Series};
use crate::io::layout;
use crate::md::{MdSystem, V3};
use crate::run::{RunOptions, RunOutcome};
use crate::scene::MdScene;
use crate::scene::SceneFile;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Where and how a stage runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    /// Output directory (the stage's scene is written there too).
    pub out: PathBuf,
    /// Steps between rows of `series.csv`.
    pub every: u64,
    /// How the run is carried out; with `resume`, a scene already written is
    /// kept and the run continues from its checkpoint.
    pub run: RunOptions,
}

impl Stage {
    /// A fresh stage in `out` with a row of `series.csv` every 1000 steps and the
    /// default [`RunOptions`].
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self { out: out.into(), every: 1000, run: RunOptions::default() }
    }

    /// Writes the scene `scene` (a generated scene: its error is an invalid
    /// input) as `out/name`, unless the stage resumes and it is there already;
    /// returns its path and whether it was written.
    pub(crate) fn write_scene(&self, name: &str, scene: impl FnOnce() -> Result<MdScene>) -> Result<(PathBuf, bool)> {
        let path = self.out.join(name);
        if self.run.resume && path.exists() {
            return Ok((path, false));
        }
        let text = scene()?.to_toml_string()?;
        crate::io::create_output_dir(&self.out)?;
        write_file(&path, &text)?;
        Ok((path, true))
    }

    /// Runs the scene at `scene` into the output directory.
    pub(crate) fn run(&self, scene: &Path, display: &dyn RunDisplay, label: &str) -> Result<RunOutcome> {
        run_scene(scene, &self.out, &self.run, display, label)
    }
}

/// What a stage did: its run, and what it then wrote in the run's folder from
/// the run's outputs (tables by file name, figures by stem: `<stem>.png` and
/// `<stem>.svg`).
#[derive(Debug, Clone, PartialEq)]
pub struct StageOutcome {
    /// The run of the stage's scene.
    pub run: RunOutcome,
    /// What the stage wrote after the run: tables by file name, figures by stem.
    pub written: Vec<String>,
}

/// `spec.json`: what a first stage was made with, read by the stages after it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TestSpec {
    /// Number of spheres of the sample.
    pub spheres: usize,
    /// Seed the sample was generated with.
    pub seed: u64,
    /// Time step (s), Karrech.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Young's modulus (Pa), Karrech.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young: Option<f64>,
    /// Friction coefficient `μ` (dimensionless), Luding.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Loading period `t₀` (s), `luding cycle`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
    /// Loading cycles of a `luding cycle` run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cycles: Option<u32>,
}

/// The name of the file of a [`TestSpec`].
pub const SPEC_FILE: &str = "spec.json";

impl TestSpec {
    /// The `spec.json` a first stage left in its output directory `dir`.
    ///
    /// # Errors
    /// [`Error::Scene`] naming the file if it cannot be read: `dir` is not the
    /// output of a first stage.
    pub fn read(dir: &Path) -> Result<Self> {
        crate::io::read_json(&dir.join(SPEC_FILE)).map_err(|e| Error::Scene(e.to_string()))
    }

    /// Writes `dir/spec.json` (creating `dir`).
    pub(crate) fn write(&self, dir: &Path) -> Result<()> {
        crate::io::create_output_dir(dir)?;
        crate::io::write_json(&dir.join(SPEC_FILE), self).map(|_| ())
    }
}

/// The system of a finished run's final scene in `dir`.
pub(crate) fn final_state(dir: &Path) -> Result<MdSystem> {
    let path = dir.join(layout::FINAL_SCENE);
    if !path.exists() {
        return Err(Error::Scene(format!("from: no finished run in '{}' (no final_scene.toml)", dir.display())));
    }
    MdScene::load(&path).and_then(|s| s.build())
}

/// The spheres of `sys` as `(radius, position)`.
pub(crate) fn spheres_of(sys: &MdSystem) -> Vec<(f64, V3)> {
    (0..sys.particles.len()).map(|i| (sys.particles.r[i], sys.particles.x[i])).collect()
}

/// The named columns of a CSV file of numbers (a run's output: a missing file
/// or column is a failure of the stage, not of its input).
pub(crate) fn columns(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>> {
    crate::io::table::read_columns(path, names).map_err(output_error)
}

/// A line chart `dir/stem` (PNG + SVG), linear in x.
pub(crate) fn chart(
    dir: &Path,
    stem: &str,
    title: &str,
    x: &str,
    y: &str,
    log_y: bool,
    series: Vec<Series>,
) -> Result<()> {
    line_chart(&dir.join(stem), &axes(title, x, y, false, log_y), &series)
}

/// The curve `label` through the points `(x, y)` that are finite.
pub(crate) fn curve(label: &str, x: &[f64], y: &[f64]) -> Series {
    Series {
        label: label.into(),
        points: x.iter().zip(y).filter(|(a, b)| a.is_finite() && b.is_finite()).map(|(a, b)| (*a, *b)).collect(),
        band: Vec::new(),
        thin: false,
        points_only: false,
    }
}
