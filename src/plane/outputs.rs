//! What both 2D engines write the same way, over [`PlaneSystem`] (their bodies,
//! clock and contact list): `final.json` bodies, `contacts.csv` rows, the
//! per-cycle output that follows a body (the sleeper: Saussine et al. 2006 §4),
//! the coordination number and the generalised positions `(x, y, θ)` a driver
//! reads. The NSCD engine ([`crate::nscd::engine`]) and the planar MD engine
//! (`md::planar::engine`) implement [`crate::engine::Engine`] through these.

use super::{Bodies, ContactInfo};
use crate::engine::contacts::{ContactKind, ContactRow};
use crate::engine::final_state::{BodyState, FinalState, Spin};
use crate::engine::Configuration;
use crate::error::{Error, Result};
use crate::plane::rows::{PlaneCycleRow, PlaneCycleState};

/// A 2D system as the shared outputs see it.
pub trait PlaneSystem {
    /// Its bodies.
    fn plane_bodies(&self) -> &Bodies;
    /// Time at the end of the last step (s).
    fn plane_time(&self) -> f64;
    /// Steps made.
    fn plane_step(&self) -> u64;
    /// The contact points of the last step with their forces, sorted by
    /// (candidate, antagonist, feature).
    fn plane_contacts(&self) -> Vec<ContactInfo>;
}

/// The state of every body for `final.json`, by engine `engine`.
pub fn final_state(sys: &impl PlaneSystem, engine: &str) -> FinalState {
    let b = sys.plane_bodies();
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
            orientation: None,
        })
        .collect();
    FinalState { engine: engine.into(), time: sys.plane_time(), step: sys.plane_step(), bodies, walls: Vec::new() }
}

/// One row of `contacts.csv` per contact point; a contact with a fixed body is a
/// `wall` row seen from the other body (normal and forces turned round if the
/// fixed body was the candidate).
pub fn contact_rows(sys: &impl PlaneSystem) -> Vec<ContactRow> {
    let info = &sys.plane_bodies().info;
    sys.plane_contacts()
        .into_iter()
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

/// Starts the per-cycle output following body `body` (the sleeper, required).
///
/// # Errors
/// [`Error::Scene`] if there is no body or it does not exist.
pub fn cycle_start(sys: &impl PlaneSystem, body: Option<usize>) -> Result<PlaneCycleState> {
    let bodies = sys.plane_bodies();
    let body = body.ok_or_else(|| Error::Scene("output.cycles.body: name the followed body (the sleeper)".into()))?;
    let q = bodies.q.get(body).ok_or_else(|| {
        Error::Scene(format!("output.cycles.body: body {body} does not exist ({} bodies)", bodies.len()))
    })?;
    Ok(PlaneCycleState::new(body, q[1]))
}

/// What one step adds to the cycle under way, besides the bodies' state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleStepStats {
    /// Contacts detected.
    pub contacts: usize,
    /// Sweeps of the solver (0 for an explicit engine).
    pub iterations: usize,
    /// Largest overlap (m).
    pub max_overlap: f64,
    /// Mean overlap of the force-carrying contacts (m).
    pub mean_overlap: f64,
}

