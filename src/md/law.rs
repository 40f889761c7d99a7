//! Contact laws between pairs of materials, with their parameters resolved once.
//!
//! - [`Model::Hertz`]: Karrech et al. (2007) §2.2. Normal force
//!   `F_n = 4/3 E* √R* δ^{3/2}` (eq. 5), Mindlin tangential stiffness
//!   `k_t = 8 G* √(R* δ)` (eq. 6), viscous damping `γ = 2 α √(m* k)` with `k` the
//!   tangent stiffness (`k_n = 2 E* √(R* δ)`, `k_t`) (eq. 7), Coulomb limit on the
//!   elastic part and on the whole tangential force (dashpot included). For two
//!   materials `1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂` and
//!   `1/G* = (2 − ν₁)/G₁ + (2 − ν₂)/G₂` with `G = E / (2(1 + ν))`; for one material
//!   these are the paper's `E* = E / (2(1 − ν²))` and `G* = G / (2(2 − ν))`.
//! - [`Model::Linear`]: David, García-Rojo, Herrmann, Luding, *Hysteresis and creep
//!   in powders and grains*, §2: `f_n = k δ + γ₀ δ̇` (eq. 1), tangential spring and
//!   dashpot (eq. 3) with static/dynamic friction and the sliding spring reset (eq. 4).
//!
//! Contact times (the time scale a time step must resolve): [`linear_contact_time`]
//! (David et al. §2) and [`hertz_contact_time`] (the classical duration of an
//! elastic Hertz impact), both through [`PairLaw::contact_time`].
//!
//! A damping given as a restitution coefficient `e` is turned into the ratio `α`:
//! for `linear` exactly, `α = −ln e / √(π² + ln² e)` (then `r = exp(−η₀ t_c)` of
//! David et al. holds with `t_c = π/ω`); for `hertz` by [`hertz_alpha_for_restitution`].

use serde::{Deserialize, Serialize};

/// Elastic properties of a material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Density (kg/m³); unused for wall materials.
    pub density: f64,
    /// Young's modulus (Pa).
    pub young: f64,
    /// Poisson's ratio `ν` (dimensionless).
    pub poisson: f64,
}

impl Material {
    /// Shear modulus `G = E / (2(1 + ν))` (Pa).
    pub fn shear(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }
}

/// Effective Young's modulus `E*` of a pair (Pa).
pub fn e_star(a: &Material, b: &Material) -> f64 {
    1.0 / ((1.0 - a.poisson * a.poisson) / a.young + (1.0 - b.poisson * b.poisson) / b.young)
}

/// Effective shear modulus `G*` of a pair (Pa).
pub fn g_star(a: &Material, b: &Material) -> f64 {
    1.0 / ((2.0 - a.poisson) / a.shear() + (2.0 - b.poisson) / b.shear())
}

/// How a dashpot is set.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Damping {
    /// A fixed coefficient γ (kg/s).
    Coefficient(f64),
    /// A ratio α: `γ = 2 α √(m* k)` with the pair's reduced mass `m*` (kg) and
    /// stiffness `k` (N/m, the tangent stiffness for `hertz`).
    Ratio(f64),
}

impl Damping {
    /// γ (kg/s) for reduced mass `m_star` (kg) and stiffness `k` (N/m).
    #[inline(always)]
    pub fn gamma(&self, m_star: f64, k: f64) -> f64 {
        match *self {
            Damping::Coefficient(g) => g,
            Damping::Ratio(a) => 2.0 * a * (m_star * k).sqrt(),
        }
    }
}

/// The contact model of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Model {
    /// Hertz–Mindlin with viscous damping (Karrech et al. 2007).
    Hertz,
    /// Linear spring–dashpot with tangential spring (David et al., Luding).
    Linear,
}

