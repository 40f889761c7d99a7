//! What the 3D NSCD engine measures of its state for the run loop and a cyclic driver: the vertical (against
//! gravity) and a body's height along it, the gravitational potential energy, the neighbours of each body that
//! carry a force, the coordination number and the mean speed of the grains.
//!
//! **Coordination.** A *neighbour* of a body is another body — mobile, or fixed (a floor, a wall) — with which the
//! last step's contact points of the pair carry a total normal force `Σ r_n` above a threshold (0: any
//! compression); a face-to-face pair with four contact points counts once. The coordination number of a set of
//! mobile bodies is the mean number of neighbours over those with **at least two** (a body with fewer is a
//! rattler: it does not take part in the force network), 0 when none has two — the definition of the 2D engines
//! ([`crate::plane::outputs::coordination`]), so the columns compare.

use super::system::System3;
use crate::geometry::Vec3;

/// The unit vector against `gravity` (`+z` without gravity).
pub fn up(gravity: &Vec3) -> Vec3 {
    let n = gravity.norm();
    if n > 0.0 && n.is_finite() {
        -gravity / n
    } else {
        Vec3::z()
    }
}

/// Body `i`'s height along `up` (m): its centroid `x · up`.
pub fn height(sys: &System3, i: usize, up: &Vec3) -> f64 {
    sys.bodies.pose[i].position.dot(up)
}

/// Potential energy (J): the gravitational energy of the mobile bodies `−Σ m g · x` (zero at the world origin)
/// plus the elastic energy of the sublayer springs.
pub fn potential_energy(sys: &System3) -> f64 {
    let g = sys.params.gravity;
    let gravitational: f64 = (0..sys.bodies.len())
        .filter(|&i| sys.bodies.is_mobile(i))
        .map(|i| -sys.bodies.info[i].mass * g.dot(&sys.bodies.pose[i].position))
        .sum();
    gravitational + sys.spring_energy()
}

/// Per body (fixed ones too), the number of bodies it touches with a pair force `Σ r_n` over the pair's contact
/// points of the last step above `threshold` (N).
pub fn neighbour_counts(sys: &System3, threshold: f64) -> Vec<usize> {
    // Contacts are sorted by (candidate, antagonist, point): a pair's points are consecutive.
    let mut pairs: Vec<(usize, usize, f64)> = Vec::new();
    for c in sys.contact_forces() {
        let (a, b) = (c.candidate as usize, c.antagonist as usize);
        match pairs.last_mut() {
            Some(p) if p.0 == a && p.1 == b => p.2 += c.r_n,
            _ => pairs.push((a, b, c.r_n)),
        }
    }
    let mut count = vec![0usize; sys.bodies.len()];
    for &(a, b, f) in &pairs {
        if f > threshold {
            count[a] += 1;
            count[b] += 1;
        }
    }
    count
}

/// Coordination of a set of grains (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coordination {
    /// Mean number of force-carrying neighbours of the grains that have at least two.
    pub z: f64,
    /// Fraction of the grains that are rattlers (fewer than two force-carrying neighbours).
    pub rattlers: f64,
}

/// The coordination of `grains` over the last step, a neighbour counting when the pair's total normal force is
/// above `threshold` (N; module doc).
pub fn coordination(sys: &System3, grains: &[usize], threshold: f64) -> Coordination {
    let count = neighbour_counts(sys, threshold);
    let active: Vec<usize> = grains.iter().map(|&i| count[i]).filter(|&k| k >= 2).collect();
    let z = if active.is_empty() { 0.0 } else { active.iter().sum::<usize>() as f64 / active.len() as f64 };
    let rattlers = if grains.is_empty() { 0.0 } else { 1.0 - active.len() as f64 / grains.len() as f64 };
    Coordination { z, rattlers }
}

/// The bodies that are not fixed.
pub fn mobile_bodies(sys: &System3) -> Vec<usize> {
    (0..sys.bodies.len()).filter(|&i| sys.bodies.is_mobile(i)).collect()
}

/// The mean speed of the centroids of the mobile bodies other than `except` (m/s), 0 if there is none.
pub fn mean_speed(sys: &System3, except: usize) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in (0..sys.bodies.len()).filter(|&i| i != except && sys.bodies.is_mobile(i)) {
        let u = &sys.bodies.u[i];
        sum += (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        n += 1;
    }
    if n > 0 {
        sum / n as f64
    } else {
        0.0
    }
}
