//! Relaxation of a 3D configuration (the settlement driver's step after an extrapolation; Karrech et al. 2007,
//! §4, carried over to rigid bodies as the 2D engines do, [`crate::plane::relax`]): the extrapolated configuration
//! `q̂` projected onto the configurations without overlap in the metric of the masses, approached by the same
//! quadratic penalty,
//!
//! `Φ(q) = ½ Σ_d m_d (q_d − q̂_d)² + ½ k Σ_c min(0, g_c(q))²`,
//!
//! the first sum over the free degrees of freedom (not fixed, not imposed, not held), the second over the contact
//! points of the 3D detector ([`super::detection`], alert distance 0) with their gaps `g_c` (m).
//!
//! **Rotations.** A body's orientation is `R = R̂ exp(ψ̂)`, `R̂` the extrapolated one and `ψ` a rotation vector in
//! the body's principal frame, the variables `ψ_1, ψ_2, ψ_3` (rad) with the masses `I_1, I_2, I_3` (kg·m²): the
//! kinetic metric `½ ψᵀ I ψ` is diagonal there, as the engine's spin is. The gap's gradient with respect to `ψ` is
//! `J_r(ψ)ᵀ (ρ × Rᵀ n)`, the contact row's rotational direction (`crate::space::bodies::gen_dir`) through the
//! right Jacobian of SO(3), `J_r(ψ) = I − (1 − cos θ)/θ² ψ̂ + (θ − sin θ)/θ³ ψ̂²` (θ = |ψ|), exact, so that the
//! minimiser's line searches see the functional they descend.
//!
//! The penalty's stiffness starts at `k = 10 m_max δ₀ / tol` and is raised tenfold up to three times while the
//! minimiser stops short of the tolerance, as in 2D (docs/relaxation.md). Springs are left out: they act on the
//! next steps, not on the geometry.

use super::bodies::{gen_dir, Bodies};
use super::detection::Detector;
use crate::engine::relax::{minimise, Functional, RelaxReport, RelaxSettings};
use crate::error::{Error, Result};
use crate::geometry::{Pose, Vec3};
use nalgebra::UnitQuaternion;

/// `J_r(ψ)ᵀ a`: `a + c₁ ψ × a + c₂ ψ × (ψ × a)` with `c₁ = (1 − cos θ)/θ²`, `c₂ = (θ − sin θ)/θ³` (module doc),
/// their series below θ = 1e-4 (the next terms are below 1e-17 there).
pub fn right_jacobian_transpose(psi: &Vec3, a: &Vec3) -> Vec3 {
    let t2 = psi.norm_squared();
    let (c1, c2) = if t2 < 1e-8 {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let pa = psi.cross(a);
    a + pa * c1 + psi.cross(&pa) * c2
}

/// The penalised projection of a 3D configuration (module doc).
pub struct Projection3<'a> {
    bodies: &'a Bodies,
    /// Free degrees of freedom: (body, dof 0..6).
    vars: Vec<(usize, usize)>,
    /// Variable of each body's dof, `usize::MAX` if not free.
    var_of: Vec<[usize; 6]>,
    /// The configuration projected: the centroid coordinates, and 0 for the rotation variables.
    target: Vec<f64>,
    mass: Vec<f64>,
    /// Penalty stiffness `k` (N/m per contact point).
    pub stiffness: f64,
    poses: Vec<Pose>,
    /// Bodies with a variable (the detector tests pairs with at least one).
    movable: Vec<bool>,
    detector: Detector,
}

impl<'a> Projection3<'a> {
    /// The projection of the current configuration of `bodies`, every free degree of freedom of the bodies not
    /// in `held` moving, with penalty stiffness `stiffness` (N/m).
    pub fn new(bodies: &'a Bodies, held: &[usize], stiffness: f64) -> Self {
        let b = bodies;
        let (mut vars, mut target, mut mass) = (Vec::new(), Vec::new(), Vec::new());
        let mut var_of = vec![[usize::MAX; 6]; b.len()];
        for (i, slots) in var_of.iter_mut().enumerate() {
            if b.info[i].fixed || held.contains(&i) {
                continue;
            }
            for (d, slot) in slots.iter_mut().enumerate() {
                if b.inv_m[i][d] > 0.0 {
                    *slot = vars.len();
                    vars.push((i, d));
                    target.push(if d < 3 { b.pose[i].position[d] } else { 0.0 });
                    mass.push(1.0 / b.inv_m[i][d]);
                }
            }
        }
        let movable = var_of.iter().map(|s| s.iter().any(|&v| v != usize::MAX)).collect();
        Self {
            bodies,
            vars,
            var_of,
            target,
            mass,
            stiffness,
            poses: b.pose.clone(),
            movable,
            detector: Detector::default(),
        }
    }

    /// The free coordinates of the current configuration (m, and 0 rad for the rotations).
    pub fn start(&self) -> Vec<f64> {
        self.target.clone()
    }

