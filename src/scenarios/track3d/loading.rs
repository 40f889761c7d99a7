//! Stage 2 of the 3D track section (Saussine et al. 2006, §3.1 and §4 in 3D): the deposited sample with a rigid
//! sleeper placed on the highest grain under its footprint, guided along `z`, under
//! `F = A + B cos(2π f t − φ)` along `z`, the cycles followed on it, the sublayer stiffness scaled (§4.2), and
//! the solver and time step of the loaded run ([`loaded_scene`]).
//!
//! Decisions, written down:
//! - **Sleeper**: a concrete box (2400 kg/m³) 0.2 m high (about the depth of a monoblock concrete sleeper under
//!   the rail seat), as wide along the track as half the box's length — 0.3 m on the default 0.6 m box, the
//!   base width of a monoblock sleeper (0.26–0.30 m); a scaled sample gets the same share of its box — and as
//!   long across the track as the box, less [`SLEEPER_GAP`] at each end (the section is a slice of the sleeper
//!   under a rail seat). Its lower face starts [`DROP`] above the highest grain vertex under its footprint;
//!   guided along `z` (`vx = vy = 0`, spin 0), as the 2D test's jack guides its sleeper.
//! - **Load as a pressure** on the sleeper's lower face (`A = p_A × w × l`, `B = p_B × w × l`): the 2D paper's
//!   `A` = −1000 N, `B` = −500 N on its 0.25 m sleeper per 1 m of depth, i.e. `p_A` = −4 kPa and `p_B` = −2 kPa,
//!   the same carry-over per unit area as the sublayer's (module doc of [`super`]); `f` = 20 Hz, `φ` = −π, so
//!   the load starts at its smallest magnitude `A − B` (−2 kPa) and peaks at `A + B` (−6 kPa) half a cycle
//!   later. A real axle load puts about a hundred times this under a sleeper; `mean_pressure` and
//!   `amplitude_pressure` set it. The sleeper's own weight (4.7 kPa for 0.2 m of concrete) adds to it.
//! - **Solver of the loaded run**: dt = 2e-4 s (250 steps per cycle at 20 Hz, the 2D study's step), `quad`
//!   1e-4, 1 to 20 000 sweeps (`docs/track3d.md` has the 3D studies of the stopping rule: over cycles 11–20 of
//!   the 200-grain section the seated sleeper settles about 2 µm per cycle at 1e-4, 0.6 at 3e-5 and 0.4 at
//!   1e-5, so most of 1e-4's is the solver's creep), a `series.csv` row every 10 steps, `cycles.csv` with the
//!   grains' positions at every cycle end (what a settlement driver fits).

use super::*;
use crate::error::Error;
use crate::scene::d3::LoadSpec3;
use crate::scene::CyclesSpec;
use std::f64::consts::PI;

/// Gap (m) between the sleeper's ends and the walls across the track.
pub const SLEEPER_GAP: f64 = 0.005;
/// Height (m) of the sleeper's lower face above the highest grain under it at the start.
pub const DROP: f64 = 5e-4;
/// The sleeper's material.
pub const CONCRETE: &str = "concrete";

