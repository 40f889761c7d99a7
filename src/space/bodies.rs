//! The bodies of a 3D engine as flat arrays: each body's pose (centroid and a unit quaternion, body → world),
//! its generalised velocity `u = (v_x, v_y, v_z, ω_1, ω_2, ω_3)` and its inverse mass per degree of freedom
//! `(1/m, 1/m, 1/m, 1/I_1, 1/I_2, 1/I_3)`.
//!
//! The spin `ω` is expressed in the body's **principal frame** (the frame of its [`Solid`], whose axes are the
//! principal axes of inertia), as LMGC90's RBDY3 keeps it: the inertia tensor is then diagonal and constant, a
//! body's inverse mass is six numbers, and the shared method's rows ([`crate::nscd::method::Row`]) see six
//! independent degrees of freedom. Euler's equations in that frame carry the gyroscopic term `−ω × I ω`, which
//! the engine's step adds (`crate::nscd::d3`).
//!
//! A fixed body has an inverse mass of zero on every component: no impulse moves it; its velocity stays the one
//! it was given (zero for a wall).

use crate::geometry::{Pose, Solid, Vec3};
use crate::space::loads::{Imposed3, Load3};
use crate::{Error, Result};
use nalgebra::UnitQuaternion;
use serde::{Deserialize, Serialize};

/// A body's generalised velocity or inverse mass in 3D: `(v_x, v_y, v_z)` in the world (m/s, or 1/kg) then
/// `(ω_1, ω_2, ω_3)` about the principal axes (rad/s, or 1/(kg·m²)).
pub type Dofs6 = [f64; 6];

/// What a 3D body is, apart from where it is and how it moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyInfo {
    /// Name (for messages and outputs).
    pub name: String,
    /// Shape in the principal frame.
    pub solid: Solid,
    /// Material index (contact laws are given per pair of materials).
    pub material: u32,
    /// Mass (kg); infinite for a fixed body (JSON `null`, read back as +∞: [`infinite`]).
    #[serde(with = "infinite")]
    pub mass: f64,
    /// Principal moments of inertia (kg·m²) about the body axes; infinite for a fixed body (JSON `null`s).
    #[serde(with = "infinite::vec3")]
    pub inertia: Vec3,
    /// Whether the body is fixed (a wall, a floor): its velocity is imposed (zero unless given) on every
    /// component.
    pub fixed: bool,
    /// Imposed velocity components (none by default; [`Imposed3`]): an imposed component has a zero inverse mass.
    #[serde(default, skip_serializing_if = "Imposed3::is_empty")]
    pub imposed: Imposed3,
    /// External forces and moments ([`Load3`]), none by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<Load3>,
}

impl BodyInfo {
    /// A mobile body of `solid` and `density` (kg/m³): mass `ρ V`, principal inertia `ρ J`.
    pub fn mobile(name: &str, solid: Solid, material: u32, density: f64) -> Result<Self> {
        if !(density.is_finite() && density > 0.0) {
            return Err(Error::Scene(format!("body '{name}': density: must be positive and finite, got {density}")));
        }
        if matches!(solid, Solid::HalfSpace) {
            return Err(Error::Scene(format!("body '{name}': a half-space can only be a fixed body")));
        }
        let (volume, second) = solid.mass_properties();
        Ok(Self {
            name: name.into(),
            solid,
            material,
            mass: density * volume,
            inertia: second * density,
            fixed: false,
            imposed: Imposed3::default(),
            loads: Vec::new(),
        })
    }

    /// A fixed body (a wall, a floor, a half-space).
    pub fn fixed(name: &str, solid: Solid, material: u32) -> Self {
        Self {
            name: name.into(),
            solid,
            material,
            mass: f64::INFINITY,
            inertia: Vec3::repeat(f64::INFINITY),
            fixed: true,
            imposed: Imposed3::default(),
            loads: Vec::new(),
        }
    }

    /// The same body with `imposed` velocity components (replacing any it had; ignored on a fixed body).
    pub fn with_imposed(mut self, imposed: Imposed3) -> Self {
        self.imposed = imposed;
        self
    }

