//! A 3D track section (issue "3D NSCD", item "A 3D track section"): the Saussine et al. (2006) test of §3–4 —
//! a ballast layer deposited under gravity on a viscoelastic sublayer (§2.9, law (17)), then a rigid sleeper
//! loaded by `F = A + B cos(2π f t − φ)` (§3.1) — with 3D polyhedral grains on the 3D NSCD engine
//! ([`crate::nscd::d3`]). The 2D twin is [`super::saussine`]; the stages are plain [`Scene3`] values, validated
//! like a scene file and saved with `to_toml_string`, so every stage reruns with `ballast run`:
//! 1. [`sample_scene`]: loose grains above the sublayer in a box of four smooth half-space walls, to deposit to
//!    equilibrium (`[simulation] equilibrium`);
//! 2. [`loaded_scene`]: the deposited sample with the sleeper placed on the highest grain under it, guided
//!    along z, under the harmonic load, `[output] cycles` following it;
//! 3. [`reloaded_scene`]: a loaded scene (a run's `final_scene.toml`) run on for more cycles under another
//!    stopping rule, the start of a study from a seated state.
//!
//! The files: `mod.rs` the sample, `loading.rs` the sleeper and its load, `reload.rs` the loaded scene run on,
//! `measure.rs` what `sample.json` records.
//!
//! Decisions, written down (every default with its unit; `docs/track3d.md` has the same table):
//! - **Axes.** `z` is up (gravity `(0, 0, −9.81)`), `x` along the track, `y` across it. The box is centred on
//!   `x = y = 0`; the pads' top faces are at `z = 0` at the start.
//! - **Section** ([`SampleSpec::track`]): 2 000 grains in a box 0.6 m along the track (one sleeper spacing) by
//!   0.4 m across (a slice of the sleeper's length under a rail seat). With the grains' mean hull volume
//!   (1.17e-5 m³) this is a layer of about 0.2 m (0.21 m at the whole-layer solid fraction of 0.46 measured on
//!   the 200-grain section). [`SampleSpec::scaled`] keeps the layer's thickness for `n` grains: the box's area
//!   scaled by `n / 2000` at the same aspect ratio, each side at least [`SampleSpec::min_side`] (one longest
//!   grain and its clearance).
//! - **Grains**: [`super::grains3d`] with its defaults — hulls of 12–30 points on random ellipsoids, sieve sizes
//!   25–50 mm uniform by mass, elongation ≤ 1.5, flatness ≥ 0.6 —, seeded by [`SampleSpec::seed`]; density
//!   2700 kg/m³ (granite; the 2D paper's 2367 kg/m³ is its cement prisms), friction μ = 0.5 with each other,
//!   the pads and the sleeper (the paper's), restitution 0 (the paper's, "dense granular packing").
//! - **Loose start**: the grains, in the drawn (random) order and each turned by a uniformly random rotation,
//!   are laid in rows along `x`, rows side by side along `y`, layers up `z`, each by the axis-aligned box of its
//!   turned hull, the boxes [`CLEARANCE`] apart and from the walls (the 2D generator's rows in 3D, tighter than a
//!   lattice of the largest grain's bounding sphere). They start at rest. The default section's loose column
//!   stands 0.93 m high (seed 1), about five times the deposited layer: its top grains land at about 4 m/s.
//! - **Walls**: four fixed half-spaces through the box's sides, frictionless ("frame", μ = 0 with everything):
//!   the sublayer alone carries the weight (no Janssen share on the walls, as the 2D sample's smooth side walls;
//!   the test checks the balance), and the walls stand for the rest of the track, not for a rough mould.
//! - **Sublayer** (§2.9): a grid of pads of side ≈ [`SampleSpec::pad_size`] = 50 mm (the largest sieve size,
//!   as the 2D pads were the largest grain's diameter: each grain rests on one to four pads), 10 mm high, 1 mm
//!   apart and from the walls, widened so that a whole number fills the box; elastomer 1100 kg/m³; each guided
//!   (`imposed = { vx = 0, vy = 0, spin = [0, 0, 0] }`, free along `z`: a pad on a compressed vertical spring is
//!   laterally unstable) on **one** compression-only spring of law (17) from the middle of its lower face to a
//!   world anchor `L0` = 10 mm below it. **The stiffness and damping per unit area are the 2D paper's pads'**:
//!   there a 20 mm pad per 1 m of depth (0.02 m²) carries `k_N` = 4100 N per unit strain and `ν` = 80 N·s on
//!   a spring of rest length 10 mm, i.e. `k = k_N / L0 / area` = 2.05e7 N/m³ (Pa per metre of compression) and
//!   `c = ν / L0 / area` = 4.0e5 N·s/m³. A 3D pad of top area `a` gets `k_N = k a L0` and `ν = c a L0`. Under
//!   the default layer (≈ 2.6 kPa) the pads sink ≈ 0.13 mm (1.3 % strain).
//! - **Deposit**: dt = 2e-4 s (the 2D sample's), **θ = 1** ([`SampleSpec::theta`]), `quad` **1e-3** with at
//!   most 2 000 sweeps ([`SampleSpec::tolerance`], [`SampleSpec::max_iterations`]), alert distance 1 mm. On the
//!   200-grain section `quad` 1e-4 made 256 sweeps per step with 194 steps at the cap for the same layer as 1e-3
//!   (50 sweeps, none at the cap). θ = 1 is numerically dissipative and θ = 1/2 is not: on seeds 1–3 of the
//!   200-grain section θ = 1 reached rest in 1.26–1.49 s every time, where θ = 1/2 hovered above the threshold
//!   until the 3 s cap once, and it left the largest overlap 1.4–2× smaller (0.24–0.64 against 0.48–1.06 mm),
//!   for the same layer (solid fraction within 0.012). The loaded runs keep the paper's θ = 1/2
//!   ([`LoadingSpec::theta`]; docs/track3d.md, "The deposit's θ"). The deposit's end state is what counts,
//!   and the equilibrium stop guarantees it is at rest: it ends when the kinetic energy of the mobile bodies
//!   has stayed below [`SampleSpec::rest_energy`] = 1e-10 J per grain (an
//!   rms speed of 8e-5 m/s for the mean grain, 32 g) for [`SampleSpec::rest_steps`] = 500 steps (0.1 s), or
//!   after [`SampleSpec::max_duration`] = 3 s.

