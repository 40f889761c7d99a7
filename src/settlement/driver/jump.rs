//! One jump of the procedure (Karrech et al. 2007, Fig. 10): the fit of every mobile body's residual
//! displacement over the window, the moves bounded and extrapolated by `h` cycles, the extrapolated cycles'
//! rows, and the landing in stages ([`crate::settlement::sweep`]); and the domain check of a configuration.

use super::*;
use crate::settlement::estimate::Fit;

/// The factor on the median of the bodies' trend moves below which a jump does
/// not bound a move: the coherent motion of the sample (the grains under the
/// sleeper follow it) is never cut, only the outliers.
pub const MEDIAN_MOVES: f64 = 3.0;

/// The median of `x` (reordered; 0 if empty).
fn median(x: &mut [f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mid = x.len() / 2;
    let (_, m, _) = x.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Checks that every body of `c` is inside the run's domain: the box of the
/// translations of `origin` (the start of the loading) widened on every side
/// by half its largest side. A body outside has left the container (through a
/// wall or over it): its motion is no settlement, and a fit would extrapolate
/// its fall. `what` says what moved it there.
pub(super) fn check_domain<E: Engine>(
    sys: &E,
    origin: &Configuration,
    c: &Configuration,
    what: impl FnOnce() -> String,
) -> Result<()> {
    let dim = E::DIM;
    let (mut lo, mut hi) = (vec![f64::INFINITY; dim], vec![f64::NEG_INFINITY; dim]);
    for b in 0..origin.len() {
        for (d, &x) in origin.body(b)[..dim].iter().enumerate() {
            lo[d] = lo[d].min(x);
            hi[d] = hi[d].max(x);
        }
    }
    let margin = 0.5 * (0..dim).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    for b in 0..c.len() {
        let x = &c.body(b)[..dim];
        if (0..dim).all(|d| x[d] >= lo[d] - margin && x[d] <= hi[d] + margin) {
            continue;
        }
        let body = c.bodies[b];
        let box_ = (0..dim).map(|d| format!("[{:.4}, {:.4}]", lo[d] - margin, hi[d] + margin)).collect::<Vec<_>>();
        return Err(Error::Diverged {
            step: sys.steps_done(),
            body,
            name: body_names(sys, &[body]).pop().unwrap_or_default(),
            what: format!(
                "{} carried it out of the domain, to {x:?} (m); the domain is {} (m), the box of the bodies at the \
                 start of the loading widened by half its size (docs/settlement-driver.md, \"Bounded moves\")",
                what(),
                box_.join(" × ")
            ),
        });
    }
    Ok(())
}

impl<E: Engine> Accelerated<E> {
    /// Whether the landing still re-seats in the computed cycle whose settlement
    /// increment is `increment` (m), the `settle_cycles`-th after it or later:
    /// with `settle_rate`, while the mean increment of the last two computed
    /// cycles since the landing exceeds `settle_rate` times the rate the jump's
    /// fit predicted there, for at most `computed_cycles` cycles past the fixed count.
    pub(super) fn still_settling(&self, st: &State<E>, increment: f64) -> bool {
        let Some(factor) = self.spec.settle_rate else { return false };
        let extra = (st.settling + 1).saturating_sub(self.spec.settle_cycles);
        if extra >= self.spec.computed_cycles {
            return false;
        }
        let mean = match st.last_increment {
            Some(previous) => 0.5 * (previous + increment),
            None => increment,
        };
        mean > factor * st.landing_rate.abs()
    }

    /// Fits the window, extrapolates, writes back and relaxes; the rows of the
    /// extrapolated cycles and the jump's row. Leaves the window as it is when
    /// the adaptive bound asks for more computed cycles. A landing that fails
    /// (a body out of the domain, a relaxation that fails or does not converge)
    /// is [`Landing::Failed`], with the state partly changed: the caller rolls
    /// it back ([`rollback`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn jump(
        &self,
        st: &mut State<E>,
        law: &dyn ResidualLaw,
        k: u64,
        left: u64,
        files: &mut Files,
        wall0: f64,
        started: &Instant,
    ) -> Result<Landing> {
        // The law's training data: the whole history, or the last window (the
        // points since the last jump).
        let first = if law.history() { 0 } else { st.window.window_start() };
        let window = if first == 0 { Cow::Borrowed(&st.window) } else { Cow::Owned(st.window.last_segment()) };
        let (settlements, boundary_points) = (&st.window_settlement[first..], &st.window_boundaries[first..]);
        let f = fit(law, &window, E::EXTRAPOLATED, E::DIM)?;
        let chernoff = match &self.spec.adaptive {
            Some(a) => {
                let need = chernoff_cycles(a.error, a.probability, f.xi_range)?;
                let cap = 10 * self.spec.computed_cycles;
                if k < need.min(cap) && left > need.min(cap) - k {
                    return Ok(Landing::Waited);
                }
                Some(need)
            }
            None => None,
        };
        let h = (st.h.round() as u64).clamp(1, left);
        let (n, segments) = (&window.cycles, &window.segments);
        let n_last = *n.last().expect("a window has points");
        let sc = law.fit(n, settlements, segments);
        // The fitted settlement's increment over the jump's last cycle.
        let landing_rate = law.trend(&sc, n_last + h as f64) - law.trend(&sc, n_last + (h - 1) as f64);
        let Moves { anchored, max_move, held, smoothing } = self.bounded_moves(st, law, &window, &f, h);
        self.write_extrapolated(
            st,
            law,
            (&window, &f, &sc),
            (h, &max_move, smoothing.as_ref()),
            files,
            wall0,
            started,
        )?;
        let (target, limited) = extrapolate_within(law, &window, &f, h as f64, &max_move, smoothing.as_ref());
        let mut row = JumpRow {
            jump: st.jumps + 1,
            from_cycle: st.cycle,
            to_cycle: st.cycle + h,
            computed_cycles: k,
            extrapolated_cycles: h,
            chernoff_cycles: chernoff,
            g_u_m: f.g_u,
            f_xi_m: f.f_xi,
            xi_range_m: f.xi_range,
            relax_tolerance_m: self.spec.relax.tolerance,
            relax_iterations: 0,
            relax_evaluations: 0,
            relax_converged: false,
            max_overlap_before_relax_m: 0.0,
            max_overlap_after_relax_m: 0.0,
            relax_largest_move: 0.0,
            relax_wall_time_s: 0.0,
            held_bodies: held,
            limited_bodies: limited as u64,
            settling_cycles: st.settling,
            landing_rate_m: landing_rate,
            rolled_back: false,
            rollback_reason: String::new(),
            relax_stages: 1,
        };
        if let Err(e) =
            check_domain(&st.sys, &st.origin, &target, || format!("the extrapolation of jump {}", st.jumps + 1))
        {
            return Ok(Landing::Failed(row, e.to_string()));
        }
        let system = (&mut st.sys, &st.boundary_origin[..], st.computed_overlap);
        let report = match self.land(system, law, (&window, boundary_points), (&target, h), &anchored, &mut row) {
            Ok(report) => report,
            Err(reason) => return Ok(Landing::Failed(row, reason)),
        };
        if let Err(e) = check_domain(&st.sys, &st.origin, &st.sys.configuration(), || {
            format!("the relaxation of jump {}", st.jumps + 1)
        }) {
            return Ok(Landing::Failed(row, e.to_string()));
        }
        st.cycle += h;
        st.jumps += 1;
        st.h *= self.spec.growth;
        let c = st.sys.configuration();
        let bounds = st.sys.boundaries();
        let s = st.settlement(&c, &bounds, E::DIM - 1, self.spec.settlement_boundary);
        st.last_settlement = s;
        if let Some(p) = files.positions.as_mut() {
            p.append(&c)?;
        }
        files.rows.write(&SettlementRow {
            cycle: st.cycle,
            computed: 0,
            settlement_m: s,
            coordination: None,
            max_overlap_before_relax_m: Some(report.max_overlap_before),
            max_overlap_after_relax_m: Some(report.max_overlap_after),
            wall_time_s: wall0 + started.elapsed().as_secs_f64(),
        })?;
        files.jumps.write(&row)?;
        st.landing_rate = landing_rate;
        st.settling = 0;
        st.last_increment = None;
        // The next window starts at the end of the first computed cycle after
        // the landing (the relaxed configuration re-seats in that cycle).
        st.since_jump = 0;
        Ok(Landing::Landed(row))
    }
}

/// What a jump may move ([`Accelerated::bounded_moves`]).
struct Moves {
    /// The anchored bodies held with `hold_anchored` (indices in the engine, sorted).
    anchored: Vec<usize>,
    /// The largest move of each body of the window (m); zero for a held body.
    max_move: Vec<f64>,
    /// How many bodies are held.
    held: u64,
    /// The smoothing of the moves over a length, if asked.
    smoothing: Option<Smoothing>,
}

impl<E: Engine> Accelerated<E> {
    /// Bounded moves: a body without a force-carrying contact is held, the others move at most
    /// `extrapolation_limit` of their size or `MEDIAN_MOVES` times the median trend move over `h` cycles,
    /// whichever is larger (docs/settlement-driver.md, "Bounded moves"); with `hold_anchored`, the sprung pads
    /// stay where the computed cycle left them, through the extrapolation and the relaxation alike.
    fn bounded_moves(&self, st: &State<E>, law: &dyn ResidualLaw, window: &Training, f: &Fit, h: u64) -> Moves {
        let bodies = &window.origin.bodies;
        let contacts = st.sys.contact_counts(bodies);
        let mut moves = trend_moves(law, window, f, h as f64);
        let coherent = MEDIAN_MOVES * median(&mut moves);
        let anchored = if self.spec.hold_anchored { st.sys.anchored_bodies() } else { Vec::new() };
        let pinned: Vec<bool> =
            (bodies.iter().zip(&contacts)).map(|(b, &n)| n == 0 || anchored.binary_search(b).is_ok()).collect();
        let max_move: Vec<f64> = (st.sys.body_sizes(bodies).iter().zip(&pinned))
            .map(|(size, &pin)| if pin { 0.0 } else { (self.spec.extrapolation_limit * size).max(coherent) })
            .collect();
        let held = pinned.iter().filter(|&&pin| pin).count() as u64;
        let smoothing = self.spec.smoothing_length.map(|length| {
            let last = window.configurations.last().expect("a fitted window has points");
            let excluded: Vec<bool> =
                (bodies.iter().zip(&pinned)).map(|(&b, &pin)| pin || Some(b) == self.spec.settlement_body).collect();
            Smoothing::new(last, E::DIM, length, &excluded)
        });
        Moves { anchored, max_move, held, smoothing }
    }

    /// The rows (and positions) of the extrapolated cycles 1 … h − 1 of a jump, on the fitted trend.
    #[allow(clippy::too_many_arguments)]
    fn write_extrapolated(
        &self,
        st: &State<E>,
        law: &dyn ResidualLaw,
        (window, f, sc): (&Training, &Fit, &[f64; 3]),
        (h, max_move, smoothing): (u64, &[f64], Option<&Smoothing>),
        files: &mut Files,
        wall0: f64,
        started: &Instant,
    ) -> Result<()> {
        let n_last = *window.cycles.last().expect("a window has points");
        for j in 1..h {
            if let Some(p) = files.positions.as_mut() {
                p.append(&extrapolate_within(law, window, f, j as f64, max_move, smoothing).0)?;
            }
            files.rows.write(&SettlementRow {
                cycle: st.cycle + j,
                computed: 0,
                settlement_m: law.extrapolate(sc, n_last, st.last_settlement, j as f64),
                coordination: None,
                max_overlap_before_relax_m: None,
                max_overlap_after_relax_m: None,
                wall_time_s: wall0 + started.elapsed().as_secs_f64(),
            })?;
        }
        Ok(())
    }

    /// The landing of a jump on `target`, `h` cycles on: the boundaries (the MD plate) extrapolated by the same
    /// law from their points in the window, then the relaxation in stages ([`sweep`]) from the computed
    /// configuration the window ends on (the system's) to the extrapolated one, holding the anchored bodies;
    /// fills the relaxation's columns of `row`. Returns why the landing failed (the relaxation failed or did not
    /// converge).
    fn land(
        &self,
        (sys, boundary_origin, computed_overlap): (&mut E, &[f64], f64),
        law: &dyn ResidualLaw,
        (window, boundary_points): (&Training, &[Vec<f64>]),
        (target, h): (&Configuration, u64),
        anchored: &[usize],
        row: &mut JumpRow,
    ) -> std::result::Result<RelaxReport, String> {
        let (n, segments) = (&window.cycles, &window.segments);
        let n_last = *n.last().expect("a window has points");
        let bodies = &window.origin.bodies;
        // The boundaries (the MD plate) follow the same law.
        let mut series = vec![0.0; n.len()];
        let boundaries: Vec<f64> = (0..boundary_origin.len())
            .map(|j| {
                series.iter_mut().zip(boundary_points).for_each(|(v, b)| *v = b[j] - boundary_origin[j]);
                let c = law.fit(n, &series, segments);
                boundary_origin[j] + law.extrapolate(&c, n_last, series[series.len() - 1], h as f64)
            })
            .collect();
        // The landing, in stages (`sweep`): from the computed configuration the
        // window ends on (the system's) to the extrapolated one.
        let from = window.configurations.last().expect("a fitted window has points").clone();
        let stages = sweep::stages(&from, target, &sys.body_sizes(bodies), E::DIM, self.spec.relax_stage);
        row.relax_stages = stages;
        let boundaries_from = coordinates(&sys.boundaries());
        let t0 = Instant::now();
        let mut relax = self.spec.relax.clone();
        for &b in anchored {
            if !relax.held.contains(&b) {
                relax.held.push(b);
            }
        }
        if self.spec.relax_to_computed {
            // A floor for a configuration without contacts: a millionth of the
            // smallest body (any overlap a jump makes there is spurious).
            let smallest = sys.body_sizes(bodies).iter().copied().fold(f64::INFINITY, f64::min);
            let floor = if smallest.is_finite() { 1e-6 * smallest } else { f64::MIN_POSITIVE };
            relax.tolerance = computed_overlap.max(floor);
        }
        row.relax_tolerance_m = relax.tolerance;
        let report: RelaxReport =
            match sweep::relax_along(sys, &from, target, (&boundaries_from, &boundaries), &relax, stages) {
                Ok(r) => r,
                Err(e) => return Err(format!("its relaxation failed: {e}")),
            };
        row.relax_iterations = report.iterations;
        row.relax_evaluations = report.evaluations;
        row.relax_converged = report.converged;
        row.max_overlap_before_relax_m = report.max_overlap_before;
        row.max_overlap_after_relax_m = report.max_overlap_after;
        row.relax_largest_move = report.largest_move;
        row.relax_wall_time_s = t0.elapsed().as_secs_f64();
        if !report.converged {
            return Err(format!(
                "its relaxation did not reach {:.3e} m ({:.3e} m left after {} iterations: {})",
                relax.tolerance, report.max_overlap_after, report.iterations, report.reason
            ));
        }
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_and_even_counts() {
        // Odd: the middle value; even: the upper middle (the bound only needs a
        // robust scale); empty: 0.
        assert_eq!(super::median(&mut [3.0, 1e-3, 2.0, 0.5, 1e3]), 2.0);
        assert_eq!(super::median(&mut [4.0, 1.0, 3.0, 2.0]), 3.0);
        assert_eq!(super::median(&mut []), 0.0);
    }
}
