//! The serde mirror of the 3D NSCD scene format (`[simulation] engine = "nscd"`, `dimension = 3`; the format is
//! described in [`super`]).
//!
//! As in the 2D format every table refuses unknown keys and optional keys are `Option`s, so that a scene written
//! back with [`to_toml_string`](crate::scene::SceneFile::to_toml_string) keeps exactly the keys the user gave.
//! `[simulation]`, `[output]`, `[settlement]`, `[nscd]`, `[[material]]` and `[[contact]]` are the 2D scene's own
//! types. Vectors are arrays of exactly 3 numbers (a quaternion of 4). A drive (an imposed velocity component) is
//! the 2D scene's [`Drive`]: a number or a harmonic table.

use crate::scene::common::{OutputSection, SettlementSection, Simulation};
use crate::scene::format::{array, opt_array, ContactEntry, Drive, Material, NscdSection};
use serde::{Deserialize, Deserializer, Serialize};

/// A whole 3D NSCD scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene3 {
    /// `[simulation]`: engine (`"nscd"`), `dimension = 3`, time step, duration, gravity (3 components), seed,
    /// equilibrium stop.
    pub simulation: Simulation,
    /// `[nscd]`: the 2D scene's settings (optional); `solver = "interior_point"` (2D only) is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nscd: Option<NscdSection>,
    /// `[output]` (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<OutputSection>,
    /// `[settlement]`: the settlement-acceleration procedure instead of a plain run (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settlement: Option<SettlementSection>,
    /// `[[material]]` entries; a material's index is its position here.
    #[serde(default, rename = "material", skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<Material>,
    /// `[[contact]]` entries: contact laws between pairs of materials (a pair without one is frictionless and
    /// plastic, as in 2D).
    #[serde(default, rename = "contact", skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<ContactEntry>,
    /// `[[body]]` entries, in order (body `i` of the system is `bodies[i]`).
    #[serde(default, rename = "body", skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySpec3>,
    /// `[[spring]]` entries: sublayer springs (law (17)).
    #[serde(default, rename = "spring", skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<SpringSpec3>,
}

/// `[[body]]` of a 3D scene: exactly one of `polyhedron`, `box`, `sphere`, `plane`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec3 {
    /// Optional name (default empty); non-empty names are unique.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Name of the body's material.
    pub material: String,
    /// Convex hull of vertices given in the body frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polyhedron: Option<PolyhedronSpec>,
    /// Box centred on the body-frame origin, along its axes.
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub cuboid: Option<BoxSpec>,
    /// Sphere centred on the body-frame origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereSpec>,
    /// Half-space wall whose boundary passes through `position` (fixed bodies only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<PlaneSpec>,
    /// World position of the body-frame origin (m).
    #[serde(deserialize_with = "array")]
    pub position: [f64; 3],
    /// Rotation of the body frame (body → world); default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<OrientationSpec>,
    /// Velocity of the body-frame origin (m/s, world); default 0.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// Angular velocity (rad/s, world axes); default 0.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub spin: Option<[f64; 3]>,
    /// A fixed body never moves; default false. A plane must be fixed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed: Option<bool>,
    /// Imposed velocity components (not on a fixed body).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imposed: Option<ImposedSpec3>,
    /// External force at the centroid (not on a fixed body).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<LoadSpec3>,
    /// External moment about an axis through the centroid (not on a fixed body); `direction` is the axis
    /// (right-hand rule), the magnitude in N·m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque: Option<LoadSpec3>,
}

/// `imposed = { vx, vy, vz, spin = [wx, wy, wz] }`: the centroid's velocity components (m/s, world), each on its
/// own, and the spin (rad/s, world axes), all three together (`crate::space::loads`: a single world component of
/// the spin cannot be imposed on the engine's principal-frame spin); absent components are free.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImposedSpec3 {
    /// Imposed x velocity of the centroid (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vx: Option<Drive>,
    /// Imposed y velocity of the centroid (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vy: Option<Drive>,
    /// Imposed z velocity of the centroid (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vz: Option<Drive>,
    /// Imposed spin (rad/s, world axes), three drives.
    #[serde(default, deserialize_with = "opt_drives", skip_serializing_if = "Option::is_none")]
    pub spin: Option<[Drive; 3]>,
}