/// Everything the force loop needs to know about a pair of materials.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PairLaw {
    /// Which force law the pair follows: Hertz–Mindlin (Karrech et al. 2007) or linear
    /// spring–dashpot (David et al.).
    pub model: Model,
    /// `hertz`: `E*` (Pa).
    pub e_star: f64,
    /// `hertz`: `G*` (Pa).
    pub g_star: f64,
    /// `linear`: normal stiffness `k` (N/m).
    pub kn: f64,
    /// `linear`: tangential stiffness `k_t` (N/m).
    pub kt: f64,
    /// Normal dashpot.
    pub damping_n: Damping,
    /// Tangential dashpot.
    pub damping_t: Damping,
    /// Static friction coefficient `μ_s`.
    pub mu_s: f64,
    /// Dynamic friction coefficient `μ_d ≤ μ_s` (`linear`; `hertz` uses `μ_s`).
    pub mu_d: f64,
    /// `hertz`: `√(k_t / k_n) = √(4 G* / E*)`, so one square root gives both dashpots.
    pub kt_kn_sqrt: f64,
}

impl PairLaw {
    /// A Hertz–Mindlin law between materials `a` and `b` with damping ratios
    /// `alpha_n`, `alpha_t` and friction `mu`.
    pub fn hertz(a: &Material, b: &Material, alpha_n: f64, alpha_t: f64, mu: f64) -> Self {
        PairLaw {
            model: Model::Hertz,
            e_star: e_star(a, b),
            g_star: g_star(a, b),
            kn: 0.0,
            kt: 0.0,
            damping_n: Damping::Ratio(alpha_n),
            damping_t: Damping::Ratio(alpha_t),
            mu_s: mu,
            mu_d: mu,
            kt_kn_sqrt: (4.0 * g_star(a, b) / e_star(a, b)).sqrt(),
        }
    }

    /// A linear spring–dashpot law.
    pub fn linear(kn: f64, kt: f64, damping_n: Damping, damping_t: Damping, mu_s: f64, mu_d: f64) -> Self {
        PairLaw {
            model: Model::Linear,
            e_star: 0.0,
            g_star: 0.0,
            kn,
            kt,
            damping_n,
            damping_t,
            mu_s,
            mu_d,
            kt_kn_sqrt: (kt / kn).sqrt(),
        }
    }
}

impl PairLaw {
    /// Normal stiffness (N/m) at overlap `delta` (m) with effective radius
    /// `r_star` (m): `k` for `linear`, the tangent stiffness `2 E* √(R* δ)` for `hertz`.
    pub fn normal_stiffness(&self, r_star: f64, delta: f64) -> f64 {
        match self.model {
            Model::Linear => self.kn,
            Model::Hertz => 2.0 * self.e_star * (r_star * delta).sqrt(),
        }
    }

    /// Normal dashpot γ_n (kg/s) at overlap `delta` (m) for reduced mass `m_star`
    /// (kg) and effective radius `r_star` (m).
    pub fn normal_dashpot(&self, m_star: f64, r_star: f64, delta: f64) -> f64 {
        self.damping_n.gamma(m_star, self.normal_stiffness(r_star, delta))
    }

    /// Elastic energy (J) of the normal spring at overlap `delta` (m): `k δ² / 2`
    /// for `linear`, `(8/15) E* √R* δ^{5/2}` for `hertz` (the work of
    /// `F_n = 4/3 E* √R* δ^{3/2}`).
    pub fn normal_energy(&self, r_star: f64, delta: f64) -> f64 {
        match self.model {
            Model::Linear => 0.5 * self.kn * delta * delta,
            Model::Hertz => 8.0 / 15.0 * self.e_star * r_star.sqrt() * delta.powf(2.5),
        }
    }

    /// Largest overlap (m) of an elastic central impact at approach speed `v`
    /// (m/s) for reduced mass `m_star` (kg) and effective radius `r_star` (m),
    /// where `m* v² / 2` has become elastic energy: `v √(m*/k)` for `linear`,
    /// [`hertz_max_overlap`] for `hertz` (a dashpot only makes it smaller).
    pub fn impact_overlap(&self, m_star: f64, r_star: f64, v: f64) -> f64 {
        match self.model {
            Model::Linear => v * (m_star / self.kn).sqrt(),
            Model::Hertz => hertz_max_overlap(m_star, r_star, self.e_star, v),
        }
    }

    /// Contact time (s) of a central impact at approach speed `v` (m/s) for
    /// reduced mass `m_star` (kg) and effective radius `r_star` (m): for `linear`
    /// [`linear_contact_time`] with the normal dashpot (independent of `v`); for
    /// `hertz` the elastic duration [`hertz_contact_time`].
    pub fn contact_time(&self, m_star: f64, r_star: f64, v: f64) -> f64 {
        match self.model {
            Model::Linear => linear_contact_time(self.kn, m_star, self.damping_n.gamma(m_star, self.kn)),
            Model::Hertz => hertz_contact_time(m_star, r_star, self.e_star, v),
        }
    }
}

