//! The folder of an accelerated run: a fresh start (the records, the table headers, the positions), the run
//! continued from its checkpoint (checked against the scene and the files) and the checkpoint written at a
//! cycle's end; the shared parts are the run loop's ([`crate::run::folder`]).

use super::*;

/// The files a run appends to.
pub(super) struct Files {
    pub(super) rows: TableWriter,
    pub(super) jumps: TableWriter,
    pub(super) positions: Option<PositionsWriter>,
}

/// Writes the checkpoint of the run in progress.
pub(super) fn checkpoint<E: Engine>(out: &Path, st: &mut State<E>, files: &mut Files) -> Result<()> {
    sync_tables(st, files)?;
    write_checked(out, st)?;
    Ok(())
}

impl<E: Engine> Accelerated<E> {
    /// A fresh run: the folder prepared, the records and table headers written.
    pub(super) fn start(&self, out: &Path) -> Result<(State<E>, Files)> {
        run_folder::prepare(
            out,
            &[layout::CHECKPOINT, layout::SUMMARY, layout::FINAL, layout::SCENE, layout::INITIAL_STATE],
        )?;
        let steps = (self.target as f64 / (self.frequency * self.system.dt())).round() as u64;
        let info = RunInfo::new(E::NAME, self.seed, (steps, self.system.dt()), self.model.clone());
        self.source.write_records(out, &info)?;
        let origin = self.system.configuration();
        let slot = match self.spec.settlement_body {
            Some(b) => Some(origin.bodies.iter().position(|&i| i == b).ok_or_else(|| {
                Error::Scene(format!("settlement.settlement_body: body {b} is not a mobile body of the scene"))
            })?),
            None => None,
        };
        let boundary_origin = coordinates(&self.system.boundaries());
        if let Some(j) = self.spec.settlement_boundary.filter(|&j| j >= boundary_origin.len()) {
            return Err(Error::Scene(format!(
                "settlement.settlement_body: boundary {j} does not exist ({} boundaries)",
                boundary_origin.len()
            )));
        }
        let mut window = Training::new(origin.clone());
        if self.spec.initial_cycles == 0 {
            window.push(0.0, origin.clone());
        }
        let st = State {
            version: env!("CARGO_PKG_VERSION").into(),
            engine: E::NAME.into(),
            source_crc32: self.source.crc32(),
            sys: self.system.clone(),
            slot,
            cycle: 0,
            computed: 0,
            jumps: 0,
            h: self.spec.extrapolated_cycles as f64,
            since_jump: 0,
            window_settlement: if self.spec.initial_cycles == 0 { vec![0.0] } else { Vec::new() },
            window_boundaries: if self.spec.initial_cycles == 0 { vec![boundary_origin.clone()] } else { Vec::new() },
            boundary_origin,
            window,
            origin,
            last_settlement: 0.0,
            computed_overlap: 0.0,
            landing_rate: 0.0,
            settling: 0,
            last_increment: None,
            wall_time_s: 0.0,
            tables: [(0, 0, 0); 2],
            positions_crc32: 0,
            rollbacks: 0,
            retries: 0,
            compute_until: 0,
            before_jump: None,
            last_jump: None,
        };
        let rows = TableWriter::create(&out.join(layout::SETTLEMENT), SettlementRow::COLUMNS)?;
        let jumps = TableWriter::create(&out.join(layout::JUMPS), JumpRow::COLUMNS)?;
        for stale in [layout::CYCLE_BODIES, layout::CYCLE_DISPLACEMENTS] {
            io::remove_stale(out, stale)?;
        }
        let positions = if self.spec.positions {
            let names = body_names(&self.system, &st.origin.bodies);
            Some(PositionsWriter::create(out, st.origin.clone(), &names)?)
        } else {
            None
        };
        Ok((st, Files { rows, jumps, positions }))
    }

    /// The run continued from `OUT/checkpoint.json`.
    pub(super) fn resume(&self, out: &Path) -> Result<(State<E>, Files)> {
        run_folder::checkpoint_to_resume(out)?;
        let (path, st): (PathBuf, State<E>) = read_checked(out)?;
        check_origin(&path, (&st.engine, &st.version, st.source_crc32), (E::NAME, self.source.crc32()))?;
        let bad = |msg: String| run_folder::invalid_checkpoint(&path, msg);
        run_folder::check_resumed(&path, "", &st.sys, &self.system)?;
        if let Some(b) = &st.before_jump {
            run_folder::check_resumed(&path, "before_jump: ", &b.sys, &self.system)?;
            if b.before_jump.is_some()
                || b.cycle > st.cycle
                || b.jumps > st.jumps
                || st.last_jump.is_none()
                || b.window.configurations.len() != b.window_settlement.len()
                || b.window.segments.len() != b.window.cycles.len()
                || b.tables[0].1 != b.cycle
                || b.tables[1].1 != b.jumps + b.rollbacks
            {
                return Err(bad("before_jump: not the state before its last jump".into()));
            }
        }
        if st.origin != self.system.configuration() {
            return Err(bad("its start configuration is not the scene's".into()));
        }
        if st.computed > st.cycle
            || st.cycle > self.target
            || st.window.configurations.len() != st.window_settlement.len()
            || st.window.segments.len() != st.window.cycles.len()
        {
            return Err(bad(format!("{} computed of {} cycles, target {}", st.computed, st.cycle, self.target)));
        }
        let [(_, rr, _), (_, jr, _)] = st.tables;
        if rr != st.cycle || jr != st.jumps + st.rollbacks {
            return Err(bad(format!(
                "{rr} rows of {SETTLEMENT} for {} cycles, {jr} of {JUMPS} for {} jumps and {} rollbacks",
                st.cycle, st.jumps, st.rollbacks
            )));
        }
        let files = self.reopen(out, &st)?;
        io::remove_stale(out, layout::SUMMARY)?;
        Ok((st, files))
    }

    /// The run's files reopened at the lengths `st` recorded (`st.tables`, its
    /// cycles of positions): cut back to them, checked against their CRCs.
    pub(super) fn reopen(&self, out: &Path, st: &State<E>) -> Result<Files> {
        let [(rb, rr, rc), (jb, jr, jc)] = st.tables;
        let rows = TableWriter::resume(&out.join(layout::SETTLEMENT), rb, rr, rc)?;
        let jumps = TableWriter::resume(&out.join(layout::JUMPS), jb, jr, jc)?;
        let positions = if self.spec.positions {
            let names = body_names(&self.system, &st.origin.bodies);
            Some(PositionsWriter::resume(out, st.origin.clone(), &names, st.cycle, st.positions_crc32)?)
        } else {
            None
        };
        Ok(Files { rows, jumps, positions })
    }
}
