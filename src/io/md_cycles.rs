//! `cycles.csv` of an MD run with `[output.cycles] frequency = f`: one row at the
//! end of each loading cycle (time `k/f`), the residual displacements of Karrech
//! et al. (2007) §3 (the displacement of each sphere since the start of the run,
//! taken where the load is back to its base value) and the servo walls' positions.
//!
//! Columns: `cycle`, `time` (s), `mean_displacement_x|y|z` (m, mean over the
//! spheres), `max_displacement` (m, the largest norm), then `<wall>_position`
//! (m) for every servo wall. The recorder holds no state but the initial
//! positions (the scene's), so a resumed run continues it exactly.

use crate::md::{MdSystem, Motion, V3};
use std::fmt::Write as _;

/// Follows the cycles of a run.
#[derive(Debug, Clone)]
pub struct MdCycleRecorder {
    /// Loading frequency (Hz).
    pub frequency: f64,
    /// Initial sphere centres (m).
    pub x0: Vec<V3>,
}

impl MdCycleRecorder {
    /// A recorder for a run that started from the positions `x0`.
    pub fn new(frequency: f64, x0: Vec<V3>) -> Self {
        MdCycleRecorder { frequency, x0 }
    }

    /// Cycles completed at time `t` (s).
    pub fn cycles_at(&self, t: f64) -> u64 {
        (t * self.frequency + 1e-9).floor().max(0.0) as u64
    }

    /// The header line.
    pub fn header(sys: &MdSystem) -> String {
        let mut h =
            String::from("cycle,time,mean_displacement_x,mean_displacement_y,mean_displacement_z,max_displacement");
        for w in sys.walls.iter().filter(|w| matches!(w.motion, Motion::Servo { .. })) {
            let _ = write!(h, ",{}_position", w.name);
        }
        h
    }

    /// The row of cycle `cycle` if the step that just ended (from `t_before` to
    /// `sys.time`) completed it.
    pub fn record(&self, sys: &MdSystem, t_before: f64) -> Option<String> {
        let cycle = self.cycles_at(sys.time);
        if cycle == 0 || cycle == self.cycles_at(t_before) {
            return None;
        }
        let n = sys.particles.len().max(1) as f64;
        let mut mean = V3::zeros();
        let mut max = 0.0f64;
        for (x, x0) in sys.particles.x.iter().zip(&self.x0) {
            let u = x - x0;
            mean += u;
            max = max.max(u.norm());
        }
        mean /= n;
        let mut row = format!("{cycle},{:e},{:e},{:e},{:e},{:e}", sys.time, mean[0], mean[1], mean[2], max);
        for w in sys.walls.iter().filter(|w| matches!(w.motion, Motion::Servo { .. })) {
            let _ = write!(row, ",{:e}", w.s);
        }
        Some(row)
    }
}
