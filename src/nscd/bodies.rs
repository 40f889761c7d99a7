//! The rigid body set of the NSCD engine, stored as flat arrays.
//!
//! Each body has the generalized coordinates `q = (x, y, θ)` of its centre of
//! mass and orientation, and velocities `u = (vx, vy, ω)` (Saussine et al. 2006,
//! §2.1: for a rigid body the inertia block is constant and diagonal). The
//! inverse mass is kept per degree of freedom so that fixed bodies and imposed
//! velocity components simply have a zero entry: contacts cannot move them.

use super::loads::{Imposed, Load};
use crate::geometry::Shape;
use serde::{Deserialize, Serialize};

/// Static description of one body (cold data).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BodyInfo {
    /// Name from the scene (may be empty).
    pub name: String,
    /// Shape in the body frame, centroid at the origin.
    pub shape: Shape,
    /// Index of the body's material.
    pub material: usize,
    /// Mass (kg).
    pub mass: f64,
    /// Polar moment of inertia about the centre of mass (kg·m²).
    pub inertia: f64,
    /// A fixed body never moves.
    pub fixed: bool,
    /// Imposed velocity components.
    pub imposed: Imposed,
    /// External forces applied at the centre of mass.
    pub loads: Vec<Load>,
}

/// The body collection, with hot arrays laid out for the solver.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Bodies {
    pub info: Vec<BodyInfo>,
    /// `(x, y, θ)`: centre of mass (m) and angle (rad).
    pub q: Vec<[f64; 3]>,
    /// `(vx, vy, ω)`: velocity of the centre of mass (m/s) and spin (rad/s).
    pub u: Vec<[f64; 3]>,
    /// Inverse mass per degree of freedom (1/kg, 1/kg, 1/(kg·m²)); zero when
    /// the body is fixed or the component is imposed.
    pub inv_m: Vec<[f64; 3]>,
}

impl Bodies {
    pub fn len(&self) -> usize {
        self.q.len()
    }

    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Adds a body at centre of mass `q` with velocity `u`; returns its index.
    pub fn push(&mut self, info: BodyInfo, q: [f64; 3], u: [f64; 3]) -> usize {
        let mut inv = [1.0 / info.mass, 1.0 / info.mass, 1.0 / info.inertia];
        if info.fixed {
            inv = [0.0; 3];
        }
        let mut u = u;
        if info.fixed {
            u = [0.0; 3];
        }
        if !info.fixed {
            for d in 0..3 {
                if let Some(f) = info.imposed.dof[d] {
                    inv[d] = 0.0;
                    u[d] = f.at(0.0);
                }
            }
        }
        self.info.push(info);
        self.q.push(q);
        self.u.push(u);
        self.inv_m.push(inv);
        self.q.len() - 1
    }

    /// Whether body `i` can move under contact forces in any direction.
    #[inline]
    pub fn is_mobile(&self, i: usize) -> bool {
        self.inv_m[i].iter().any(|&x| x > 0.0)
    }

    /// Kinetic energy ½ Σ (m v² + I ω²) of all non-fixed bodies (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.info
            .iter()
            .zip(&self.u)
            .filter(|(b, _)| !b.fixed)
            .map(|(b, u)| 0.5 * (b.mass * (u[0] * u[0] + u[1] * u[1]) + b.inertia * u[2] * u[2]))
            .sum()
    }
}
