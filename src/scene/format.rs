//! The serde mirror of the TOML scene format (see `docs/scene-format.md`).
//!
//! Every table refuses unknown keys. Optional keys are `Option`s (or empty
//! vectors) so that a scene written back with [`Scene::to_toml_string`](crate::scene::SceneFile::to_toml_string) keeps
//! exactly the keys the user gave; the engine's defaults are those of
//! [`crate::nscd::NscdParams::default`] (θ, gravity, NLGS settings), the others
//! live in the accessor methods and the `DEFAULT_*` constants. All quantities
//! are SI.

pub use super::common::{CyclesSpec, OutputSection, Simulation, DEFAULT_OUTPUT_EVERY};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::marker::PhantomData;

/// Default out-of-plane thickness (m).
pub const DEFAULT_THICKNESS: f64 = 1.0;

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// `[simulation]`: engine, time step, duration, gravity, thickness, seed,
    /// equilibrium stop (shared with MD scenes).
    pub simulation: Simulation,
    /// `[nscd]`: settings of the NSCD engine (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nscd: Option<NscdSection>,
    /// `[soft]`: stiffness and time step of the planar MD engine (optional; an
    /// NSCD run ignores it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub soft: Option<super::soft::SoftSection>,
    /// `[output]`: output settings (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<OutputSection>,
    /// `[settlement]`: the settlement-acceleration procedure instead of a plain run (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settlement: Option<crate::scene::common::SettlementSection>,
    /// `[[material]]` entries; a material's index is its position here.
    #[serde(default, rename = "material", skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<Material>,
    /// `[[contact]]` entries: contact laws between pairs of materials.
    #[serde(default, rename = "contact", skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<ContactEntry>,
    /// `[[body]]` entries, in order (body `i` of the system is `bodies[i]`).
    #[serde(default, rename = "body", skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySpec>,
    /// `[[spring]]` entries: viscoelastic sublayer springs.
    #[serde(default, rename = "spring", skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<SpringSpec>,
}

/// `[nscd]`: every key is optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NscdSection {
    /// θ of the θ-method, in [0.5, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta: Option<f64>,
    /// `"strict"`, `"quad"`, `"quad_max"` or `"energy"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub criterion: Option<String>,
    /// NLGS tolerance (dimensionless), in (0, 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Minimum NLGS sweeps per step, ≥ 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_iterations: Option<usize>,
    /// Maximum NLGS sweeps per step, ≥ `min_iterations`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<usize>,
    /// `quad_max`: the maximum norm may reach `max_factor · tolerance`; ≥ 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_factor: Option<f64>,
    /// Alternate forward and backward NLGS sweeps (symmetric Gauss–Seidel); default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub symmetric: Option<bool>,
    /// Over-relaxation factor `ω` of the NLGS sweeps, in (0, 2); default 1 (none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relaxation: Option<f64>,
    /// Depth `m` of the Anderson mixing of the NLGS sweeps, 0 to 8; default 0 (plain sweeps;
    /// `crate::nscd::method::anderson`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anderson: Option<usize>,
    /// Where the convergence norms are measured: `"sweep"` (during the updating
    /// sweep) or `"check"` (a separate pass after it that updates nothing, as LMGC90).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measure: Option<String>,
    /// The solver of each step: `"nlgs"` (default), `"apgd"` (NLGS first, then
    /// the accelerated projected gradient; `docs/accelerated-solver.md`) or
    /// `"interior_point"` (NLGS first, then an interior point on the law's
    /// complementarity form, then NLGS; `nscd::interior`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<String>,
    /// What a step does when `max_iterations` sweeps stop short of the tolerance:
    /// `"accept"` (default), `"extend"` (up to `stall_max_iterations` sweeps) or `"stop"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on_stall: Option<String>,
    /// `on_stall = "extend"`: sweeps made at most in all, ≥ `max_iterations`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stall_max_iterations: Option<usize>,
    /// Alert distance (m), ≥ 0; default: [`crate::nscd::system::DEFAULT_ALERT_FRACTION`] times the
    /// smallest inner radius of the non-fixed bodies (of all bodies if none moves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alert_distance: Option<f64>,
    /// 3D scenes only: how the points of a face–face contact of two polyhedra get their gaps, `"exact"`
    /// (default: each its own) or `"common_plane"` (LMGC90's rule: the smallest, the faces counted flush;
    /// [`crate::space::detection::FaceGaps`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub face_gaps: Option<String>,
    /// 3D scenes only: what a closed contact does with an overlap, `"kept"` (default: Moreau–Jean's
    /// velocity-level law) or `"held"` (an overlap may not grow past the shallowest the point has had;
    /// [`crate::nscd::d3::overlaps::Overlaps`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub overlaps: Option<String>,
}

