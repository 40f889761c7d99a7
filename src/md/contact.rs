//! The force of one contact: kinematics (David et al. eq. 2) and the two laws.
//!
//! The normal `n` points from the second body to the first; `δ > 0` is the
//! overlap; `v_rel` is the relative velocity of the contact surfaces (first minus
//! second), `v_n = v_rel · n` (negative when approaching), `v_t = v_rel − v_n n`.
//! The returned force acts on the first body; the second gets its opposite.
//!
//! Per-contact memory ([`History`]) holds, for `hertz`, the elastic tangential
//! force (N), built incrementally `F_t ← F_t − k_t(δ) v_t Δt` from the relative
//! tangential velocity since contact start (Karrech et al. eq. 6 in rate form), and
//! scaled by `k_t(δ_new)/k_t(δ_old) = √(δ_new/δ_old)` whenever the overlap (hence the
//! normal force) decreases: the fix against fictive energy at the end of §2.2 (the
//! tangential force is set back to its value when the normal force was this low).
//! For `linear` it holds the tangential spring `ξ` (m) and the stick/slip state.
//! In both, the memory is projected into the current tangent plane each step.

use super::law::{Damping, Model, PairLaw};
use super::particles::V3;
use serde::{Deserialize, Serialize};

/// Memory of one contact (zero when the pair is not touching).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct History {
    /// `hertz`: elastic tangential force (N); `linear`: tangential spring ξ (m).
    pub t: V3,
    /// Overlap at the previous evaluation (m); 0 when not touching.
    pub delta: f64,
    /// `linear`: 1 while sliding (dynamic friction), 0 while sticking.
    pub sliding: u32,
    /// The whole contact force on the first body at the last evaluation (N),
    /// normal and tangential, dashpots included: what the step applied, kept for
    /// the contact list ([`crate::md::MdSystem::contact_forces`]); zero when not
    /// touching. Not read by the dynamics.
    #[serde(default)]
    pub force: V3,
}

impl History {
    /// True if the pair was touching at the last evaluation.
    #[inline(always)]
    pub fn touching(&self) -> bool {
        self.delta > 0.0
    }
}

/// Geometry and kinematics of one contact.
pub struct Kinematics {
    /// Unit normal, from the second body to the first.
    pub n: V3,
    /// Overlap (m), > 0.
    pub delta: f64,
    /// Relative velocity of the contact surfaces, first minus second (m/s).
    pub v_rel: V3,
    /// Effective radius `R*` (m).
    pub r_star: f64,
    /// Reduced mass `m*` (kg).
    pub m_star: f64,
    /// Compute the elastic energy (skipped on steps that are not measured).
    pub measure: bool,
}

/// Normal and tangential force on the first body (N), and the scalar normal force.
pub struct ContactForce {
    /// Total contact force on the first body (N).
    pub force: V3,
    /// Tangential part of `force` (N), for the torques.
    pub tangential: V3,
    /// Normal force `f_n` (N); may be slightly negative for `linear` (dashpot).
    pub normal: f64,
    /// Elastic energy stored in the contact (J).
    pub energy: f64,
}

/// Evaluates the law for one contact, updating its history over a step `dt` (s).
#[inline(always)]
pub fn force(law: &PairLaw, k: &Kinematics, h: &mut History, dt: f64) -> ContactForce {
    match law.model {
        Model::Hertz => hertz(law, k, h, dt),
        Model::Linear => linear(law, k, h, dt),
    }
}

