//! The figures of a finished run, drawn from its output folder alone (`ballast figures DIR`, `ballast run
//! --figures` at the end of a run, the studies), each as `<stem>.png` + `<stem>.svg` in the folder: the top of
//! the crate, above the engines, the run loop and the settlement driver, whose files it reads.
//! [`draw_run_figures`] dispatches on the folder: an accelerated run (a folder with `settlement.csv`,
//! [`settlement`]), else the engine `final.json` names ([`plane`]: NSCD and planar MD; [`md`]: 3D MD; [`d3`]:
//! 3D NSCD).
//!
//! A figure whose data the folder does not hold (no cycles, an older run without `contacts.csv`) is skipped
//! and said so in [`RunFigures::skipped`].

pub mod d3;
pub mod md;
pub mod plane;
pub mod settlement;

use crate::engine::contacts::{self, ContactKind, ContactRow};
use crate::engine::FinalState;
use crate::error::{Error, Result};
use crate::io::figures::ForceLine;
use crate::io::layout;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What [`draw_run_figures`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunFigures {
    /// The stems written (each as `<stem>.png` and `<stem>.svg`).
    pub written: Vec<PathBuf>,
    /// The figures not drawn, by stem, and why.
    pub skipped: Vec<(String, String)>,
}

impl RunFigures {
    /// Records `stem` as written.
    pub(crate) fn wrote(&mut self, stem: PathBuf) {
        self.written.push(stem);
    }

    /// Records `stem` as skipped for `why`.
    pub(crate) fn skip(&mut self, stem: &str, why: &str) {
        self.skipped.push((stem.to_string(), why.to_string()));
    }
}

/// Draws the figures of the finished run in `dir`, of either engine, from its
/// files (see the module documentation and [`md`], [`plane`], [`settlement`]).
///
/// # Errors
/// [`Error::Scene`] naming the folder and the missing file if `dir` is not the
/// folder of a finished run (no `final.json` or `series.csv`, or for NSCD
/// neither `scene.toml` nor `initial_state.json`), or if a file does not fit
/// the others; [`Error::Io`] naming the file if one cannot be read or a figure
/// written.
pub fn draw_run_figures(dir: &Path) -> Result<RunFigures> {
    if dir.join(layout::SETTLEMENT).is_file() {
        // An accelerated run (either engine).
        return settlement::draw(dir, None);
    }
    let fin = read_final(dir)?;
    match fin.engine.as_str() {
        "nscd" | "md2d" => plane::nscd_figures(dir, None),
        "md" => md::md_figures(dir),
        "nscd3d" => d3::nscd3d_figures(dir),
        other => Err(Error::Scene(format!("{}: unknown engine '{other}'", dir.join(layout::FINAL).display()))),
    }
}

/// The path of `dir/name`, which must exist.
pub(crate) fn require(dir: &Path, name: &str) -> Result<PathBuf> {
    if !dir.is_dir() {
        return Err(Error::Scene(format!("'{}' is not a folder", dir.display())));
    }
    let path = dir.join(name);
    if path.is_file() {
        Ok(path)
    } else {
        Err(Error::Scene(format!("'{}' is not the folder of a finished run: it has no {name}", dir.display())))
    }
}

/// `dir/final.json`, which must exist.
pub(crate) fn read_final(dir: &Path) -> Result<FinalState> {
    FinalState::read(&require(dir, layout::FINAL)?)
}

/// Reads `dir/contacts.csv` if it exists (`None` for a run older than the file).
pub(crate) fn read_contacts(dir: &Path) -> Result<Option<Vec<contacts::ContactRow>>> {
    let path = dir.join(layout::CONTACTS);
    if path.is_file() {
        Ok(Some(contacts::read(&path)?))
    } else {
        Ok(None)
    }
}

/// The largest absolute value of `v` (finite ones only; 0 if none).
pub(crate) fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
    v.filter(|x| x.is_finite()).fold(0.0, |m, x| m.max(x.abs()))
}

/// Force chain segments of a contact list ([`crate::engine::contacts`]), in the plane
/// `project` maps a point (m) to: one per pair of moving bodies, between their
/// centres (`centre` of a body index, m), with the sum of the normal forces (N)
/// of the pair's contact points; one per contact with a wall, a fixed body or a
/// symmetry image, from the body's centre to the contact point, with its normal
/// force (so that a wall's forces are drawn where they act, not at its centre).
/// Contacts whose body has no centre are left out.
pub fn force_lines(
    rows: &[ContactRow],
    centre: impl Fn(usize) -> Option<[f64; 3]>,
    project: impl Fn([f64; 3]) -> [f64; 2],
) -> Vec<ForceLine> {
    let mut pairs = BTreeMap::<(usize, usize), f64>::new();
    let mut lines = Vec::new();
    for r in rows {
        match r.kind {
            ContactKind::Pair => *pairs.entry((r.a, r.b)).or_default() += r.f_n,
            ContactKind::Wall | ContactKind::Image => {
                if let Some(c) = centre(r.a) {
                    lines.push(ForceLine { from: project(c), to: project(r.point()), normal_force: r.f_n });
                }
            }
        }
    }
    for ((a, b), f) in pairs {
        if let (Some(ca), Some(cb)) = (centre(a), centre(b)) {
            lines.push(ForceLine { from: project(ca), to: project(cb), normal_force: f });
        }
    }
    lines
}
