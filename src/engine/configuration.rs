//! What a cyclic driver reads from and writes back into an engine: the generalised positions of its mobile
//! bodies ([`Configuration`]; Karrech et al. 2007, Fig. 10: fit, extrapolate, write back) and the boundary bodies
//! that move under their own dynamics ([`Boundary`]).

use crate::error::Result;
use serde::{Deserialize, Serialize};

/// The generalised positions of some bodies of an engine: `dof` coordinates per
/// body, body after body.
///
/// In 2D (NSCD) `dof = 3`: the centre of mass `x`, `y` (m) and the angle `θ`
/// (rad). In 3D (MD) `dof = 6`: the centre `x`, `y`, `z` (m) and the rotation
/// vector of the orientation (axis × angle, rad, angle in [0, π]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Configuration {
    /// Coordinates per body.
    pub dof: usize,
    /// Index of each body in the engine (its order in the scene).
    pub bodies: Vec<usize>,
    /// Coordinate `d` of the `k`-th body is `q[k * dof + d]` (m or rad).
    pub q: Vec<f64>,
}

impl Configuration {
    /// The coordinates of the `k`-th body of the configuration.
    pub fn body(&self, k: usize) -> &[f64] {
        &self.q[k * self.dof..(k + 1) * self.dof]
    }

    /// The coordinates of the `k`-th body, mutable.
    pub fn body_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.q[k * self.dof..(k + 1) * self.dof]
    }

    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.bodies.len()
    }

    /// True if there are no bodies.
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    /// Checks the shape of the configuration against an engine with `bodies`
    /// bodies and `dof` coordinates each, and that every number is finite; the
    /// message names the first offending body.
    pub fn check(&self, dof: usize, bodies: usize) -> Result<()> {
        let bad = |msg: String| Err(crate::Error::Scene(format!("configuration: {msg}")));
        if self.dof != dof {
            return bad(format!("{} coordinates per body, the engine has {dof}", self.dof));
        }
        if self.q.len() != self.bodies.len() * dof {
            return bad(format!("{} coordinates for {} bodies of {dof}", self.q.len(), self.bodies.len()));
        }
        for (k, &i) in self.bodies.iter().enumerate() {
            if i >= bodies {
                return bad(format!("body {i} does not exist (the engine has {bodies})"));
            }
            if let Some(d) = self.body(k).iter().position(|x| !x.is_finite()) {
                return bad(format!("body {i}: coordinate {d} is not finite ({})", self.body(k)[d]));
            }
        }
        Ok(())
    }
}

/// A boundary body that moves under its own dynamics, outside the
/// [`Configuration`] of the bodies (MD: a servo wall, e.g. the loading plate).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Boundary {
    /// Its name in the scene.
    pub name: String,
    /// Its coordinate (m): a servo wall's displacement along its normal since the start.
    pub s: f64,
    /// How far it goes down (along gravity) per unit of `s` (dimensionless: `−n·up`).
    pub down: f64,
}
