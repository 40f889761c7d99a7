//! Errors of the crate.

use crate::geometry::GeometryError;

/// Everything that can go wrong in loading a scene, building a system or running it.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene is invalid, or a system built in code is (a contact law missing,
    /// a mass not positive, …); the message names the field and the body or
    /// section.
    #[error("{0}")]
    Scene(String),
    /// An input file (a scene) could not be read: missing, unreadable or not UTF-8. `source` keeps the
    /// operating system's kind (`NotFound`, `PermissionDenied`, …).
    #[error("cannot read {what} '{}': {source}", path.display())]
    File {
        /// What the file was to be (`scene file`).
        what: &'static str,
        /// The path as given.
        path: std::path::PathBuf,
        /// Why it could not be read.
        source: std::io::Error,
    },
    /// A checkpoint to resume from was refused, or there is none: truncated or edited (checksum), of another
    /// engine, version or scene, a state that does not hold together or is not the scene's model, or counters
    /// that do not match the run's files. The message names the file; nothing was run.
    #[error("{0}")]
    Checkpoint(String),
    /// A shape was refused ([`GeometryError`]), e.g. a polygon given clockwise to
    /// a constructor in code; converts with `?`. (Scenes report their shapes'
    /// errors as [`Error::Scene`], with the body named.)
    #[error("{0}")]
    Geometry(#[from] GeometryError),
    /// The simulation produced a non-finite value or a runaway overlap. The system
    /// keeps the state of the last good step.
    #[error("step {step}: body {body} ('{name}'): {what}")]
    Diverged {
        /// The step being made (counted from the engine's step origin).
        step: u64,
        /// Index of the body in the engine (its order in the scene).
        body: usize,
        /// Its name.
        name: String,
        /// What went wrong (a non-finite value, a runaway overlap, …).
        what: String,
    },
    /// An NSCD step reached its sweep cap short of the tolerance and the scene asked
    /// to stop then (`[nscd] on_stall = "stop"`). The system keeps the state of the
    /// last good step.
    #[error(
        "step {step}: the NLGS stalled: criterion {criterion:.3e} after {iterations} sweeps, tolerance {tolerance:e} \
         (nscd.on_stall = \"stop\"; raise nscd.max_iterations, use on_stall = \"extend\" or \"accept\", or see README, \"not converged\")"
    )]
    Stalled {
        /// The step being made (counted from the engine's step origin).
        step: u64,
        /// Sweeps made.
        iterations: usize,
        /// The policy's value after the last sweep (dimensionless).
        criterion: f64,
        /// The policy's tolerance.
        tolerance: f64,
    },
    /// A file could not be read or written.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

impl Error {
    /// The message on a single line (white space folded), as the command line
    /// prints it and the study tables record a failed run.
    pub fn one_line(&self) -> String {
        self.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
    }

    /// The scene key or argument a bad input ([`Error::Scene`]) names. Its message leads with it followed by a
    /// colon (`simulation.dt: …`, `nscd.tolerance: …`, `threads: …`, `perturbation.distance_m: …`,
    /// `spring[0].k_n: …`), or with a named item and its field (`body[1] 'block': polygon: …` gives
    /// `body[1].polygon`); a message about a call as a whole leads with the function
    /// (`loaded_scene: the sample already has a sleeper`). A key is a path of identifiers (ASCII letters,
    /// digits, `_`, `.`, `[`, `]`, starting with a letter). `None` for the other kinds and for a message that
    /// leads with anything else (a syntax error, `scene.toml line 3: …`).
    pub fn key(&self) -> Option<String> {
        let Error::Scene(message) = self else { return None };
        let is_path = |s: &str| {
            s.starts_with(|c: char| c.is_ascii_alphabetic())
                && s.chars().all(|c| c.is_ascii_alphanumeric() || "_.[]".contains(c))
        };
        let (head, rest) = message.split_once(':')?;
        match head.split_once(" '") {
            // An item named in quotes, then its field.
            Some((item, name)) if is_path(item) && name.ends_with('\'') => match rest.trim_start().split_once(':') {
                Some((field, _)) if is_path(field) => Some(format!("{item}.{field}")),
                _ => Some(item.to_string()),
            },
            _ => is_path(head).then(|| head.to_string()),
        }
    }

    /// Whether the error is the caller's input (a scene, an argument, a file to read, a checkpoint to resume
    /// from, a shape) rather than a run that failed: the command line exits with code 2 on it, and a study
    /// stops on it instead of recording a failed run.
    pub fn is_input(&self) -> bool {
        matches!(self, Error::Scene(_) | Error::File { .. } | Error::Checkpoint(_) | Error::Geometry(_))
    }
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, Error>;

/// A user's string for an error message: at most 64 characters (longer ones cut
/// with `…`), control characters replaced.
pub fn clip(s: &str) -> String {
    const MAX: usize = 64;
    let mut out: String = s.chars().take(MAX).map(|c| if c.is_control() { '?' } else { c }).collect();
    if s.chars().count() > MAX {
        out.push('…');
    }
    out
}