mod loading;
mod measure;
mod reload;

pub use loading::{loaded_scene, LoadingSpec, SLEEPER_GAP};
pub use measure::{measure_sample, SampleReport};
pub use reload::{is_loaded, reloaded_scene};

use super::grains3d::{grains, GrainSpec};
use super::{non_negative, positive, refuse, theta};
use crate::error::Result;
use crate::geometry::Vec3;
use crate::nscd::Policy;
use crate::run::Equilibrium;
use crate::scene::d3::{BodySpec3, BoxSpec, ImposedSpec3, OrientationSpec, PlaneSpec, PolyhedronSpec, SpringSpec3};
use crate::scene::{ContactEntry, Drive, Material, NscdSection, OutputSection, Scene3, SceneFile, Simulation};
use nalgebra::UnitQuaternion;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The followed body of the loaded stage.
pub const SLEEPER: &str = "sleeper";
/// Prefix of the sublayer pads' names (`pad0`, `pad1`, …).
pub const PAD_PREFIX: &str = "pad";
/// Prefix of the grains' names (`g0`, `g1`, …).
pub const GRAIN_PREFIX: &str = "g";
/// The walls' names: the planes `x = −L/2`, `x = +L/2`, `y = −W/2`, `y = +W/2`.
pub const WALLS: [&str; 4] = ["wall_x0", "wall_x1", "wall_y0", "wall_y1"];
/// Materials: grains, pads, walls.
pub const BALLAST: &str = "ballast";
/// The pads' material.
pub const ELASTOMER: &str = "elastomer";
/// The walls' material.
pub const FRAME: &str = "frame";
/// Gap (m) between the grains' turned boxes at the start, and between them and the walls.
pub const CLEARANCE: f64 = 0.002;

/// Mixed into the seed of the grains' orientations, so that they are not drawn from the grains' own stream
/// ("track3d" in ASCII).
const ORIENTATIONS: u64 = 0x0074_7261_636b_3364;

/// Sublayer stiffness per unit area (N/m³) carried over from the 2D paper's pads: `4100 / 0.01 / (0.02 × 1)`.
pub const STIFFNESS_PER_AREA: f64 = 4100.0 / 0.01 / 0.02;
/// Sublayer damping per unit area (N·s/m³) carried over from the 2D paper's pads: `80 / 0.01 / (0.02 × 1)`.
pub const DAMPING_PER_AREA: f64 = 80.0 / 0.01 / 0.02;
/// Grains of the full section ([`SampleSpec::track`]).
pub const TRACK_GRAINS: usize = 2000;

