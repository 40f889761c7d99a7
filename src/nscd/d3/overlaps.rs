//! What a closed contact point's Signorini condition does with an overlap: the velocity-level law of Moreau–Jean
//! (Saussine et al. 2006 §2.3, LMGC90's `IQS_CLB`: an overlap is kept as it is, `U_N ≥ 0` once closed) or the same
//! law with the overlap **held**: a point's end-of-step gap may not go below the shallowest overlap the point has
//! had (a ratchet after LMGC90's `GAP_SGR_CLB_g0`, whose reference gap is the point's first one).
//!
//! Why: with the velocity-level law a solve stopped at a loose tolerance leaves closed contacts slightly
//! approaching, `U_N = −ε`, and the overlap grows by `θ h ε` every step, for ever. Under [`Overlaps::Held`] the
//! next step's threshold pushes that growth back out, `s_open = −(g − g_ref)/h > 0` when `g < g_ref`, so an
//! overlap stays within one step's growth of its reference. An overlap the point already had (the deposit's locked
//! pairs, a first contact found overlapping) is not pushed out: its reference is its own gap, and a point whose
//! overlap shrinks takes the smaller one as its reference.
//!
//! Measured on the loaded 200-grain track section (`docs/track3d.md`, "Holding the overlaps over 20 cycles"): the
//! mean overlap stops growing, but the loose solve's excess settlement per cycle stays (it is not the
//! interpenetration), the sweeps per step rise 2–6× and the push-out, a velocity the grains keep, shakes the
//! packing at `quad` 1e-3. The pushed-out growth must be small: a solve capped at a few sweeps per step leaves
//! growths whose push-out throws bodies apart. So the velocity-level law is the default.
//!
//! The reference `g_ref` of a point is, with `g` its gap at the intermediate configuration `q_m`:
//! - `min(0, g)` for a new point (no point of the same pair last step within the alert distance that an earlier
//!   point of the pair has not continued: the system finds a point's last step by place, not by rank);
//! - `min(0, max(g_ref_last, g))` for a point that carries on.
//!
//! and the row's opening threshold is `s_open = −(g − g_ref)/h`, which is the velocity-level law's `−g/h` for an
//! open point (`g > 0`, `g_ref = 0`) and its `0` for a point at its reference.

use serde::{Deserialize, Serialize};

/// The Signorini condition of closed contacts (`nscd.overlaps`; module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Overlaps {
    /// Moreau–Jean's velocity-level law (`"kept"`, the default): `U_N ≥ 0` once closed; an overlap stays as it is.
    #[default]
    Kept,
    /// An overlap may not grow past the shallowest one the point has had (`"held"`).
    Held,
}

impl Overlaps {
    /// The rule named `name` (`"kept"` or `"held"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "kept" => Some(Self::Kept),
            "held" => Some(Self::Held),
            _ => None,
        }
    }

    /// The rule's name in scenes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Kept => "kept",
            Self::Held => "held",
        }
    }
}

/// The reference gap (m) of a point of gap `gap` (m) at `q_m` whose key carried `last` last step (`None` for a new
/// point): `min(0, max(last, gap))`, or `min(0, gap)` when new.
#[inline]
pub fn reference_gap(gap: f64, last: Option<f64>) -> f64 {
    match last {
        Some(r) => r.max(gap).min(0.0),
        None => gap.min(0.0),
    }
}

/// The opening threshold `s_open` (m/s) of a point of gap `gap` and reference `g_ref` over a step `h` (s).
#[inline]
pub fn opening_threshold(gap: f64, g_ref: f64, h: f64) -> f64 {
    -(gap - g_ref) / h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The held law reduces to the velocity-level law's thresholds for open points and points at their
    /// reference, and pushes a grown overlap back to the reference (exact arithmetic on these values).
    #[test]
    fn thresholds() {
        let h = 1e-3;
        // Open: g_ref = 0, s_open = −g/h as in the velocity-level law.
        assert_eq!(opening_threshold(2e-6, reference_gap(2e-6, None), h), -2e-6 / h);
        assert_eq!(opening_threshold(2e-6, reference_gap(2e-6, Some(-1e-6)), h), -2e-6 / h);
        // A new overlapping point keeps its overlap: s_open = 0.
        assert_eq!(opening_threshold(-3e-6, reference_gap(-3e-6, None), h), 0.0);
        // Grown from −1 to −3 µm: pushed back out at 2 µm per step.
        assert_eq!(reference_gap(-3e-6, Some(-1e-6)), -1e-6);
        assert!((opening_threshold(-3e-6, -1e-6, h) - 2e-6 / h).abs() < 1e-18);
        // Shrunk from −3 to −1 µm: the reference follows, s_open = 0.
        assert_eq!(reference_gap(-1e-6, Some(-3e-6)), -1e-6);
        assert_eq!(Overlaps::from_name(Overlaps::Held.name()), Some(Overlaps::Held));
        assert_eq!(Overlaps::from_name("gap"), None);
    }
}
