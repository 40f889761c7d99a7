//! The MD system as an [`Engine`] of the run loop and of cyclic drivers: its
//! rows of `series.csv` (energies, contacts, overlaps, wall forces and servo
//! positions) and `cycles.csv` (the residual displacements of Karrech et al.
//! 2007 §3), final state, snapshots, and its generalised positions per sphere
//! (centre and rotation vector), read and written back
//! ([`MdSystem::set_configuration`]).
//!
//! A run measures energies and overlaps on every step (`measure_every` = 1 is
//! the default of [`MdSystem`]), so that the largest overlap of `summary.json`
//! is that of the whole run and the equilibrium rule sees every step.

use super::contacts::MdContactKind;
use super::system::{MdStepStats, MdSystem};
use super::walls::Motion;
use crate::engine::contacts::{ContactKind, ContactRow};
use crate::engine::final_state::{BodyState, FinalState, Spin, WallState};
use crate::engine::StepSummary;
use crate::engine::{Configuration, Energies, Engine};
use crate::error::{Error, Result};
use crate::io::vtk::PvdCollection;
use crate::md::rows::{MdCycleRow, MdCycleState, MD_CYCLE_COLUMNS};
use crate::md::rows::{MdSeriesRow, MD_SERIES_COLUMNS};
use std::path::Path;

impl MdSystem {
    /// The servo walls, in scene order.
    fn servo_walls(&self) -> impl Iterator<Item = &super::walls::Wall> {
        self.walls.iter().filter(|w| matches!(w.motion, Motion::Servo { .. }))
    }
}

impl Engine for MdSystem {
    const NAME: &'static str = "md";
    const DOF: usize = 6;
    const DIM: usize = 3;
    const EXTRAPOLATED: usize = 3;
    const ITERATIVE: bool = false;
    type Stats = MdStepStats;
    type Row = MdSeriesRow;
    type CycleState = MdCycleState;
    type CycleRow = MdCycleRow;