/// `[[material]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Unique, non-empty name.
    pub name: String,
    /// Density (kg/m³), > 0.
    pub density: f64,
}

/// `[[contact]]`: the contact law between two materials. Pairs of materials
/// without an entry are frictionless, with zero restitution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactEntry {
    /// The two material names (may be the same material twice).
    #[serde(deserialize_with = "pair")]
    pub between: [String; 2],
    /// Coulomb friction coefficient, ≥ 0.
    pub friction: f64,
    /// Normal restitution coefficient, in [0, 1]; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
    /// Tangential restitution coefficient, in [0, 1]; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_restitution: Option<f64>,
}

/// `regular = { sides, radius }`: a regular polygon.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegularSpec {
    /// Number of sides, ≥ 3.
    pub sides: usize,
    /// Circumradius (m), > 0; the first vertex is on the body-frame +x axis.
    pub radius: f64,
}

/// A vertex list `[[x, y], …]` (m).
pub type VertexList = Vec<[f64; 2]>;

/// `[[body]]`: one rigid body. Exactly one of `polygon`, `regular`, `disc`, `parts`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Optional name (default empty); non-empty names are unique.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Name of the body's material.
    pub material: String,
    /// Convex polygon: vertices (m) in the body frame, counter-clockwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_points")]
    pub polygon: Option<Vec<[f64; 2]>>,
    /// Regular polygon centred on the body-frame origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regular: Option<RegularSpec>,
    /// Disc of this radius (m) centred on the body-frame origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disc: Option<f64>,
    /// Compound body: a rigid union of convex polygons, each a vertex list (m)
    /// in the body frame, counter-clockwise; parts may share edges but not overlap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_parts")]
    pub parts: Option<Vec<VertexList>>,
    /// World position of the body-frame origin (m).
    #[serde(deserialize_with = "pair")]
    pub position: [f64; 2],
    /// Angle of the body frame (rad), counter-clockwise; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<f64>,
    /// Velocity of the body-frame origin (m/s); default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_pair")]
    pub velocity: Option<[f64; 2]>,
    /// Angular velocity (rad/s), counter-clockwise; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin: Option<f64>,
    /// A fixed body never moves; default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed: Option<bool>,
    /// Imposed velocity components.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imposed: Option<ImposedSpec>,
    /// External force at the centre of mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<LoadSpec>,
}

impl BodySpec {
    /// Angle (rad).
    pub fn angle(&self) -> f64 {
        self.angle.unwrap_or(0.0)
    }

    /// Velocity of the body-frame origin (m/s).
    pub fn velocity(&self) -> [f64; 2] {
        self.velocity.unwrap_or([0.0, 0.0])
    }

    /// Spin (rad/s).
    pub fn spin(&self) -> f64 {
        self.spin.unwrap_or(0.0)
    }

    /// Whether the body is fixed.
    pub fn is_fixed(&self) -> bool {
        self.fixed.unwrap_or(false)
    }
}

/// `imposed = { vx, vy, spin }`: imposed velocity components of the centre of
/// mass (m/s) and spin (rad/s); absent components are free.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImposedSpec {
    /// Imposed x velocity of the centre of mass (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vx: Option<Drive>,
    /// Imposed y velocity of the centre of mass (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vy: Option<Drive>,
    /// Imposed spin (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin: Option<Drive>,
}

/// A time-dependent value: a constant, or `mean + amplitude·cos(2π·frequency·t − phase)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Drive {
    /// A constant value (unit of the driven quantity).
    Constant(f64),
    /// A harmonic value.
    Harmonic(HarmonicSpec),
}

impl Drive {
    /// As the engine's harmonic law.
    pub fn to_harmonic(self) -> crate::nscd::Harmonic {
        match self {
            Drive::Constant(v) => crate::nscd::Harmonic::constant(v),
            Drive::Harmonic(h) => h.to_harmonic(),
        }
    }
}