    /// The same body with one more load.
    pub fn with_load(mut self, load: Load3) -> Self {
        self.loads.push(load);
        self
    }

    /// The inverse mass per degree of freedom ([`Dofs6`]): zero for a fixed body and for an imposed component.
    pub fn inverse_mass(&self) -> Dofs6 {
        if self.fixed {
            return [0.0; 6];
        }
        let (m, i) = (1.0 / self.mass, self.inertia);
        let mut inv = [m, m, m, 1.0 / i.x, 1.0 / i.y, 1.0 / i.z];
        for (d, v) in self.imposed.velocity.iter().enumerate() {
            if v.is_some() {
                inv[d] = 0.0;
            }
        }
        if self.imposed.spin.is_some() {
            inv[3..].fill(0.0);
        }
        inv
    }

    /// The velocity ([`Dofs6`]) `u` with the imposed components set to their values at time `t` (s), for a body at
    /// `pose` (the imposed world spin turned into the principal frame); a fixed body's `u` as it is.
    pub fn impose(&self, u: &mut Dofs6, pose: &Pose, t: f64) {
        if self.fixed {
            return;
        }
        for (d, v) in self.imposed.velocity.iter().enumerate() {
            if let Some(v) = v {
                u[d] = v.at(t);
            }
        }
        if let Some(w) = self.imposed.spin_at(t) {
            let w = pose.rotation.inverse_transform_vector(&w);
            u[3..].copy_from_slice(w.as_slice());
        }
    }
}

/// The serde form of a number that is infinite for a fixed body (its mass, its moments of inertia): JSON has no
/// infinity, serde_json writes a non-finite number as `null`; this reads `null` back as +∞, so that a state with
/// walls (a checkpoint, `initial_state.json`) reads back as it was written. A finite number reads back bit for bit.
pub mod infinite {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes `x` (`null` when not finite).
    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        x.serialize(s)
    }

    /// Reads a number, or `null` as +∞.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }

    /// The same for the three components of a vector.
    pub mod vec3 {
        use crate::geometry::Vec3;
        use serde::{Deserialize, Deserializer, Serialize, Serializer};

        /// Writes `[x, y, z]` (`null` for a component that is not finite).
        pub fn serialize<S: Serializer>(v: &Vec3, s: S) -> Result<S::Ok, S::Error> {
            [v.x, v.y, v.z].serialize(s)
        }

        /// Reads `[x, y, z]`, `null` as +∞.
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
            let c = <[Option<f64>; 3]>::deserialize(d)?;
            Ok(Vec3::from(c.map(|x| x.unwrap_or(f64::INFINITY))))
        }
    }
}

/// A body is seen by the detection as its shape.
impl std::borrow::Borrow<Solid> for BodyInfo {
    fn borrow(&self) -> &Solid {
        &self.solid
    }
}

/// The bodies of a 3D system, as parallel arrays.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Bodies {
    /// What each body is.
    pub info: Vec<BodyInfo>,
    /// Where each is: centroid (m) and rotation body → world.
    pub pose: Vec<Pose>,
    /// Generalised velocity of each ([`Dofs6`]).
    pub u: Vec<Dofs6>,
    /// Inverse mass of each ([`Dofs6`]): zero for a fixed body.
    pub inv_m: Vec<Dofs6>,
}

impl Bodies {
    /// The number of bodies.
    pub fn len(&self) -> usize {
        self.info.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.info.is_empty()
    }

    /// Adds a body at `pose` with velocity `u` and returns its index. The velocity of a fixed body is imposed
    /// for the whole run; an imposed component takes its value at `t = 0`.
    pub fn push(&mut self, info: BodyInfo, pose: Pose, u: Dofs6) -> u32 {
        let mut u = u;
        info.impose(&mut u, &pose, 0.0);
        self.inv_m.push(info.inverse_mass());
        self.info.push(info);
        self.pose.push(pose);
        self.u.push(u);
        (self.info.len() - 1) as u32
    }

