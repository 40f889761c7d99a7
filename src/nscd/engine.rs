//! The NSCD system as an [`Engine`] of the run loop and of cyclic drivers: its
//! rows of `series.csv` and `cycles.csv` (Saussine et al. 2006 §3–4: sweeps,
//! interpenetration, sleeper settlement), final state, snapshots and figures,
//! and its generalised positions `(x, y, θ)` per body, read and written back
//! ([`System::set_configuration`]).

use super::system::{StepStats, System};
use crate::error::{Error, Result};
use crate::io::contacts::{ContactKind, ContactRow};
use crate::io::cycles::{NscdCycleRow, NscdCycleState, NSCD_CYCLE_COLUMNS};
use crate::io::final_state::{BodyState, FinalState, Spin};
use crate::io::run_figures::RunFigures;
use crate::io::series::{NscdSeriesRow, NSCD_SERIES_COLUMNS};
use crate::io::summary::StepSummary;
use crate::io::vtk::PvdCollection;
use crate::run::{Configuration, Energies, Engine};
use std::path::Path;

impl Engine for System {
    const NAME: &'static str = "nscd";
    const DOF: usize = 3;
    const DIM: usize = 2;
    const EXTRAPOLATED: usize = 2;
    const ITERATIVE: bool = true;
    type Stats = StepStats;
    type Row = NscdSeriesRow;
    type CycleState = NscdCycleState;
    type CycleRow = NscdCycleRow;

