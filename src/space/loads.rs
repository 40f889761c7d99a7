//! What drives a 3D body besides gravity and contacts: external forces and moments that follow the harmonic law
//! `A + B cos(2π f t − φ)` of the sleeper load (Saussine et al. 2006, §3.1; [`Harmonic`], shared with 2D), and
//! imposed velocity components.
//!
//! **Which frame.** The translation components `v_x, v_y, v_z` are the world velocity of the centroid, each
//! imposed on its own. The spin is imposed **as a whole vector** in world axes: the engine keeps the spin in the
//! body's principal frame (`crate::space::bodies`), where the inverse mass is diagonal, and imposing one world
//! component of it alone is a constraint that mixes the three principal components — it has no diagonal inverse
//! mass, so the shared method's rows could not honour it. A whole imposed spin `ω(t)` (world) is `Rᵀ ω(t)` in the
//! principal frame at every step, whatever the body's orientation. (LMGC90's RBDY3 drives its dofs 4–6 in the
//! inertia frame one by one; that is well defined only while a body's principal axes keep their directions, which
//! the imposed spin `0` — the usual case, a sleeper that may not tilt — does for all three at once.)
//!
//! A load is a force along a world direction applied at the centroid, or a moment about a world axis through the
//! centroid (N·m), of magnitude `A + B cos(2π f t − φ)`. The engine evaluates loads at `t_m = t_n + (1 − θ) h`
//! and imposed velocities at the end of the step, as the 2D engine does.

use crate::geometry::Vec3;
pub use crate::plane::loads::Harmonic;
use serde::{Deserialize, Serialize};

/// What a [`Load3`] pushes: the centroid (a force) or the rotation (a moment about the centroid).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadKind {
    /// A force (N) along the direction, at the centroid.
    Force,
    /// A moment (N·m) about the direction, through the centroid.
    Moment,
}

/// An external force or moment `value(t) · direction` (world).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Load3 {
    /// A force or a moment.
    pub kind: LoadKind,
    /// Unit direction (a force's line, a moment's axis), world.
    pub direction: Vec3,
    /// Magnitude along `direction` (N or N·m).
    pub value: Harmonic,
}

impl Load3 {
    /// A force of magnitude `value` (N) along `direction` (any non-zero length; normalised here).
    pub fn force(direction: Vec3, value: Harmonic) -> Self {
        Self { kind: LoadKind::Force, direction: direction.normalize(), value }
    }

    /// A moment of magnitude `value` (N·m) about `direction` (any non-zero length; normalised here).
    pub fn moment(direction: Vec3, value: Harmonic) -> Self {
        Self { kind: LoadKind::Moment, direction: direction.normalize(), value }
    }

    /// The vector (N or N·m, world) at time `t` (s).
    #[inline]
    pub fn at(&self, t: f64) -> Vec3 {
        self.direction * self.value.at(t)
    }
}

/// Imposed velocity components of a 3D body; `None` leaves a component free.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Imposed3 {
    /// The centroid's `v_x`, `v_y`, `v_z` (m/s, world), each on its own.
    pub velocity: [Option<Harmonic>; 3],
    /// The spin (rad/s, world axes), all three components together (module doc).
    pub spin: Option<[Harmonic; 3]>,
}

impl Imposed3 {
    /// Whether nothing is imposed.
    pub fn is_empty(&self) -> bool {
        self.velocity.iter().all(Option::is_none) && self.spin.is_none()
    }

    /// The imposed spin at time `t` (rad/s, world), if the spin is imposed.
    pub fn spin_at(&self, t: f64) -> Option<Vec3> {
        self.spin.map(|s| Vec3::new(s[0].at(t), s[1].at(t), s[2].at(t)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loads_follow_their_law_along_a_unit_direction() {
        let h = Harmonic { mean: -1000.0, amplitude: -500.0, frequency: 20.0, phase: -std::f64::consts::PI };
        let f = Load3::force(Vec3::new(0.0, 0.0, 2.0), h);
        // F(0) = −1000 − 500 cos(π) = −500 N along z; a quarter period later (1/40 s) the peak −1500 N.
        assert!((f.at(0.0) - Vec3::new(0.0, 0.0, -500.0)).norm() < 1e-9);
        assert!((f.at(1.0 / 40.0) - Vec3::new(0.0, 0.0, -1500.0)).norm() < 1e-9);
        let m = Load3::moment(Vec3::new(3.0, 4.0, 0.0), Harmonic::constant(5.0));
        assert_eq!(m.kind, LoadKind::Moment);
        assert!((m.at(1.0) - Vec3::new(3.0, 4.0, 0.0)).norm() < 1e-12);
        let imposed = Imposed3 { velocity: [None, Some(Harmonic::constant(1.0)), None], spin: None };
        assert!(!imposed.is_empty() && imposed.spin_at(0.0).is_none());
        assert!(Imposed3::default().is_empty());
    }
}
