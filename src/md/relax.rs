//! The relaxation functional of Karrech et al. 2007, eq. (29), for the MD
//! engine: with every velocity zero and the tangential memory of the contacts
//! forgotten, the potential energy of the spheres,
//!
//! `F(x) = Σ_β m_β |g| h_β + Σ_contacts ψ(δ)`,  `ψ = λ_n δ^(γ+1)/(γ+1)`
//!
//! (`h` the height of a centre along `−g`; `γ = 3/2`, `λ_n = 4/3 E* √R*` for the
//! Hertz law, `γ = 1`, `λ_n = k_n` for the linear law; a contact with a
//! symmetry image counts half, as in the engine's energy), whose gradient is
//! minus the gravity and contact forces the engine's own force loop computes
//! there (the dashpots and tangential springs are zero at rest). The walls are
//! held (a servo wall at its position: the external-work term of eq. 29 acts on
//! degrees of freedom that do not move), and so are the spheres the settings
//! hold; the other spheres' centres are the variables (their orientation plays
//! no part in a sphere's contacts).

use super::contact::History;
use super::system::MdSystem;
use crate::engine::relax::{minimise, Functional, RelaxReport, RelaxSettings};
use crate::error::{Error, Result};
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Eq. (29) over the free spheres of a system (module doc).
pub struct Potential<'a> {
    sys: &'a mut MdSystem,
    free: Vec<usize>,
    /// The last point evaluated, with its largest overlap (m).
    last: Option<(Vec<f64>, f64)>,
}

impl<'a> Potential<'a> {
    /// The functional of `sys` with the spheres not in `held` free; every
    /// velocity is set to zero.
    pub fn new(sys: &'a mut MdSystem, held: &[usize]) -> Self {
        let p = &mut sys.particles;
        p.v.iter_mut().chain(p.w.iter_mut()).for_each(|v| *v = V3::zeros());
        for w in &mut sys.walls {
            w.s_dot = 0.0;
        }
        let free = (0..p.len()).filter(|i| !held.contains(i)).collect();
        Self { sys, free, last: None }
    }

    /// The centres of the free spheres (m), 3 per sphere.
    pub fn start(&self) -> Vec<f64> {
        self.free.iter().flat_map(|&i| self.sys.particles.x[i].iter().copied().collect::<Vec<_>>()).collect()
    }

    /// The free spheres.
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Moves the free spheres to `x`, rebuilds the neighbour list when a sphere
    /// went further than half the skin since the last build, mirrors the images,
    /// forgets the contact memory and evaluates the forces.
    fn place(&mut self, x: &[f64]) -> Result<(f64, f64)> {
        let sys = &mut *self.sys;
        for (k, &i) in self.free.iter().enumerate() {
            sys.particles.x[i] = V3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
        }
        let n = sys.particles.len();
        let built = sys.neighbours.x_build.len() == n;
        let moved = if built {
            (0..n).map(|i| (sys.particles.x[i] - sys.neighbours.x_build[i]).norm()).fold(0.0, f64::max)
        } else {
            f64::INFINITY
        };
        if 2.0 * moved > sys.settings.skin {
            sys.rebuild();
        }
        sys.ghosts.update(&sys.particles);
        sys.neighbours.hist.iter_mut().for_each(|h| *h = History::default());
        sys.wall_hist.iter_mut().for_each(|h| *h = History::default());
        sys.relaxing = true;
        let stats = sys.forces(0.0, true, false);
        sys.relaxing = false;
        let (stats, _, _) = stats?;
        let value = stats.elastic_energy + sys.gravitational_energy();
        self.last = Some((x.to_vec(), stats.max_overlap));
        Ok((value, stats.max_overlap))
    }
}

impl Functional for Potential<'_> {
    fn metric(&self) -> Vec<f64> {
        self.free.iter().flat_map(|&i| [self.sys.particles.m[i]; 3]).collect()
    }

    fn evaluate(&mut self, x: &[f64], grad: &mut [f64]) -> Result<f64> {
        let (value, _) = self.place(x)?;
        let p = &self.sys.particles;
        let g = self.sys.settings.gravity;
        for (k, &i) in self.free.iter().enumerate() {
            let f = p.f[i] + g * p.m[i];
            for d in 0..3 {
                grad[3 * k + d] = -f[d];
            }
        }
        if !value.is_finite() {
            return Err(Error::Scene("relaxation: the functional is not finite".into()));
        }
        Ok(value)
    }

    fn max_overlap(&mut self, x: &[f64]) -> Result<f64> {
        if let Some((at, overlap)) = &self.last {
            if at.as_slice() == x {
                return Ok(*overlap);
            }
        }
        Ok(self.place(x)?.1)
    }
}

impl MdSystem {
    /// Minimises eq. (29) over the spheres not held (module doc) until the largest
    /// overlap is at most `settings.tolerance`, then writes the result back as
    /// [`MdSystem::set_configuration`] does (velocities zero, contact memory
    /// forgotten, neighbour list, forces and integrator history rebuilt). On an
    /// error the configuration is the one before.
    ///
    /// # Errors
    /// [`Error::Scene`] for settings out of range or a held sphere that does not
    /// exist; [`Error::Diverged`] if a configuration the minimiser tries has a
    /// runaway overlap (more than half a radius).
    pub fn relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport> {
        settings.check()?;
        let n = self.particles.len();
        if let Some(&i) = settings.held.iter().find(|&&i| i >= n) {
            return Err(Error::Scene(format!("relaxation: held sphere {i} does not exist ({n} spheres)")));
        }
        let before = crate::engine::Engine::configuration(self);
        let outcome = {
            let mut potential = Potential::new(self, &settings.held);
            let mut x = potential.start();
            minimise(&mut potential, &mut x, settings).map(|r| (r, x, potential.free().to_vec()))
        };
        match outcome {
            Ok((report, x, free)) => {
                let mut c = before;
                for (k, &i) in free.iter().enumerate() {
                    let at = c.bodies.iter().position(|&b| b == i).expect("every sphere is in the configuration");
                    c.body_mut(at)[..3].copy_from_slice(&x[3 * k..3 * k + 3]);
                }
                self.set_configuration(&c)?;
                Ok(report)
            }
            Err(e) => {
                self.set_configuration(&before)?;
                Err(e)
            }
        }
    }
}
