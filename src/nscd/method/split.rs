//! Domain-split NLGS: the two halves of the sample swept side by side, the
//! rows that join them after (in the spirit of the parallel NSCD of Renouf,
//! Dubois & Alart 2004, ref. \[25\] of Saussine et al. 2006).
//!
//! The mobile bodies are split at the median abscissa of their centres (at
//! `q_m`) into a left and a right set. A row (contact or spring) whose mobile
//! bodies are all on the left belongs to the left half, all on the right to the
//! right half, otherwise to the interface. Left and right rows never touch the
//! same mobile body, so one Gauss–Seidel sweep of the left rows and one of the
//! right rows can run at the same time on two threads; the interface rows are
//! swept after both, then the next sweep begins. Bodies with a zero inverse mass
//! (fixed, or every velocity imposed) are never changed by a row: each part has
//! its own copy of them.
//!
//! Each part owns its velocities (`[its mobile bodies | fixed bodies]`) and its
//! rows with renumbered body indices, so the plain [`super::gauss_seidel::sweep`] runs
//! on it. Between two sweeps the interface bodies' velocities are gathered from
//! the halves and scattered back. The order of the updates (left rows, right
//! rows, interface rows, each in key order) depends on the positions only,
//! never on the number of threads: a run gives the same numbers on one core or
//! two. With two threads each sweep of the right half runs on the helper of a
//! [`Team`], started once and spinning between sweeps (a sweep lasts tens of
//! microseconds, far less than a sleep and wake-up); the caller sweeps the right
//! half itself when the helper has not started it, and the team sweeps both in
//! turn while it measures two threads slower than one on a shared machine.
//!
//! Nothing is allocated once the buffers have grown to the problem's size.

use super::anderson::{Lane, Mixer};
use super::apgd::{AffineRow, ConeRow};
use super::criterion::SweepNorms;
use super::gauss_seidel::{pass, Pass};
use super::Row;
use crate::team::Team;

const LEFT: u8 = 0;
const RIGHT: u8 = 1;
const FIXED: u8 = 2;
const NONE: u32 = u32::MAX;

/// One part of the split problem, with its own velocities and rows.
#[derive(Debug, Clone)]
struct Part<R: Row, S: Row<Dofs = R::Dofs>> {
    u: Vec<R::Dofs>,
    inv_m: Vec<R::Dofs>,
    rows: Vec<R>,
    springs: Vec<S>,
    /// Original index of each row and spring.
    row_of: Vec<u32>,
    spring_of: Vec<u32>,
    /// Original index of each mobile body (the fixed copies follow them).
    body_of: Vec<u32>,
    /// The part's history of the Anderson mixing ([`super::anderson`]).
    lane: Lane,
}

impl<R: Row, S: Row<Dofs = R::Dofs>> Default for Part<R, S> {
    fn default() -> Self {
        Self {
            u: Vec::new(),
            inv_m: Vec::new(),
            rows: Vec::new(),
            springs: Vec::new(),
            row_of: Vec::new(),
            spring_of: Vec::new(),
            body_of: Vec::new(),
            lane: Lane::default(),
        }
    }
}

impl<R: Row, S: Row<Dofs = R::Dofs>> Part<R, S> {
    fn pass(&mut self, kind: Pass) -> SweepNorms {
        pass(kind, &mut self.u, &self.inv_m, &mut self.rows, &mut self.springs)
    }

    fn absorb(&mut self, slots: &super::anderson::Slots) -> super::anderson::Dots
    where
        R: ConeRow,
        S: AffineRow<Dofs = R::Dofs>,
    {
        self.lane.absorb(slots, &self.u, &self.rows, &self.springs)
    }

    fn mix(&mut self, gamma: &[f64; super::anderson::MAX_DEPTH])
    where
        R: ConeRow,
        S: AffineRow<Dofs = R::Dofs>,
    {
        self.lane.mix(gamma, &mut self.u, &self.inv_m, &mut self.rows, &mut self.springs);
    }

    fn clear(&mut self) {
        self.u.clear();
        self.inv_m.clear();
        self.rows.clear();
        self.springs.clear();
        self.row_of.clear();
        self.spring_of.clear();
        self.body_of.clear();
    }
}

/// Buffers of the split solve of contact rows `R` and spring rows `S`, kept from step to step.
#[derive(Debug, Clone)]
pub struct SplitWorkspace<R: Row, S: Row<Dofs = R::Dofs>> {
    /// Per body: side, and slot in its part (interface slot in `iface_slot`).
    side: Vec<u8>,
    slot: Vec<u32>,
    iface_slot: Vec<u32>,
    xs: Vec<f64>,
    fixed: Vec<u32>,
    left: Part<R, S>,
    right: Part<R, S>,
    iface: Part<R, S>,
    /// The caller and, with two threads, the helper that sweeps the right half.
    team: Team,
}