impl<'de> Deserialize<'de> for Drive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct DriveVisitor;
        impl<'de> Visitor<'de> for DriveVisitor {
            type Value = Drive;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a table { mean, amplitude, frequency, phase }")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Drive, E> {
                Ok(Drive::Constant(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Drive, E> {
                Ok(Drive::Constant(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Drive, E> {
                Ok(Drive::Constant(v as f64))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Drive, A::Error> {
                HarmonicSpec::deserialize(de::value::MapAccessDeserializer::new(map)).map(Drive::Harmonic)
            }
        }
        d.deserialize_any(DriveVisitor)
    }
}

/// `{ mean, amplitude, frequency, phase }`:
/// `mean + amplitude·cos(2π·frequency·t − phase)`; `amplitude`, `frequency` (Hz)
/// and `phase` (rad) default to 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HarmonicSpec {
    /// Mean value (unit of the driven quantity).
    pub mean: f64,
    /// Amplitude (unit of the driven quantity); default 0.
    #[serde(default)]
    pub amplitude: f64,
    /// Frequency (Hz); default 0.
    #[serde(default)]
    pub frequency: f64,
    /// Phase (rad); default 0.
    #[serde(default)]
    pub phase: f64,
}

impl HarmonicSpec {
    /// As the engine's harmonic law.
    pub fn to_harmonic(self) -> crate::nscd::Harmonic {
        crate::nscd::Harmonic {
            mean: self.mean,
            amplitude: self.amplitude,
            frequency: self.frequency,
            phase: self.phase,
        }
    }
}

/// `load = { direction, mean, amplitude, frequency, phase }`: the force
/// `(mean + amplitude·cos(2π·frequency·t − phase)) · unit(direction)` (N) at the
/// centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Direction of the force (any non-zero length; it is normalised).
    #[serde(deserialize_with = "pair")]
    pub direction: [f64; 2],
    /// Mean force (N).
    pub mean: f64,
    /// Amplitude (N); default 0.
    #[serde(default)]
    pub amplitude: f64,
    /// Frequency (Hz); default 0.
    #[serde(default)]
    pub frequency: f64,
    /// Phase (rad); default 0.
    #[serde(default)]
    pub phase: f64,
}

impl LoadSpec {
    /// As the engine's load: unit direction and harmonic magnitude (N). The
    /// direction must be non-zero (checked by the validation).
    pub fn to_load(&self) -> crate::nscd::Load {
        crate::nscd::Load::new(
            self.direction,
            crate::nscd::Harmonic {
                mean: self.mean,
                amplitude: self.amplitude,
                frequency: self.frequency,
                phase: self.phase,
            },
        )
    }
}

/// `[[spring]]`: a viscoelastic sublayer spring (law (17), see
/// [`crate::nscd::sublayer`]) between a point of `body` and either a world
/// `anchor` or a point of the body `other`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    /// Name of the first body.
    pub body: String,
    /// Attachment on `body` (m), in its body frame (relative to the body-frame
    /// origin, like polygon vertices); default `[0, 0]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_pair")]
    pub point: Option<[f64; 2]>,
    /// World anchor point (m); exactly one of `anchor` and `other`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_pair")]
    pub anchor: Option<[f64; 2]>,
    /// Name of the second body; exactly one of `anchor` and `other`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub other: Option<String>,
    /// Attachment on `other` (m), in its body frame; default `[0, 0]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "opt_pair")]
    pub other_point: Option<[f64; 2]>,
    /// Force per unit strain `k_N` (N), ≥ 0.
    pub k_n: f64,
    /// Force per unit strain rate `ν` (N·s), ≥ 0; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    /// Rest length `L0` (m), > 0; default: the initial length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
    /// Prestrain `ε0`; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prestrain: Option<f64>,
    /// Only pushes the ends apart; default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression_only: Option<bool>,
}

/// Visitor of an array of exactly `N` `T` (serde's own `[T; N]` lets `toml`
/// ignore extra elements).
struct ArrayVisitor<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for ArrayVisitor<T, N> {
    type Value = [T; N];
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "an array of exactly {N} elements")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut items = Vec::with_capacity(N);
        while items.len() < N {
            match seq.next_element()? {
                Some(x) => items.push(x),
                None => return Err(de::Error::invalid_length(items.len(), &self)),
            }
        }
        let mut n = N;
        while seq.next_element::<de::IgnoredAny>()?.is_some() {
            n += 1;
        }
        if n > N {
            return Err(de::Error::invalid_length(n, &self));
        }
        items.try_into().map_err(|_| de::Error::invalid_length(n, &self))
    }
}

/// An array that is exactly `N` elements long.
#[derive(Debug, Clone, Copy)]
struct Exact<T, const N: usize>([T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(ArrayVisitor(PhantomData)).map(Exact)
    }
}

/// An array of exactly `N` elements (`deserialize_with`), e.g. a 2D or 3D vector.
pub(crate) fn array<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(d: D) -> Result<[T; N], D::Error> {
    Exact::deserialize(d).map(|p| p.0)
}

/// As [`array`], for an optional key (with `#[serde(default)]`).
pub(crate) fn opt_array<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<Option<[f64; N]>, D::Error> {
    Exact::deserialize(d).map(|p| Some(p.0))
}

fn pair<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<[T; 2], D::Error> {
    array(d)
}

fn opt_pair<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    opt_array(d)
}

fn opt_points<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
    Vec::<Exact<f64, 2>>::deserialize(d).map(|v| Some(v.into_iter().map(|p| p.0).collect()))
}

fn opt_parts<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<VertexList>>, D::Error> {
    Vec::<Vec<Exact<f64, 2>>>::deserialize(d)
        .map(|v| Some(v.into_iter().map(|p| p.into_iter().map(|q| q.0).collect()).collect()))
}
