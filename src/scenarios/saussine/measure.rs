//! What `sample.json` records about a deposited Saussine sample ([`measure_sample`]): its grains, layer
//! height, solid fraction and coordination (Saussine et al. 2006, §3).

use super::*;
use crate::scene::SceneFile;

/// What `sample.json` records about a deposited sample.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SampleReport {
    /// Seed of the sample scene.
    pub seed: u64,
    /// Number of grains (bodies named `g…`).
    pub grains: usize,
    /// Total weight `Σ m |g|` of the non-fixed bodies (N), from the vertical
    /// balance of the last of 20 steps at rest.
    pub weight_n: f64,
    /// Upward force of the world-anchored sublayer springs on the pads (N).
    pub sublayer_reaction_n: f64,
    /// Upward force of the fixed bodies through contacts whose normal is
    /// closer to vertical than to horizontal (floors; N).
    pub floor_reaction_n: f64,
    /// Upward force of the fixed bodies through the other contacts (side walls, by friction; N).
    pub wall_friction_n: f64,
    /// (springs + floors + walls − weight) / weight.
    pub balance_error: f64,
    /// Mean overlap over the active contacts at the last of the 20 steps (m).
    pub mean_overlap_m: f64,
    /// Largest overlap at the last of the 20 steps (m).
    pub max_overlap_m: f64,
    /// Window of the solid fraction (m): `[x0, x1, y0, y1]`, the middle half of
    /// the layer's width, from one largest grain size above the pads' top (`y = 0`)
    /// to one below the lowest surface point of that middle half.
    pub window_m: [f64; 4],
    /// Solid fraction of the grains in `window_m` (dimensionless); NaN if the window is empty.
    pub solid_fraction: f64,
    /// Mean number of force-carrying neighbours of the non-rattler grains.
    pub coordination: f64,
    /// Fraction of the grains with fewer than 2 force-carrying neighbours (dimensionless).
    pub rattler_fraction: f64,
    /// Mean height of the layer's top surface above the sublayer (m).
    pub thickness_m: f64,
}

/// Measures a deposited sample: 20 steps at rest, then balance, overlaps,
/// solid fraction in a window away from the walls, floor and surface, coordination.
pub fn measure_sample(scene: &Scene) -> Result<SampleReport> {
    let mut sys = scene.build()?;
    let mut st = sys.step()?;
    for _ in 1..20 {
        st = sys.step()?;
    }
    let grains: Vec<usize> =
        scene.bodies.iter().enumerate().filter(|(_, b)| b.name.starts_with(GRAIN_PREFIX)).map(|(i, _)| i).collect();
    let polys: Vec<Vec<[f64; 2]>> = grains.iter().map(|&i| crate::nscd::measure::world_polygon(&sys, i)).collect();
    let (mut x0, mut x1, mut d) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for p in &polys {
        for v in p {
            x0 = x0.min(v[0]);
            x1 = x1.max(v[0]);
        }
        let (lo, hi) = p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v[1]), h.max(v[1])));
        d = d.max(hi - lo);
    }
    // Top surface: highest vertex in bins one largest grain wide; thickness = mean.
    let bins = (((x1 - x0) / d).floor() as usize).max(1);
    let mut surf = vec![f64::NEG_INFINITY; bins];
    for p in &polys {
        for v in p {
            let k = (((v[0] - x0) / d) as usize).min(bins - 1);
            surf[k] = surf[k].max(v[1]);
        }
    }
    // Only the middle half of the bins: the banks (if any) are lower.
    let mid = &surf[bins / 4..bins - bins / 4];
    let thickness = mid.iter().sum::<f64>() / mid.len() as f64;
    let low = mid.iter().copied().fold(f64::INFINITY, f64::min);
    let window = [-0.25 * (x1 - x0) + 0.5 * (x0 + x1), 0.25 * (x1 - x0) + 0.5 * (x0 + x1), d, low - d];
    let phi =
        if window[3] > window[2] { crate::nscd::measure::solid_fraction(&sys, &grains, window) } else { f64::NAN };
    let z = crate::nscd::measure::coordination(&sys, &grains, 0.0);
    let b = crate::nscd::measure::vertical_balance(&sys);
    Ok(SampleReport {
        seed: scene.seed(),
        grains: grains.len(),
        weight_n: b.weight,
        sublayer_reaction_n: b.springs,
        floor_reaction_n: b.floors,
        wall_friction_n: b.walls,
        balance_error: b.residual() / b.weight,
        mean_overlap_m: st.mean_overlap,
        max_overlap_m: st.max_overlap,
        window_m: window,
        solid_fraction: phi,
        coordination: z.z,
        rattler_fraction: z.rattlers,
        thickness_m: thickness,
    })
}