impl<R: Row, S: Row<Dofs = R::Dofs>> Default for SplitWorkspace<R, S> {
    fn default() -> Self {
        Self {
            side: Vec::new(),
            slot: Vec::new(),
            iface_slot: Vec::new(),
            xs: Vec::new(),
            fixed: Vec::new(),
            left: Part::default(),
            right: Part::default(),
            iface: Part::default(),
            team: Team::default(),
        }
    }
}

/// Which part a row between `a` and `b` belongs to: 0 left, 1 right, 2 interface.
fn part_of(side: &[u8], a: u32, b: u32) -> usize {
    let side = |i: u32| if i == NONE { FIXED } else { side[i as usize] };
    match (side(a), side(b)) {
        (RIGHT, RIGHT) | (RIGHT, FIXED) | (FIXED, RIGHT) => 1,
        (LEFT, RIGHT) | (RIGHT, LEFT) => 2,
        _ => 0,
    }
}

impl<R: Row, S: Row<Dofs = R::Dofs>> SplitWorkspace<R, S> {
    /// Splits the problem: body `i` at abscissa `abscissa(i)`, velocities `u`.
    pub(crate) fn load(
        &mut self,
        abscissa: impl Fn(usize) -> f64,
        u: &[R::Dofs],
        inv_m: &[R::Dofs],
        rows: &[R],
        springs: &[S],
    ) {
        let n = u.len();
        let still = R::Dofs::default();
        let mobile = |i: usize| inv_m[i] != still;
        self.xs.clear();
        self.xs.extend((0..n).filter(|&i| mobile(i)).map(&abscissa));
        let median = if self.xs.is_empty() {
            0.0
        } else {
            let k = self.xs.len() / 2;
            *self.xs.select_nth_unstable_by(k, f64::total_cmp).1
        };
        self.side.clear();
        self.slot.clear();
        self.fixed.clear();
        self.left.clear();
        self.right.clear();
        self.iface.clear();
        for i in 0..n {
            let (side, part) = if !mobile(i) {
                self.slot.push(self.fixed.len() as u32);
                self.fixed.push(i as u32);
                self.side.push(FIXED);
                continue;
            } else if abscissa(i) < median {
                (LEFT, &mut self.left)
            } else {
                (RIGHT, &mut self.right)
            };
            self.side.push(side);
            self.slot.push(part.body_of.len() as u32);
            part.body_of.push(i as u32);
        }
        // The interface's mobile bodies: those of its rows, in order of first use.
        self.iface_slot.clear();
        self.iface_slot.resize(n, NONE);
        let iface_body = |i: u32, slot: &mut Vec<u32>, body_of: &mut Vec<u32>| {
            if i != NONE && inv_m[i as usize] != still && slot[i as usize] == NONE {
                slot[i as usize] = body_of.len() as u32;
                body_of.push(i);
            }
        };
        let bodies = rows.iter().map(R::bodies).chain(springs.iter().map(S::bodies));
        for (a, b) in bodies.filter(|&(a, b)| part_of(&self.side, a, b) == 2) {
            iface_body(a, &mut self.iface_slot, &mut self.iface.body_of);
            iface_body(b, &mut self.iface_slot, &mut self.iface.body_of);
        }
        // Velocities: each part's mobile bodies, then a copy of the fixed ones.
        let fixed = &self.fixed;
        for part in [&mut self.left, &mut self.right, &mut self.iface] {
            for &i in part.body_of.iter().chain(fixed) {
                part.u.push(u[i as usize]);
                part.inv_m.push(inv_m[i as usize]);
            }
        }
        // Rows, renumbered into their part, in their original order.
        for (k, r) in rows.iter().enumerate() {
            let (a, b) = r.bodies();
            let p = part_of(&self.side, a, b);
            let mut r = *r;
            r.set_bodies(self.index(a, p), self.index(b, p));
            let part = self.part_mut(p);
            part.rows.push(r);
            part.row_of.push(k as u32);
        }
        for (k, s) in springs.iter().enumerate() {
            let (a, b) = s.bodies();
            let p = part_of(&self.side, a, b);
            let mut s = *s;
            s.set_bodies(self.index(a, p), self.index(b, p));
            let part = self.part_mut(p);
            part.springs.push(s);
            part.spring_of.push(k as u32);
        }
    }

    fn part_mut(&mut self, p: usize) -> &mut Part<R, S> {
        match p {
            0 => &mut self.left,
            1 => &mut self.right,
            _ => &mut self.iface,
        }
    }

    /// Index of body `i` in part `p`; `u32::MAX` (a world anchor) stays.
    fn index(&self, i: u32, p: usize) -> u32 {
        if i == NONE {
            return i;
        }
        let i = i as usize;
        let movers = [&self.left, &self.right, &self.iface][p].body_of.len() as u32;
        match (self.side[i], p) {
            (FIXED, _) => movers + self.slot[i],
            (_, 2) => self.iface_slot[i],
            _ => self.slot[i],
        }
    }

