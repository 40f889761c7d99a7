//! The 3D NSCD system as an [`Engine`] of the run loop ([`crate::run::Runner`]) and of cyclic drivers: its rows
//! ([`super::rows`]: `series.csv`, `cycles.csv` following a body's height along `−g`), final state (centroids,
//! velocities, spins as world vectors, orientation quaternions), contacts, snapshots ([`super::vtk`]), state
//! checks, and its generalised positions, read and written back.
//!
//! Choices of this implementation:
//!
//! - **Name and dimension**: `"nscd3d"` in the outputs (`final.json`, `run.json`, checkpoints; the scene says
//!   `engine = "nscd"` with `dimension = 3`, as the planar MD engine is `"md2d"`), `DIM = 3`; `ITERATIVE` (NLGS sweeps, criterion and convergence in the
//!   rows and the run's summary).
//! - **Configuration**: `DOF = 6` per body, the centroid `x, y, z` (m) and the **rotation vector** of the
//!   orientation (axis × angle of the rotation from the principal frame to the world, rad, angle in `[0, π]`),
//!   as the MD engine writes its spheres. Not the 7 numbers of a quaternion: the run loop's positions file
//!   (`cycle_bodies.csv`, [`crate::run::positions`]) and the settlement driver (its stages measure a rotation
//!   in radians times a body's size, [`crate::settlement::sweep::stages`]; its fits and interpolations act on
//!   each coordinate alone) need coordinates that are free — any 6 numbers are a configuration, while a
//!   quaternion's 4 must stay on the unit sphere — and of the MD engine's layout. The driver extrapolates the
//!   first three only (`EXTRAPOLATED = 3`: a polyhedron turns by rolling events, not by a creep a law can follow,
//!   as in 2D). [`Engine::set_configuration`] builds the quaternion from the rotation vector (unit by
//!   construction, renormalised) and refuses a non-finite value, a fixed or unknown body, naming it.
//! - **Threads**: the contact solve of a problem of at least `nscd.split_min_rows` rows (default 512) is the
//!   shared domain split (two halves along x swept side by side, then the interface), on two threads when asked;
//!   the detection's narrow phase shares the pairs between the two threads; the numbers do not depend on the
//!   count.
//! - **Coordination**: [`super::measure::coordination`] — per mobile body, the bodies (mobile or fixed) it
//!   touches with a total normal force `Σ r_n > 0` over the pair's contact points of the last step (a pair
//!   counts once); the mean over the mobile bodies that have at least two (rattlers excluded), 0 if none has.
//!   The cycle rows take it over the mobile bodies other than the followed one, as the 2D engines do.
//! - **Potential energy** (when the equilibrium rule asks): `−Σ m g · x` over the mobile bodies.
//! - **Body sizes**: the radius of the sphere of the body's volume, `(3V/4π)^(1/3)` — the 3D analogue of the
//!   2D engines' `√(A/π)` and the MD engine's sphere radius, the contract's scale; infinite for a half-space.
//! - **Relaxation**: the 2D engines' mass-metric projection carried over to 3D ([`crate::space::relax`]: the
//!   centroids and rotation vectors in the principal frames, the moments of inertia as their masses, the gaps'
//!   gradients through SO(3)'s right Jacobian), written back by [`System3::place`].

use super::measure::{self, Coordination};
use super::rows::{CycleRow3, CycleState3, SeriesRow3, CYCLE3_COLUMNS, SERIES3_COLUMNS};
use super::system::{StepStats3, System3};
use crate::engine::contacts::{ContactKind, ContactRow};
use crate::engine::final_state::{BodyState, FinalState, Spin};
use crate::engine::{Configuration, Energies, Engine, RelaxReport, RelaxSettings, StepSummary};
use crate::error::{Error, Result};
use crate::geometry::{Solid, Vec3};
use crate::io::vtk::PvdCollection;
use std::path::Path;

impl System3 {
    /// The unit vector against gravity (`+z` without gravity).
    fn up(&self) -> Vec3 {
        measure::up(&self.params.gravity)
    }
}

