//! The statistics of an ensemble of replicas: the mean with its Student-t 95 % interval ([`Estimate`],
//! [`t_quantile_975`] from `statrs`) and the difference of two means with Welch's interval ([`welch`]).

use super::*;

/// The 0.975 quantile of Student's t distribution with `dof` degrees of
/// freedom (> 0, not necessarily whole): the factor of a two-sided 95 %
/// interval (`statrs`; 12.706 for 1, 2.776445 for 4, → 1.959964 as `dof` → ∞).
/// NaN for `dof` ≤ 0 or NaN.
///
/// `statrs` inverts the regularised incomplete beta function: within 1e-9 of
/// the tables up to 1e4 degrees of freedom, but 7e-6 off at 1e5 and 0.13 at 1e7.
/// Above [`T_EXPANSION_DOF`] the Cornish–Fisher expansion of the t quantile
/// about the normal one is taken instead (`z + (z³ + z)/4ν + (5z⁵ + 16z³ +
/// 3z)/96ν² + (3z⁷ + 19z⁵ + 17z³ − 15z)/384ν³`, Abramowitz & Stegun 26.7.5),
/// whose first omitted term is below 1e-14 there. Replicas give far fewer
/// degrees of freedom; this only keeps the function right everywhere.
pub fn t_quantile_975(dof: f64) -> f64 {
    if dof > T_EXPANSION_DOF {
        let z = Z_975;
        let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
        return z
            + (z3 + z) / (4.0 * dof)
            + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof)
            + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * dof.powi(3));
    }
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(t) if dof > 0.0 => t.inverse_cdf(0.975),
        _ => f64::NAN,
    }
}

/// Degrees of freedom above which [`t_quantile_975`] is an expansion about the
/// normal quantile rather than `statrs`.
pub const T_EXPANSION_DOF: f64 = 1e4;

/// The 0.975 quantile of the standard normal distribution.
const Z_975: f64 = 1.959_963_984_540_054;

/// The mean of some replicas' values and its 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Number of values (replicas).
    pub n: usize,
    /// Arithmetic mean (unit of the values).
    pub mean: f64,
    /// Sample standard deviation, divisor `n − 1`; `None` for one value.
    pub sd: Option<f64>,
    /// 95 % confidence interval of the mean, `(low, high)` =
    /// `mean ∓ t_{0.975, n−1} · sd / √n`; `None` for one value.
    pub ci95: Option<(f64, f64)>,
}

impl Estimate {
    /// The estimate of the mean of `values`; `None` if there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        if n == 1 {
            return Some(Self { n, mean, sd: None, ci95: None });
        }
        let var = values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let sd = var.sqrt();
        let half = t_quantile_975((n - 1) as f64) * sd / (n as f64).sqrt();
        Some(Self { n, mean, sd: Some(sd), ci95: Some((mean - half, mean + half)) })
    }

    /// The lower end of the interval.
    pub fn low(&self) -> Option<f64> {
        self.ci95.map(|c| c.0)
    }

    /// The upper end of the interval.
    pub fn high(&self) -> Option<f64> {
        self.ci95.map(|c| c.1)
    }
}

/// The difference of two means, `mean(a) − mean(b)`, with Welch's 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Difference {
    /// `mean(a) − mean(b)` (unit of the values).
    pub diff: f64,
    /// Its standard error `√(s_a²/n_a + s_b²/n_b)`.
    pub se: f64,
    /// Welch–Satterthwaite degrees of freedom; when both samples have a zero
    /// spread (`se = 0`) it is undefined and `n_a + n_b − 2` is taken (the
    /// interval has zero width whatever it is).
    pub dof: f64,
    /// 95 % interval `(low, high)` = `diff ∓ t_{0.975, dof} · se`.
    pub ci95: (f64, f64),
}

impl Difference {
    /// Whether 0 is inside the interval: the two means cannot be told apart at 95 %.
    pub fn contains_zero(&self) -> bool {
        self.ci95.0 <= 0.0 && 0.0 <= self.ci95.1
    }
}

/// The difference of the means of `a` and `b` with Welch's 95 % interval
/// (unequal variances); `None` unless each has two values or more.
pub fn welch(a: &[f64], b: &[f64]) -> Option<Difference> {
    let (ea, eb) = (Estimate::of(a)?, Estimate::of(b)?);
    let (sa, sb) = (ea.sd?, eb.sd?);
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (va, vb) = (sa * sa / na, sb * sb / nb);
    let se = (va + vb).sqrt();
    let dof = if se > 0.0 { (va + vb).powi(2) / (va * va / (na - 1.0) + vb * vb / (nb - 1.0)) } else { na + nb - 2.0 };
    let diff = ea.mean - eb.mean;
    let half = t_quantile_975(dof) * se;
    Some(Difference { diff, se, dof, ci95: (diff - half, diff + half) })
}
