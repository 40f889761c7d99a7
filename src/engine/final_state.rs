//! `final.json`: the time, step and state of every body (and, in MD, every wall)
//! at the end of a run, in scene order. One type for both engines:
//!
//! - NSCD: `{"engine": "nscd", "time": 1.0, "step": 1000, "bodies": [{"name":
//!   "block", "position": [x, y], "angle": a, "velocity": [vx, vy], "spin": w},
//!   …]}`: centre of mass (m; not the scene's body-frame origin), angle (rad),
//!   velocity of the centre of mass (m/s), spin (rad/s);
//! - MD: `{"engine": "md", …, "bodies": [{"name": "s0", "position": [x, y, z],
//!   "velocity": [vx, vy, vz], "spin": [wx, wy, wz], "radius": r}, …], "walls":
//!   [{"name": "base", "displacement": s, "force": [fx, fy, fz]}, …]}` (m, m/s,
//!   rad/s, m; a wall's displacement along its normal since the start in m, and
//!   the total contact force of the spheres on it in N).
//! - 3D NSCD: `{"engine": "nscd3d", …, "bodies": [{"name": "cube", "position":
//!   [x, y, z], "velocity": [vx, vy, vz], "spin": [wx, wy, wz], "orientation":
//!   [w, x, y, z]}, …]}`: centroid (m), velocity (m/s), spin as a world vector
//!   (rad/s), the unit quaternion of the principal frame (body → world); a
//!   sphere also has its `radius` (m). Walls and floors are fixed bodies.
//!
//! Written with `serde_json` (floats as the shortest text that reads back to
//! the same `f64`).

use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The spin of a body: a scalar in 2D (rad/s, counter-clockwise), a vector in 3D.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Spin {
    /// 2D spin (rad/s).
    Planar(f64),
    /// 3D spin (rad/s).
    Spatial([f64; 3]),
}

/// State of one body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Name from the scene (may be empty).
    pub name: String,
    /// Centre of mass (m): 2 coordinates in 2D, 3 in 3D.
    pub position: Vec<f64>,
    /// Angle (rad), 2D only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f64>,
    /// Velocity of the centre of mass (m/s).
    pub velocity: Vec<f64>,
    /// Angular velocity (rad/s).
    pub spin: Spin,
    /// Radius (m), spheres only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Orientation (3D NSCD): the unit quaternion `[w, x, y, z]` of the rotation from the body's principal
    /// frame to the world.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<[f64; 4]>,
}

/// State of one wall (MD).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WallState {
    /// Name from the scene.
    pub name: String,
    /// Displacement along the normal since the start (m); 0 for a fixed wall.
    pub displacement: f64,
    /// Total contact force of the spheres on the wall at the last step (N).
    pub force: [f64; 3],
}

/// Contents of `final.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinalState {
    /// `"nscd"`, `"md2d"`, `"nscd3d"` or `"md"`.
    pub engine: String,
    /// Time (s).
    pub time: f64,
    /// Number of steps done.
    pub step: u64,
    /// Every body, in scene order.
    pub bodies: Vec<BodyState>,
    /// Every wall, in scene order (MD).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallState>,
}

impl FinalState {
    /// Writes the state as pretty JSON to `path`.
    pub fn write(&self, path: &Path) -> Result<PathBuf> {
        crate::io::write_json(path, self)
    }

    /// Reads a `final.json`; the error names the file.
    pub fn read(path: &Path) -> Result<Self> {
        crate::io::read_json(path)
    }
}