impl Engine for System3 {
    const NAME: &'static str = "nscd3d";
    const DOF: usize = 6;
    const DIM: usize = 3;
    const EXTRAPOLATED: usize = 3;
    const ITERATIVE: bool = true;
    const SOLVER_KEYS: &'static [&'static str] = &crate::nscd::method::NlgsSettings::SCENE_KEYS;
    type Stats = StepStats3;
    type Row = SeriesRow3;
    type CycleState = CycleState3;
    type CycleRow = CycleRow3;

    fn step(&mut self) -> Result<StepStats3> {
        System3::step(self)
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn steps_done(&self) -> u64 {
        self.steps
    }

    fn dt(&self) -> f64 {
        self.params.dt
    }

    /// The split contact solve's threads (module doc).
    fn set_threads(&mut self, threads: usize) {
        System3::set_threads(self, threads);
    }

    fn body_count(&self) -> usize {
        self.bodies.len()
    }

    fn summary(s: &StepStats3) -> StepSummary {
        StepSummary {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts as f64,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            iterations: s.nlgs.iterations as u64,
            converged: s.nlgs.converged,
            criterion: s.nlgs.criterion,
        }
    }

    fn energies(&self, s: &StepStats3, potential: bool) -> Energies {
        Energies { kinetic: s.kinetic_energy, potential: if potential { measure::potential_energy(self) } else { 0.0 } }
    }

    fn series_header(&self) -> Vec<String> {
        SERIES3_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn series_row(&self, s: &StepStats3) -> SeriesRow3 {
        SeriesRow3 {
            time_s: s.time,
            kinetic_energy_j: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            iterations: s.nlgs.iterations,
            criterion: s.nlgs.criterion,
            converged: u8::from(s.nlgs.converged),
            mean_overlap_m: s.mean_overlap,
            max_overlap_m: s.max_overlap,
            total_overlap_m: s.total_overlap,
        }
    }

    fn final_state(&self) -> FinalState {
        let b = &self.bodies;
        let bodies = (0..b.len())
            .map(|i| {
                let (v, w) = b.world_velocity(i);
                BodyState {
                    name: b.info[i].name.clone(),
                    position: b.pose[i].position.iter().copied().collect(),
                    angle: None,
                    velocity: v.iter().copied().collect(),
                    spin: Spin::Spatial(w.into()),
                    radius: match b.info[i].solid {
                        Solid::Sphere { radius } => Some(radius),
                        _ => None,
                    },
                    orientation: Some(b.orientation(i)),
                }
            })
            .collect();
        FinalState { engine: Self::NAME.into(), time: self.time, step: self.steps, bodies, walls: Vec::new() }
    }

    /// One row per contact point of the last step; a contact with a fixed body is a `wall` row seen from the
    /// mobile body (normal and forces turned round if the fixed body was the candidate); the force is split into
    /// its normal component `f_n` (along the normal from `b` towards `a`) and its tangential world components.
    fn contact_rows(&self) -> Vec<ContactRow> {
        let (info, h) = (&self.bodies.info, self.params.dt);
        self.contacts()
            .iter()
            .map(|c| {
                let (cand, ant) = (c.key.0 as usize, c.key.1 as usize);
                let (a, b, s) = if info[cand].fixed && !info[ant].fixed { (ant, cand, -1.0) } else { (cand, ant, 1.0) };
                let kind = if info[a].fixed || info[b].fixed { ContactKind::Wall } else { ContactKind::Pair };
                // The force on `a` is `s (P_N n + P_T1 t₁ + P_T2 t₂) / h`, and its normal is `s n`.
                let n = c.frame[0] * s;
                let f_n = c.p[0] / h;
                let f_t = (c.frame[1] * c.p[1] + c.frame[2] * c.p[2]) * (s / h);
                ContactRow {
                    kind,
                    a,
                    a_name: info[a].name.clone(),
                    b,
                    b_name: info[b].name.clone(),
                    point_x_m: c.point.x,
                    point_y_m: c.point.y,
                    point_z_m: Some(c.point.z),
                    normal_x: n.x,
                    normal_y: n.y,
                    normal_z: Some(n.z),
                    gap_m: c.gap,
                    f_n,
                    f_t_x: f_t.x,
                    f_t_y: f_t.y,
                    f_t_z: Some(f_t.z),
                }
            })
            .collect()
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        super::vtk::write_snapshot(pvd, dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        System3::check_state(self)
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        System3::check_same_model(self, fresh)
    }

    fn change_solver(&mut self, fresh: &Self) -> Result<Vec<[String; 3]>> {
        let changes = self.params.nlgs.changes(&fresh.params.nlgs);
        self.params.nlgs = fresh.params.nlgs;
        Ok(changes)
    }

    /// Follows body `body` (required: the settlement of a body is what the 3D cycles report).
    fn cycle_start(&self, body: Option<usize>) -> Result<CycleState3> {
        let body = body.ok_or_else(|| Error::Scene("output.cycles.body: name the followed body".into()))?;
        if body >= self.bodies.len() {
            let n = self.bodies.len();
            return Err(Error::Scene(format!("output.cycles.body: body {body} does not exist ({n} bodies)")));
        }
        let up = self.up();
        Ok(CycleState3::new(body, up.into(), measure::height(self, body, &up)))
    }

    fn cycle_step(&self, c: &mut CycleState3, s: &StepStats3) {
        c.steps += 1;
        c.sum_h += measure::height(self, c.body, &Vec3::from(c.up));
        c.sum_speed += measure::mean_speed(self, c.body);
        c.sum_contacts += s.contacts as f64;
        c.sum_iterations += s.nlgs.iterations as f64;
        c.max_overlap = c.max_overlap.max(s.max_overlap);
        c.sum_mean_overlap += s.mean_overlap;
    }

    fn cycle_end(&self, c: &mut CycleState3, cycle: u64) -> CycleRow3 {
        let k = c.steps.max(1) as f64;
        let grains: Vec<usize> = measure::mobile_bodies(self).into_iter().filter(|&i| i != c.body).collect();
        let row = CycleRow3 {
            cycle,
            time_s: self.time,
            settlement_m: c.h0 - measure::height(self, c.body, &Vec3::from(c.up)),
            settlement_mean_m: c.h0 - c.sum_h / k,
            mean_grain_speed_m_s: c.sum_speed / k,
            contacts: c.sum_contacts / k,
            iterations: c.sum_iterations / k,
            max_overlap_m: c.max_overlap,
            mean_overlap_m: c.sum_mean_overlap / k,
            coordination: measure::coordination(self, &grains, 0.0).z,
        };
        c.restart();
        row
    }

    fn cycle_header(&self) -> Vec<String> {
        CYCLE3_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn settlement(&self, c: &CycleState3) -> Option<f64> {
        (c.body < self.bodies.len()).then(|| c.h0 - measure::height(self, c.body, &Vec3::from(c.up)))
    }

    fn coordination(&self) -> f64 {
        let Coordination { z, .. } = measure::coordination(self, &measure::mobile_bodies(self), 0.0);
        z
    }

    fn mobile_bodies(&self) -> Vec<usize> {
        measure::mobile_bodies(self)
    }

    fn configuration_of(&self, bodies: &[usize]) -> Configuration {
        let mut q = Vec::with_capacity(6 * bodies.len());
        for &i in bodies {
            let pose = &self.bodies.pose[i];
            q.extend(pose.position.iter());
            q.extend(pose.rotation.scaled_axis().iter());
        }
        Configuration { dof: 6, bodies: bodies.to_vec(), q }
    }

    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64> {
        let radius = |volume: f64| (3.0 * volume / (4.0 * std::f64::consts::PI)).cbrt();
        bodies.iter().map(|&i| radius(self.bodies.info[i].solid.mass_properties().0)).collect()
    }

    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize> {
        let count = measure::neighbour_counts(self, 0.0);
        bodies.iter().map(|&i| count[i]).collect()
    }

    fn set_configuration(&mut self, c: &Configuration) -> Result<()> {
        c.check(6, self.bodies.len())?;
        let x: Vec<Vec3> = (0..c.len()).map(|k| Vec3::new(c.body(k)[0], c.body(k)[1], c.body(k)[2])).collect();
        let rotations: Vec<nalgebra::Quaternion<f64>> = (0..c.len())
            .map(|k| {
                let r = c.body(k);
                nalgebra::UnitQuaternion::from_scaled_axis(Vec3::new(r[3], r[4], r[5])).into_inner()
            })
            .collect();
        self.place(&c.bodies, &x, &rotations)
    }

    fn anchored_bodies(&self) -> Vec<usize> {
        crate::space::springs::anchored(&self.springs)
    }

    /// The mass-metric projection of [`crate::space::relax`], written back as a configuration (velocities
    /// zeroed, imposed components at their values now, contact memory forgotten).
    fn relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport> {
        let (report, poses) = crate::space::relax::project(&self.bodies, settings)?;
        let bodies = self.mobile_bodies();
        let x: Vec<Vec3> = bodies.iter().map(|&i| poses[i].position).collect();
        let rotations: Vec<nalgebra::Quaternion<f64>> =
            bodies.iter().map(|&i| poses[i].rotation.into_inner()).collect();
        self.place(&bodies, &x, &rotations)?;
        Ok(report)
    }
}