/// The sample of stage 1 (module doc for the defaults and why).
#[derive(Debug, Clone, PartialEq)]
pub struct SampleSpec {
    /// Number of grains.
    pub grains: usize,
    /// The grains' shapes and grading; its `seed` is replaced by [`Self::seed`].
    pub grain: GrainSpec,
    /// Inner size of the box along the track, `x` (m).
    pub length: f64,
    /// Inner size of the box across the track, `y` (m).
    pub width: f64,
    /// Side of a sublayer pad as asked (m); the pads are widened so that a whole number fills the box.
    pub pad_size: f64,
    /// Height of a pad (m).
    pub pad_height: f64,
    /// Gap between pads, and between the outer pads and the walls (m).
    pub pad_gap: f64,
    /// Rest length `L0` of the pads' springs (m).
    pub spring_length: f64,
    /// Sublayer stiffness per unit area (N/m³): a pad of top area `a` gets `k_N = k a L0`.
    pub stiffness_per_area: f64,
    /// Sublayer damping per unit area (N·s/m³): a pad of top area `a` gets `ν = c a L0`.
    pub damping_per_area: f64,
    /// Grain density (kg/m³).
    pub density: f64,
    /// Density of the pads (kg/m³).
    pub pad_density: f64,
    /// Coulomb friction between grains and with the pads (the walls are smooth).
    pub friction: f64,
    /// Seed of the grains and their orientations; recorded in the scene.
    pub seed: u64,
    /// Time step of the deposit (s).
    pub dt: f64,
    /// Longest deposit (s).
    pub max_duration: f64,
    /// θ of the deposit's Moreau–Jean scheme, in [1/2, 1] (module doc, "Deposit": default 1).
    pub theta: f64,
    /// Tolerance of the deposit's NLGS (`quad` policy), in (0, 1).
    pub tolerance: f64,
    /// Most NLGS sweeps per step of the deposit (≥ 1).
    pub max_iterations: usize,
    /// Equilibrium: kinetic energy per grain (J) below which a step is calm.
    pub rest_energy: f64,
    /// Equilibrium: consecutive calm steps that end the deposit.
    pub rest_steps: u64,
}

impl SampleSpec {
    /// The full section: 2 000 grains in a 0.6 × 0.4 m box on the 2D paper's sublayer per unit area (module doc).
    pub fn track(seed: u64) -> Self {
        Self {
            grains: TRACK_GRAINS,
            grain: GrainSpec::default(),
            length: 0.6,
            width: 0.4,
            pad_size: 0.05,
            pad_height: 0.01,
            pad_gap: 0.001,
            spring_length: 0.01,
            stiffness_per_area: STIFFNESS_PER_AREA,
            damping_per_area: DAMPING_PER_AREA,
            density: 2700.0,
            pad_density: 1100.0,
            friction: 0.5,
            seed,
            dt: 2e-4,
            max_duration: 3.0,
            theta: 1.0,
            tolerance: 1e-3,
            max_iterations: 2000,
            rest_energy: 1e-10,
            rest_steps: 500,
        }
    }

    /// The same section for `n` grains with the layer's thickness kept: the box's area scaled by
    /// `n / grains`, the aspect ratio kept, each side at least [`Self::min_side`].
    pub fn scaled(mut self, n: usize) -> Self {
        let f = (n as f64 / self.grains.max(1) as f64).sqrt();
        let min = self.min_side();
        self.length = (self.length * f).max(min);
        self.width = (self.width * f).max(min);
        self.grains = n;
        self
    }

    /// The narrowest side (m) that holds any grain of the grading with its clearance: the longest axis a grain
    /// can have, `elongation_max × d_max`, and [`CLEARANCE`] on each side.
    pub fn min_side(&self) -> f64 {
        self.grain.elongation_max * self.grain.d_max + 2.0 * CLEARANCE
    }

