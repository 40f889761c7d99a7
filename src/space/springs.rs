//! Viscoelastic springs between 3D bodies or to a world anchor: the sublayer of Saussine et al. 2006, §2.9, law
//! (17), in 3D (the 2D spring and the sign convention are [`crate::plane::springs`]; the NSCD row is
//! `crate::nscd::d3::spring`).
//!
//! A spring joins a point of body `a` to a point of body `b` or to a fixed anchor in the world. With `L` its
//! length, `L0` its rest length and `ε0` a prestrain, the strain is `ε = (L − L0)/L0 − ε0` and the force pushing
//! the ends apart along the axis is `R_N = −k_N ε − ν ε̇`, `ε̇ = U_N / L0`, `U_N` the rate at which the ends move
//! apart. The attachment points are kept in the body's **principal frame** (relative to its centroid), as the
//! engine keeps the body: a point `ρ` is at `x + R ρ` in the world.
//!
//! The axis velocity of an end at lever arm `r = R ρ` (world) with axis `n` is `n · (v + R ω × ρ)` =
//! `n · v + ω · (ρ × Rᵀ n)`: its generalised direction is `(n, ρ × Rᵀ n)`, the 3D twin of the 2D `(n, r × n)`.

use crate::geometry::{Pose, Vec3};
use crate::space::bodies::{dot6, gen_dir, Dofs6};
use serde::{Deserialize, Serialize};

pub use crate::plane::springs::CRUSHED;

/// A sublayer spring in 3D.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spring3 {
    /// Body at the first end.
    pub a: usize,
    /// Attachment on `a` (m), in its principal frame, relative to its centroid.
    pub point_a: Vec3,
    /// Body at the second end, or `None` for a world anchor.
    pub b: Option<usize>,
    /// Attachment on `b` (principal frame, relative to its centroid), or the world anchor point (m).
    pub point_b: Vec3,
    /// Force per unit strain `k_N` (N).
    pub k_n: f64,
    /// Force per unit strain rate `ν` (N·s).
    pub nu: f64,
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// Prestrain `ε0` (dimensionless).
    pub prestrain: f64,
    /// Only pushes (`R_N ≥ 0`).
    pub compression_only: bool,
    /// Impulse of the last step (N·s): the warm start.
    pub impulse: f64,
}

/// The geometry of a spring in a configuration: unit axis from the second end to the first, length, and the
/// generalised axis directions of both ends (zero for a world anchor).
#[derive(Debug, Clone, Copy)]
pub struct SpringState {
    /// Unit axis (world), from the second end to the first; `+z` for a zero length.
    pub axis: Vec3,
    /// Length (m).
    pub length: f64,
    /// Generalised direction of the first end, `(n, ρ_a × R_aᵀ n)`.
    pub h_a: Dofs6,
    /// Generalised direction of the second end, zero for an anchor.
    pub h_b: Dofs6,
}

impl Spring3 {
    /// The spring's geometry with the bodies at `poses`.
    pub fn state(&self, poses: &[Pose]) -> SpringState {
        let pa = &poses[self.a];
        let end_a = pa.position + pa.rotation * self.point_a;
        let end_b = match self.b {
            Some(b) => poses[b].position + poses[b].rotation * self.point_b,
            None => self.point_b,
        };
        let d = end_a - end_b;
        let length = d.norm();
        let axis = if length > 0.0 { d / length } else { Vec3::z() };
        let h_a = gen_dir(pa, &self.point_a, &axis);
        let h_b = self.b.map_or([0.0; 6], |b| gen_dir(&poses[b], &self.point_b, &axis));
        SpringState { axis, length, h_a, h_b }
    }

    /// The rate `U_N` (m/s) at which the ends move apart, for `state` and velocities `u`.
    pub fn axial_velocity(&self, state: &SpringState, u: &[Dofs6]) -> f64 {
        dot6(&state.h_a, &u[self.a]) - self.b.map_or(0.0, |b| dot6(&state.h_b, &u[b]))
    }