    /// Whether body `i` is not fixed (it moves, freely or as imposed).
    pub fn is_mobile(&self, i: usize) -> bool {
        !self.info[i].fixed
    }

    /// Whether an impulse can change body `i`'s velocity: some component neither fixed nor imposed.
    pub fn is_free(&self, i: usize) -> bool {
        self.inv_m[i].iter().any(|&x| x > 0.0)
    }

    /// Body `i`'s velocity: translation (m/s, world) and spin (rad/s, world).
    pub fn world_velocity(&self, i: usize) -> (Vec3, Vec3) {
        let u = &self.u[i];
        (Vec3::new(u[0], u[1], u[2]), self.pose[i].rotation * Vec3::new(u[3], u[4], u[5]))
    }

    /// Body `i`'s orientation as a unit quaternion `[w, x, y, z]` (body → world).
    pub fn orientation(&self, i: usize) -> [f64; 4] {
        let q = self.pose[i].rotation.quaternion();
        [q.w, q.i, q.j, q.k]
    }

    /// The velocity (m/s, world) of the material point of body `i` at `point` (world): `v + R ω × (p − x)`.
    pub fn point_velocity(&self, i: usize, point: &Vec3) -> Vec3 {
        let (v, w) = self.world_velocity(i);
        v + w.cross(&(point - self.pose[i].position))
    }

    /// Body `i`'s angular momentum about its centroid (kg·m²/s, world): `R I ω`.
    pub fn angular_momentum(&self, i: usize) -> Vec3 {
        let (u, inertia) = (&self.u[i], &self.info[i].inertia);
        self.pose[i].rotation * Vec3::new(inertia.x * u[3], inertia.y * u[4], inertia.z * u[5])
    }

    /// The kinetic energy of the mobile bodies (J).
    pub fn kinetic_energy(&self) -> f64 {
        (0..self.len())
            .filter(|&i| self.is_mobile(i))
            .map(|i| {
                let (u, b) = (&self.u[i], &self.info[i]);
                0.5 * b.mass * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
                    + 0.5 * (b.inertia.x * u[3] * u[3] + b.inertia.y * u[4] * u[4] + b.inertia.z * u[5] * u[5])
            })
            .sum()
    }
}

/// `h · u` of two [`Dofs6`]: a generalised direction times a velocity (m/s).
#[inline(always)]
pub fn dot6(h: &Dofs6, u: &Dofs6) -> f64 {
    h[0] * u[0] + h[1] * u[1] + h[2] * u[2] + h[3] * u[3] + h[4] * u[4] + h[5] * u[5]
}

/// The generalised direction `h_d = (d, ρ × Rᵀ d)` of direction `d` (world) at lever arm `rho` (principal frame)
/// of a body at `pose`: `h_d · u = d · (v + R (ω × ρ))`, the velocity along `d` of the body's point at `ρ`.
#[inline]
pub fn gen_dir(pose: &Pose, rho: &Vec3, d: &Vec3) -> Dofs6 {
    let local = pose.rotation.inverse_transform_vector(d);
    let m = rho.cross(&local);
    [d.x, d.y, d.z, m.x, m.y, m.z]
}

/// The rotation by the rotation vector `phi` (rad, world): `exp(φ̂)`, exact (the quaternion of angle `|φ|` about
/// `φ/|φ|`), the identity for `φ = 0`.
#[inline]
pub fn rotation(phi: Vec3) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(phi)
}

/// A pose moved by a velocity over `dt` (s): the centroid by `v dt`, the frame by the rotation `exp(dt R ω)`
/// with `ω` in the body frame (`R` the pose's rotation), composed on the left (a world-frame rotation) and
/// renormalised.
#[inline]
pub fn advance(pose: &Pose, u: &Dofs6, dt: f64) -> Pose {
    let spin = pose.rotation * Vec3::new(u[3], u[4], u[5]);
    let rotation = UnitQuaternion::new_normalize((rotation(spin * dt) * pose.rotation).into_inner());
    Pose { position: pose.position + Vec3::new(u[0], u[1], u[2]) * dt, rotation }
}
