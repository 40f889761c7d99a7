//! Soft contact laws of the planar MD engine: the 3D laws of [`crate::md::law`]
//! and [`crate::md::contact`] (same normal dashpot, same tangential spring with
//! its Coulomb limit and stick/slip logic) on contact points of 2D bodies.
//!
//! A 2D body is a prism of thickness `t` out of the plane, so the stiffness of a
//! contact is given per metre of thickness and multiplied by `t`:
//! - `linear`: `F_n = k_n δ + γ_n δ̇` (David et al. eq. 1, the dashpot acting on
//!   approach and separation alike), `k_n = normal_stiffness × t` (N/m);
//! - `hertz` (Hertz-like power law): `F_n = K δ^{3/2} + γ_n(δ) δ̇`, clamped at 0,
//!   `K = normal_stiffness × t` (N/m^{3/2}), tangent stiffness `3/2 K √δ`. This
//!   is the 3D Hertz–Mindlin law of [`crate::md::contact`] with `R* = 1 m` and
//!   `E* = 3K/4` (its `4/3 E* √R* δ^{3/2}` is then `K δ^{3/2}`) and `G* = ρ E*/4`,
//!   so that its tangential stiffness `8 G* √(R* δ)` is `ρ` times the normal
//!   tangent stiffness (`ρ` the `tangential_ratio`), with Karrech's unloading fix.
//!
//! The tangential spring has stiffness `k_t = ρ k_n` (`linear`) and the
//! Coulomb limit `μ F_n`. The dashpots come from the restitution coefficient `e`
//! of a central impact: `α = −ln e / √(π² + ln² e)` for `linear` (exact),
//! [`crate::md::law::hertz_alpha_for_restitution`] for `hertz`, the same ratio
//! for the tangential dashpot, `γ = 2 α √(m* k)`. The ratio is at most 1, critical
//! damping: a restitution below that of a critically damped impact (0 for
//! `linear`; the NSCD default of a pair without a `[[contact]]` entry is 0) gets
//! `α = 1`, no rebound without an infinitely stiff dashpot.
//!
//! **Points of a polygon–polygon contact share its stiffness.** The shadow
//! overlap gives one point for a corner in an edge and two for edges in contact
//! (the ends of the overlap segment). Each point of a contact between two
//! polygons (or compound parts) carries half the pair's stiffnesses, so that a
//! face resting flat (two points) has the stiffness `k_n` of the pair and its
//! static overlap under a load `P` is `P / k_n`, whichever way it is meshed;
//! a corner alone then carries `k_n / 2`. This keeps the force continuous when a
//! tilting face lands on its second corner (that point enters at zero overlap).
//! A contact with a disc has one point, with the whole stiffness.

use crate::error::{Error, Result};
use crate::md::law::{hertz_alpha_for_restitution, linear_alpha_for_restitution, Damping, Model, PairLaw};
use serde::{Deserialize, Serialize};

/// The normal force law of a soft 2D contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SoftModel {
    /// Linear spring–dashpot.
    Linear,
    /// Hertz-like power law `K δ^{3/2}`.
    Hertz,
}

impl SoftModel {
    /// The model of a scene's name (`"linear"`, `"hertz"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "linear" => Some(Self::Linear),
            "hertz" => Some(Self::Hertz),
            _ => None,
        }
    }
}

/// The soft law of one pair of materials, as a scene gives it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SoftLaw {
    /// Normal force law.
    pub model: SoftModel,
    /// `linear`: k_n (N/m); `hertz`: K (N/m^{3/2}): the whole contact's, thickness
    /// included (module doc).
    pub normal_stiffness: f64,
    /// `ρ = k_t / k_n` (dimensionless, ≥ 0).
    pub tangential_ratio: f64,
    /// Restitution coefficient of a central impact, in `[0, 1]` (module doc: at
    /// most critical damping).
    pub restitution: f64,
    /// Coulomb friction coefficient (static = dynamic), ≥ 0.
    pub friction: f64,
}

impl SoftLaw {
    /// Checks the values (one-line error naming the field).
    ///
    /// # Errors
    /// [`Error::Scene`] for a stiffness not positive and finite, a ratio or
    /// friction negative or not finite, a restitution outside `(0, 1]`.
    pub fn check(&self) -> Result<()> {
        let bad =
            |what: &str, v: f64, need: &str| Err(Error::Scene(format!("soft law: {what} must be {need}, got {v}")));
        if !(self.normal_stiffness.is_finite() && self.normal_stiffness > 0.0) {
            return bad("normal_stiffness", self.normal_stiffness, "positive and finite");
        }
        if !(self.tangential_ratio.is_finite() && self.tangential_ratio >= 0.0) {
            return bad("tangential_ratio", self.tangential_ratio, ">= 0 and finite");
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return bad("restitution", self.restitution, "in [0, 1]");
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return bad("friction", self.friction, ">= 0 and finite");
        }
        Ok(())
    }

    /// The damping ratio `α` of both dashpots (module doc), at most 1 (critical).
    pub fn damping_ratio(&self) -> f64 {
        if self.restitution <= 0.0 {
            return 1.0;
        }
        let alpha = match self.model {
            SoftModel::Linear => linear_alpha_for_restitution(self.restitution),
            SoftModel::Hertz => hertz_alpha_for_restitution(self.restitution),
        };
        alpha.min(1.0)
    }

    /// The law of one contact point carrying `share` of the pair's stiffness
    /// (1, or 1/2 for a point of a polygon–polygon contact), as the 3D force
    /// routine takes it (evaluated with `R* = 1 m` for `hertz`).
    pub fn point_law(&self, share: f64) -> PairLaw {
        let alpha = self.damping_ratio();
        let k = self.normal_stiffness * share;
        let rho = self.tangential_ratio;
        match self.model {
            SoftModel::Linear => {
                PairLaw::linear(k, rho * k, Damping::Ratio(alpha), Damping::Ratio(alpha), self.friction, self.friction)
            }
            SoftModel::Hertz => {
                let e_star = 0.75 * k;
                PairLaw {
                    model: Model::Hertz,
                    e_star,
                    g_star: 0.25 * rho * e_star,
                    kn: 0.0,
                    kt: 0.0,
                    damping_n: Damping::Ratio(alpha),
                    damping_t: Damping::Ratio(alpha),
                    mu_s: self.friction,
                    mu_d: self.friction,
                    kt_kn_sqrt: rho.sqrt(),
                }
            }
        }
    }

    /// Overlap (m) at which a point carrying `share` of the stiffness bears
    /// a static normal force `force` (N): `F / k` or `(F / K)^{2/3}`.
    pub fn static_overlap(&self, force: f64, share: f64) -> f64 {
        let k = self.normal_stiffness * share;
        match self.model {
            SoftModel::Linear => force / k,
            SoftModel::Hertz => (force / k).powf(2.0 / 3.0),
        }
    }

    /// Duration (s) of a central impact of reduced mass `m_star` (kg) at approach
    /// speed `v` (m/s) on a point with the whole stiffness: `π/ω` of the damped
    /// linear oscillator (independent of `v`); for `hertz` the elastic duration
    /// [`crate::md::law::hertz_contact_time`] with `R* = 1 m`, `E* = 3K/4`.
    pub fn contact_time(&self, m_star: f64, v: f64) -> f64 {
        self.point_law(1.0).contact_time(m_star, 1.0, v)
    }
}
