//! The contact list of an MD system: every contact of the last force evaluation
//! with its point, normal and force ([`MdSystem::contact_forces`]), as the NSCD
//! engine gives its own ([`crate::nscd::System::contact_forces`]).
//!
//! Nothing is recomputed from the state after the step: each contact's force is
//! the one the step applied, kept in its memory ([`super::contact::History`]),
//! and its geometry comes from the centres the forces were evaluated at (with a
//! Gear integrator the predicted ones, kept for this; the images mirrored from
//! them by the same operations), so that the normal is the same unit vector the
//! step used and the forces of a sphere's contacts add up to its contact force.
//!
//! Conventions (those of [`super::contact`]): the force acts on `sphere`, the
//! first body; the normal points from the other body to it; the point is the
//! middle of the overlap for two spheres (`x_i − n (r_i − δ/2)`), the foot of the
//! sphere's centre on the wall surface for a wall (`x_i − n (r_i − δ)`).
//!
//! A contact with a symmetry image ([`super::ghosts`]) is listed once for every
//! real sphere that touches an image: the force acts on that sphere only, its
//! mirror partner's own contact with the mirror image is listed on its own row
//! (both are the same contact of the full sample, seen from each side). The
//! forces of the list therefore add up, sphere by sphere, to every sphere's
//! contact force; in the contact count of the statistics each image contact
//! counts half.

use super::contact::History;
use super::particles::V3;
use super::system::MdSystem;
use serde::{Deserialize, Serialize};

/// What a sphere touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MdContactKind {
    /// Another sphere, `j > sphere` (each pair once; it gets the opposite force).
    Pair {
        /// The other sphere's index.
        j: usize,
    },
    /// The image of sphere `origin` through the symmetry planes of bit mask
    /// `planes` (bit `s`: plane `s` of [`super::Ghosts::planes`]).
    Image {
        /// Index of the imaged sphere.
        origin: usize,
        /// Bit mask of the planes it is mirrored through.
        planes: u32,
    },
    /// Wall `wall` (its index in [`MdSystem::walls`]).
    Wall {
        /// The wall's index.
        wall: usize,
    },
}

/// One contact of the last force evaluation, as seen from outside (SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MdContactInfo {
    /// The sphere the force acts on (the first body of the contact).
    pub sphere: usize,
    /// What it touches.
    pub kind: MdContactKind,
    /// Contact point (m).
    pub point: [f64; 3],
    /// Unit normal, from the other body towards `sphere`.
    pub normal: [f64; 3],
    /// Overlap `δ > 0` (m).
    pub overlap: f64,
    /// Normal force on `sphere` along `normal` (N): positive when the bodies push
    /// each other apart; the linear law's dashpot may make it slightly negative
    /// while the spheres separate, Hertz–Mindlin's never.
    pub f_n: f64,
    /// Tangential force on `sphere` (N), perpendicular to `normal` (friction and
    /// tangential dashpot).
    pub f_t: [f64; 3],
}

impl MdContactInfo {
    /// The whole force on `sphere` (N): `f_n normal + f_t`.
    pub fn force(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.f_n * self.normal[k] + self.f_t[k])
    }
}

/// The contact seen from `sphere`, its force (kept in `h`) split along the unit `n`.
fn info(sphere: usize, kind: MdContactKind, point: V3, n: V3, h: &History) -> MdContactInfo {
    let f_n = h.force.dot(&n);
    let f_t = h.force - n * f_n;
    MdContactInfo { sphere, kind, point: point.into(), normal: n.into(), overlap: h.delta, f_n, f_t: f_t.into() }
}

impl MdSystem {
    /// The centres of the spheres (m) at the last force evaluation, those the
    /// contact list's geometry comes from: with a Gear integrator the predicted
    /// centres of the last step (the corrector has moved the spheres since), else
    /// the current ones.
    pub fn force_positions(&self) -> &[V3] {
        if self.force_x.len() == self.particles.len() {
            &self.force_x
        } else {
            &self.particles.x
        }
    }

    /// The contacts of the last force evaluation (the last step's, or the one made
    /// when the system was built or its configuration written), with the forces
    /// that evaluation applied: the contacts with spheres and images sphere by
    /// sphere (in the order of the neighbour list), then the wall contacts wall
    /// by wall.
    /// See the module documentation of [`crate::md::contacts`] for the
    /// conventions; the forces of the list add up, sphere by sphere, to
    /// [`super::Particles::f`] minus the background damping.
    pub fn contact_forces(&self) -> Vec<MdContactInfo> {
        let p = &self.particles;
        let n = p.len();
        let x = self.force_positions();
        let nb = &self.neighbours;
        let g = &self.ghosts;
        let mut out = Vec::new();
        if nb.start.len() == n + 1 && nb.hist.len() == nb.j.len() {
            for i in 0..n {
                for e in nb.start[i] as usize..nb.start[i + 1] as usize {
                    let h = &nb.hist[e];
                    if !h.touching() {
                        continue;
                    }
                    let j = nb.j[e] as usize;
                    let (xj, kind) = if j < n {
                        (x[j], MdContactKind::Pair { j })
                    } else {
                        let k = j - n;
                        let o = g.origin[k] as usize;
                        (g.image_of(k, &x[o]), MdContactKind::Image { origin: o, planes: g.mask[k] })
                    };
                    // The operations of the pair loop, hence its normal bit for bit.
                    let d = x[i] - xj;
                    let dist = d.norm_squared().sqrt();
                    let nrm = if dist > 0.0 { d * (1.0 / dist) } else { V3::z() };
                    let point = x[i] - nrm * (p.r[i] - 0.5 * h.delta);
                    out.push(info(i, kind, point, nrm, h));
                }
            }
        }
        let nw = self.walls.len();
        if self.wall_hist.len() == n * nw {
            for (k, wall) in self.walls.iter().enumerate() {
                for &i in &wall.candidates {
                    let i = i as usize;
                    let h = &self.wall_hist[i * nw + k];
                    if !h.touching() {
                        continue;
                    }
                    // The normal depends on the centre only (not on a servo
                    // wall's displacement, which moved after the evaluation).
                    let Some((_, nrm, _)) = wall.gap(&x[i], p.r[i]) else { continue };
                    let point = x[i] - nrm * (p.r[i] - h.delta);
                    out.push(info(i, MdContactKind::Wall { wall: k }, point, nrm, h));
                }
            }
        }
        out
    }
}