/// The loading stage's settings, for the scene ([`loaded_scene`]), the studies and the command line.
/// [`LoadingSpec::default`]: the 2D paper's load per unit area, 100 cycles.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadingSpec {
    /// Width of the sleeper along the track, `x` (m); `None`: half the box's length.
    pub sleeper_width: Option<f64>,
    /// Length of the sleeper across the track, `y` (m); `None`: the box's width less [`SLEEPER_GAP`] at each end.
    pub sleeper_length: Option<f64>,
    /// Height of the sleeper (m).
    pub sleeper_height: f64,
    /// Density of the sleeper (kg/m³).
    pub sleeper_density: f64,
    /// `A / (w l)`: the load's mean as a pressure on the sleeper's lower face (Pa; negative pushes down).
    pub mean_pressure: f64,
    /// `B / (w l)`: the amplitude of its cosine as a pressure (Pa).
    pub amplitude_pressure: f64,
    /// `f`: loading frequency (Hz).
    pub frequency: f64,
    /// `φ`: phase of the cosine (rad).
    pub phase: f64,
    /// Factor on the sublayer's stiffness, each spring keeping its static force (§4.2: 1, 100, 1000).
    pub stiffness_factor: f64,
    /// Number of loading cycles.
    pub cycles: u64,
    /// Time step (s).
    pub dt: f64,
    /// θ of the Moreau–Jean scheme, in [1/2, 1]: the paper's 1/2 (default), whatever θ the sample was deposited
    /// with ([`super::SampleSpec::theta`]).
    pub theta: f64,
    /// NLGS policy: `strict`, `quad`, `quad_max`, `energy` or `velocity`.
    pub criterion: String,
    /// Tolerance of the policy, in (0, 1).
    pub tolerance: f64,
    /// Fewest sweeps per step (≥ 1).
    pub min_iterations: usize,
    /// Most sweeps per step (≥ `min_iterations`); default 20 000. At 2 000, the default before, steps ended at
    /// the cap and the sleeper slipped by 0.1–0.4 mm in single cycles over 20 cycles of the 200-grain section;
    /// at 20 000 no replica slipped, for fewer sweeps on average (`docs/track3d.md`,
    /// "The sweep cap and the creep over 20 cycles").
    pub max_iterations: usize,
    /// The face–face gap rule of the grains' contacts (`nscd.face_gaps`): `exact` (default) or `common_plane`
    /// (LMGC90's; [`crate::space::detection::FaceGaps`]).
    pub face_gaps: String,
    /// What a closed contact does with an overlap (`nscd.overlaps`): `kept` (default, Moreau–Jean's
    /// velocity-level law) or `held` (an overlap may not grow; [`crate::nscd::d3::overlaps::Overlaps`]).
    pub overlaps: String,
    /// Depth of the Anderson mixing of the sweeps (`nscd.anderson`, 0 to
    /// [`crate::nscd::method::anderson::MAX_DEPTH`]; 0: plain sweeps).
    pub anderson: usize,
    /// Steps between rows of `series.csv`.
    pub output_every: u64,
}

/// Default of [`LoadingSpec::anderson`]: the sweeps mixed over the last 5 differences (BENCHMARKS.md, "Anderson
/// acceleration of the NLGS sweeps").
pub const DEFAULT_ANDERSON: usize = 5;

impl LoadingSpec {
    /// The 2D paper's load carried over as a pressure, on a concrete sleeper (module doc), `cycles` cycles.
    pub fn track(cycles: u64) -> Self {
        Self {
            sleeper_width: None,
            sleeper_length: None,
            sleeper_height: 0.2,
            sleeper_density: 2400.0,
            mean_pressure: -1000.0 / 0.25,
            amplitude_pressure: -500.0 / 0.25,
            frequency: 20.0,
            phase: -PI,
            stiffness_factor: 1.0,
            cycles,
            dt: 2e-4,
            theta: 0.5,
            criterion: "quad".into(),
            tolerance: 1e-4,
            min_iterations: 1,
            max_iterations: 20_000,
            face_gaps: crate::space::detection::FaceGaps::Exact.name().into(),
            overlaps: crate::nscd::d3::overlaps::Overlaps::Kept.name().into(),
            anderson: DEFAULT_ANDERSON,
            output_every: 10,
        }
    }

