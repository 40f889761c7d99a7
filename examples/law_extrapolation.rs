//! The settlement law alone, with no landing: a full run's own settlement
//! (its `settlement.csv`) fitted on the cycles `k_i … k_i + k` and extrapolated
//! to cycle `N`, against what that run accrued from `k_i` to `N`. No write-back,
//! relaxation or re-seating is involved, so this is the error the settlement
//! driver cannot go below with one jump of `N − k_i − k` cycles after a window
//! of `k` (Karrech et al. 2007, eqs. 17–21 and Fig. 11's error against `k`; the
//! error measured, as everywhere, on the settlement accrued after `k_i`).
//!
//! ```sh
//! cargo run --release --example law_extrapolation -- N K_I LAW FULL_DIR [FULL_DIR …]
//! cargo run --release --example law_extrapolation -- 200 10 shenton_decelerating \
//!     data/karrech2007/acceleration-200/full data/karrech2007/acceleration-200/replica1
//! ```
//! Prints one line per run: the error for k = 10, 20, 30, 40, 60, 80, 100
//! (those that end before `N`), in per cent of the run's own accrual.

use ballast::settlement::{law_named, SettlementRow};
use std::path::Path;

const USAGE: &str = "usage: law_extrapolation N K_I LAW FULL_DIR [FULL_DIR …]";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [n, ki, law, dirs @ ..] = args.as_slice() else { return Err(USAGE.into()) };
    if dirs.is_empty() {
        return Err(USAGE.into());
    }
    let (target, ki): (u64, u64) = (n.parse()?, ki.parse()?);
    let law = law_named(law)?;
    println!("accrual {ki} -> {target} by the {} fit on cycles {ki}..{ki}+k, error against the run's own:", law.name());
    for dir in dirs {
        let rows: Vec<SettlementRow> = ballast::io::read_csv(&Path::new(dir).join("settlement.csv"))?;
        let at = |cycle: u64| -> Result<f64, String> {
            rows.iter()
                .find(|r| r.cycle == cycle && r.computed == 1)
                .map(|r| r.settlement_m)
                .ok_or_else(|| format!("{dir}: no computed cycle {cycle}"))
        };
        let accrued = at(target)? - at(ki)?;
        let mut line = Vec::new();
        for k in [10u64, 20, 30, 40, 60, 80, 100].into_iter().filter(|&k| ki + k < target) {
            let cycles: Vec<f64> = (ki..=ki + k).map(|c| c as f64).collect();
            let u = (ki..=ki + k).map(&at).collect::<Result<Vec<f64>, String>>()?;
            let c = law.fit(&cycles, &u, &vec![0; cycles.len()]);
            let last = (ki + k) as f64;
            let predicted = law.extrapolate(&c, last, u[u.len() - 1], target as f64 - last) - u[0];
            line.push(format!("k={k}: {:+.0} %", 100.0 * (predicted - accrued) / accrued));
        }
        println!("  {dir} (accrued {:.1} um): {}", accrued * 1e6, line.join(", "));
    }
    Ok(())
}
