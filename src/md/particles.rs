//! The sphere set of the MD engine, stored as flat arrays (struct of arrays).
//!
//! Each sphere has a centre `x` (m), velocity `v` (m/s), spin `w` (rad/s) and an
//! orientation quaternion (kept only for output: a sphere's forces do not depend
//! on it). Mass `m = ρ 4/3 π r³` and moment of inertia `I = 2/5 m r²` of a solid
//! sphere (Karrech et al. 2007, eq. 1; David et al., eq. 5). Forces `f` (N) and
//! torques `t` (N·m) are the contact sums of the last force evaluation.

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A 3-vector of `f64` (SI units of the quantity it holds).
pub type V3 = Vector3<f64>;

/// The spheres, hot arrays first.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Particles {
    /// Centres (m).
    pub x: Vec<V3>,
    /// Velocities (m/s).
    pub v: Vec<V3>,
    /// Spins (rad/s).
    pub w: Vec<V3>,
    /// Contact forces of the last evaluation (N), without gravity.
    pub f: Vec<V3>,
    /// Contact torques of the last evaluation (N·m).
    pub t: Vec<V3>,
    /// Radii (m).
    pub r: Vec<f64>,
    /// Masses (kg).
    pub m: Vec<f64>,
    /// Inverse masses (1/kg).
    pub inv_m: Vec<f64>,
    /// Inverse moments of inertia `1 / (2/5 m r²)` (1/(kg·m²)).
    pub inv_i: Vec<f64>,
    /// Material index of each sphere.
    pub material: Vec<u32>,
    /// Orientations (unit quaternions, body to world).
    pub q: Vec<UnitQuaternion<f64>>,
    /// Names from the scene (may be empty).
    pub name: Vec<String>,
}

impl Particles {
    /// Copies `src` into `self`, reusing `self`'s buffers (no allocation once the sizes match): the backup of
    /// an MD step ([`crate::md::MdSystem`]). The destructuring names every field, so a field added to the
    /// struct does not compile until it is copied here too (a field forgotten would be a silent replay bug).
    pub(crate) fn copy_from(&mut self, src: &Particles) {
        let Particles { x, v, w, f, t, r, m, inv_m, inv_i, material, q, name } = src;
        self.x.clone_from(x);
        self.v.clone_from(v);
        self.w.clone_from(w);
        self.f.clone_from(f);
        self.t.clone_from(t);
        self.r.clone_from(r);
        self.m.clone_from(m);
        self.inv_m.clone_from(inv_m);
        self.inv_i.clone_from(inv_i);
        self.material.clone_from(material);
        self.q.clone_from(q);
        self.name.clone_from(name);
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True if there are no spheres.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a solid sphere of `radius` (m) made of material `material` (an index
    /// of the [`super::LawTable`]) of `density` (kg/m³), centred at `x` (m) with
    /// velocity `v` (m/s), no spin and no name; returns its index. Its mass is
    /// `m = ρ 4/3 π r³` (kg) and its moment of inertia `2/5 m r²` (kg·m²)
    /// ([`sphere_mass`]), as for a sphere of an MD scene. Set a name or a spin
    /// afterwards through [`Particles::name`] and [`Particles::w`], or use
    /// [`Particles::push`].
    ///
    /// # Errors
    /// [`crate::Error::Scene`] if `radius` or `density` is not positive and
    /// finite or `x` or `v` is not finite; the spheres are then unchanged.
    pub fn add_sphere(&mut self, material: u32, density: f64, radius: f64, x: V3, v: V3) -> crate::Result<usize> {
        let i = self.len();
        let bad = |what: String| Err(crate::Error::Scene(format!("sphere {i}: {what}")));
        for (what, value, unit) in [("radius", radius, "m"), ("density", density, "kg/m^3")] {
            if !(value.is_finite() && value > 0.0) {
                return bad(format!("{what} must be positive and finite, got {value} {unit}"));
            }
        }
        for (what, p) in [("position", x), ("velocity", v)] {
            if p.iter().any(|c| !c.is_finite()) {
                return bad(format!("{what} must be finite, got [{}, {}, {}]", p[0], p[1], p[2]));
            }
        }
        Ok(self.push("", material, density, radius, x, v, V3::zeros()))
    }

    /// Adds a solid sphere named `name` of radius `r` (m) and density `density`
    /// (kg/m³) made of `material`, at `x` (m) with velocity `v` (m/s) and spin `w`
    /// (rad/s); returns its index. Mass and inertia as [`Particles::add_sphere`];
    /// nothing is checked.
    #[allow(clippy::too_many_arguments)]
    pub fn push(&mut self, name: &str, material: u32, density: f64, r: f64, x: V3, v: V3, w: V3) -> usize {
        let m = sphere_mass(density, r);
        self.x.push(x);
        self.v.push(v);
        self.w.push(w);
        self.f.push(V3::zeros());
        self.t.push(V3::zeros());
        self.r.push(r);
        self.m.push(m);
        self.inv_m.push(1.0 / m);
        self.inv_i.push(1.0 / (0.4 * m * r * r));
        self.material.push(material);
        self.q.push(UnitQuaternion::identity());
        self.name.push(name.to_string());
        self.len() - 1
    }

    /// Translational plus rotational kinetic energy (J).
    pub fn kinetic_energy(&self) -> f64 {
        (0..self.len())
            .map(|i| 0.5 * self.m[i] * self.v[i].norm_squared() + 0.5 / self.inv_i[i] * self.w[i].norm_squared())
            .sum()
    }

    /// Volume of the spheres (m³).
    pub fn volume(&self) -> f64 {
        self.r.iter().map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r).sum()
    }

    /// Largest radius (m), 0 if empty.
    pub fn max_radius(&self) -> f64 {
        self.r.iter().cloned().fold(0.0, f64::max)
    }
}

/// Mass (kg) of a solid sphere of `density` (kg/m³) and `radius` (m):
/// `ρ 4/3 π r³`. Its moment of inertia is `2/5 m r²` (kg·m²).
pub fn sphere_mass(density: f64, radius: f64) -> f64 {
    density * 4.0 / 3.0 * std::f64::consts::PI * radius * radius * radius
}

/// Rotates `q` by the spin `w` (rad/s) held for `dt` (s): `q ← q + dt/2 (0, w) q`,
/// then renormalised, so the orientation stays a rotation (orthonormal) whatever
/// the step. First order in `w dt` (≪ 1 in any stable run); orientations are
/// outputs only (a sphere's forces do not depend on them), so no trigonometry
/// in the step.
#[inline]
pub fn rotate(q: &mut UnitQuaternion<f64>, w: &V3, dt: f64) {
    let h = 0.5 * dt;
    let (a, b) = (q.w, q.imag());
    let dw = -h * w.dot(&b);
    let dv = (w * a + w.cross(&b)) * h;
    let raw = nalgebra::Quaternion::new(a + dw, b[0] + dv[0], b[1] + dv[1], b[2] + dv[2]);
    // |raw|² = 1 + ε with ε = (|w| dt/2)² (+ round-off): for |ε| < 1e-8 one Newton
    // step 1 − ε/2 gives 1/|raw| to within 3ε²/8 < 4e-17, below round-off,
    // without a square root and a division; otherwise the exact inverse norm.
    let n2 = raw.norm_squared();
    let eps = n2 - 1.0;
    let inv = if eps.abs() < 1e-8 { 1.0 - 0.5 * eps } else { 1.0 / n2.sqrt() };
    *q = UnitQuaternion::new_unchecked(raw * inv);
}