/// Contact time (s) of the linear spring–dashpot, David et al. §2: the half
/// period `t_c = π / ω` of the damped oscillation, `ω = √(k/m* − η₀²)`,
/// `η₀ = γ₀ / (2 m*)`, for normal stiffness `k` (N/m), reduced mass `m_star`
/// (kg) and normal dashpot `gamma` (kg/s). Undamped, `t_c = π √(m*/k)`.
/// Infinite when the dashpot is critical or stronger (`η₀² ≥ k/m*`: no rebound).
pub fn linear_contact_time(k: f64, m_star: f64, gamma: f64) -> f64 {
    let eta = gamma / (2.0 * m_star);
    let omega2 = k / m_star - eta * eta;
    if omega2 > 0.0 {
        std::f64::consts::PI / omega2.sqrt()
    } else {
        f64::INFINITY
    }
}

/// The coefficient of [`hertz_contact_time`]: `(4/5) B(2/5, 1/2) (15/16)^{2/5}`
/// = 2.8683, with B the Beta function. The duration of an elastic impact is
/// `2 ∫₀^{δ_max} dδ / δ̇ = 2.9433 δ_max / v` (`(4/5) B(2/5, 1/2) = 2.9433`; Johnson,
/// *Contact Mechanics*, 1985, §11.4: `2.94 δ_max / v`), and
/// [`hertz_max_overlap`] turns `δ_max / v` into `(m*² / (R* E*² v))^{1/5}` times
/// `(15/16)^{2/5}`.
pub const HERTZ_DURATION: f64 = 2.868_265_699_195_331_5;

/// Duration (s) of an elastic central impact between Hertz bodies (Hertz 1882;
/// Johnson 1985 §11.4): `t_H = 2.868 (m*² / (R* E*² v))^{1/5}`
/// ([`HERTZ_DURATION`]) for reduced mass `m_star` (kg), effective radius
/// `r_star` (m), effective modulus `e_star` (Pa, as in `F_n = 4/3 E* √R* δ^{3/2}`)
/// and approach speed `v` (m/s). The stiffness grows with the overlap, so the
/// duration shrinks, slowly, with the speed: `t_H ∝ v^{-1/5}`.
pub fn hertz_contact_time(m_star: f64, r_star: f64, e_star: f64, v: f64) -> f64 {
    HERTZ_DURATION * (m_star * m_star / (r_star * e_star * e_star * v)).powf(0.2)
}

/// Largest overlap (m) of an elastic central Hertz impact at approach speed `v`
/// (m/s): `δ_max = (15 m* v² / (16 E* √R*))^{2/5}`, where the kinetic energy
/// `m* v² / 2` has become elastic energy `(8/15) E* √R* δ^{5/2}`.
pub fn hertz_max_overlap(m_star: f64, r_star: f64, e_star: f64, v: f64) -> f64 {
    (15.0 * m_star * v * v / (16.0 * e_star * r_star.sqrt())).powf(0.4)
}

/// The pair laws of all material pairs, `n × n`, symmetric.
///
/// Every pair of materials that can touch needs a law: [`crate::md::MdSystem::new`]
/// refuses a system with a pair left out ([`LawTable::check_covers`]), as MD
/// scenes do.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct LawTable {
    /// Number of materials (the table is `n × n`).
    pub n: usize,
    /// Row-major `n × n` table: `laws[a * n + b]` is the law of materials `a` and `b`,
    /// `None` when the pair does not interact.
    pub laws: Vec<Option<PairLaw>>,
    /// Names of the materials (empty, or one per material), for messages (empty:
    /// they are called by their indices). Scenes set them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub names: Vec<String>,
}

impl LawTable {
    /// A table for `n` materials (indices `0..n`) with no law yet.
    pub fn new(n: usize) -> Self {
        LawTable { n, laws: vec![None; n * n], names: Vec::new() }
    }