#[inline(always)]
fn hertz(law: &PairLaw, k: &Kinematics, h: &mut History, dt: f64) -> ContactForce {
    let n = k.n;
    // 1/√(R* δ_old), from the memory alone, so that it is computed while the
    // current overlap is (off the step's chain of dependent square roots).
    let inv_sq_old = if h.delta > 0.0 { 1.0 / (k.r_star * h.delta).sqrt() } else { 0.0 };
    let vn = k.v_rel.dot(&n);
    let vt = k.v_rel - n * vn;
    let sq = (k.r_star * k.delta).sqrt();
    let kn = 2.0 * law.e_star * sq;
    let fn_el = (2.0 / 3.0) * kn * k.delta;
    let kt = 8.0 * law.g_star * sq;
    // γ = 2α√(m* k): one square root for both directions when both are ratios.
    let (gn, gt) = match (law.damping_n, law.damping_t) {
        (Damping::Ratio(an), Damping::Ratio(at)) => {
            let s = (k.m_star * kn).sqrt();
            (2.0 * an * s, 2.0 * at * s * law.kt_kn_sqrt)
        }
        (dn, dt_) => (dn.gamma(k.m_star, kn), dt_.gamma(k.m_star, kt)),
    };
    let fn_ = (fn_el - gn * vn).max(0.0);
    // Memory into the current tangent plane.
    let mut ft = h.t - n * n.dot(&h.t);
    if h.delta > 0.0 && k.delta < h.delta {
        // Unloading: back to the tangential force of this normal force (Karrech §2.2).
        // k_t(δ)/k_t(δ_old) = √(δ/δ_old) = √(R* δ) / √(R* δ_old).
        ft *= sq * inv_sq_old;
    }
    ft -= vt * (kt * dt);
    let limit = law.mu_s * fn_;
    let norm2 = ft.norm_squared();
    if norm2 > limit * limit {
        ft *= limit / norm2.sqrt();
    }
    h.t = ft;
    h.delta = k.delta;
    // Coulomb bounds the whole tangential force, dashpot included (as in David et
    // al. eqs. 3–4): Karrech's eq. 7 read literally adds `−γ_t v_t` beyond `μ F_n`
    // while sliding, and a sliding contact would then resist as a viscous one
    // (no sliding at `g(sin α − μ cos α)` down an incline).
    let mut tangential = ft - vt * gt;
    let t2 = tangential.norm_squared();
    if t2 > limit * limit {
        tangential *= limit / t2.sqrt();
    }
    let energy = if k.measure && kt > 0.0 { 0.4 * fn_el * k.delta + 0.5 * ft.norm_squared() / kt } else { 0.0 };
    ContactForce { force: n * fn_ + tangential, tangential, normal: fn_, energy }
}

#[inline(always)]
fn linear(law: &PairLaw, k: &Kinematics, h: &mut History, dt: f64) -> ContactForce {
    let n = k.n;
    let vn = k.v_rel.dot(&n);
    let vt = k.v_rel - n * vn;
    // δ̇ = −v_n: the dashpot resists approach and separation alike (eq. 1).
    let fn_ = law.kn * k.delta - law.damping_n.gamma(k.m_star, law.kn) * vn;
    let gt = law.damping_t.gamma(k.m_star, law.kt);
    let xi = h.t - n * n.dot(&h.t);
    let f0 = -xi * law.kt - vt * gt;
    let f0n = f0.norm();
    let fpos = fn_.max(0.0);
    let mut sliding = h.sliding != 0;
    if sliding {
        if f0n <= law.mu_d * fpos {
            sliding = false;
        }
    } else if f0n > law.mu_s * fpos {
        sliding = true;
    }
    let tangential = if !sliding {
        h.t = xi + vt * dt;
        f0
    } else {
        let t_hat = if f0n > 0.0 { f0 / f0n } else { V3::zeros() };
        let ft = t_hat * (law.mu_d * fpos);
        // Eq. 4: the spring length consistent with Coulomb's condition.
        h.t = -(ft + vt * gt) / law.kt;
        ft
    };
    h.sliding = sliding as u32;
    h.delta = k.delta;
    let energy = if k.measure { 0.5 * law.kn * k.delta * k.delta + 0.5 * law.kt * h.t.norm_squared() } else { 0.0 };
    ContactForce { force: n * fn_ + tangential, tangential, normal: fn_, energy }
}
