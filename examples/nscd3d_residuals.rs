//! Which contact points hold a 3D NSCD solve: a 3D scene run for some steps, then its last step's check pass
//! point by point ([`ballast::nscd::d3::system::System3::check_by_point`]), the diagnosis behind
//! docs/track3d.md, "Why Gauss–Seidel stops at the cap on the loaded 2 000-grain section".
//!
//! `cargo run --release --example nscd3d_residuals -- SCENE.toml [STEPS] [THREADS] [TOP] [RUN_DIR]` (defaults 1, 1,
//! 10). The scene runs with its own `[nscd]` settings; with `RUN_DIR`, from the state of that run's
//! `checkpoint.json` (its warm start included) instead of the scene's, with the scene's `[nscd]` settings (as
//! `ballast run --resume --change-solver` takes them). Each step's sweeps are printed, and after the last step:
//! - the step's sweeps and the `quad` norms of the check pass of the final iterate (`QuadDV`, `QuadDVR`,
//!   `MeanDVoR`), summed over the springs and the points;
//! - the share of `QuadDV`² and of `QuadDVR`² held by the springs and by the 1, 10, 100 and 1 000 leading points;
//! - the TOP points by their share of `QuadDVR`² (of the springs' and points' sum), with their bodies, normal, impulse and the ratio
//!   `|P_T| / P_N` (the friction coefficient when the point slides).

use ballast::nscd::method::criterion::SweepNorms;

#[path = "common/resumed.rs"]
mod resumed;

/// One of the sums of [`SweepNorms`].
type Part = fn(&SweepNorms) -> f64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().ok_or("usage: nscd3d_residuals SCENE.toml [STEPS] [THREADS] [TOP]")?;
    let steps: u64 = args.get(1).map_or(Ok(1), |s| s.parse())?;
    let threads: usize = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let top: usize = args.get(3).map_or(Ok(10), |s| s.parse())?;
    let mut sys = resumed::system(path, args.get(4).map(String::as_str))?;
    sys.set_threads(threads);
    let mut last = None;
    for _ in 0..steps {
        let t = std::time::Instant::now();
        let stats = sys.step()?;
        let s = t.elapsed().as_secs_f64();
        println!("step {}: {} sweeps, converged {}, {s:.2} s", sys.steps, stats.nlgs.iterations, stats.nlgs.converged);
        last = Some(stats);
    }
    let stats = last.ok_or("STEPS must be at least 1")?;
    let (springs, points) = sys.check_by_point();
    let of_springs = springs.iter().fold(SweepNorms::default(), |s, n| s.merged(*n));
    let sum = points.iter().fold(of_springs, |s, (_, n)| s.merged(*n));
    let [quad_dv, _, quad_dvr, _, mean_dvor] = sum.norms();
    println!(
        "step {}: {} contact points, {} loaded; {} sweeps, converged {}; QuadDV {quad_dv:.3e}, QuadDVR {quad_dvr:.3e}, \
         MeanDVoR {mean_dvor:.3e}",
        sys.steps, stats.contacts, sum.active, stats.nlgs.iterations, stats.nlgs.converged
    );
    // Shares of the sum over the springs and the points: the springs' together, then the leading points'.
    let share = |value: Part| {
        let mut v: Vec<f64> = points.iter().map(|(_, n)| value(n)).collect();
        v.sort_by(|a, b| b.total_cmp(a));
        let part = |x: f64| fraction(x, value(&sum));
        (part(value(&of_springs)), [1, 10, 100, 1000].map(|k| part(v.iter().take(k).sum())))
    };
    let norms: [(&str, Part); 2] = [("QuadDV² ", |n| n.sum_dvdv), ("QuadDVR²", |n| n.sum_dvdvrr)];
    for (label, value) in norms {
        let (by_springs, leading) = share(value);
        println!(
            "share of {label}: the {} springs {by_springs:.3}; the leading 1, 10, 100, 1000 points {leading:.3?}",
            springs.len()
        );
    }
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| points[j].1.sum_dvdvrr.total_cmp(&points[i].1.sum_dvdvrr));
    let name = |i: u32| sys.bodies.info[i as usize].name.clone();
    for &i in order.iter().take(top) {
        let ((a, b, k), n) = points[i];
        let c = &sys.contacts()[i];
        let pt = c.p[1].hypot(c.p[2]);
        println!(
            "  {:5.1} %  {} – {} (point {k}): n [{:+.3}, {:+.3}, {:+.3}], P_N {:.3e} N·s, |P_T|/P_N {:.3}, gap {:.2e} m",
            100.0 * fraction(n.sum_dvdvrr, sum.sum_dvdvrr),
            name(a),
            name(b),
            c.frame[0].x,
            c.frame[0].y,
            c.frame[0].z,
            c.p[0],
            if c.p[0] > 0.0 { pt / c.p[0] } else { 0.0 },
            c.gap
        );
    }
    Ok(())
}

/// `x / total`, 0 when the total is (a converged step whose check pass changes nothing).
fn fraction(x: f64, total: f64) -> f64 {
    if total > 0.0 {
        x / total
    } else {
        0.0
    }
}