    fn step(&mut self) -> Result<StepStats> {
        System::step(self)
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn dt(&self) -> f64 {
        self.params.dt
    }

    fn set_threads(&mut self, threads: usize) {
        System::set_threads(self, threads);
    }

    fn body_count(&self) -> usize {
        self.bodies.len()
    }

    fn summary(s: &StepStats) -> StepSummary {
        StepSummary {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts as f64,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            iterations: s.iterations as u64,
            converged: s.converged,
            criterion: s.criterion,
        }
    }

    fn energies(&self, stats: &StepStats, potential: bool) -> Energies {
        Energies { kinetic: stats.kinetic_energy, potential: if potential { self.potential_energy() } else { 0.0 } }
    }

    fn series_header(&self) -> Vec<String> {
        NSCD_SERIES_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn series_row(&self, s: &StepStats) -> NscdSeriesRow {
        NscdSeriesRow {
            time_s: s.time,
            kinetic_energy_j: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            iterations: s.iterations,
            criterion: s.criterion,
            converged: u8::from(s.converged),
            mean_overlap_m: s.mean_overlap,
            max_overlap_m: s.max_overlap,
            total_overlap_m: s.total_overlap,
        }
    }

    fn final_state(&self) -> FinalState {
        let b = &self.bodies;
        let bodies = b
            .info
            .iter()
            .zip(&b.q)
            .zip(&b.u)
            .map(|((info, q), u)| BodyState {
                name: info.name.clone(),
                position: vec![q[0], q[1]],
                angle: Some(q[2]),
                velocity: vec![u[0], u[1]],
                spin: Spin::Planar(u[2]),
                radius: None,
            })
            .collect();
        FinalState { engine: Self::NAME.into(), time: self.time, step: self.step, bodies, walls: Vec::new() }
    }

    /// One row per contact point; a contact with a fixed body is a `wall` row
    /// seen from the other body (normal and forces turned round if the fixed
    /// body was the candidate).
    fn contact_rows(&self) -> Vec<ContactRow> {
        let info = &self.bodies.info;
        self.contact_forces()
            .map(|c| {
                let (a, b, s) = if info[c.candidate].fixed && !info[c.antagonist].fixed {
                    (c.antagonist, c.candidate, -1.0)
                } else {
                    (c.candidate, c.antagonist, 1.0)
                };
                let kind = if info[a].fixed || info[b].fixed { ContactKind::Wall } else { ContactKind::Pair };
                // The tangent of `r_t` is the candidate's normal turned by +90°.
                let t = [-c.normal[1], c.normal[0]];
                ContactRow {
                    kind,
                    a,
                    a_name: info[a].name.clone(),
                    b,
                    b_name: info[b].name.clone(),
                    point_x_m: c.point[0],
                    point_y_m: c.point[1],
                    point_z_m: None,
                    normal_x: s * c.normal[0],
                    normal_y: s * c.normal[1],
                    normal_z: None,
                    gap_m: c.gap,
                    f_n: c.r_n,
                    f_t_x: s * c.r_t * t[0],
                    f_t_y: s * c.r_t * t[1],
                    f_t_z: None,
                }
            })
            .collect()
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        pvd.write_snapshot(dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        System::check_state(self)
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        System::check_same_model(self, fresh)
    }

    fn cycle_start(&self, body: Option<usize>) -> Result<NscdCycleState> {
        let body =
            body.ok_or_else(|| Error::Scene("output.cycles.body: name the followed body (the sleeper)".into()))?;
        let q = self.bodies.q.get(body).ok_or_else(|| {
            Error::Scene(format!("output.cycles.body: body {body} does not exist ({} bodies)", self.bodies.len()))
        })?;
        Ok(NscdCycleState::new(body, q[1]))
    }

    fn cycle_step(&self, c: &mut NscdCycleState, stats: &StepStats) {
        let y = self.bodies.q[c.body][1];
        let load: [f64; 2] = self.bodies.info[c.body].loads.iter().fold([0.0, 0.0], |f, l| {
            let g = l.at(self.time);
            [f[0] + g[0], f[1] + g[1]]
        });
        let magnitude = load[0].hypot(load[1]);
        if magnitude < c.min_load {
            c.min_load = magnitude;
            c.y_at_min_load = y;
        }
        c.steps += 1;
        c.sum_y += y;
        let (mut speed, mut n) = (0.0, 0usize);
        for (i, (info, u)) in self.bodies.info.iter().zip(&self.bodies.u).enumerate() {
            if i != c.body && !info.fixed {
                speed += u[0].hypot(u[1]);
                n += 1;
            }
        }
        c.sum_speed += if n > 0 { speed / n as f64 } else { 0.0 };
        c.sum_contacts += stats.contacts as f64;
        c.sum_iterations += stats.iterations as f64;
        c.max_overlap = c.max_overlap.max(stats.max_overlap);
    }

    fn cycle_end(&self, c: &mut NscdCycleState, cycle: u64) -> NscdCycleRow {
        let k = c.steps.max(1) as f64;
        let row = NscdCycleRow {
            cycle,
            time_s: self.time,
            settlement_mean_m: c.y0 - c.sum_y / k,
            settlement_at_min_load_m: c.y0 - c.y_at_min_load,
            mean_grain_speed_m_s: c.sum_speed / k,
            contacts: c.sum_contacts / k,
            iterations: c.sum_iterations / k,
            max_overlap_m: c.max_overlap,
        };
        if c.first_cycle_q.is_none() {
            c.first_cycle_q = Some(self.bodies.q.clone());
        }
        c.restart();
        row
    }

    fn cycle_header(&self) -> Vec<String> {
        NSCD_CYCLE_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn settlement(&self, c: &NscdCycleState) -> Option<f64> {
        self.bodies.q.get(c.body).map(|q| c.y0 - q[1])
    }

    fn figures(&self, dir: &Path, cycles: Option<&NscdCycleState>) -> Result<RunFigures> {
        let first = cycles.and_then(|c| c.first_cycle_q.as_deref());
        crate::io::run_figures::nscd_figures(dir, first)
    }

    fn coordination(&self) -> f64 {
        let grains: Vec<usize> = (0..self.bodies.len()).filter(|&i| !self.bodies.info[i].fixed).collect();
        super::measure::coordination(self, &grains, 0.0).z
    }

    fn mobile_bodies(&self) -> Vec<usize> {
        (0..self.bodies.len()).filter(|&i| !self.bodies.info[i].fixed).collect()
    }

    fn configuration_of(&self, bodies: &[usize]) -> Configuration {
        let q = bodies.iter().flat_map(|&i| self.bodies.q[i]).collect();
        Configuration { dof: 3, bodies: bodies.to_vec(), q }
    }

    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64> {
        // The radius of the disc of the same area: a compound (the sleeper and
        // its feet) is as large as its area, not as its smallest part.
        bodies
            .iter()
            .map(|&i| (self.bodies.info[i].shape.area_and_polar_moment().0 / std::f64::consts::PI).sqrt())
            .collect()
    }

    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize> {
        let count = super::measure::neighbour_counts(self, 0.0);
        bodies.iter().map(|&i| count[i]).collect()
    }

    fn set_configuration(&mut self, c: &Configuration) -> Result<()> {
        System::set_configuration(self, c)
    }

    fn relax(&mut self, settings: &crate::settlement::RelaxSettings) -> Result<crate::settlement::RelaxReport> {
        System::relax(self, settings)
    }
}
