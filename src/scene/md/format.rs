//! The serde mirror of the TOML format of MD scenes (`engine = "md"`, see the
//! section "MD scenes" of `docs/scene-format.md`): 3D spheres, walls, symmetry
//! planes, materials with elastic moduli and pairwise contact laws.
//!
//! As for NSCD scenes, every table refuses unknown keys and optional keys are
//! `Option`s, so that [`MdScene::to_toml_string`](crate::scene::SceneFile::to_toml_string) writes back exactly the keys the
//! user gave; the defaults are those of [`crate::md::MdSettings::default`]
//! (and of the shared sections, [`crate::scene::common`]). Vectors are arrays of exactly 3 numbers. All quantities are SI.

use crate::scene::common::{OutputSection, Simulation};
use crate::scene::format::{array, opt_array};
use serde::{Deserialize, Serialize};

pub use crate::md::system::DEFAULT_SKIN_FRACTION;
/// Deepest initial overlap a scene may have, as a fraction of the smaller radius
/// of the pair (sphere–sphere, sphere–wall, sphere and its symmetry image). A
/// deposited sample written back by `final_scene.toml` overlaps by about 1e-3 of
/// a radius (1e-6 m on the 1.5–5 mm spheres of Karrech et al.), a soft one by a
/// few 1e-2; at 0.1 of the radius Hertz's contact radius `√(R* δ)` is already a
/// third of `R*` (the theory wants it small), a 1 mm diorite sphere stores
/// enough energy to leave at ~100 m/s, and deeper overlaps are typos (a sphere
/// placed inside another or in a wall). The engine stops at 0.5 (a runaway overlap).
pub const MAX_INITIAL_OVERLAP: f64 = 0.1;
/// Slowest impact speed (m/s) at which Hertz contact times are taken for the
/// time-step check (a fall of 5 cm; faster if the initial state can produce
/// faster impacts). The Hertz contact time varies as `v^{-1/5}`: an estimate off
/// by 10× in speed is off by 1.6× in time.
pub const REFERENCE_SPEED: f64 = 1.0;

/// A whole MD scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MdScene {
    /// `[simulation]`: engine, dimension, time step, duration, gravity, seed, equilibrium stop.
    pub simulation: Simulation,
    /// `[md]`: integrator, skin, background damping, threads (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub md: Option<MdSection>,
    /// `[output]` (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<OutputSection>,
    /// `[settlement]`: the settlement-acceleration procedure instead of a plain run (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settlement: Option<crate::scene::common::SettlementSection>,
    /// `[[symmetry]]` planes: 0, 1 or 2 (perpendicular).
    #[serde(default, rename = "symmetry", skip_serializing_if = "Vec::is_empty")]
    pub symmetry: Vec<SymmetrySpec>,
    /// `[[material]]` entries; a material's index is its position here.
    #[serde(default, rename = "material", skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<MdMaterial>,
    /// `[[contact]]` entries: the law of each pair of materials that can touch.
    #[serde(default, rename = "contact", skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<MdContact>,
    /// `[[wall]]` entries, in order.
    #[serde(default, rename = "wall", skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallSpec>,
    /// `[[body]]` entries: the spheres, in order (sphere `i` of the system is `bodies[i]`).
    #[serde(default, rename = "body", skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<SphereSpec>,
}

/// `[md]`: settings of the MD engine; every key is optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MdSection {
    /// `"verlet"` (default) or `"gear"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integrator: Option<String>,
    /// With `integrator = "gear"`: `"karrech"` (default), `"gear3"` … `"gear6"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gear: Option<String>,
    /// Neighbour-list skin (m), > 0; default [`DEFAULT_SKIN_FRACTION`] × the mean sphere diameter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin: Option<f64>,
    /// Translational background damping `γ_b` (kg/s), ≥ 0; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background_damping: Option<f64>,
    /// Rotational background damping `γ_br` (kg·m²/s), ≥ 0; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background_rotational_damping: Option<f64>,
    /// Force-evaluation threads, ≥ 1; default: `--threads` of `ballast run` (whose
    /// default is 2 on a machine with 2 cores or more).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threads: Option<usize>,
}

/// `[[symmetry]]`: a symmetry plane (mirror images of the spheres near it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SymmetrySpec {
    /// A point of the plane (m).
    #[serde(deserialize_with = "array")]
    pub point: [f64; 3],
    /// Normal into the sample (non-zero; normalised).
    #[serde(deserialize_with = "array")]
    pub normal: [f64; 3],
}

/// `[[material]]` of an MD scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MdMaterial {
    /// Unique, non-empty name.
    pub name: String,
    /// Density (kg/m³), > 0 (unused by walls).
    pub density: f64,
    /// Young's modulus (Pa), > 0.
    pub young: f64,
    /// Poisson's ratio, in (−1, 0.5).
    pub poisson: f64,
}

