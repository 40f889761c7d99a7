//! The rigid body set of the 2D engines (NSCD and planar MD), stored as flat arrays.
//!
//! Each body has the generalized coordinates `q = (x, y, θ)` of its centre of
//! mass and orientation, and velocities `u = (vx, vy, ω)` (Saussine et al. 2006,
//! §2.1: for a rigid body the inertia block is constant and diagonal). The
//! inverse mass is kept per degree of freedom so that fixed bodies and imposed
//! velocity components simply have a zero entry: contacts cannot move them.
//!
//! Building bodies in code: [`BodyInfo::new`] takes a shape in its body frame
//! (centroid at the origin) and computes the mass `ρ t A` and the inertia
//! `ρ t J` about the centroid, with `t` the out-of-plane thickness (the prism a
//! 2D body stands for, [`crate::geometry`]); [`BodyInfo::polygon`],
//! [`BodyInfo::compound`] and [`BodyInfo::disc`] take the shape where it is in
//! the world and also return the position `q = (x_c, y_c, 0)` of its centroid to
//! [`Bodies::push`]. [`BodyInfo::into_fixed`], [`BodyInfo::with_imposed`] and
//! [`BodyInfo::with_load`] make it fixed, drive it, load it. Scenes build their
//! bodies through the same constructor and [`centroid_state`].
//!
//! ```
//! use ballast::nscd::{BodyInfo, Harmonic, Load, NscdParams, System};
//! let mut sys = System::new(NscdParams::default(), 1);
//! // A 1 m × 0.2 m floor, fixed; a 0.1 m square of granite (2700 kg/m³) on it,
//! // both 1 m thick; world coordinates (m), counter-clockwise.
//! let (floor, q) = BodyInfo::polygon("floor", &[[-0.5, -0.2], [0.5, -0.2], [0.5, 0.0], [-0.5, 0.0]], 0, 2700.0, 1.0)?;
//! sys.bodies.push(floor.into_fixed(), q, [0.0; 3]);
//! let (block, q) = BodyInfo::polygon("block", &[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]], 0, 2700.0, 1.0)?;
//! assert!((q[0] - 0.05).abs() < 1e-15 && (q[1] - 0.05).abs() < 1e-15); // the centroid
//! assert!((block.mass - 27.0).abs() < 1e-12); // ρ a² t
//! let block = block.with_load(Load::new([0.0, -1.0], Harmonic::constant(100.0))); // 100 N down
//! sys.bodies.push(block, q, [0.0; 3]);
//! # Ok::<(), ballast::Error>(())
//! ```

use super::loads::{Imposed, Load};
use crate::error::{Error, Result};
use crate::geometry::{perp, rotate, Compound, ConvexPolygon, Shape, Vec2};
use serde::{Deserialize, Serialize};

/// Static description of one body (cold data).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BodyInfo {
    /// Name from the scene (may be empty).
    pub name: String,
    /// Shape in the body frame, centroid at the origin.
    pub shape: Shape,
    /// Index of the body's material.
    pub material: usize,
    /// Mass (kg).
    pub mass: f64,
    /// Polar moment of inertia about the centre of mass (kg·m²).
    pub inertia: f64,
    /// A fixed body never moves.
    pub fixed: bool,
    /// Imposed velocity components.
    pub imposed: Imposed,
    /// External forces applied at the centre of mass.
    pub loads: Vec<Load>,
}

