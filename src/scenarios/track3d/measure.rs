//! What `sample.json` records about a deposited 3D track section ([`measure_sample`]): its grains, the layer's
//! height, solid fraction and coordination, and the vertical balance of the weight on the sublayer (Saussine et
//! al. 2006 §3, the 2D sample's measures in 3D).
//!
//! Definitions:
//! - **Measured over 20 steps from the saved state** (as the 2D sample): the scene is built from `sample.toml`,
//!   stepped 20 times, and the forces are the steps' own impulses divided by `h`, averaged over the 20 steps, so
//!   the balance is the momentum balance of those steps: `(Σ reactions − weight) × 20 h` = the change of the
//!   bodies' vertical momentum, which is small at rest.
//! - **Weight**: `Σ m |g|` over the mobile bodies (grains and pads); **sublayer reaction**: the springs' impulses
//!   along their axes, vertical component; **wall reaction**: the vertical component of the contact impulses
//!   from the fixed walls (zero for smooth vertical walls, reported as a check).
//! - **Surface**: the box divided into bins about as wide as the largest grain's bounding sphere (a whole number
//!   per side, at least one), the highest grain vertex in each bin; the surface height is their mean. **Pad
//!   top**: the mean height of the pads' top faces. **Layer height** `H` = surface − pad top.
//! - **Solid fraction**: `Σ V_grain / (L W H)`, the grains' volume over the box's inner area times the layer
//!   height (the whole layer: its wall and surface voids lower it by a few per cent against a window inside).
//! - **Coordination** ([`crate::nscd::d3::measure::coordination`]): the mean number of bodies (grains, pads,
//!   walls) pressing on each grain that has at least two, over the last step's contacts; the rattlers' fraction.

use super::*;
use crate::nscd::d3::measure as m3;
use crate::nscd::d3::system::System3;

/// What `sample.json` records about a deposited section (module doc).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SampleReport {
    /// Seed of the sample scene.
    pub seed: u64,
    /// Number of grains (bodies named `g…`).
    pub grains: usize,
    /// Number of sublayer pads.
    pub pads: usize,
    /// Inner size of the box `[length along x, width along y]` (m).
    pub box_m: [f64; 2],
    /// Total volume of the grains (m³).
    pub grain_volume_m3: f64,
    /// Weight of the grains `Σ m |g|` (N).
    pub grain_weight_n: f64,
    /// Weight of the mobile bodies, grains and pads (N).
    pub weight_n: f64,
    /// Upward force of the sublayer springs on the pads, mean over the 20 steps (N).
    pub sublayer_reaction_n: f64,
    /// Upward force of the walls through their contacts, mean over the 20 steps (N).
    pub wall_reaction_n: f64,
    /// (sublayer + walls − weight) / weight.
    pub balance_error: f64,
    /// Kinetic energy of the mobile bodies after the 20 steps (J).
    pub kinetic_energy_j: f64,
    /// Mean overlap over the active contacts at the last step (m).
    pub mean_overlap_m: f64,
    /// Largest overlap at the last step (m).
    pub max_overlap_m: f64,
    /// Mean height of the pads' top faces (m).
    pub pad_top_m: f64,
    /// Mean height of the layer's top surface (m).
    pub surface_m: f64,
    /// Layer height: surface − pad top (m).
    pub layer_height_m: f64,
    /// Lowest grain vertex (m).
    pub lowest_grain_m: f64,
    /// Solid fraction `Σ V / (L W H)` (dimensionless).
    pub solid_fraction: f64,
    /// Mean number of force-carrying neighbours of the grains with at least two.
    pub coordination: f64,
    /// Fraction of the grains with fewer than two force-carrying neighbours.
    pub rattler_fraction: f64,
}

/// Steps made from the saved state before measuring (module doc).
pub const MEASURE_STEPS: usize = 20;

/// The world positions of the vertices of body `i` (a polyhedron; the centroid for another shape).
pub(crate) fn world_vertices(sys: &System3, i: usize) -> Vec<Vec3> {
    let pose = &sys.bodies.pose[i];
    match &sys.bodies.info[i].solid {
        crate::geometry::Solid::Polyhedron(p) => p.vertices.iter().map(|v| pose.point(v)).collect(),
        _ => vec![pose.position],
    }
}

/// The lowest and highest coordinates of `points`.
pub(crate) fn extent(points: &[Vec3]) -> (Vec3, Vec3) {
    points
        .iter()
        .fold((Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.inf(p), hi.sup(p)))
}

/// The indices of the bodies of `scene` whose names start with `prefix` followed by a digit.
pub(crate) fn named(scene: &Scene3, prefix: &str) -> Vec<usize> {
    let is = |name: &str| name.strip_prefix(prefix).is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()));
    scene.bodies.iter().enumerate().filter(|(_, b)| is(&b.name)).map(|(i, _)| i).collect()
}

