//! The copy of the last good state of an MD system, taken every [`BACKUP_EVERY`] steps and restored when a
//! step fails, so that the system holds the step before the failure (the steps since the copy are replayed).

use super::*;

/// A copy of the whole dynamic state, for going back to the last good step when a step fails: the spheres,
/// the walls, the neighbour list with its contact memory, the images, the integrator's derivatives, the
/// virial, the last statistics and the clock, each field of [`MdSystem`] copied whole into the buffers of
/// the previous copy (no allocation once the sizes match): the structures copy themselves with a destructuring
/// of all their fields (`copy_from`), so a field added to one of them does not compile until it is copied. What a step only reads (settings, laws, the origins of the clock and of the energy check)
/// is not copied.
#[derive(Debug, Clone, Default)]
pub(super) struct Backup {
    /// Whether a copy has been taken.
    taken: bool,
    particles: Particles,
    walls: Vec<Wall>,
    wall_hist: Vec<History>,
    neighbours: Neighbours,
    ghosts: Ghosts,
    gear_x: Vec<[V3; 6]>,
    gear_w: Vec<[V3; 6]>,
    force_x: Vec<V3>,
    virial: Matrix3<f64>,
    last: MdStepStats,
    time: f64,
    step: u64,
    drive_work: f64,
}

impl MdSystem {
    pub(super) fn save_backup(&mut self) {
        let b = &mut self.backup;
        b.taken = true;
        b.particles.copy_from(&self.particles);
        copy_walls(&mut b.walls, &self.walls);
        b.wall_hist.clone_from(&self.wall_hist);
        b.neighbours.copy_from(&self.neighbours);
        b.ghosts.copy_from(&self.ghosts);
        b.gear_x.clone_from(&self.gear_x);
        b.gear_w.clone_from(&self.gear_w);
        b.force_x.clone_from(&self.force_x);
        b.virial = self.virial;
        b.last = self.last;
        b.time = self.time;
        b.step = self.step;
        b.drive_work = self.drive_work;
    }

    pub(super) fn restore_backup(&mut self) {
        let b = &self.backup;
        if !b.taken || b.particles.len() != self.particles.len() {
            return;
        }
        self.particles.copy_from(&b.particles);
        copy_walls(&mut self.walls, &b.walls);
        self.wall_hist.clone_from(&b.wall_hist);
        self.neighbours.copy_from(&b.neighbours);
        self.ghosts.copy_from(&b.ghosts);
        self.ghosts.update(&self.particles);
        self.gear_x.clone_from(&b.gear_x);
        self.gear_w.clone_from(&b.gear_w);
        self.force_x.clone_from(&b.force_x);
        self.virial = b.virial;
        self.last = b.last;
        self.time = b.time;
        self.step = b.step;
        self.drive_work = b.drive_work;
    }
}

/// Copies the walls `src` into `dst`, reusing `dst`'s walls and their buffers.
fn copy_walls(dst: &mut Vec<Wall>, src: &[Wall]) {
    dst.truncate(src.len());
    for (d, w) in dst.iter_mut().zip(src) {
        d.copy_from(w);
    }
    let have = dst.len();
    dst.extend_from_slice(&src[have..]);
}
