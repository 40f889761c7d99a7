//! Relaxation of a 2D configuration (the settlement driver's step after an
//! extrapolation; Karrech et al. 2007, §4, carried over to rigid bodies), for
//! both 2D engines: the NSCD engine, whose rigid bodies have no contact
//! potential, and the planar MD engine, whose soft contacts are relaxed the same
//! way so that the two methods restart from configurations made alike.
//!
//! Rigid bodies have no contact potential, so the paper's functional (29) has
//! nothing to balance gravity with: minimised, a frictionless rigid assembly
//! would flow. What an extrapolated NSCD configuration needs is its overlaps
//! removed while the bodies move as little as possible, so that the
//! extrapolated settlement is kept. That is the projection of the extrapolated
//! configuration `q̂` onto the configurations without overlap in the metric of
//! the masses (the kinetic metric of Moreau's sweeping process), approached by
//! a quadratic penalty:
//!
//! `Φ(q) = ½ Σ_d m_d (q_d − q̂_d)² + ½ k Σ_c min(0, g_c(q))²`,
//!
//! the sum over the free degrees of freedom (not fixed, not imposed, not held;
//! `m_d` the mass or the moment of inertia) and over the contact points of the
//! shadow-overlap detector with their gaps `g_c` (m); `∂g_c/∂q` are the normal
//! rows `(n, r × n)` of the two bodies (`super::contact::gen_dir`). At the
//! penalty's minimum an overlap `δ` left between a body of mass `m` and a fixed
//! one is `δ₀ m/(m + k)` of the initial `δ₀`, so the stiffness starts at
//! `k = 10 m_max δ₀ / tol` (`m_max` the heaviest free body) and is raised tenfold,
//! up to three times, while the minimiser stops short of the tolerance. The
//! minimisation stops as soon as the largest overlap is at most the tolerance
//! (docs/relaxation.md). The sublayer springs are left out: they act on the
//! next steps, not on the geometry.

use super::detection::Detector;
use super::springs::gen_dir;
use super::Bodies;
use crate::engine::relax::{penalised_projection, Functional, Penalty, RelaxReport, RelaxSettings};
use crate::error::{Error, Result};
use crate::geometry::Vec2;

/// The penalised projection of a configuration (module doc).
pub struct Projection<'a> {
    bodies: &'a Bodies,
    /// Free degrees of freedom: (body, coordinate).
    vars: Vec<(usize, usize)>,
    /// Variable of each body's coordinate, `usize::MAX` if not free.
    var_of: Vec<[usize; 3]>,
    /// The configuration projected, `q̂` of the free coordinates.
    target: Vec<f64>,
    mass: Vec<f64>,
    /// Penalty stiffness `k` (J/m², i.e. N/m per contact point).
    pub stiffness: f64,
    q: Vec<[f64; 3]>,
    detector: Detector,
}

impl<'a> Projection<'a> {
    /// The projection of the current configuration of `sys`, every free degree of
    /// freedom of the bodies not in `held` moving, with penalty stiffness `stiffness` (N/m).
    pub fn new(bodies: &'a Bodies, held: &[usize], stiffness: f64) -> Self {
        let b = bodies;
        let mut vars = Vec::new();
        let mut var_of = vec![[usize::MAX; 3]; b.len()];
        for (i, slots) in var_of.iter_mut().enumerate() {
            if b.info[i].fixed || held.contains(&i) {
                continue;
            }
            for (d, slot) in slots.iter_mut().enumerate() {
                if b.inv_m[i][d] > 0.0 {
                    *slot = vars.len();
                    vars.push((i, d));
                }
            }
        }
        let target = vars.iter().map(|&(i, d)| b.q[i][d]).collect();
        let mass = vars.iter().map(|&(i, d)| 1.0 / b.inv_m[i][d]).collect();
        Self { bodies, vars, var_of, target, mass, stiffness, q: b.q.clone(), detector: Detector::default() }
    }

    /// The free coordinates of the current configuration (m, rad).
    pub fn start(&self) -> Vec<f64> {
        self.target.clone()
    }

    /// The free coordinates `x` written into a configuration of every body.
    pub fn place(&mut self, x: &[f64]) {
        for (&(i, d), &v) in self.vars.iter().zip(x) {
            self.q[i][d] = v;
        }
    }

    /// The configuration of every body after [`Projection::place`].
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.q
    }

    fn detect(&mut self, x: &[f64]) {
        self.place(x);
        // Only overlapping pairs matter: alert distance 0.
        self.detector.run(self.bodies, &self.q, 0.0);
    }
}

impl Penalty for Projection<'_> {
    fn heaviest(&self) -> f64 {
        self.vars.iter().filter(|(_, d)| *d < 2).map(|&(i, _)| self.bodies.info[i].mass).fold(0.0, f64::max)
    }

    fn stiffness(&self) -> f64 {
        self.stiffness
    }

    fn set_stiffness(&mut self, k: f64) {
        self.stiffness = k;
    }
}

impl Functional for Projection<'_> {
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
        for (key, c) in &self.detector.found {
            if c.gap >= 0.0 {
                continue;
            }
            phi += 0.5 * k * c.gap * c.gap;
            let f = k * c.gap;
            for (body, sign) in [(key.0 as usize, 1.0), (key.1 as usize, -1.0)] {
                let centre = Vec2::new(self.q[body][0], self.q[body][1]);
                let h = gen_dir(c.point - centre, c.normal);
                for (d, hd) in h.iter().enumerate() {
                    let v = self.var_of[body][d];
                    if v != usize::MAX {
                        grad[v] += sign * f * hd;
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
        Ok(self.detector.found.iter().map(|(_, c)| -c.gap).fold(0.0, f64::max))
    }
}

/// Removes the overlaps of the configuration of `bodies`, moving them as little
/// as possible in the metric of their masses (module doc), until the largest
/// overlap is at most `settings.tolerance`: the report and the positions of
/// every body, which the engine writes back (velocities zeroed, contact memory
/// forgotten). `bodies` is not changed.
///
/// # Errors
/// [`Error::Scene`] for settings out of range or a held body that does not exist.
pub fn project(bodies: &Bodies, settings: &RelaxSettings) -> Result<(RelaxReport, Vec<[f64; 3]>)> {
    settings.check()?;
    if let Some(&i) = settings.held.iter().find(|&&i| i >= bodies.len()) {
        return Err(Error::Scene(format!("relaxation: held body {i} does not exist ({} bodies)", bodies.len())));
    }
    let mut projection = Projection::new(bodies, &settings.held, 0.0);
    let mut x = projection.start();
    let report = penalised_projection(&mut projection, &mut x, settings)?;
    projection.place(&x);
    Ok((report, projection.positions().to_vec()))
}