/// `load = { direction, mean, amplitude, frequency, phase }` (or `torque = { … }`): the force (N)
/// `(mean + amplitude·cos(2π·frequency·t − phase)) · unit(direction)` at the centroid, or the moment (N·m) about
/// the axis `direction` through it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec3 {
    /// Direction of the force or axis of the moment (world, any non-zero length; normalised).
    #[serde(deserialize_with = "array")]
    pub direction: [f64; 3],
    /// Mean (N or N·m).
    pub mean: f64,
    /// Amplitude (N or N·m); default 0.
    #[serde(default)]
    pub amplitude: f64,
    /// Frequency (Hz); default 0.
    #[serde(default)]
    pub frequency: f64,
    /// Phase (rad); default 0.
    #[serde(default)]
    pub phase: f64,
}

impl LoadSpec3 {
    /// The harmonic magnitude.
    pub fn value(&self) -> crate::nscd::Harmonic {
        crate::nscd::Harmonic {
            mean: self.mean,
            amplitude: self.amplitude,
            frequency: self.frequency,
            phase: self.phase,
        }
    }
}

/// `[[spring]]` of a 3D scene: a sublayer spring (law (17)) between a point of `body` and either a world `anchor`
/// or a point of the body `other`; the 2D table's keys with 3 coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec3 {
    /// Name of the first body.
    pub body: String,
    /// Attachment on `body` (m), in its scene frame (the frame of its vertices, as `position` places it); default
    /// the frame's origin.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// World anchor point (m); exactly one of `anchor` and `other`.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub anchor: Option<[f64; 3]>,
    /// Name of the second body; exactly one of `anchor` and `other`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub other: Option<String>,
    /// Attachment on `other` (m), in its scene frame; default its origin.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub other_point: Option<[f64; 3]>,
    /// Force per unit strain `k_N` (N), ≥ 0.
    pub k_n: f64,
    /// Force per unit strain rate `ν` (N·s), ≥ 0; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nu: Option<f64>,
    /// Rest length `L0` (m), > 0; default the initial length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
    /// Prestrain `ε0`; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prestrain: Option<f64>,
    /// Only pushes the ends apart; default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression_only: Option<bool>,
}

fn opt_drives<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[Drive; 3]>, D::Error> {
    array(d).map(Some)
}

impl BodySpec3 {
    /// Whether the body is fixed.
    pub fn is_fixed(&self) -> bool {
        self.fixed.unwrap_or(false)
    }

    /// Velocity of the body-frame origin (m/s).
    pub fn velocity(&self) -> [f64; 3] {
        self.velocity.unwrap_or([0.0; 3])
    }

    /// Angular velocity (rad/s, world).
    pub fn spin(&self) -> [f64; 3] {
        self.spin.unwrap_or([0.0; 3])
    }
}

/// `polyhedron = { vertices = [[x, y, z], …], merge_angle = rad }`: the convex hull of the vertices (m, body
/// frame); points inside the hull are dropped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolyhedronSpec {
    /// At least 4 points spanning a volume (m, body frame).
    #[serde(deserialize_with = "points")]
    pub vertices: Vec<[f64; 3]>,
    /// Adjacent hull triangles whose normals are within this angle (rad) make one face; default
    /// [`crate::geometry::Polyhedron::MERGE_ANGLE`], at most [`crate::geometry::Polyhedron::MAX_MERGE_ANGLE`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merge_angle: Option<f64>,
}

/// `box = { half = [a, b, c] }`: a box of half sizes `a, b, c` (m) along the body axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Half sizes (m), > 0.
    #[serde(deserialize_with = "array")]
    pub half: [f64; 3],
}

/// `sphere = { radius = r }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Radius (m), > 0.
    pub radius: f64,
}

/// `plane = { normal = [nx, ny, nz] }`: the half-space behind the plane through the body's `position`, `normal`
/// pointing out of it (towards the bodies it carries).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    /// Outward normal, any non-zero length (normalised).
    #[serde(deserialize_with = "array")]
    pub normal: [f64; 3],
}

/// `orientation = { quaternion = [w, x, y, z] }` or `orientation = { rotation_vector = [rx, ry, rz] }`: exactly
/// one of the two.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientationSpec {
    /// A unit quaternion, scalar first (`[cos ½α, sin ½α · axis]`).
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub quaternion: Option<[f64; 4]>,
    /// A rotation vector (rad): the rotation by its length about its direction.
    #[serde(default, deserialize_with = "opt_array", skip_serializing_if = "Option::is_none")]
    pub rotation_vector: Option<[f64; 3]>,
}

/// A point of exactly 3 coordinates.
#[derive(Deserialize)]
#[serde(transparent)]
struct Point3(#[serde(deserialize_with = "array")] [f64; 3]);

fn points<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f64; 3]>, D::Error> {
    Vec::<Point3>::deserialize(d).map(|v| v.into_iter().map(|p| p.0).collect())
}
