//! The checks of an MD state read back from a checkpoint: that it holds together ([`MdSystem::check_state`])
//! and that it is a state of the model built from the scene ([`MdSystem::check_same_model`]).

use super::*;

impl MdSystem {
    /// Checks that the state holds together (a state read from a checkpoint):
    /// array lengths, material and partner indices, the neighbour rows, finite
    /// positions and velocities, the clock, the Gear positions, and the state
    /// derived from the positions at the last neighbour build (images, neighbour
    /// list, wall candidates, their contact memory: built again from
    /// `neighbours.x_build` and the walls at `s_build`, they must come out the
    /// same). The message names what is wrong.
    pub fn check_state(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(msg));
        let p = &self.particles;
        let n = p.len();
        let lens = [p.v.len(), p.w.len(), p.f.len(), p.t.len(), p.r.len(), p.m.len(), p.inv_m.len()];
        let more = [p.inv_i.len(), p.material.len(), p.q.len(), p.name.len()];
        if lens.iter().chain(&more).any(|&l| l != n) {
            return bad(format!("spheres: arrays of different lengths for {n} spheres"));
        }
        let finite = |v: &V3| v.iter().all(|x| x.is_finite());
        if let Some(i) = (0..n).find(|&i| !(finite(&p.x[i]) && finite(&p.v[i]) && finite(&p.w[i]))) {
            return bad(format!("sphere {i}: a position or velocity is not finite"));
        }
        if let Some(i) = (0..n).find(|&i| !(p.r[i] > 0.0 && p.m[i] > 0.0 && p.inv_m[i].is_finite())) {
            return bad(format!("sphere {i}: radius or mass is not positive"));
        }
        if let Some(i) = (0..n).find(|&i| p.material[i] as usize >= self.laws.n) {
            return bad(format!("sphere {i}: material {} of {}", p.material[i], self.laws.n));
        }
        if self.laws.n.checked_mul(self.laws.n) != Some(self.laws.laws.len()) {
            return bad(format!("{} laws for {} materials", self.laws.laws.len(), self.laws.n));
        }
        if !(self.laws.names.is_empty() || self.laws.names.len() == self.laws.n) {
            return bad(format!("{} material names for {} materials", self.laws.names.len(), self.laws.n));
        }
        let gear = matches!(self.settings.integrator, Integrator::Gear(_));
        let expected = if gear { n } else { 0 };
        if self.gear_x.len() != expected || self.gear_w.len() != expected {
            return bad(format!("Gear derivatives of {} spheres for {n}", self.gear_x.len()));
        }
        // The corrector leaves the position in the first Gear row.
        if let Some(i) = (0..self.gear_x.len()).find(|&i| !same_bits(&self.gear_x[i][0], &p.x[i])) {
            return bad(format!("sphere {i}: the Gear position is not the sphere's"));
        }
        if !self.force_x.is_empty() && self.force_x.len() != n {
            return bad(format!("centres of the last force evaluation: {} for {n} spheres", self.force_x.len()));
        }
        let nw = self.walls.len();
        if self.wall_hist.len() != n * nw {
            return bad(format!(
                "wall contact memory of {} entries for {n} spheres and {nw} walls",
                self.wall_hist.len()
            ));
        }
        let nb = &self.neighbours;
        let rows_ok = nb.start.len() == n + 1
            && nb.start[0] == 0
            && nb.start.windows(2).all(|w| w[0] <= w[1])
            && nb.start[n] as usize == nb.j.len();
        if !rows_ok || nb.key.len() != nb.j.len() || nb.hist.len() != nb.j.len() {
            return bad("neighbour list: rows, partners, keys and memory do not match".into());
        }
        let n_all = n + self.ghosts.len();
        if nb.j.iter().any(|&j| j as usize >= n_all) || nb.x_build.len() != n {
            return bad("neighbour list: a partner or build position out of range".into());
        }
        if nb.skin.to_bits() != self.settings.skin.to_bits() {
            return bad(format!("neighbour list: skin {} m, the settings' is {} m", nb.skin, self.settings.skin));
        }
        let g = &self.ghosts;
        if g.mask.len() != g.len() || g.key.len() != g.len() || g.origin.iter().any(|&i| i as usize >= n) {
            return bad("symmetry images: origins, masks and keys do not match".into());
        }
        if let Some(w) = self.walls.iter().find(|w| w.candidates.iter().any(|&i| i as usize >= n)) {
            return bad(format!("wall '{}': a candidate sphere out of range", crate::error::clip(&w.name)));
        }
        if !(self.settings.dt.is_finite() && self.settings.dt > 0.0) {
            return bad(format!("time step {} s", self.settings.dt));
        }
        // The derived state, built again where it was built.
        let mut again = self.clone();
        again.particles.x.clone_from(&nb.x_build);
        for w in &mut again.walls {
            w.s = w.s_build;
        }
        again.rebuild();
        let (a, b) = (&again.neighbours, &again.ghosts);
        if a.start != nb.start || a.j != nb.j || a.key != nb.key || a.hist != nb.hist {
            return bad("neighbour list: not the list of the spheres at its build".into());
        }
        if b.origin != g.origin || b.mask != g.mask || b.key != g.key {
            return bad("symmetry images: not the images of the spheres at the last build".into());
        }
        if let Some((w, _)) = self.walls.iter().zip(&again.walls).find(|(w, v)| w.candidates != v.candidates) {
            let name = crate::error::clip(&w.name);
            return bad(format!("wall '{name}': not the candidate spheres of the last build"));
        }
        if again.wall_hist != self.wall_hist {
            return bad("wall contact memory: held for spheres that are not candidates".into());
        }
        self.origin.check(self.step, Some(self.time), self.settings.dt).or_else(bad)?;
        Ok(())
    }

    /// Checks that `self` is a state of the model `fresh` (the system built from
    /// the same scene): the same spheres (names, radii, masses, materials),
    /// walls (names, shapes, motions), laws, symmetry planes, settings,
    /// measurement period, clock origin, zero of the gravitational energy and
    /// energy at the start.
    pub fn check_same_model(&self, fresh: &MdSystem) -> Result<()> {
        let bad = |what: String| Err(Error::Scene(format!("{what} differs from the scene's")));
        let (a, b) = (&self.particles, &fresh.particles);
        if a.len() != b.len() {
            return bad(format!("the number of spheres ({})", a.len()));
        }
        for i in 0..a.len() {
            let same = a.name[i] == b.name[i]
                && a.r[i].to_bits() == b.r[i].to_bits()
                && a.m[i].to_bits() == b.m[i].to_bits()
                && a.inv_m[i].to_bits() == b.inv_m[i].to_bits()
                && a.inv_i[i].to_bits() == b.inv_i[i].to_bits()
                && a.material[i] == b.material[i];
            if !same {
                return bad(format!("sphere {i} ('{}')", crate::error::clip(&b.name[i])));
            }
        }
        if self.walls.len() != fresh.walls.len() {
            return bad(format!("the number of walls ({})", self.walls.len()));
        }
        for (w, f) in self.walls.iter().zip(&fresh.walls) {
            if w.name != f.name || w.material != f.material || w.shape != f.shape || w.motion != f.motion {
                return bad(format!("wall '{}'", crate::error::clip(&f.name)));
            }
        }
        let same = |x: &dyn Fn(&MdSystem) -> serde_json::Value| x(self) == x(fresh);
        if !same(&|s| serde_json::to_value(&s.laws).unwrap_or_default()) {
            return bad("the contact laws".into());
        }
        if !same(&|s| serde_json::to_value(&s.ghosts.planes).unwrap_or_default()) {
            return bad("the symmetry planes".into());
        }
        if self.settings != fresh.settings || self.measure_every != fresh.measure_every {
            return bad("the [md] settings, time step or measurement period".into());
        }
        // The run loop never changes the time step: the clock keeps its origin.
        if !self.origin.same(&fresh.origin) {
            return bad("the clock's origin".into());
        }
        // Set when the system is built: the zero of the gravitational energy. (The
        // energy budget of the divergence check is state: a configuration written
        // back during a run resets it.)
        if self.gravity_reference.to_bits() != fresh.gravity_reference.to_bits() {
            return bad("the zero of the gravitational energy".into());
        }
        Ok(())
    }
}