impl BodyInfo {
    /// A free body (not fixed, no imposed velocity, no load) of `shape`, given in
    /// its body frame with its centroid at the origin (as [`ConvexPolygon::new`],
    /// [`ConvexPolygon::regular`], [`Compound::new`] and [`Shape::disc`] give it),
    /// made of material `material` (an index of the system's materials) of
    /// `density` (kg/m³), as a prism of `thickness` (m) out of the plane: mass
    /// `ρ t A` (kg) and polar inertia `ρ t J` about the centroid (kg·m²)
    /// ([`Shape::mass_properties`]; a scene's `simulation.thickness` defaults to 1 m).
    /// Push it with the position of its centroid.
    ///
    /// # Errors
    /// [`Error::Scene`] if `density` or `thickness` is not positive and finite, or
    /// the mass or inertia is not (a shape too small or too large for `f64`).
    pub fn new(name: impl Into<String>, shape: Shape, material: usize, density: f64, thickness: f64) -> Result<Self> {
        let name = name.into();
        let who = || crate::error::clip(&name);
        for (what, v, unit) in [("density", density, "kg/m^3"), ("thickness", thickness, "m")] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Scene(format!(
                    "body '{}': {what} must be positive and finite, got {v} {unit}",
                    who()
                )));
            }
        }
        let (mass, inertia) = shape.mass_properties(density, thickness);
        if !(mass.is_finite() && mass > 0.0 && inertia.is_finite() && inertia > 0.0) {
            return Err(Error::Scene(format!("body '{}': {}", who(), mass_error(mass, inertia))));
        }
        Ok(Self { name, shape, material, mass, inertia, fixed: false, imposed: Imposed::default(), loads: Vec::new() })
    }

    /// A free convex polygon whose `vertices` (m) are given where they are in the
    /// world, counter-clockwise: the body (its shape re-centred on the centroid,
    /// mass and inertia as [`BodyInfo::new`]) and the position `q = (x_c, y_c, 0)`
    /// of its centroid (m, m, rad) to [`Bodies::push`] it at.
    ///
    /// # Errors
    /// [`Error::Geometry`] if the polygon is refused ([`ConvexPolygon::new`]);
    /// those of [`BodyInfo::new`].
    pub fn polygon(
        name: impl Into<String>,
        vertices: &[[f64; 2]],
        material: usize,
        density: f64,
        thickness: f64,
    ) -> Result<(Self, [f64; 3])> {
        let (polygon, c) = ConvexPolygon::new(vertices)?;
        Ok((Self::new(name, Shape::Polygon(polygon), material, density, thickness)?, [c.x, c.y, 0.0]))
    }

    /// A free compound body (a rigid union of convex polygons that may share
    /// edges but not overlap), each part a vertex list (m) where it is in the
    /// world, counter-clockwise: the body and the position `q = (x_c, y_c, 0)`
    /// of the union's centroid, as [`BodyInfo::polygon`].
    ///
    /// # Errors
    /// [`Error::Geometry`] if the parts are refused ([`Compound::new`]); those of
    /// [`BodyInfo::new`].
    pub fn compound(
        name: impl Into<String>,
        parts: &[Vec<[f64; 2]>],
        material: usize,
        density: f64,
        thickness: f64,
    ) -> Result<(Self, [f64; 3])> {
        let (compound, c) = Compound::new(parts)?;
        Ok((Self::new(name, Shape::Compound(compound), material, density, thickness)?, [c.x, c.y, 0.0]))
    }

    /// A free disc of `radius` (m) centred at `centre` (m): the body (mass
    /// `ρ t π r²`, inertia `ρ t π r⁴ / 2`) and `q = (x_c, y_c, 0)`.
    ///
    /// # Errors
    /// [`Error::Geometry`] if the radius is not positive and finite; those of
    /// [`BodyInfo::new`].
    pub fn disc(
        name: impl Into<String>,
        centre: [f64; 2],
        radius: f64,
        material: usize,
        density: f64,
        thickness: f64,
    ) -> Result<(Self, [f64; 3])> {
        Ok((Self::new(name, Shape::disc(radius)?, material, density, thickness)?, [centre[0], centre[1], 0.0]))
    }

    /// The same body, fixed: it never moves (its velocity is zero whatever is
    /// pushed, its imposed velocities and loads are ignored); its mass and
    /// inertia are kept (they enter no equation).
    pub fn into_fixed(mut self) -> Self {
        self.fixed = true;
        self
    }

    /// The same body with `imposed` velocity components ([`Imposed`]: each of
    /// `vx`, `vy` (m/s), spin (rad/s) a [`super::Harmonic`] of time or free),
    /// replacing any it had. An imposed component takes its value at `t = 0` when
    /// pushed, whatever velocity is given, and contacts cannot change it.
    pub fn with_imposed(mut self, imposed: Imposed) -> Self {
        self.imposed = imposed;
        self
    }

    /// The same body with `load` (N, at the centre of mass) added to its loads.
    pub fn with_load(mut self, load: Load) -> Self {
        self.loads.push(load);
        self
    }
}

