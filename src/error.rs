//! Errors of the crate.

/// Everything that can go wrong in loading a scene or running it.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene is invalid; the message names the field and the body or section.
    #[error("{0}")]
    Scene(String),
    /// The simulation produced a non-finite value or a runaway overlap. The system
    /// keeps the state of the last good step.
    #[error("step {step}: body {body} ('{name}'): {what}")]
    Diverged { step: u64, body: usize, name: String, what: String },
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

impl Error {
    /// The message on a single line (white space folded), as the command line
    /// prints it and the study tables record a failed run.
    pub fn one_line(&self) -> String {
        self.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
    }
}

pub type Result<T> = std::result::Result<T, Error>;