    /// Copies the interface bodies' velocities from the halves (`to_iface`) or back.
    fn exchange(
        left: &mut Part<R, S>,
        right: &mut Part<R, S>,
        iface: &mut Part<R, S>,
        side: &[u8],
        slot: &[u32],
        to_iface: bool,
    ) {
        for (k, &i) in iface.body_of.iter().enumerate() {
            let half = if side[i as usize] == LEFT { &mut *left } else { &mut *right };
            let j = slot[i as usize] as usize;
            if to_iface {
                iface.u[k] = half.u[j];
            } else {
                half.u[j] = iface.u[k];
            }
        }
    }

    /// Runs `sweeps` with a function doing one split sweep (on one thread, or on
    /// two when `threads ≥ 2`), then nothing more: call [`Self::store`] after.
    pub(crate) fn run<T>(&mut self, threads: usize, sweeps: impl FnOnce(&mut dyn FnMut(Pass) -> SweepNorms) -> T) -> T {
        self.set_threads(threads);
        let Self { left, right, iface, side, slot, team, .. } = self;
        let (side, slot) = (&side[..], &slot[..]);
        sweeps(&mut |kind| Self::split_pass(kind, [&mut *left, &mut *right, &mut *iface], team, side, slot))
    }

    fn set_threads(&mut self, threads: usize) {
        if (threads >= 2) != (self.team.threads() >= 2) {
            self.team = Team::new(threads);
        }
    }

    /// One pass of `kind` over the three parts: left and right side by side (in turn on one thread), then the
    /// interface between two exchanges of its bodies' velocities. A check updates nothing: the interface bodies'
    /// velocities are already equal.
    fn split_pass(
        kind: Pass,
        [left, right, iface]: [&mut Part<R, S>; 3],
        team: &mut Team,
        side: &[u8],
        slot: &[u32],
    ) -> SweepNorms {
        let (l, r) = team.join(|| left.pass(kind), || right.pass(kind));
        if kind == Pass::Check {
            return l.merged(r).merged(iface.pass(kind));
        }
        Self::exchange(left, right, iface, side, slot, true);
        let i = iface.pass(kind);
        Self::exchange(left, right, iface, side, slot, false);
        l.merged(r).merged(i)
    }

    /// [`Self::run`] with the Anderson mixing of `mixer` after its sweeps ([`super::anderson`]): each part
    /// keeps its own history, the halves' passes over it run side by side (in turn on one thread) and the
    /// interface's after them, the halves' velocities mixed from their histories and the interface's copied from
    /// them; the dot products are added left, right, interface, whatever the threads.
    pub(crate) fn run_mixed<T>(
        &mut self,
        threads: usize,
        mixer: &mut Mixer,
        sweeps: impl FnOnce(&mut dyn FnMut(Pass) -> SweepNorms) -> T,
    ) -> T
    where
        R: ConeRow,
        S: AffineRow<Dofs = R::Dofs>,
    {
        self.set_threads(threads);
        let depth = mixer.depth();
        for (part, velocities) in [(&mut self.left, true), (&mut self.right, true), (&mut self.iface, false)] {
            part.lane.begin(depth, velocities, &part.u, &part.rows, &part.springs);
        }
        let Self { left, right, iface, side, slot, team, .. } = self;
        let (side, slot) = (&side[..], &slot[..]);
        sweeps(&mut |kind| {
            let norms = Self::split_pass(kind, [&mut *left, &mut *right, &mut *iface], team, side, slot);
            if let Some(slots) = mixer.due(kind) {
                let (dl, dr) = team.join(|| left.absorb(&slots), || right.absorb(&slots));
                let dots = dl.merged(dr).merged(iface.absorb(&slots));
                if let Some(gamma) = mixer.solve(slots, &dots) {
                    team.join(|| left.mix(&gamma), || right.mix(&gamma));
                    Self::exchange(left, right, iface, side, slot, true);
                    iface.mix(&gamma);
                    Self::exchange(left, right, iface, side, slot, false);
                }
            }
            norms
        })
    }

    /// What the two-thread team's joins did so far (zero on one thread).
    pub(crate) fn team_stats(&self) -> crate::team::TeamStats {
        self.team.stats()
    }

    /// Writes the velocities and impulses back in the caller's order.
    pub(crate) fn store(&self, u: &mut [R::Dofs], rows: &mut [R], springs: &mut [S]) {
        for part in [&self.left, &self.right] {
            for (&i, ui) in part.body_of.iter().zip(&part.u) {
                u[i as usize] = *ui;
            }
        }
        for part in [&self.left, &self.right, &self.iface] {
            for (r, &k) in part.rows.iter().zip(&part.row_of) {
                rows[k as usize].take_impulse(r);
            }
            for (s, &k) in part.springs.iter().zip(&part.spring_of) {
                springs[k as usize].take_impulse(s);
            }
        }
    }
}
