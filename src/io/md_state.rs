//! `final.json` of an MD run: the time, step and state of every sphere and wall
//! at the end, in scene order, e.g.
//! `{"time": 0.5, "step": 100000, "bodies": [{"name": "s0", "position": [x, y, z],
//! "velocity": [vx, vy, vz], "spin": [wx, wy, wz], "radius": r}, …], "walls":
//! [{"name": "base", "displacement": s, "force": [fx, fy, fz]}, …]}` (m, m/s,
//! rad/s, m; a wall's displacement along its normal since the start in m, and the
//! total contact force of the spheres on it in N).

use crate::error::Result;
use crate::md::MdSystem;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// State of one sphere.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SphereState {
    /// Name from the scene (may be empty).
    pub name: String,
    /// Centre (m).
    pub position: [f64; 3],
    /// Velocity (m/s).
    pub velocity: [f64; 3],
    /// Angular velocity (rad/s).
    pub spin: [f64; 3],
    /// Radius (m).
    pub radius: f64,
}

/// State of one wall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WallState {
    pub name: String,
    /// Displacement along the normal since the start (m); 0 for a fixed wall.
    pub displacement: f64,
    /// Total contact force of the spheres on the wall at the last step (N).
    pub force: [f64; 3],
}

/// Contents of `final.json` of an MD run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MdFinalState {
    /// Time (s).
    pub time: f64,
    /// Number of steps done.
    pub step: u64,
    /// Every sphere, in scene order.
    pub bodies: Vec<SphereState>,
    /// Every wall, in scene order.
    pub walls: Vec<WallState>,
}

impl MdFinalState {
    /// The current state of `sys`.
    pub fn of(sys: &MdSystem) -> Self {
        let p = &sys.particles;
        let bodies = (0..p.len())
            .map(|i| SphereState {
                name: p.name[i].clone(),
                position: p.x[i].into(),
                velocity: p.v[i].into(),
                spin: p.w[i].into(),
                radius: p.r[i],
            })
            .collect();
        let walls = sys
            .walls
            .iter()
            .map(|w| WallState { name: w.name.clone(), displacement: w.s, force: w.force.into() })
            .collect();
        Self { time: sys.time, step: sys.step, bodies, walls }
    }

    /// The JSON text, one sphere or wall per line.
    pub fn to_json(&self) -> String {
        fn list<T: Serialize>(key: &str, items: &[T]) -> String {
            let mut text = format!("  \"{key}\": [");
            for (i, item) in items.iter().enumerate() {
                text.push_str(if i == 0 { "\n    " } else { ",\n    " });
                text.push_str(&serde_json::to_string(item).unwrap_or_else(|_| "null".into()));
            }
            text.push_str(if items.is_empty() { "]" } else { "\n  ]" });
            text
        }
        let num = |x: f64| serde_json::to_string(&x).unwrap_or_else(|_| "null".into());
        format!(
            "{{\n  \"time\": {},\n  \"step\": {},\n{},\n{}\n}}\n",
            num(self.time),
            self.step,
            list("bodies", &self.bodies),
            list("walls", &self.walls)
        )
    }

    /// Writes [`MdFinalState::to_json`] to `path`.
    pub fn write(&self, path: &Path) -> Result<PathBuf> {
        std::fs::write(path, self.to_json()).map_err(|e| super::io_error(path, "write", e))?;
        Ok(path.to_path_buf())
    }
}
