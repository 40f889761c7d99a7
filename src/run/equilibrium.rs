//! The equilibrium stop of a run, one rule for both engines.
//!
//! A deposit is run "until equilibrium": the run ends once every condition given
//! has held for `steps` consecutive steps — the kinetic energy `E_k` below
//! `kinetic_energy` (J), and `E_k` below `energy_ratio` times the potential
//! energy `E_p` (the `E_c/E_p ≤ 10⁻⁶` criterion of Karrech et al. 2007 §2.3). A
//! window of steps, so that the rest at the top of a bounce does not count; and
//! the steps count only after a first step that *failed* the conditions, since a
//! sample released from rest meets `E_k < r E_p` before anything has fallen.
//!
//! `E_k` is that of everything that moves (bodies, and servo walls in MD); `E_p`
//! is gravitational (from a fixed reference height, so that `E_k + E_p` is
//! conserved without dissipation) plus elastic (MD contacts, NSCD sublayer
//! springs); see [`super::Engine::energies`].

use serde::{Deserialize, Serialize};

/// Default number of consecutive steps of the window.
pub const DEFAULT_EQUILIBRIUM_STEPS: u64 = 100;

/// `simulation.equilibrium` of a scene: `{ kinetic_energy = J, energy_ratio = r,
/// steps = N }`, at least one of the two thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Equilibrium {
    /// Threshold on the kinetic energy `E_k` (J), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinetic_energy: Option<f64>,
    /// Threshold on `E_k / E_p`, > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_ratio: Option<f64>,
    /// Consecutive steps, ≥ 1; default [`DEFAULT_EQUILIBRIUM_STEPS`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
}

impl Equilibrium {
    /// Consecutive steps required.
    pub fn steps(&self) -> u64 {
        self.steps.unwrap_or(DEFAULT_EQUILIBRIUM_STEPS)
    }

    /// Whether the rule needs the potential energy (it has an `energy_ratio`).
    pub fn needs_potential(&self) -> bool {
        self.energy_ratio.is_some()
    }

    /// Whether a step with kinetic energy `ek` (J) and potential energy `ep` (J)
    /// meets every condition given.
    pub fn holds(&self, ek: f64, ep: f64) -> bool {
        self.kinetic_energy.is_none_or(|k| ek < k) && self.energy_ratio.is_none_or(|r| ek < r * ep)
    }

    /// Checks the values; the message names the field (`simulation.equilibrium.…`).
    pub fn check(&self) -> crate::Result<()> {
        let bad = |what: &str, v: String| {
            Err(crate::Error::Scene(format!("simulation.equilibrium.{what}: must be positive and finite, got {v}")))
        };
        if self.kinetic_energy.is_none() && self.energy_ratio.is_none() {
            return Err(crate::Error::Scene(
                "simulation.equilibrium: give kinetic_energy (J), energy_ratio (E_k/E_p) or both".into(),
            ));
        }
        if let Some(k) = self.kinetic_energy.filter(|k| !(k.is_finite() && *k > 0.0)) {
            return bad("kinetic_energy", format!("{k}"));
        }
        if let Some(r) = self.energy_ratio.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return bad("energy_ratio", format!("{r}"));
        }
        if self.steps == Some(0) {
            return Err(crate::Error::Scene("simulation.equilibrium.steps: must be at least 1, got 0".into()));
        }
        Ok(())
    }
}

/// The state of the rule along a run (kept in checkpoints).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EquilibriumWatch {
    /// Whether some step so far failed the conditions: only then do calm steps count.
    pub moved: bool,
    /// Consecutive calm steps counted so far.
    pub calm_steps: u64,
}

impl EquilibriumWatch {
    /// Records a step that met the conditions (`calm`) or not; returns whether the
    /// window is complete.
    pub fn observe(&mut self, rule: &Equilibrium, calm: bool) -> bool {
        self.moved |= !calm;
        self.calm_steps = if calm && self.moved { self.calm_steps + 1 } else { 0 };
        self.calm_steps >= rule.steps()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calm_steps_count_only_after_a_failure() {
        let rule = Equilibrium { kinetic_energy: Some(1.0), energy_ratio: None, steps: Some(3) };
        let mut w = EquilibriumWatch::default();
        // At rest from the start: never reached.
        for _ in 0..10 {
            assert!(!w.observe(&rule, rule.holds(0.0, 0.0)));
        }
        assert!(!w.observe(&rule, rule.holds(2.0, 0.0)), "moving");
        assert!(!w.observe(&rule, true));
        assert!(!w.observe(&rule, true));
        assert!(w.observe(&rule, true), "three calm steps after moving");
        // A failure restarts the window.
        assert!(!w.observe(&rule, false));
        assert_eq!(w.calm_steps, 0);
    }

    #[test]
    fn both_conditions_must_hold() {
        let rule = Equilibrium { kinetic_energy: Some(1.0), energy_ratio: Some(1e-3), steps: None };
        assert!(rule.holds(0.5, 1000.0));
        assert!(!rule.holds(0.5, 100.0), "E_k/E_p = 5e-3");
        assert!(!rule.holds(1.5, 1e9), "E_k above 1 J");
        assert_eq!(rule.steps(), DEFAULT_EQUILIBRIUM_STEPS);
        assert!(Equilibrium { kinetic_energy: None, energy_ratio: None, steps: None }.check().is_err());
        assert!(Equilibrium { kinetic_energy: Some(f64::NAN), energy_ratio: None, steps: None }.check().is_err());
    }
}