/// Measures a deposited section (module doc).
///
/// # Errors
/// [`crate::Error::Scene`] for a scene without grains, walls or pads of this generator, or one that does not
/// build; a step that diverges.
pub fn measure_sample(scene: &Scene3) -> Result<SampleReport> {
    let mut sys = scene.build()?;
    let grains = named(scene, GRAIN_PREFIX);
    let pads = named(scene, PAD_PREFIX);
    if grains.is_empty() || pads.is_empty() {
        return refuse("sample: no grains or no pads (not a sample of scenarios::track3d::sample_scene)".into());
    }
    let at = |name: &str, k: usize| scene.bodies.iter().find(|b| b.name == name).map(|b| b.position[k]);
    let (Some(x0), Some(x1), Some(y0), Some(y1)) = (at(WALLS[0], 0), at(WALLS[1], 0), at(WALLS[2], 1), at(WALLS[3], 1))
    else {
        return refuse("sample: its walls are missing (not a sample of scenarios::track3d::sample_scene)".into());
    };
    let up = m3::up(&sys.params.gravity);
    let g = sys.params.gravity.norm();
    let h = sys.params.dt;
    let (mut springs, mut walls) = (0.0, 0.0);
    let mut last = None;
    for _ in 0..MEASURE_STEPS {
        last = Some(sys.step()?);
        springs += sys.springs.iter().map(|s| s.impulse * s.state(&sys.bodies.pose).axis.dot(&up)).sum::<f64>() / h;
        for c in sys.contact_forces() {
            let (a, b) = (c.candidate as usize, c.antagonist as usize);
            let (fa, fb) = (sys.bodies.info[a].fixed, sys.bodies.info[b].fixed);
            if fb && !fa {
                walls += c.force.dot(&up);
            } else if fa && !fb {
                walls -= c.force.dot(&up);
            }
        }
    }
    let n = MEASURE_STEPS as f64;
    let (springs, walls) = (springs / n, walls / n);
    let st = last.unwrap_or_default();
    let info = &sys.bodies.info;
    let grain_weight: f64 = grains.iter().map(|&i| info[i].mass * g).sum();
    let weight: f64 = m3::mobile_bodies(&sys).iter().map(|&i| info[i].mass * g).sum();
    let volume: f64 = grains.iter().map(|&i| info[i].solid.mass_properties().0).sum();

    // Surface: the highest vertex per bin, the bins about one largest bounding diameter wide.
    let (length, width) = (x1 - x0, y1 - y0);
    let d = grains.iter().map(|&i| 2.0 * info[i].solid.radius()).fold(0.0, f64::max);
    let bin = |size: f64| ((size / d.max(1e-9)).floor() as usize).max(1);
    let (bx, by) = (bin(length), bin(width));
    let mut surface = vec![f64::NEG_INFINITY; bx * by];
    let mut lowest = f64::INFINITY;
    for &i in &grains {
        for p in world_vertices(&sys, i) {
            let kx = (((p.x - x0) / length * bx as f64).floor().max(0.0) as usize).min(bx - 1);
            let ky = (((p.y - y0) / width * by as f64).floor().max(0.0) as usize).min(by - 1);
            let z = p.dot(&up);
            surface[ky * bx + kx] = surface[ky * bx + kx].max(z);
            lowest = lowest.min(z);
        }
    }
    let filled: Vec<f64> = surface.into_iter().filter(|z| z.is_finite()).collect();
    let surface = filled.iter().sum::<f64>() / filled.len().max(1) as f64;
    let pad_top = pads
        .iter()
        .map(|&i| world_vertices(&sys, i).iter().map(|p| p.dot(&up)).fold(f64::NEG_INFINITY, f64::max))
        .sum::<f64>()
        / pads.len() as f64;
    let height = surface - pad_top;
    let z = m3::coordination(&sys, &grains, 0.0);
    Ok(SampleReport {
        seed: scene.seed(),
        grains: grains.len(),
        pads: pads.len(),
        box_m: [length, width],
        grain_volume_m3: volume,
        grain_weight_n: grain_weight,
        weight_n: weight,
        sublayer_reaction_n: springs,
        wall_reaction_n: walls,
        balance_error: (springs + walls - weight) / weight,
        kinetic_energy_j: sys.bodies.kinetic_energy(),
        mean_overlap_m: st.mean_overlap,
        max_overlap_m: st.max_overlap,
        pad_top_m: pad_top,
        surface_m: surface,
        layer_height_m: height,
        lowest_grain_m: lowest,
        solid_fraction: volume / (length * width * height),
        coordination: z.z,
        rattler_fraction: z.rattlers,
    })
}