    /// The strain `ε = (L − L0)/L0 − ε0` at length `length` (m).
    pub fn strain(&self, length: f64) -> f64 {
        (length - self.rest_length) / self.rest_length - self.prestrain
    }

    /// The force `R_N` (N) pushing the ends apart with the bodies at `poses` moving at `u` (law (17), clamped to
    /// `R_N ≥ 0` for a compression-only spring).
    pub fn force(&self, poses: &[Pose], u: &[Dofs6]) -> f64 {
        let s = self.state(poses);
        let r = -self.k_n * self.strain(s.length) - self.nu * self.axial_velocity(&s, u) / self.rest_length;
        if self.compression_only {
            r.max(0.0)
        } else {
            r
        }
    }

    /// Elastic energy (J) with the bodies at `poses`: `½ k_N L0 ε²` (0 for a compression-only spring in tension).
    pub fn elastic_energy(&self, poses: &[Pose]) -> f64 {
        let eps = self.strain(self.state(poses).length);
        if self.compression_only && eps > 0.0 {
            0.0
        } else {
            0.5 * self.k_n * self.rest_length * eps * eps
        }
    }
}

/// The first spring of `springs` shorter than [`CRUSHED`] times its rest length with the bodies at `poses`: the
/// body at its first end and what happened (law (17) turns over where the length passes through zero).
pub fn crushed(springs: &[Spring3], poses: &[Pose]) -> Option<(usize, String)> {
    springs.iter().enumerate().find_map(|(k, s)| {
        let l = s.state(poses).length;
        (l < CRUSHED * s.rest_length).then(|| (s.a, crate::plane::springs::crushed_message(k, l, s.rest_length)))
    })
}

/// The bodies tied to a world anchor by a spring (the sublayer pads), sorted, each once.
pub fn anchored(springs: &[Spring3]) -> Vec<usize> {
    crate::plane::springs::anchored_ends(springs.iter().map(|s| (s.a, s.b.is_none())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// The generalised direction gives the axial rate of a rigid motion: ends moved by `v + ω × r` (world)
    /// separate at `n · (v_a + ω_a × r_a − v_b − ω_b × r_b)`.
    #[test]
    fn axial_velocity_is_the_rate_of_the_ends_moving_apart() {
        let pa =
            Pose { position: Vec3::new(0.1, 0.2, 0.5), rotation: UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1) };
        let pb =
            Pose { position: Vec3::new(-0.2, 0.1, 0.0), rotation: UnitQuaternion::from_euler_angles(-0.5, 0.4, 0.2) };
        let s = Spring3 {
            a: 0,
            point_a: Vec3::new(0.05, -0.02, 0.01),
            b: Some(1),
            point_b: Vec3::new(-0.03, 0.04, 0.02),
            k_n: 1.0,
            nu: 0.0,
            rest_length: 0.5,
            prestrain: 0.0,
            compression_only: false,
            impulse: 0.0,
        };
        let u = [[0.3, -0.1, 0.2, 1.0, -2.0, 0.5], [-0.4, 0.2, 0.1, 0.3, 0.7, -1.2]];
        let poses = [pa, pb];
        let st = s.state(&poses);
        // The same rate by a finite difference of the length, the bodies advanced by the exact motion.
        let dt = 1e-7;
        let moved: Vec<Pose> = poses.iter().zip(&u).map(|(p, u)| crate::space::bodies::advance(p, u, dt)).collect();
        let back: Vec<Pose> = poses.iter().zip(&u).map(|(p, u)| crate::space::bodies::advance(p, u, -dt)).collect();
        let rate = (s.state(&moved).length - s.state(&back).length) / (2.0 * dt);
        // A central difference: error O(dt²) times the third derivative, far below 1e-6.
        assert!((s.axial_velocity(&st, &u) - rate).abs() < 1e-6, "{} vs {rate}", s.axial_velocity(&st, &u));
    }
}