    fn step(&mut self) -> Result<MdStepStats> {
        MdSystem::step(self)
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn dt(&self) -> f64 {
        self.settings.dt
    }

    fn set_threads(&mut self, threads: usize) {
        MdSystem::set_threads(self, threads);
    }

    fn body_count(&self) -> usize {
        self.particles.len()
    }

    fn summary(s: &MdStepStats) -> StepSummary {
        StepSummary {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts + s.wall_contacts as f64,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            iterations: 0,
            converged: true,
            criterion: 0.0,
        }
    }

    fn initial_summary(&self) -> Option<StepSummary> {
        Some(Self::summary(&self.last))
    }

    fn energies(&self, stats: &MdStepStats, potential: bool) -> Energies {
        Energies {
            // Moving servo walls are part of the motion that has to die out.
            kinetic: stats.kinetic_energy + self.wall_kinetic_energy(),
            potential: if potential { self.gravitational_energy() + stats.elastic_energy } else { 0.0 },
        }
    }

    fn series_header(&self) -> Vec<String> {
        let mut h: Vec<String> = MD_SERIES_COLUMNS.iter().map(|s| s.to_string()).collect();
        h.extend(self.walls.iter().map(|w| format!("{}_force_N", w.name)));
        h.extend(self.servo_walls().map(|w| format!("{}_position_m", w.name)));
        h
    }

    fn series_row(&self, s: &MdStepStats) -> MdSeriesRow {
        // 0 − F rather than −F: no `-0.0` for an untouched wall.
        let mut walls: Vec<f64> = self.walls.iter().map(|w| 0.0 - w.normal_force()).collect();
        walls.extend(self.servo_walls().map(|w| w.s));
        MdSeriesRow {
            time_s: s.time,
            kinetic_energy_j: s.kinetic_energy,
            elastic_energy_j: s.elastic_energy,
            potential_energy_j: self.gravitational_energy() + s.elastic_energy,
            contacts: s.contacts,
            wall_contacts: s.wall_contacts,
            max_overlap_m: s.max_overlap,
            mean_overlap_m: s.mean_overlap,
            coordination: s.coordination,
            packing_fraction: self.packing_fraction_bulk(),
            walls,
        }
    }

    fn final_state(&self) -> FinalState {
        let p = &self.particles;
        let bodies = (0..p.len())
            .map(|i| BodyState {
                name: p.name[i].clone(),
                position: p.x[i].iter().copied().collect(),
                angle: None,
                velocity: p.v[i].iter().copied().collect(),
                spin: Spin::Spatial(p.w[i].into()),
                radius: Some(p.r[i]),
                orientation: None,
            })
            .collect();
        let walls = self
            .walls
            .iter()
            .map(|w| WallState { name: w.name.clone(), displacement: w.s, force: w.force.into() })
            .collect();
        FinalState { engine: Self::NAME.into(), time: self.time, step: self.step, bodies, walls }
    }

    /// One row per contact of [`MdSystem::contact_forces`]: `pair`, `image` (`b`
    /// the imaged sphere) or `wall` (`b` the wall's index among the walls).
    fn contact_rows(&self) -> Vec<ContactRow> {
        let name = |i: usize| self.particles.name[i].clone();
        self.contact_forces()
            .into_iter()
            .map(|c| {
                let (kind, b, b_name) = match c.kind {
                    MdContactKind::Pair { j } => (ContactKind::Pair, j, name(j)),
                    MdContactKind::Image { origin, .. } => (ContactKind::Image, origin, name(origin)),
                    MdContactKind::Wall { wall } => (ContactKind::Wall, wall, self.walls[wall].name.clone()),
                };
                ContactRow {
                    kind,
                    a: c.sphere,
                    a_name: name(c.sphere),
                    b,
                    b_name,
                    point_x_m: c.point[0],
                    point_y_m: c.point[1],
                    point_z_m: Some(c.point[2]),
                    normal_x: c.normal[0],
                    normal_y: c.normal[1],
                    normal_z: Some(c.normal[2]),
                    gap_m: -c.overlap,
                    f_n: c.f_n,
                    f_t_x: c.f_t[0],
                    f_t_y: c.f_t[1],
                    f_t_z: Some(c.f_t[2]),
                }
            })
            .collect()
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        super::vtk::write_snapshot(pvd, dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        MdSystem::check_state(self)
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        MdSystem::check_same_model(self, fresh)
    }

    fn cycle_start(&self, body: Option<usize>) -> Result<MdCycleState> {
        if body.is_some() {
            return Err(Error::Scene("output.cycles.body: not used by the md engine".into()));
        }
        Ok(MdCycleState { x0: self.particles.x.iter().map(|x| (*x).into()).collect(), max_overlap: 0.0 })
    }

    fn cycle_step(&self, c: &mut MdCycleState, stats: &MdStepStats) {
        c.max_overlap = c.max_overlap.max(stats.max_overlap);
    }

    fn cycle_end(&self, c: &mut MdCycleState, cycle: u64) -> MdCycleRow {
        let n = self.particles.len().max(1) as f64;
        let mut mean = super::V3::zeros();
        let mut max = 0.0f64;
        for (x, x0) in self.particles.x.iter().zip(&c.x0) {
            let u = x - super::V3::from(*x0);
            mean += u;
            max = max.max(u.norm());
        }
        mean /= n;
        let row = MdCycleRow {
            cycle,
            time_s: self.time,
            mean_displacement_x_m: mean[0],
            mean_displacement_y_m: mean[1],
            mean_displacement_z_m: mean[2],
            max_displacement_m: max,
            max_overlap_m: c.max_overlap,
            walls: self.servo_walls().map(|w| w.s).collect(),
        };
        c.max_overlap = 0.0;
        row
    }

    fn cycle_header(&self) -> Vec<String> {
        let mut h: Vec<String> = MD_CYCLE_COLUMNS.iter().map(|s| s.to_string()).collect();
        h.extend(self.servo_walls().map(|w| format!("{}_position_m", w.name)));
        h
    }

    fn coordination(&self) -> f64 {
        self.last.coordination
    }

    fn mobile_bodies(&self) -> Vec<usize> {
        (0..self.particles.len()).collect()
    }

    fn configuration_of(&self, bodies: &[usize]) -> Configuration {
        let p = &self.particles;
        let mut q = Vec::with_capacity(6 * bodies.len());
        for &i in bodies {
            q.extend(p.x[i].iter());
            q.extend(p.q[i].scaled_axis().iter());
        }
        Configuration { dof: 6, bodies: bodies.to_vec(), q }
    }

    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64> {
        bodies.iter().map(|&i| self.particles.r[i]).collect()
    }

    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize> {
        // The pair list is a half list: a pair (or a sphere and the image of
        // another) is listed once, and counts for both spheres.
        let mut count = vec![0usize; self.particles.len()];
        for c in self.contact_forces() {
            count[c.sphere] += 1;
            match c.kind {
                MdContactKind::Pair { j } => count[j] += 1,
                MdContactKind::Image { origin, .. } => count[origin] += 1,
                MdContactKind::Wall { .. } => {}
            }
        }
        bodies.iter().map(|&i| count[i]).collect()
    }

    fn set_configuration(&mut self, c: &Configuration) -> Result<()> {
        MdSystem::set_configuration(self, c)
    }

    fn boundaries(&self) -> Vec<crate::engine::Boundary> {
        let up = self.up();
        self.walls
            .iter()
            .filter(|w| matches!(w.motion, super::Motion::Servo { .. }))
            .map(|w| crate::engine::Boundary {
                name: w.name.clone(),
                s: w.s,
                down: w.normal().map_or(0.0, |n| -n.dot(&up)),
            })
            .collect()
    }

    fn set_boundaries(&mut self, s: &[f64]) -> Result<()> {
        MdSystem::set_servo_positions(self, s)
    }

    fn relax(&mut self, settings: &crate::engine::RelaxSettings) -> Result<crate::engine::RelaxReport> {
        MdSystem::relax(self, settings)
    }
}
