//! `final.json`: the time, step and state of every body at the end of a run,
//! in scene order, e.g.
//! `{"time": 1.0, "step": 1000, "bodies": [{"name": "block", "position": [x, y],
//! "angle": a, "velocity": [vx, vy], "spin": w}, …]}`.
//! Positions and velocities are those of the centre of mass (the system's `q`
//! and `u`), not of the scene's body-frame origin.

use crate::error::Result;
use crate::nscd::System;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// State of one body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Name from the scene (may be empty).
    pub name: String,
    /// Centre of mass (m).
    pub position: [f64; 2],
    /// Angle (rad).
    pub angle: f64,
    /// Velocity of the centre of mass (m/s).
    pub velocity: [f64; 2],
    /// Angular velocity (rad/s).
    pub spin: f64,
}

/// Contents of `final.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinalState {
    /// Time (s).
    pub time: f64,
    /// Number of steps done.
    pub step: u64,
    /// Every body, in scene order.
    pub bodies: Vec<BodyState>,
}

impl FinalState {
    /// The current state of `sys`.
    pub fn of(sys: &System) -> Self {
        let b = &sys.bodies;
        let bodies = b
            .info
            .iter()
            .zip(&b.q)
            .zip(&b.u)
            .map(|((info, q), u)| BodyState {
                name: info.name.clone(),
                position: [q[0], q[1]],
                angle: q[2],
                velocity: [u[0], u[1]],
                spin: u[2],
            })
            .collect();
        Self { time: sys.time, step: sys.step, bodies }
    }

    /// The JSON text, one body per line.
    pub fn to_json(&self) -> String {
        let num = |x: f64| serde_json::to_string(&x).unwrap_or_else(|_| "null".into());
        let mut text = format!("{{\n  \"time\": {},\n  \"step\": {},\n  \"bodies\": [", num(self.time), self.step);
        for (i, b) in self.bodies.iter().enumerate() {
            let body = serde_json::to_string(b).unwrap_or_else(|_| "null".into());
            text.push_str(if i == 0 { "\n    " } else { ",\n    " });
            text.push_str(&body);
        }
        text.push_str(if self.bodies.is_empty() { "]\n}\n" } else { "\n  ]\n}\n" });
        text
    }

    /// Writes [`FinalState::to_json`] to `path`.
    pub fn write(&self, path: &Path) -> Result<PathBuf> {
        std::fs::write(path, self.to_json()).map_err(|e| super::io_error(path, "write", e))?;
        Ok(path.to_path_buf())
    }
}