    /// Checks every field; one-line errors led by the field's name.
    ///
    /// # Errors
    /// [`crate::Error::Scene`] naming the first field out of range.
    pub fn check(&self) -> Result<()> {
        if self.grains == 0 {
            return refuse("grains: must be at least 1, got 0".into());
        }
        GrainSpec { seed: self.seed, ..self.grain.clone() }.check()?;
        let min = self.min_side();
        for (key, v) in [("length", self.length), ("width", self.width)] {
            positive(&format!("{key}: the box's side (m)"), v)?;
            if v < min {
                return refuse(format!(
                    "{key}: a box side of {v} m cannot hold the longest grain of the grading (at least {min} m)"
                ));
            }
        }
        let pad = positive("pad_size: the pads' side (m)", self.pad_size)?;
        positive("pad_height: the pads' height (m)", self.pad_height)?;
        let gap = non_negative("pad_gap: the gap between pads (m)", self.pad_gap)?;
        if 2.0 * gap >= pad {
            return refuse(format!("pad_gap: {gap} m must be less than half the pad_size {pad} m"));
        }
        positive("spring_length: the pads' spring rest length (m)", self.spring_length)?;
        positive("stiffness_per_area: the sublayer's stiffness (N/m³)", self.stiffness_per_area)?;
        non_negative("damping_per_area: the sublayer's damping (N·s/m³)", self.damping_per_area)?;
        positive("density: the grains' density (kg/m³)", self.density)?;
        positive("pad_density: the pads' density (kg/m³)", self.pad_density)?;
        non_negative("friction: the grains' friction coefficient", self.friction)?;
        positive("dt: the deposit's time step (s)", self.dt)?;
        positive("max_duration: the longest deposit (s)", self.max_duration)?;
        theta("theta: the deposit's θ", self.theta)?;
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return refuse(format!("tolerance: must be in (0, 1), got {}", self.tolerance));
        }
        if self.max_iterations == 0 {
            return refuse("max_iterations: must be at least 1, got 0".into());
        }
        positive("rest_energy: the kinetic energy per grain at rest (J)", self.rest_energy)?;
        if self.rest_steps == 0 {
            return refuse("rest_steps: must be at least 1, got 0".into());
        }
        Ok(())
    }

    /// The pads along one side of `size` (m): their number and their side (m), widened to fill the side with
    /// [`Self::pad_gap`] between them and at the ends.
    pub fn pads_along(&self, size: f64) -> (usize, f64) {
        let n = ((size - self.pad_gap) / (self.pad_size + self.pad_gap)).floor().max(1.0) as usize;
        (n, (size - self.pad_gap * (n as f64 + 1.0)) / n as f64)
    }
}

impl Default for SampleSpec {
    /// The full section, seed 1.
    fn default() -> Self {
        Self::track(1)
    }
}

/// A body of `material` at `position` (m) with no shape yet and every optional key absent.
pub(crate) fn body3(name: impl Into<String>, material: &str, position: [f64; 3]) -> BodySpec3 {
    BodySpec3 {
        name: name.into(),
        material: material.into(),
        polyhedron: None,
        cuboid: None,
        sphere: None,
        plane: None,
        position,
        orientation: None,
        velocity: None,
        spin: None,
        fixed: None,
        imposed: None,
        load: None,
        torque: None,
    }
}

/// Guided along `z`: `vx = vy = 0`, spin zero.
pub(crate) fn guided() -> ImposedSpec3 {
    let zero = Drive::Constant(0.0);
    ImposedSpec3 { vx: Some(zero), vy: Some(zero), vz: None, spin: Some([zero; 3]) }
}

/// A contact law between two materials (restitution 0, the paper's).
pub(crate) fn law(a: &str, b: &str, friction: f64) -> ContactEntry {
    ContactEntry { between: [a.into(), b.into()], friction, restitution: None, tangential_restitution: None }
}