    /// A table for the materials `names` (material `i` is `names[i]`), with no
    /// law yet; the names appear in the messages of [`LawTable::check_covers`].
    pub fn named<S: AsRef<str>>(names: &[S]) -> Self {
        LawTable { names: names.iter().map(|s| s.as_ref().to_string()).collect(), ..LawTable::new(names.len()) }
    }

    /// `'name'` of material `i` if the table has names, else `material i`.
    pub fn material_name(&self, i: usize) -> String {
        match self.names.get(i) {
            Some(name) => format!("'{}'", crate::error::clip(name)),
            None => format!("material {i}"),
        }
    }

    /// Checks that every pair of materials that can touch in a system of these
    /// spheres and walls has a law ([`first_uncovered`]: two spheres, a sphere
    /// and its image by a symmetry plane if `symmetry`, a sphere and a wall), and
    /// that every material index is below [`LawTable::n`].
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) naming both materials and a sphere
    /// and its partner, e.g. `no contact law between materials 'glass' and
    /// 'steel', which can touch (sphere 0 'a' and wall 0 'floor')`.
    pub fn check_covers(
        &self,
        particles: &super::Particles,
        walls: &[super::Wall],
        symmetry: bool,
    ) -> crate::Result<()> {
        let bad = |msg: String| Err(crate::Error::Scene(msg));
        let n = self.n;
        if self.laws.len() != n * n {
            return bad(format!("contact laws: {} laws for {n} materials (need {})", self.laws.len(), n * n));
        }
        let sphere = |i: usize| match particles.name[i].as_str() {
            "" => format!("sphere {i}"),
            name => format!("sphere {i} '{}'", crate::error::clip(name)),
        };
        let wall = |k: usize| match walls[k].name.as_str() {
            "" => format!("wall {k}"),
            name => format!("wall {k} '{}'", crate::error::clip(name)),
        };
        if let Some(i) = (0..particles.len()).find(|&i| particles.material[i] as usize >= n) {
            return bad(format!("{}: material {} of {n}", sphere(i), particles.material[i]));
        }
        if let Some(k) = (0..walls.len()).find(|&k| walls[k].material as usize >= n) {
            return bad(format!("{}: material {} of {n}", wall(k), walls[k].material));
        }
        let spheres: Vec<usize> = particles.material.iter().map(|&m| m as usize).collect();
        let wall_materials: Vec<usize> = walls.iter().map(|w| w.material as usize).collect();
        let Some(u) = first_uncovered(n, &spheres, &wall_materials, symmetry, |a, b| self.get(a, b).is_some()) else {
            return Ok(());
        };
        let what = match u.meeting {
            Meeting::Spheres(i, j) => format!("{} and {}", sphere(i), sphere(j)),
            Meeting::Image(i) => format!("{} and its symmetry image", sphere(i)),
            Meeting::Wall(i, k) => format!("{} and {}", sphere(i), wall(k)),
        };
        bad(format!(
            "no contact law between materials {} and {}, which can touch ({what})",
            self.material_name(u.a),
            self.material_name(u.b)
        ))
    }

    /// Sets the law of the pair `(a, b)` and `(b, a)`.
    pub fn set(&mut self, a: usize, b: usize, law: PairLaw) {
        self.laws[a * self.n + b] = Some(law);
        self.laws[b * self.n + a] = Some(law);
    }

    /// The law of the pair `(a, b)`.
    #[inline(always)]
    pub fn get(&self, a: usize, b: usize) -> Option<&PairLaw> {
        self.laws[a * self.n + b].as_ref()
    }
}

/// Where two materials without a law meet (indices of spheres and walls).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Meeting {
    /// Spheres `.0` and `.1`.
    Spheres(usize, usize),
    /// Sphere `.0` and its image by a symmetry plane.
    Image(usize),
    /// Sphere `.0` and wall `.1`.
    Wall(usize, usize),
}

/// A pair of materials that can touch and has no law ([`first_uncovered`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Uncovered {
    /// The sphere's material.
    pub a: usize,
    /// The partner's material (a sphere's, or a wall's).
    pub b: usize,
    /// The first spheres or walls found that meet with these materials.
    pub meeting: Meeting,
}