    /// The rotation variables of body `i` at `x` (zero where not free).
    fn psi(&self, i: usize, x: &[f64]) -> Vec3 {
        Vec3::from_fn(|k, _| match self.var_of[i][3 + k] {
            usize::MAX => 0.0,
            v => x[v],
        })
    }

    /// The free coordinates `x` written into the poses of every body.
    pub fn place(&mut self, x: &[f64]) {
        for i in 0..self.bodies.len() {
            if !self.movable[i] {
                continue;
            }
            let start = &self.bodies.pose[i];
            let mut position = start.position;
            for d in 0..3 {
                let v = self.var_of[i][d];
                if v != usize::MAX {
                    position[d] = x[v];
                }
            }
            let psi = self.psi(i, x);
            let rotation =
                UnitQuaternion::new_normalize((start.rotation * UnitQuaternion::from_scaled_axis(psi)).into_inner());
            self.poses[i] = Pose { position, rotation };
        }
    }

    /// The poses of every body after [`Projection3::place`].
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    fn detect(&mut self, x: &[f64]) {
        self.place(x);
        // Only overlapping pairs matter: alert distance 0.
        self.detector.run(&self.bodies.info, &self.poses, &self.movable, 0.0);
    }

    /// The heaviest free body's mass (kg).
    pub fn heaviest(&self) -> f64 {
        self.vars.iter().filter(|(_, d)| *d < 3).map(|&(i, _)| self.bodies.info[i].mass).fold(0.0, f64::max)
    }
}

impl Functional for Projection3<'_> {
    fn metric(&self) -> Vec<f64> {
        self.mass.clone()
    }

    fn evaluate(&mut self, x: &[f64], grad: &mut [f64]) -> Result<f64> {
        let mut phi = 0.0;
        for (k, g) in grad.iter_mut().enumerate() {
            let dx = x[k] - self.target[k];
            phi += 0.5 * self.mass[k] * dx * dx;
            *g = self.mass[k] * dx;
        }
        self.detect(x);
        let k = self.stiffness;
        for c in &self.detector.found {
            if c.gap >= 0.0 {
                continue;
            }
            phi += 0.5 * k * c.gap * c.gap;
            let f = k * c.gap;
            for (body, sign) in [(c.key.0 as usize, 1.0), (c.key.1 as usize, -1.0)] {
                if !self.movable[body] {
                    continue;
                }
                let pose = &self.poses[body];
                let rho = pose.rotation.inverse_transform_vector(&(c.position - pose.position));
                let h = gen_dir(pose, &rho, &c.normal);
                let turn = right_jacobian_transpose(&self.psi(body, x), &Vec3::new(h[3], h[4], h[5]));
                for d in 0..6 {
                    let v = self.var_of[body][d];
                    if v != usize::MAX {
                        grad[v] += sign * f * if d < 3 { h[d] } else { turn[d - 3] };
                    }
                }
            }
        }
        if !phi.is_finite() {
            return Err(Error::Scene("relaxation: the functional is not finite".into()));
        }
        Ok(phi)
    }

    fn max_overlap(&mut self, x: &[f64]) -> Result<f64> {
        self.detect(x);
        Ok(self.detector.found.iter().map(|c| -c.gap).fold(0.0, f64::max))
    }
}

/// Removes the overlaps of the configuration of `bodies`, moving them as little as possible in the metric of
/// their masses and moments (module doc), until the largest overlap is at most `settings.tolerance`: the report
/// and the pose of every body, which the engine writes back (velocities zeroed, contact memory forgotten).
/// `bodies` is not changed.
///
/// # Errors
/// [`Error::Scene`] for settings out of range or a held body that does not exist.
pub fn project(bodies: &Bodies, settings: &RelaxSettings) -> Result<(RelaxReport, Vec<Pose>)> {
    settings.check()?;
    if let Some(&i) = settings.held.iter().find(|&&i| i >= bodies.len()) {
        return Err(Error::Scene(format!("relaxation: held body {i} does not exist ({} bodies)", bodies.len())));
    }
    let mut projection = Projection3::new(bodies, &settings.held, 0.0);
    let mut x = projection.start();
    let before = projection.max_overlap(&x)?;
    projection.stiffness = 10.0 * projection.heaviest().max(f64::MIN_POSITIVE) * (before / settings.tolerance).max(1.0);
    let mut report = minimise(&mut projection, &mut x, settings)?;
    let mut raises = 0;
    while !report.converged && raises < 3 && report.iterations < settings.max_iterations {
        raises += 1;
        projection.stiffness *= 10.0;
        let left = RelaxSettings { max_iterations: settings.max_iterations - report.iterations, ..settings.clone() };
        let next = minimise(&mut projection, &mut x, &left)?;
        report.iterations += next.iterations;
        report.evaluations += next.evaluations;
        // A raised stiffness is a new functional: its own sequence.
        report.functional = next.functional;
        report.max_overlap_after = next.max_overlap_after;
        report.converged = next.converged;
        report.reason = next.reason;
    }
    projection.place(&x);
    report.max_overlap_before = before;
    report.largest_move = x.iter().zip(projection.start()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok((report, projection.poses().to_vec()))
}