/// The message of a mass or inertia that is not positive and finite.
pub(crate) fn mass_error(mass: f64, inertia: f64) -> String {
    format!("mass {mass:e} kg or inertia {inertia:e} kg m^2 (density*thickness*area) is not positive and finite")
}

/// The state `(q, u)` of a body's centre of mass from that of a frame attached
/// to it (a scene's body frame): `centroid` (m) is the centroid in that frame,
/// `position` (m) and `angle` (rad) place the frame's origin, `velocity` (m/s) is
/// the velocity of that origin and `spin` (rad/s) the body's. With `R` the
/// rotation by `angle`: `q = (position + R c, angle)`,
/// `u = (velocity + spin × R c, spin)`.
pub fn centroid_state(
    centroid: Vec2,
    position: [f64; 2],
    angle: f64,
    velocity: [f64; 2],
    spin: f64,
) -> ([f64; 3], [f64; 3]) {
    let (s, c) = angle.sin_cos();
    let rc = rotate(centroid, c, s);
    let q = [position[0] + rc.x, position[1] + rc.y, angle];
    let vc = Vec2::new(velocity[0], velocity[1]) + spin * perp(rc);
    (q, [vc.x, vc.y, spin])
}

/// Default alert distance of a scene, as a fraction of the smallest inner
/// radius of the non-fixed bodies (of all bodies if none moves) (m/m).
pub const DEFAULT_ALERT_FRACTION: f64 = 0.01;

/// [`DEFAULT_ALERT_FRACTION`] × the smallest inner radius (m) of the bodies given
/// as `(fixed, inner radius)`: of the non-fixed ones, or of all if none moves
/// (infinite if there is none). Scenes of both 2D engines and [`Bodies::default_alert_distance`].
pub fn default_alert_distance(bodies: impl Iterator<Item = (bool, f64)> + Clone) -> f64 {
    let inner = |mobile_only: bool| {
        bodies.clone().filter(|&(fixed, _)| !mobile_only || !fixed).map(|(_, r)| r).fold(f64::INFINITY, f64::min)
    };
    let r = if bodies.clone().any(|(fixed, _)| !fixed) { inner(true) } else { inner(false) };
    DEFAULT_ALERT_FRACTION * r
}

/// The alert distance (m) of a body set without bodies (and the NSCD engine's
/// default for a system built in code): 0.1 mm.
pub const EMPTY_ALERT_DISTANCE: f64 = 1e-4;

/// The body collection, with hot arrays laid out for the solvers.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Bodies {
    /// Static description of each body.
    pub info: Vec<BodyInfo>,
    /// `(x, y, θ)`: centre of mass (m) and angle (rad).
    pub q: Vec<[f64; 3]>,
    /// `(vx, vy, ω)`: velocity of the centre of mass (m/s) and spin (rad/s).
    pub u: Vec<[f64; 3]>,
    /// Inverse mass per degree of freedom (1/kg, 1/kg, 1/(kg·m²)); zero when
    /// the body is fixed or the component is imposed.
    pub inv_m: Vec<[f64; 3]>,
}

impl Bodies {
    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// True if there are no bodies.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Adds a body whose centre of mass is at `q = (x, y, θ)` (m, m, rad) with
    /// velocity `u = (vx, vy, ω)` (m/s, m/s, rad/s); returns its index. A fixed
    /// body gets `u = 0` and zero inverse masses; an imposed component takes its
    /// value at `t = 0` and a zero inverse mass.
    pub fn push(&mut self, info: BodyInfo, q: [f64; 3], u: [f64; 3]) -> usize {
        let mut inv = [1.0 / info.mass, 1.0 / info.mass, 1.0 / info.inertia];
        if info.fixed {
            inv = [0.0; 3];
        }
        let mut u = u;
        if info.fixed {
            u = [0.0; 3];
        }
        if !info.fixed {
            for d in 0..3 {
                if let Some(f) = info.imposed.dof[d] {
                    inv[d] = 0.0;
                    u[d] = f.at(0.0);
                }
            }
        }
        self.info.push(info);
        self.q.push(q);
        self.u.push(u);
        self.inv_m.push(inv);
        self.q.len() - 1
    }