/// The first pair of materials (of `materials`) that can touch and for which
/// `has_law(a, b)` (`a ≤ b` for two spheres) is false, if any: two spheres of
/// materials `a` and `b` (for `a = b`, two spheres of `a`, or one and its image
/// when `symmetry` planes mirror the spheres), or a sphere of `a` and a wall of
/// `b`. `spheres[i]` is sphere `i`'s material, `walls[k]` wall `k`'s; any sphere
/// may meet any sphere or wall (positions are not looked at: spheres move).
/// Pairs are visited by sphere material `a` (increasing), then partner sphere
/// materials `b ≥ a`, then walls in order. MD scenes
/// (`contact: no [[contact]] between …`) and [`LawTable::check_covers`] both
/// check through it.
pub fn first_uncovered(
    materials: usize,
    spheres: &[usize],
    walls: &[usize],
    symmetry: bool,
    has_law: impl Fn(usize, usize) -> bool,
) -> Option<Uncovered> {
    let (mut first, mut second) = (vec![None; materials], vec![None; materials]);
    for (i, &m) in spheres.iter().enumerate() {
        if first[m].is_none() {
            first[m] = Some(i);
        } else if second[m].is_none() {
            second[m] = Some(i);
        }
    }
    for a in 0..materials {
        let Some(i) = first[a] else { continue };
        for (b, &first_b) in first.iter().enumerate().skip(a) {
            let partner = if a == b { second[a].or(symmetry.then_some(i)) } else { first_b };
            match partner {
                Some(j) if !has_law(a, b) => {
                    let meeting = if j == i { Meeting::Image(i) } else { Meeting::Spheres(i, j) };
                    return Some(Uncovered { a, b, meeting });
                }
                _ => {}
            }
        }
        for (k, &b) in walls.iter().enumerate() {
            if !has_law(a.min(b), a.max(b)) {
                return Some(Uncovered { a, b, meeting: Meeting::Wall(i, k) });
            }
        }
    }
    None
}

/// Damping ratio `α = −ln e / √(π² + ln² e)` of a linear spring–dashpot whose
/// restitution coefficient is `e` (exact: `e = exp(−η₀ π/ω)`, `η₀ = α √(k/m*)`).
pub fn linear_alpha_for_restitution(e: f64) -> f64 {
    let l = e.ln();
    -l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
}

/// Restitution coefficient of a central Hertz impact with damping ratio `alpha`:
/// the model `m* δ̈ = −K δ^{3/2} − 2α √(m* · 3/2 K δ^{1/2}) δ̇` (the normal force
/// clamped at 0) is scaled to `x'' = −x^{3/2} − 2α √(3/2) x^{1/4} x'`, `x'(0) = 1`,
/// whose rebound speed is `e(α)`, independent of the impact speed, masses and
/// moduli. Integrated with RK4 at 20 000 steps per unit time (error < 1e-9).
pub fn hertz_restitution(alpha: f64) -> f64 {
    let c = 2.0 * alpha * 1.5f64.sqrt();
    let acc = |x: f64, v: f64| -> f64 {
        if x <= 0.0 {
            0.0
        } else {
            (-(x.powf(1.5)) - c * x.powf(0.25) * v).min(0.0)
        }
    };
    let h = 5e-5;
    let (mut x, mut v) = (0.0f64, 1.0f64);
    for _ in 0..2_000_000 {
        let (k1x, k1v) = (v, acc(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v));
        let xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if xn <= 0.0 && vn < 0.0 {
            return -vn;
        }
        if vn <= 0.0 && xn > 0.0 && acc(xn, vn) == 0.0 {
            // Force clamped to zero while still overlapping: the sphere leaves at
            // the speed it has now.
            return -vn;
        }
        x = xn;
        v = vn;
    }
    0.0
}

/// The damping ratio `α` of a Hertz contact that gives restitution `e` in a
/// central impact: the inverse of [`hertz_restitution`] (bisection to 1e-12).
/// This is the exact mapping of the model, computed from its own dimensionless
/// impact rather than an approximate fit such as Tsuji et al. (1992)'s.
pub fn hertz_alpha_for_restitution(e: f64) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while hertz_restitution(hi) > e {
        hi *= 2.0;
        if hi > 1e3 {
            break;
        }
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if hertz_restitution(mid) > e {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 {
            break;
        }
    }
    0.5 * (lo + hi)
}