/// Adds a step to the cycle under way: the followed body's position and the
/// load minimum, the other mobile bodies' mean speed, the step's `stats`.
pub fn cycle_step(sys: &impl PlaneSystem, c: &mut PlaneCycleState, stats: CycleStepStats) {
    let CycleStepStats { contacts, iterations, max_overlap, mean_overlap } = stats;
    let bodies = sys.plane_bodies();
    let y = bodies.q[c.body][1];
    let load: [f64; 2] = bodies.info[c.body].loads.iter().fold([0.0, 0.0], |f, l| {
        let g = l.at(sys.plane_time());
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
    for (i, (info, u)) in bodies.info.iter().zip(&bodies.u).enumerate() {
        if i != c.body && !info.fixed {
            speed += u[0].hypot(u[1]);
            n += 1;
        }
    }
    c.sum_speed += if n > 0 { speed / n as f64 } else { 0.0 };
    c.sum_contacts += contacts as f64;
    c.sum_iterations += iterations as f64;
    c.max_overlap = c.max_overlap.max(max_overlap);
    c.sum_mean_overlap += mean_overlap;
}

/// Closes cycle `cycle` at the current step: its row; the accumulators start again.
pub fn cycle_end(sys: &impl PlaneSystem, c: &mut PlaneCycleState, cycle: u64) -> PlaneCycleRow {
    let k = c.steps.max(1) as f64;
    let row = PlaneCycleRow {
        cycle,
        time_s: sys.plane_time(),
        settlement_mean_m: c.y0 - c.sum_y / k,
        settlement_at_min_load_m: c.y0 - c.y_at_min_load,
        mean_grain_speed_m_s: c.sum_speed / k,
        contacts: c.sum_contacts / k,
        iterations: c.sum_iterations / k,
        max_overlap_m: c.max_overlap,
        mean_overlap_m: c.sum_mean_overlap / k,
        coordination: {
            let grains: Vec<usize> = mobile_bodies(sys.plane_bodies()).into_iter().filter(|&i| i != c.body).collect();
            coordination(sys, &grains, 0.0).z
        },
    };
    if c.first_cycle_q.is_none() {
        c.first_cycle_q = Some(sys.plane_bodies().q.clone());
    }
    c.restart();
    row
}

/// The settlement of the followed body since the start (m, positive downwards).
pub fn settlement(sys: &impl PlaneSystem, c: &PlaneCycleState) -> Option<f64> {
    sys.plane_bodies().q.get(c.body).map(|q| c.y0 - q[1])
}

/// Coordination of a set of grains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coordination {
    /// Mean number of force-carrying neighbours of the non-rattler grains
    /// (neighbours: grains or boundary bodies; a pair touching along an edge,
    /// with two contact points, counts once).
    pub z: f64,
    /// Fraction of the grains that are rattlers (fewer than 2 force-carrying neighbours).
    pub rattlers: f64,
}

/// Coordination number of `grains` over the last step: a neighbour counts when
/// the pair's total normal force exceeds `threshold` (N).
pub fn coordination(sys: &impl PlaneSystem, grains: &[usize], threshold: f64) -> Coordination {
    let count = neighbour_counts(sys, threshold);
    let active: Vec<usize> = grains.iter().map(|&i| count[i]).filter(|&k| k >= 2).collect();
    let z = if active.is_empty() { 0.0 } else { active.iter().sum::<usize>() as f64 / active.len() as f64 };
    let rattlers = if grains.is_empty() { 0.0 } else { 1.0 - active.len() as f64 / grains.len() as f64 };
    Coordination { z, rattlers }
}

/// Per body (every body, fixed ones too), the number of bodies it touches with
/// a pair force `Σ r_n` (summed over the pair's contact points, N) above
/// `threshold`.
pub fn neighbour_counts(sys: &impl PlaneSystem, threshold: f64) -> Vec<usize> {
    let n = sys.plane_bodies().len();
    // Contacts come sorted by (candidate, antagonist, feature): sum each pair's points.
    let mut pairs: Vec<(usize, usize, f64)> = Vec::new();
    for c in sys.plane_contacts() {
        match pairs.last_mut() {
            Some(p) if p.0 == c.candidate && p.1 == c.antagonist => p.2 += c.r_n,
            _ => pairs.push((c.candidate, c.antagonist, c.r_n)),
        }
    }
    let mut count = vec![0usize; n];
    for &(a, b, f) in &pairs {
        if f > threshold {
            count[a] += 1;
            count[b] += 1;
        }
    }
    count
}

/// The bodies that are not fixed.
pub fn mobile_bodies(bodies: &Bodies) -> Vec<usize> {
    (0..bodies.len()).filter(|&i| !bodies.info[i].fixed).collect()
}

/// The generalised positions `(x, y, θ)` of `which`.
pub fn configuration_of(bodies: &Bodies, which: &[usize]) -> Configuration {
    let q = which.iter().flat_map(|&i| bodies.q[i]).collect();
    Configuration { dof: 3, bodies: which.to_vec(), q }
}

/// The radius of the disc of the same area per body of `which` (m): a compound
/// (the sleeper and its feet) is as large as its area, not as its smallest part.
pub fn body_sizes(bodies: &Bodies, which: &[usize]) -> Vec<f64> {
    which.iter().map(|&i| (bodies.info[i].shape.area_and_polar_moment().0 / std::f64::consts::PI).sqrt()).collect()
}

/// Checks that a 2D state holds together (a state read from a checkpoint):
/// array lengths, finite positions, velocities and inverse masses, material
/// indices below `materials`, springs' bodies in range. The message names what
/// is wrong.
///
/// # Errors
/// [`Error::Scene`] naming the body or spring.
pub fn check_bodies(b: &Bodies, materials: usize, springs: &[super::Spring]) -> Result<()> {
    let bad = |msg: String| Err(Error::Scene(msg));
    let n = b.len();
    if b.info.len() != n || b.u.len() != n || b.inv_m.len() != n {
        return bad(format!(
            "bodies: {} positions, {} velocities, {} inverse masses, {} descriptions",
            n,
            b.u.len(),
            b.inv_m.len(),
            b.info.len()
        ));
    }
    if let Some(i) = (0..n).find(|&i| b.q[i].iter().chain(&b.u[i]).chain(&b.inv_m[i]).any(|x| !x.is_finite())) {
        return bad(format!("body {i}: a position, velocity or inverse mass is not finite"));
    }
    if let Some(i) = (0..n).find(|&i| b.info[i].material >= materials) {
        return bad(format!("body {i}: material {} of {materials}", b.info[i].material));
    }
    for (k, s) in springs.iter().enumerate() {
        if s.a >= n || s.b.is_some_and(|j| j >= n) {
            return bad(format!("spring {k}: body out of range ({n} bodies)"));
        }
    }
    Ok(())
}

/// Checks that the bodies and springs of a state (read from a checkpoint) are
/// those of the model built from the scene, `fresh`: names, shapes, materials,
/// masses, inverse masses, fixed, imposed, loads; springs but their impulses.
///
/// # Errors
/// [`Error::Scene`] "… differs from the scene's", naming the body or spring.
pub fn check_same_bodies(state: (&Bodies, &[super::Spring]), fresh: (&Bodies, &[super::Spring])) -> Result<()> {
    let bad = |what: String| Err(Error::Scene(format!("{what} differs from the scene's")));
    let ((bodies, springs), (fresh_bodies, fresh_springs)) = (state, fresh);
    if bodies.len() != fresh_bodies.len() {
        return bad(format!("the number of bodies ({})", bodies.len()));
    }
    for (i, (a, b)) in bodies.info.iter().zip(&fresh_bodies.info).enumerate() {
        if !same(a, b) {
            return bad(format!("body {i} ('{}')", crate::error::clip(&b.name)));
        }
    }
    if springs.len() != fresh_springs.len() {
        return bad(format!("the number of springs ({})", springs.len()));
    }
    for (k, (a, b)) in springs.iter().zip(fresh_springs).enumerate() {
        let a = super::Spring { impulse: 0.0, ..a.clone() };
        let b = super::Spring { impulse: 0.0, ..b.clone() };
        if !same(&a, &b) {
            return bad(format!("spring {k}"));
        }
    }
    if let Some(i) = (0..bodies.len()).find(|&i| !same(&bodies.inv_m[i], &fresh_bodies.inv_m[i])) {
        return bad(format!("the inverse masses of body {i} ('{}')", crate::error::clip(&fresh_bodies.info[i].name)));
    }
    Ok(())
}

/// Whether two values serialise to the same JSON (bit-exact floats through
/// serde_json's shortest round-trip form).
pub(crate) fn same<T: serde::Serialize>(a: &T, b: &T) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}