    /// Checks every field; one-line errors led by the field's name.
    ///
    /// # Errors
    /// [`Error::Scene`] naming the first field out of range.
    pub fn check(&self) -> Result<()> {
        if let Some(w) = self.sleeper_width {
            positive("sleeper_width: the sleeper's width (m)", w)?;
        }
        if let Some(l) = self.sleeper_length {
            positive("sleeper_length: the sleeper's length (m)", l)?;
        }
        positive("sleeper_height: the sleeper's height (m)", self.sleeper_height)?;
        positive("sleeper_density: the sleeper's density (kg/m³)", self.sleeper_density)?;
        super::super::finite("mean_pressure: the load's mean A per unit area (Pa)", self.mean_pressure)?;
        super::super::finite("amplitude_pressure: the load's amplitude B per unit area (Pa)", self.amplitude_pressure)?;
        positive("frequency: the loading frequency (Hz)", self.frequency)?;
        super::super::finite("phase: the load's phase φ (rad)", self.phase)?;
        positive("stiffness_factor: the factor on the sublayer's stiffness", self.stiffness_factor)?;
        if self.cycles == 0 {
            return refuse("cycles: must be at least 1, got 0".into());
        }
        positive("dt: the time step (s)", self.dt)?;
        theta("theta:", self.theta)?;
        if Policy::from_name(&self.criterion).is_none() {
            return refuse(format!(
                "criterion: '{}' is not one of 'strict', 'quad', 'quad_max', 'energy', 'velocity'",
                self.criterion
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return refuse(format!("tolerance: must be in (0, 1), got {}", self.tolerance));
        }
        if crate::space::detection::FaceGaps::from_name(&self.face_gaps).is_none() {
            return refuse(format!("face_gaps: '{}' is not one of 'exact', 'common_plane'", self.face_gaps));
        }
        if crate::nscd::d3::overlaps::Overlaps::from_name(&self.overlaps).is_none() {
            return refuse(format!("overlaps: '{}' is not one of 'kept', 'held'", self.overlaps));
        }
        if self.anderson > crate::nscd::method::anderson::MAX_DEPTH {
            return refuse(format!(
                "anderson: the depth of the mixing must be 0 to {}, got {}",
                crate::nscd::method::anderson::MAX_DEPTH,
                self.anderson
            ));
        }
        if self.min_iterations == 0 || self.max_iterations < self.min_iterations {
            return refuse(format!(
                "min_iterations: must be at least 1 and max_iterations at least min_iterations, got {} and {}",
                self.min_iterations, self.max_iterations
            ));
        }
        if self.output_every == 0 {
            return refuse("output_every: must be at least 1, got 0".into());
        }
        Ok(())
    }

    /// The sleeper's width and length (m) in a box of inner `length × width` (m): the given ones, or half the
    /// box's length and its width less [`SLEEPER_GAP`] at each end.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `sleeper_width` or `sleeper_length` if the sleeper does not fit between the walls.
    pub fn footprint(&self, length: f64, width: f64) -> Result<(f64, f64)> {
        let w = self.sleeper_width.unwrap_or(length / 2.0);
        let l = self.sleeper_length.unwrap_or(width - 2.0 * SLEEPER_GAP);
        for (key, v, room) in [("sleeper_width", w, length), ("sleeper_length", l, width)] {
            if !(v > 0.0 && v <= room - 2.0 * SLEEPER_GAP) {
                return refuse(format!(
                    "{key}: a sleeper of {v} m does not fit in the box's {room} m with {SLEEPER_GAP} m at each end"
                ));
            }
        }
        Ok((w, l))
    }
}

impl Default for LoadingSpec {
    /// [`LoadingSpec::track`] with 100 cycles.
    fn default() -> Self {
        Self::track(100)
    }
}

/// The box's inner length and width (m) from the walls of `sample`.
fn box_of(sample: &Scene3) -> Result<(f64, f64)> {
    let at = |name: &str, k: usize| {
        sample.bodies.iter().find(|b| b.name == name).map(|b| b.position[k]).ok_or_else(|| {
            Error::Scene(format!("sample: no wall '{name}' (not a sample of scenarios::track3d::sample_scene)"))
        })
    };
    Ok((at(WALLS[1], 0)? - at(WALLS[0], 0)?, at(WALLS[3], 1)? - at(WALLS[2], 1)?))
}

/// The highest grain vertex (m) of `sample` (built as `sys`) among the grains whose horizontal extent meets the
/// footprint `|x| ≤ w/2`, `|y| ≤ l/2`.
fn surface_under(sample: &Scene3, sys: &crate::nscd::d3::system::System3, w: f64, l: f64) -> Result<f64> {
    let mut top = f64::NEG_INFINITY;
    for (i, b) in sample.bodies.iter().enumerate() {
        if !b.name.starts_with(GRAIN_PREFIX) {
            continue;
        }
        let points = measure::world_vertices(sys, i);
        let (lo, hi) = measure::extent(&points);
        if hi.x >= -w / 2.0 && lo.x <= w / 2.0 && hi.y >= -l / 2.0 && lo.y <= l / 2.0 {
            top = top.max(hi.z);
        }
    }
    if top.is_finite() {
        Ok(top)
    } else {
        Err(Error::Scene(format!("sample: no grain under the sleeper's footprint {w} × {l} m")))
    }
}

/// The stage-2 scene: `sample` (a deposited sample, `sample.toml`) with the sleeper on the highest grain under
/// it, loaded for `spec.cycles` cycles; validated like a scene file (module doc).
///
/// # Errors
/// [`Error::Scene`]: a sample that already has a sleeper, has no walls of this generator, is invalid or has no
/// grain under the sleeper; a field of `spec` out of range (named).
pub fn loaded_scene(sample: &Scene3, spec: &LoadingSpec) -> Result<Scene3> {
    if sample.bodies.iter().any(|b| b.name == SLEEPER) {
        return Err(Error::Scene("sample: the sample already has a sleeper".into()));
    }
    spec.check()?;
    let (length, width) = box_of(sample)?;
    let (w, l) = spec.footprint(length, width)?;
    let sys = sample.build()?;
    let top = surface_under(sample, &sys, w, l)?;
    let mut out = sample.clone();
    out.simulation.equilibrium = None;
    out.simulation.dt = spec.dt;
    out.simulation.duration = spec.cycles as f64 / spec.frequency;
    let nscd = out.nscd.get_or_insert_with(Default::default);
    nscd.theta = Some(spec.theta);
    nscd.criterion = Some(spec.criterion.clone());
    nscd.tolerance = Some(spec.tolerance);
    nscd.min_iterations = Some(spec.min_iterations);
    nscd.max_iterations = Some(spec.max_iterations);
    nscd.face_gaps = Some(spec.face_gaps.clone());
    nscd.overlaps = Some(spec.overlaps.clone());
    nscd.anderson = Some(spec.anderson);
    out.output = Some(OutputSection {
        every: Some(spec.output_every),
        cycles: Some(CyclesSpec { frequency: spec.frequency, body: Some(SLEEPER.into()), positions: Some(true) }),
    });
    // A stiffer sublayer carries the same static load: each spring's prestrain is reset so that its force at the
    // current length is unchanged (the 2D loaded_scene's rule).
    for (s, spring) in out.springs.iter_mut().zip(&sys.springs) {
        let stretch = (spring.state(&sys.bodies.pose).length - spring.rest_length) / spring.rest_length;
        let eps = stretch - spring.prestrain;
        s.k_n *= spec.stiffness_factor;
        s.rest_length = Some(spring.rest_length);
        s.prestrain = Some(stretch - eps / spec.stiffness_factor);
    }
    if !out.materials.iter().any(|m| m.name == CONCRETE) {
        out.materials.push(Material { name: CONCRETE.into(), density: spec.sleeper_density });
    }
    let friction = out.contacts.iter().find(|c| c.between == [BALLAST, BALLAST]).map_or(0.5, |c| c.friction);
    out.contacts.push(law(BALLAST, CONCRETE, friction));
    out.contacts.push(law(CONCRETE, FRAME, 0.0));
    let h = spec.sleeper_height;
    let area = w * l;
    out.bodies.push(BodySpec3 {
        cuboid: Some(BoxSpec { half: [w / 2.0, l / 2.0, h / 2.0] }),
        imposed: Some(guided()),
        load: Some(LoadSpec3 {
            direction: [0.0, 0.0, 1.0],
            mean: spec.mean_pressure * area,
            amplitude: spec.amplitude_pressure * area,
            frequency: spec.frequency,
            phase: spec.phase,
        }),
        ..body3(SLEEPER, CONCRETE, [0.0, 0.0, top + DROP + h / 2.0])
    });
    out.validate()?;
    Ok(out)
}