    /// Whether body `i` can move under contact forces in any direction.
    #[inline]
    pub fn is_mobile(&self, i: usize) -> bool {
        self.inv_m[i].iter().any(|&x| x > 0.0)
    }

    /// The alert distance (m) a scene gets by default:
    /// [`DEFAULT_ALERT_FRACTION`] × the smallest inner radius of the
    /// non-fixed bodies (of all bodies if none moves); the default of
    /// [`EMPTY_ALERT_DISTANCE`] (1e-4 m) if there is no body. Set it on a system built
    /// in code with `sys.params.alert_distance = sys.bodies.default_alert_distance()`.
    pub fn default_alert_distance(&self) -> f64 {
        if self.is_empty() {
            return EMPTY_ALERT_DISTANCE;
        }
        default_alert_distance(self.info.iter().map(|b| (b.fixed, b.shape.inner_radius())))
    }

    /// Kinetic energy ½ Σ (m v² + I ω²) of all non-fixed bodies (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.info
            .iter()
            .zip(&self.u)
            .filter(|(b, _)| !b.fixed)
            .map(|(b, u)| 0.5 * (b.mass * (u[0] * u[0] + u[1] * u[1]) + b.inertia * u[2] * u[2]))
            .sum()
    }

    /// The lowest point of the non-fixed bodies along `up` (m; their bounding
    /// circles), 0 if there is none.
    pub fn lowest_point(&self, up: [f64; 2]) -> f64 {
        let low = (0..self.len())
            .filter(|&i| !self.info[i].fixed)
            .map(|i| {
                let q = self.q[i];
                q[0] * up[0] + q[1] * up[1] - self.info[i].shape.bounding_radius()
            })
            .fold(f64::INFINITY, f64::min);
        if low.is_finite() {
            low
        } else {
            0.0
        }
    }

    /// Gravitational energy `Σ m |g| h` of the non-fixed bodies (J) under
    /// `gravity` (m/s²), `h` the height of the centre of mass above `reference`
    /// (m, along [`up`]).
    pub fn gravitational_energy(&self, gravity: [f64; 2], reference: f64) -> f64 {
        let gn = gravity[0].hypot(gravity[1]);
        if gn == 0.0 {
            return 0.0;
        }
        let up = up(gravity);
        (0..self.len())
            .filter(|&i| !self.info[i].fixed)
            .map(|i| self.info[i].mass * gn * (self.q[i][0] * up[0] + self.q[i][1] * up[1] - reference))
            .sum()
    }

    /// Moves the bodies of `c` to its positions `(x, y, θ)` and sets every
    /// velocity to zero, an imposed component to its value at `time` (s): the
    /// write-back of both 2D engines, which then forget their contact memory.
    ///
    /// # Errors
    /// [`Error::Scene`] if `c` has not 3 coordinates per body, names an unknown
    /// or fixed body or holds a non-finite value; the bodies are then unchanged.
    pub fn place(&mut self, c: &crate::engine::Configuration, time: f64) -> Result<()> {
        c.check(3, self.len())?;
        if let Some(&i) = c.bodies.iter().find(|&&i| self.info[i].fixed) {
            return Err(Error::Scene(format!(
                "configuration: body {i} ('{}') is fixed",
                crate::error::clip(&self.info[i].name)
            )));
        }
        for (k, &i) in c.bodies.iter().enumerate() {
            self.q[i].copy_from_slice(c.body(k));
        }
        for (info, u) in self.info.iter().zip(self.u.iter_mut()) {
            *u = [0.0; 3];
            if !info.fixed {
                for (v, f) in u.iter_mut().zip(&info.imposed.dof) {
                    if let Some(f) = f {
                        *v = f.at(time);
                    }
                }
            }
        }
        Ok(())
    }
}

/// The unit vector against `gravity` (`+y` without gravity).
pub fn up(gravity: [f64; 2]) -> [f64; 2] {
    let n = gravity[0].hypot(gravity[1]);
    if n > 0.0 {
        [-gravity[0] / n, -gravity[1] / n]
    } else {
        [0.0, 1.0]
    }
}
