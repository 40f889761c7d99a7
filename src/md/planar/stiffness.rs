//! Stiffness and time step of a planar MD scene from what the scene is: the
//! load its grains carry and their sizes and masses (the `[soft]` table's
//! `max_overlap_ratio` and `dt = "auto"`, `docs/scene-format.md`).
//!
//! **Reference load.** The largest static load of the scene is the weight of its
//! mobile bodies plus the peak of their loads along gravity (the sleeper's
//! `A + |B|`), carried by the bottom layer; spread over the `n` columns of
//! grains that fit across the sample (`n = round(W / d)`, `W` the sample's width
//! across gravity, `d` the median diameter of the mobile bodies' equal-area
//! discs), one base contact carries `F_ref = (W_tot + L_peak) / n`. This is the
//! mean force of a base contact; force chains carry a few times more, so the
//! largest overlap of a run exceeds the target (the run reports both).
//!
//! **Stiffness from an overlap ratio.** A face resting flat has the pair's
//! stiffness ([`super::law`]), so the overlap under `F_ref` is
//! `δ = ρ r_min` (`ρ` the ratio, `r_min` the smallest inradius of the mobile
//! bodies) for `k_n = F_ref / δ` (linear) or `K = F_ref / δ^{3/2}` (Hertz-like).
//!
//! **Time step.** The stiffest oscillator of the scene is a point with the
//! whole stiffness `k` between the two lightest bodies, each with its effective
//! mass at a corner `m_e = 1 / (1/m + R²/I)` (`R` the bounding radius, `I` the
//! polar inertia): `ω = √(k / m*)`, `m* = m_e / 2`, `k` the tangent stiffness at
//! the reference overlap for `hertz`. Its contact time is `t_c = π / ω`; velocity
//! Verlet is stable below `h_max = (2/ω)(√(1 + α²) − α)` with the dashpot's
//! ratio `α`. `dt = "auto"` takes `h = fraction × t_c` (default 1/50).

use super::law::SoftModel;
use crate::plane::Bodies;

/// The default fraction of the contact time `dt = "auto"` takes.
pub const DEFAULT_DT_FRACTION: f64 = 0.02;

/// What the scene's bodies give the stiffness and the time step (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    /// `F_ref` (N): the mean force of a base contact under the peak load.
    pub load: f64,
    /// Columns of grains across the sample.
    pub columns: usize,
    /// Smallest inradius of the mobile bodies (m).
    pub inradius: f64,
    /// Reduced mass `m*` of the stiffest oscillator (kg).
    pub reduced_mass: f64,
}

/// The reference of the mobile bodies of `bodies` under `gravity` (m/s²); `None`
/// if no body moves.
pub fn reference(bodies: &Bodies, gravity: [f64; 2]) -> Option<Reference> {
    let mobile: Vec<usize> = (0..bodies.len()).filter(|&i| !bodies.info[i].fixed).collect();
    if mobile.is_empty() {
        return None;
    }
    let gn = gravity[0].hypot(gravity[1]);
    let down = if gn > 0.0 { [gravity[0] / gn, gravity[1] / gn] } else { [0.0, -1.0] };
    let across = [-down[1], down[0]];
    let mut load = 0.0;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut diameters = Vec::with_capacity(mobile.len());
    let (mut inradius, mut reduced) = (f64::INFINITY, f64::INFINITY);
    for &i in &mobile {
        let info = &bodies.info[i];
        load += info.mass * gn;
        for l in &info.loads {
            let along = l.direction[0] * down[0] + l.direction[1] * down[1];
            let f = &l.force;
            let peak = [f.mean + f.amplitude.abs(), f.mean - f.amplitude.abs()]
                .into_iter()
                .map(|v| along * v)
                .fold(0.0, f64::max);
            load += peak;
        }
        let q = bodies.q[i];
        let r = info.shape.bounding_radius();
        let s = q[0] * across[0] + q[1] * across[1];
        lo = lo.min(s - r);
        hi = hi.max(s + r);
        diameters.push(2.0 * (info.shape.area_and_polar_moment().0 / std::f64::consts::PI).sqrt());
        inradius = inradius.min(info.shape.inner_radius());
        let effective = 1.0 / (1.0 / info.mass + r * r / info.inertia);
        reduced = reduced.min(0.5 * effective);
    }
    diameters.sort_by(f64::total_cmp);
    let d = diameters[diameters.len() / 2];
    let columns = ((hi - lo) / d).round().max(1.0) as usize;
    Some(Reference { load: load / columns as f64, columns, inradius, reduced_mass: reduced })
}

/// The pair stiffness (N/m for `linear`, N/m^{3/2} for `hertz`, thickness
/// included) for which a flat face under `F_ref` overlaps by `ratio × r_min`.
pub fn stiffness_for_overlap(model: SoftModel, r: &Reference, ratio: f64) -> f64 {
    let delta = ratio * r.inradius;
    match model {
        SoftModel::Linear => r.load / delta,
        SoftModel::Hertz => r.load / delta.powf(1.5),
    }
}

/// The contact time `t_c = π/ω` (s) and the stability limit `h_max` (s) of
/// velocity Verlet for the pair stiffness `stiffness` and the dashpot ratio
/// `alpha` (module doc).
pub fn time_scales(model: SoftModel, stiffness: f64, alpha: f64, r: &Reference) -> (f64, f64) {
    let k = match model {
        SoftModel::Linear => stiffness,
        SoftModel::Hertz => {
            let delta = (r.load / stiffness).powf(2.0 / 3.0);
            1.5 * stiffness * delta.sqrt()
        }
    };
    let omega = (k / r.reduced_mass).sqrt();
    (std::f64::consts::PI / omega, 2.0 / omega * ((1.0 + alpha * alpha).sqrt() - alpha))
}
