//! Time-dependent drivers: the harmonic law `f(t) = A + B cos(2π f t − φ)` of the
//! sleeper load (Saussine et al. 2006, §3.1), used both for external forces along
//! a direction and for imposed velocity components.

use serde::{Deserialize, Serialize};

/// `value(t) = mean + amplitude · cos(2π · frequency · t − phase)`.
///
/// Units follow the quantity driven (N for a force, m/s or rad/s for a velocity);
/// `frequency` is in Hz, `phase` in rad, `t` in s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Harmonic {
    /// `A`: the mean value (unit of the quantity driven).
    pub mean: f64,
    /// `B`: amplitude of the cosine (unit of the quantity driven); its sign sets the
    /// value at `t = 0` together with `phase`.
    pub amplitude: f64,
    /// `f`: frequency of the cosine (Hz); one loading cycle lasts `1/f`.
    pub frequency: f64,
    /// `φ`: phase subtracted from `2π f t` (rad).
    pub phase: f64,
}

impl Harmonic {
    /// A constant value.
    pub fn constant(value: f64) -> Self {
        Self { mean: value, amplitude: 0.0, frequency: 0.0, phase: 0.0 }
    }

    /// The value at time `t` (s).
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        if self.amplitude == 0.0 {
            self.mean
        } else {
            self.mean + self.amplitude * (std::f64::consts::TAU * self.frequency * t - self.phase).cos()
        }
    }
}

/// External force `F(t) = value(t) · direction` applied at the centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Load {
    /// Unit direction of the force in the world frame.
    pub direction: [f64; 2],
    /// Magnitude along `direction` (N).
    pub force: Harmonic,
}

impl Load {
    /// The force `force(t)` (N) along `direction` (any non-zero vector, made a
    /// unit vector here as a scene's `load.direction` is).
    ///
    /// A zero or non-finite `direction` gives a non-finite direction (refused by
    /// scenes; a step with it diverges).
    pub fn new(direction: [f64; 2], force: Harmonic) -> Self {
        let n = direction[0].hypot(direction[1]);
        Self { direction: [direction[0] / n, direction[1] / n], force }
    }

    /// Force vector (N) at time `t` (s).
    #[inline]
    pub fn at(&self, t: f64) -> [f64; 2] {
        let f = self.force.at(t);
        [f * self.direction[0], f * self.direction[1]]
    }
}

/// Per-degree-of-freedom imposed velocity `(vx, vy, spin)`; `None` leaves the
/// degree of freedom free (driven by forces and contacts).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Imposed {
    /// Imposed law of `v_x` (m/s), `v_y` (m/s) and the spin `ω` (rad/s), world frame;
    /// `None` for a free degree of freedom.
    pub dof: [Option<Harmonic>; 3],
}

impl Imposed {
    /// The components `vx` (m/s), `vy` (m/s) and spin (rad/s) imposed as given
    /// (`None`: free), e.g. `Imposed::new(Some(Harmonic::constant(0.0)), None,
    /// Some(Harmonic::constant(0.0)))` for a body that may only move vertically.
    pub fn new(vx: Option<Harmonic>, vy: Option<Harmonic>, spin: Option<Harmonic>) -> Self {
        Self { dof: [vx, vy, spin] }
    }

    /// Whether no degree of freedom is imposed.
    pub fn is_empty(&self) -> bool {
        self.dof.iter().all(Option::is_none)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleeper_load_extrema() {
        // A = −1000 N, B = −500 N, f = 20 Hz, φ = −π: F(0) = −1000 − 500 cos(π) = −500 N
        // (unloaded), F(1/40 s) = −1500 N (peak).
        let h = Harmonic { mean: -1000.0, amplitude: -500.0, frequency: 20.0, phase: -std::f64::consts::PI };
        assert!((h.at(0.0) + 500.0).abs() < 1e-9);
        assert!((h.at(1.0 / 40.0) + 1500.0).abs() < 1e-9);
    }
}