/// The stage-1 scene: loose grains above the sublayer in the box, to deposit to equilibrium; validated like a
/// scene file (module doc).
///
/// # Errors
/// [`crate::Error::Scene`] naming the field of `spec` out of range.
pub fn sample_scene(spec: &SampleSpec) -> Result<Scene3> {
    spec.check()?;
    let drawn = grains(&GrainSpec { seed: spec.seed, ..spec.grain.clone() }, spec.grains)?;
    let (hl, hw) = (spec.length / 2.0, spec.width / 2.0);
    let (ph, l0) = (spec.pad_height, spec.spring_length);

    // Walls: the half-spaces behind the box's four sides, normals into the box.
    let mut bodies = Vec::with_capacity(4 + spec.grains + 200);
    for (name, position, normal) in [
        (WALLS[0], [-hl, 0.0, 0.0], [1.0, 0.0, 0.0]),
        (WALLS[1], [hl, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        (WALLS[2], [0.0, -hw, 0.0], [0.0, 1.0, 0.0]),
        (WALLS[3], [0.0, hw, 0.0], [0.0, -1.0, 0.0]),
    ] {
        bodies.push(BodySpec3 { plane: Some(PlaneSpec { normal }), fixed: Some(true), ..body3(name, FRAME, position) });
    }

    // Sublayer: a grid of pads, top faces at z = 0, each on one spring from the middle of its lower face to an
    // anchor L0 below.
    let (nx, px) = spec.pads_along(spec.length);
    let (ny, py) = spec.pads_along(spec.width);
    let centre = |k: usize, side: f64, half: f64| -half + spec.pad_gap + side / 2.0 + k as f64 * (side + spec.pad_gap);
    let (k_n, nu) = (spec.stiffness_per_area * px * py * l0, spec.damping_per_area * px * py * l0);
    let mut springs = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let name = format!("{PAD_PREFIX}{}", j * nx + i);
            let (x, y) = (centre(i, px, hl), centre(j, py, hw));
            bodies.push(BodySpec3 {
                cuboid: Some(BoxSpec { half: [px / 2.0, py / 2.0, ph / 2.0] }),
                imposed: Some(guided()),
                ..body3(name.clone(), ELASTOMER, [x, y, -ph / 2.0])
            });
            springs.push(SpringSpec3 {
                body: name,
                point: Some([0.0, 0.0, -ph / 2.0]),
                anchor: Some([x, y, -ph - l0]),
                other: None,
                other_point: None,
                k_n,
                nu: Some(nu),
                rest_length: Some(l0),
                prestrain: None,
                compression_only: Some(true),
            });
        }
    }

    // Grains: each turned at random, laid by its turned hull's axis-aligned box in rows along x, rows side by
    // side along y, layers up z, the boxes CLEARANCE apart.
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed ^ ORIENTATIONS);
    let c = CLEARANCE;
    let (mut x, mut y, mut z) = (-hl + c, -hw + c, c);
    let (mut row_depth, mut layer_height) = (0.0f64, 0.0f64);
    for (k, g) in drawn.into_iter().enumerate() {
        let q: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(&mut rng));
        let turn = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
        let turned: Vec<Vec3> = g.shape.vertices.iter().map(|v| turn * v).collect();
        let (lo, hi) = measure::extent(&turned);
        let size = hi - lo;
        if x + size.x + c > hl {
            // The row is full: the next one beside it, or the next layer.
            x = -hl + c;
            y += row_depth + c;
            row_depth = 0.0;
        }
        if y + size.y + c > hw {
            y = -hw + c;
            z += layer_height + c;
            layer_height = 0.0;
        }
        let r = turn.quaternion();
        let s = if r.w < 0.0 { -1.0 } else { 1.0 };
        // The hull's centroid is its frame's origin: the box's lower corner goes to the cursor.
        let position = [x - lo.x, y - lo.y, z - lo.z];
        let vertices = g.shape.vertices.iter().map(|v: &Vec3| [v.x, v.y, v.z]).collect();
        bodies.push(BodySpec3 {
            polyhedron: Some(PolyhedronSpec { vertices, merge_angle: None }),
            orientation: Some(OrientationSpec {
                quaternion: Some([s * r.w, s * r.i, s * r.j, s * r.k]),
                rotation_vector: None,
            }),
            ..body3(format!("{GRAIN_PREFIX}{k}"), BALLAST, position)
        });
        x += size.x + c;
        row_depth = row_depth.max(size.y);
        layer_height = layer_height.max(size.z);
    }

    let scene = Scene3 {
        simulation: Simulation {
            engine: "nscd".into(),
            dimension: Some(3),
            dt: spec.dt,
            duration: spec.max_duration,
            gravity: Some(vec![0.0, 0.0, -9.81]),
            thickness: None,
            seed: Some(spec.seed),
            equilibrium: Some(Equilibrium {
                kinetic_energy: Some(spec.rest_energy * spec.grains as f64),
                energy_ratio: None,
                steps: Some(spec.rest_steps),
            }),
        },
        nscd: Some(NscdSection {
            theta: Some(spec.theta),
            criterion: Some(Policy::Quad.name().into()),
            tolerance: Some(spec.tolerance),
            max_iterations: Some(spec.max_iterations),
            alert_distance: Some(1e-3),
            ..NscdSection::default()
        }),
        output: Some(OutputSection { every: Some(50), cycles: None }),
        settlement: None,
        materials: [(BALLAST, spec.density), (ELASTOMER, spec.pad_density), (FRAME, 2400.0)]
            .into_iter()
            .map(|(name, density)| Material { name: name.into(), density })
            .collect(),
        contacts: vec![
            law(BALLAST, BALLAST, spec.friction),
            law(BALLAST, ELASTOMER, spec.friction),
            law(BALLAST, FRAME, 0.0),
            law(ELASTOMER, FRAME, 0.0),
        ],
        bodies,
        springs,
    };
    scene.validate()?;
    Ok(scene)
}