/// `[[contact]]`: the contact law between two materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MdContact {
    /// The two material names (may be the same material twice).
    #[serde(deserialize_with = "array")]
    pub between: [String; 2],
    /// `"hertz"` or `"linear"`.
    pub model: String,
    /// Coulomb friction coefficient μ ≥ 0 (static = dynamic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// `linear`: static friction coefficient μ_s ≥ 0, with `dynamic_friction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub static_friction: Option<f64>,
    /// `linear`: dynamic friction coefficient, 0 ≤ μ_d ≤ μ_s, with `static_friction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dynamic_friction: Option<f64>,
    /// Restitution coefficient of a central impact, in (0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
    /// `hertz`: normal damping ratio α_n ≥ 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_damping_ratio: Option<f64>,
    /// `hertz`: tangential damping ratio α_t ≥ 0; default α_n.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_damping_ratio: Option<f64>,
    /// `linear`: normal stiffness (N/m), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_stiffness: Option<f64>,
    /// `linear`: tangential stiffness (N/m), > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_stiffness: Option<f64>,
    /// `linear`: normal dashpot (kg/s), ≥ 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_damping: Option<f64>,
    /// `linear`: tangential dashpot (kg/s), ≥ 0; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_damping: Option<f64>,
}

/// `[[body]]` of an MD scene: a solid sphere.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Optional name (default empty); non-empty names are unique.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Name of the sphere's material.
    pub material: String,
    /// Radius (m), > 0.
    pub sphere: f64,
    /// Centre (m).
    #[serde(deserialize_with = "array")]
    pub position: [f64; 3],
    /// Velocity (m/s); default 0.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "opt_array")]
    pub velocity: Option<[f64; 3]>,
    /// Spin (rad/s); default 0.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "opt_array")]
    pub spin: Option<[f64; 3]>,
}

impl SphereSpec {
    /// Velocity (m/s).
    pub fn velocity(&self) -> [f64; 3] {
        self.velocity.unwrap_or([0.0; 3])
    }

    /// Spin (rad/s).
    pub fn spin(&self) -> [f64; 3] {
        self.spin.unwrap_or([0.0; 3])
    }
}

/// `[[wall]]`: exactly one of `plane`, `disc`, `cylinder`; plane and disc walls
/// may be servo-controlled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Unique, non-empty name (the `series.csv` columns `<name>_force`, `<name>_position`).
    pub name: String,
    /// Name of the wall's material.
    pub material: String,
    /// An infinite plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<PlaneSpec>,
    /// A plane limited to a disc.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disc: Option<DiscSpec>,
    /// The inside of a cylinder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<CylinderSpec>,
    /// Motion along the normal under a prescribed stress or force.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub servo: Option<ServoSpec>,
}

/// `plane = { point, normal }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    /// A point of the plane (m).
    #[serde(deserialize_with = "array")]
    pub point: [f64; 3],
    /// Normal into the free side, where the spheres are (non-zero; normalised).
    #[serde(deserialize_with = "array")]
    pub normal: [f64; 3],
}

/// `disc = { point, normal, radius }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscSpec {
    /// Centre of the disc (m).
    #[serde(deserialize_with = "array")]
    pub point: [f64; 3],
    /// Normal into the free side (non-zero; normalised).
    #[serde(deserialize_with = "array")]
    pub normal: [f64; 3],
    /// Radius (m), > 0.
    pub radius: f64,
}

/// `cylinder = { axis_point, axis, radius }`: the spheres are inside.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    /// A point of the axis (m).
    #[serde(deserialize_with = "array")]
    pub axis_point: [f64; 3],
    /// Direction of the axis (non-zero; normalised).
    #[serde(deserialize_with = "array")]
    pub axis: [f64; 3],
    /// Radius (m), > 0.
    pub radius: f64,
}

/// `servo = { mass, viscosity, stress | force, amplitude, period, area }`: the wall
/// moves along its normal, `m s̈ = value(t) (· area) + F_contacts − γ ṡ`, with
/// `value(t) = base + amplitude (1 − cos 2πt/period) / 2`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoSpec {
    /// Mass of the wall (kg), > 0.
    pub mass: f64,
    /// Viscosity γ (kg/s), ≥ 0.
    pub viscosity: f64,
    /// Base stress (Pa); exactly one of `stress` and `force`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stress: Option<f64>,
    /// Base force (N); exactly one of `stress` and `force`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<f64>,
    /// Amplitude (Pa or N); default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f64>,
    /// Period (s), ≥ 0; default 0 (constant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
    /// Area (m²) the stress acts on, > 0, only with `stress`; default: the box
    /// face from the other axis-aligned walls.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area: Option<f64>,
}
