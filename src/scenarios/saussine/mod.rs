//! The ballast sample of Saussine et al. (2006), §3–4: a pentagon layer
//! deposited under gravity on a viscoelastic sublayer, then a rigid sleeper with
//! bars under its lower face, loaded by `F = A + B cos(2π f t − φ)`.
//!
//! Two stages, each a plain [`Scene`] value, validated like a scene file and
//! saved with [`Scene::to_toml_string`](crate::scene::SceneFile::to_toml_string) to be run by `ballast run`, so that every
//! stage is saved, validated and rerun like a hand-written scene:
//! 1. [`sample_scene`]: the loose sample above the sublayer, between two side
//!    walls, to deposit until equilibrium. With [`SampleSpec::bank`] the side walls
//!    of the deposit are a mould that [`open_bank`] removes afterwards, so the
//!    layer ends with a free bank formed by the grains themselves (a second run
//!    to equilibrium), inside a wider frame.
//! 2. [`loaded_scene`]: the deposited sample with the sleeper placed on top and
//!    loaded, the sublayer stiffness scaled, the solver and step set for a study.
//!
//! The geometry and its reasoning are in `data/saussine2006/README.md`:
//! "diameter" of the paper's grading is the circumscribed diameter (circumradii
//! 5, 7.5, 10 mm); the out-of-plane thickness is 1 m (LMGC90's 2D convention, so
//! the paper's force and sublayer values apply as printed); each sublayer pad
//! is a 20 × 10 mm rigid block on one spring of law (17) of rest length 10 mm
//! with `k_N` = 4100 N per unit strain and `ν` = 80 N·s, moving vertically only.

//!
//! The files: `mod.rs` the sample, `loading.rs` the sleeper and its load, `measure.rs` what `sample.json` records.

mod loading;
mod measure;

pub use loading::{loaded_scene, Guide, LoadingSpec, SLEEPER_WIDTH};
pub use measure::{measure_sample, SampleReport};

use super::{body, finite, non_negative, positive, rect, refuse, validated};
use crate::error::{Error, Result};
use crate::nscd::Policy;
use crate::run::Equilibrium;
use crate::scene::{
    BodySpec, ContactEntry, Drive, ImposedSpec, LoadSpec, Material, NscdSection, OutputSection, RegularSpec, Scene,
    Simulation, SpringSpec,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// Names of the bodies the stages look for.
pub const SLEEPER: &str = "sleeper";
/// Prefix of the sublayer pads' names (`pad0`, `pad1`, …).
pub const PAD_PREFIX: &str = "pad";
/// Prefix of the grains' names (`g0`, `g1`, …).
pub const GRAIN_PREFIX: &str = "g";
/// Names of the mould walls removed by [`open_bank`].
pub const MOULD: [&str; 2] = ["mould_left", "mould_right"];

/// The fewest grains the paper's sample can be [scaled](SampleSpec::scaled) to:
/// the scaled width `n / 724` m must hold the largest grain (2 × 10 mm + 2 × 1 mm
/// of clearance = 22 mm, `n ≥ 15.9`), and [`sample_scene`] refuses a narrower
/// one. Fewer grains gave a box narrower than a grain (the grains started inside
/// the walls and the deposit diverged at its first step) and, for a width below
/// two pad gaps (2 mm, one grain), pads of negative width (a clockwise polygon).
pub const MIN_SCALED_GRAINS: usize = 16;

/// The sample of stage 1.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleSpec {
    /// `(circumradius m, count)` of each grain class.
    pub grading: Vec<(f64, usize)>,
    /// Inner width between the side walls of the deposit (m).
    pub width: f64,
    /// The deposit walls are a mould removed after deposition (free banks).
    pub bank: bool,
    /// With `bank`: extent of the sublayer and frame beyond the mould on each side (m).
    pub bank_margin: f64,
    /// Width of each sublayer pad (m) as asked; the pads are widened slightly so
    /// that a whole number of them fills the frame.
    pub pad_width: f64,
    /// Height of each sublayer pad (m); the pads' top faces are at `y = 0`.
    pub pad_height: f64,
    /// Gap between neighbouring pads, and between the outer pads and the frame (m).
    pub pad_gap: f64,
    /// Rest length `L0` of the pad springs (m).
    pub spring_length: f64,
    /// Law (17): force per unit strain `k_N` of each pad spring (N), before
    /// [`LoadingSpec::stiffness_factor`].
    pub k_n: f64,
    /// Law (17): force per unit strain rate `ν` of each pad spring (N·s), the dashpot.
    pub nu: f64,
    /// Grain density (kg/m³; the out-of-plane thickness is 1 m).
    pub density: f64,
    /// Coulomb friction coefficient `μ` of grain–grain and grain–pad contacts
    /// (dimensionless; the side walls are smooth).
    pub friction: f64,
    /// Seed of the random grading order, grain angles and initial velocities
    /// (±0.02 m/s per component); recorded in the scene.
    pub seed: u64,
    /// Time step of the deposit (s).
    pub dt: f64,
    /// Longest deposit (s): the run stops earlier at equilibrium (kinetic energy below
    /// 1e-11 J per grain for 500 steps).
    pub max_duration: f64,
}

impl SampleSpec {
    /// The paper's sample: 361 pentagons of 1 cm, 242 of 1.5 cm, 121 of 2 cm
    /// (circumscribed diameters), ρ = 2367 kg/m³, μ = 0.5, e = 0, between walls 1 m
    /// apart (a layer about 10 cm thick), on pads with k_N = 4100 N, ν = 80 N·s.
    pub fn saussine(seed: u64) -> Self {
        Self {
            grading: vec![(0.005, 361), (0.0075, 242), (0.01, 121)],
            width: 1.0,
            bank: false,
            bank_margin: 0.25,
            pad_width: 0.02,
            pad_height: 0.01,
            pad_gap: 0.001,
            spring_length: 0.01,
            k_n: 4100.0,
            nu: 80.0,
            density: 2367.0,
            friction: 0.5,
            seed,
            dt: 2e-4,
            max_duration: 4.0,
        }
    }

    /// The same grading scaled to about `n` grains in the proportions 361 : 242 : 121
    /// (at least one of each size), and the width scaled by `n` over the grading's
    /// number of grains (724 for the paper's) to keep the layer's thickness (for
    /// quick tests). The width must still hold the largest grain
    /// ([`SampleSpec::min_width`], 22 mm for the paper's grading): below
    /// [`MIN_SCALED_GRAINS`] grains it does not, and [`sample_scene`] refuses the spec.
    pub fn scaled(mut self, n: usize) -> Self {
        let total: usize = self.grading.iter().map(|g| g.1).sum();
        let f = n as f64 / total as f64;
        self.grading.iter_mut().for_each(|g| g.1 = ((g.1 as f64 * f).round() as usize).max(1));
        self.width *= f;
        self
    }

    /// The narrowest `width` (m) that holds the largest grain between the walls:
    /// its circumscribed diameter and [`CLEARANCE`] on each side.
    pub fn min_width(&self) -> f64 {
        let r_max = self.grading.iter().filter(|g| g.1 > 0).map(|g| g.0).fold(0.0, f64::max);
        2.0 * r_max + 2.0 * CLEARANCE
    }

    /// Width of the frame and of the sublayer (m): `width`, plus `bank_margin` on
    /// each side with `bank`.
    pub fn frame_width(&self) -> f64 {
        if self.bank {
            self.width + 2.0 * self.bank_margin
        } else {
            self.width
        }
    }

    /// Total solid area of the grains (m²): a regular pentagon of circumradius r has area (5/2) r² sin 72°.
    pub fn solid_area(&self) -> f64 {
        self.grading.iter().map(|&(r, n)| n as f64 * 2.5 * r * r * (0.4 * PI).sin()).sum()
    }
}

/// Gap (m) between neighbouring grains of a row, and between rows, at the start
/// of the deposit (and between a row's ends and the walls).
pub const CLEARANCE: f64 = 0.001;

/// Checks the sample `spec`; returns the number of grains.
fn check_sample(spec: &SampleSpec) -> Result<usize> {
    let (n, r_min, r_max) = super::grading("sample", &spec.grading)?;
    let width = positive("sample: width (m)", spec.width)?;
    let min_width = spec.min_width();
    if width < min_width {
        return refuse(format!(
            "sample: width {width} m cannot hold the largest grain (at least 2 × {r_max} m + 2 × {CLEARANCE} m =              {min_width} m; a grading scaled to fewer than {MIN_SCALED_GRAINS} grains is too narrow)"
        ));
    }
    let pad_width = positive("sample: pad_width (m)", spec.pad_width)?;
    positive("sample: pad_height (m)", spec.pad_height)?;
    let gap = non_negative("sample: pad_gap (m)", spec.pad_gap)?;
    if 2.0 * gap >= pad_width {
        return refuse(format!("sample: pad_gap {gap} m must be less than half the pad_width {pad_width} m"));
    }
    if spec.bank {
        non_negative("sample: bank_margin (m)", spec.bank_margin)?;
        // The mould stands 1 mm above the pads: the grains must not pass under it.
        let inradius = r_min * (PI / 5.0).cos();
        if inradius <= MOULD_GAP {
            return refuse(format!(
                "sample: grading: with a bank, the smallest grain (inradius {inradius} m) would pass under the mould                  ({MOULD_GAP} m above the pads)"
            ));
        }
    }
    // The frame holds at least one pad with its gaps (the sample's width does:
    // it holds a grain of 2 r_max ≥ pad_width + 2 pad_gap for the paper's values).
    let frame = spec.frame_width();
    if frame < pad_width + 2.0 * gap {
        return refuse(format!(
            "sample: width {frame} m of the frame cannot hold one pad (pad_width {pad_width} m + 2 × pad_gap {gap} m)"
        ));
    }
    positive("sample: spring_length (m)", spec.spring_length)?;
    non_negative("sample: k_n (N)", spec.k_n)?;
    non_negative("sample: nu (N·s)", spec.nu)?;
    positive("sample: density (kg/m³)", spec.density)?;
    non_negative("sample: friction", spec.friction)?;
    positive("sample: dt (s)", spec.dt)?;
    positive("sample: max_duration (s)", spec.max_duration)?;
    Ok(n)
}

/// Height (m) of the mould's lower edge above the pads' top faces.
const MOULD_GAP: f64 = 0.001;

/// The stage-1 scene: loose grains above the sublayer, to deposit until
/// equilibrium (kinetic energy below 1e-11 J per grain for 500 steps),
/// validated like a scene file.
///
/// # Errors
/// [`Error::Scene`] naming the parameter: a grading without grains or with a
/// radius that is not positive, a `width` narrower than [`SampleSpec::min_width`]
/// (a grading [scaled](SampleSpec::scaled) to fewer than [`MIN_SCALED_GRAINS`]
/// grains), pads that do not fit, with `bank` a smallest grain that would pass
/// under the mould (1 mm above the pads), a size, stiffness, density, time step or
/// duration that is not positive (or, for `pad_gap`, `bank_margin`, `k_n`, `nu`
/// and `friction`, non-negative) and finite.
pub fn sample_scene(spec: &SampleSpec) -> Result<Scene> {
    let n = check_sample(spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let radii = super::deposit::shuffled_radii(&spec.grading, &mut rng);

    // Sublayer: pads side by side over the frame's width, top faces at y = 0.
    let frame = spec.frame_width();
    let pitch = spec.pad_width + spec.pad_gap;
    let pads = ((frame + spec.pad_gap) / pitch).floor().max(1.0) as usize;
    let pad_w = (frame - spec.pad_gap * (pads as f64 + 1.0)) / pads as f64;
    let pad_x = |k: usize| -frame / 2.0 + spec.pad_gap + pad_w / 2.0 + k as f64 * (pad_w + spec.pad_gap);
    let (ph, l0) = (spec.pad_height, spec.spring_length);
    let y_anchor = -ph / 2.0 - l0;

    // Grains: rows filled left to right inside the deposit walls, each grain
    // 1 mm from its neighbours, rows one largest diameter + 1 mm apart: a loose
    // but compact start, so the layer falls only a few centimetres. The width
    // holds the largest grain (checked), so every row has at least one grain.
    let clearance = CLEARANCE;
    let (left, right) = (-spec.width / 2.0, spec.width / 2.0);
    let mut placed = Vec::with_capacity(n);
    let (mut x, mut y_row, mut row_r) = (left, ph.max(0.0) + clearance, 0.0f64);
    let mut row: Vec<(f64, f64)> = Vec::new();
    let flush = |row: &mut Vec<(f64, f64)>, y_row: f64, row_r: f64, placed: &mut Vec<(f64, f64, f64)>| {
        for &(xc, r) in row.iter() {
            placed.push((xc, y_row + row_r, r));
        }
        row.clear();
    };
    for &r in &radii {
        if x + 2.0 * r + clearance > right {
            flush(&mut row, y_row, row_r, &mut placed);
            y_row += 2.0 * row_r + clearance;
            x = left;
            row_r = 0.0;
        }
        row.push((x + clearance + r, r));
        x += 2.0 * r + clearance;
        row_r = row_r.max(r);
    }
    flush(&mut row, y_row, row_r, &mut placed);
    let top = placed.iter().map(|p| p.1 + p.2).fold(0.0, f64::max);
    let wall_top = top + 0.05;

    // Frame: side walls down past the pads (the sublayer stands in the frame).
    let t = 0.05;
    let bottom = y_anchor - 0.01;
    let (fl, fr) = (-frame / 2.0, frame / 2.0);
    let mut walls =
        vec![("left_wall", rect(fl - t, bottom, fl, wall_top)), ("right_wall", rect(fr, bottom, fr + t, wall_top))];
    if spec.bank {
        // The mould stands 1 mm above the pads (checked: the grains cannot pass).
        walls.push((MOULD[0], rect(left - t, MOULD_GAP, left, wall_top)));
        walls.push((MOULD[1], rect(right, MOULD_GAP, right + t, wall_top)));
    }
    let mut bodies = Vec::with_capacity(walls.len() + pads + n);
    for (name, poly) in walls {
        bodies.push(BodySpec { polygon: Some(poly), fixed: Some(true), ..body(name, "frame", [0.0, 0.0]) });
    }
    let zero = Some(Drive::Constant(0.0));
    for k in 0..pads {
        bodies.push(BodySpec {
            polygon: Some(rect(-pad_w / 2.0, -ph / 2.0, pad_w / 2.0, ph / 2.0)),
            imposed: Some(ImposedSpec { vx: zero, vy: None, spin: zero }),
            ..body(format!("{PAD_PREFIX}{k}"), "elastomer", [pad_x(k), -ph / 2.0])
        });
    }
    for (k, &(xc, yc, r)) in placed.iter().enumerate() {
        let angle = 2.0 * PI * rng.random::<f64>();
        let v = [0.02 * rng.random_range(-1.0..1.0), 0.02 * rng.random_range(-1.0..1.0)];
        bodies.push(BodySpec {
            regular: Some(RegularSpec { sides: 5, radius: r }),
            angle: Some(angle),
            velocity: Some(v),
            ..body(format!("{GRAIN_PREFIX}{k}"), "ballast", [xc, yc])
        });
    }
    let springs = (0..pads)
        .map(|k| SpringSpec {
            body: format!("{PAD_PREFIX}{k}"),
            point: None,
            anchor: Some([pad_x(k), y_anchor]),
            other: None,
            other_point: None,
            k_n: spec.k_n,
            nu: Some(spec.nu),
            rest_length: Some(l0),
            prestrain: None,
            compression_only: None,
        })
        .collect();
    // Grain–grain and grain–sublayer contacts have the paper's μ; the frame's side
    // walls are smooth (μ = 0), so that the sublayer alone carries the weight (no
    // Janssen share on the walls; measured with μ = 0.5 walls: −1.3 % of the weight,
    // held down by the walls after the sublayer's rebound).
    let contacts = [("ballast", spec.friction), ("elastomer", spec.friction), ("frame", 0.0)]
        .into_iter()
        .map(|(other, friction)| ContactEntry {
            between: ["ballast".into(), other.into()],
            friction,
            restitution: None,
            tangential_restitution: None,
        })
        .collect();
    validated(Scene {
        soft: None,
        simulation: Simulation {
            engine: "nscd".into(),
            dt: spec.dt,
            duration: spec.max_duration,
            gravity: Some(vec![0.0, -9.81]),
            dimension: None,
            thickness: Some(1.0),
            seed: Some(spec.seed),
            equilibrium: Some(Equilibrium {
                kinetic_energy: Some(1e-11 * n as f64),
                energy_ratio: None,
                steps: Some(500),
            }),
        },
        nscd: Some(NscdSection {
            theta: Some(0.5),
            criterion: Some("quad_max".into()),
            tolerance: Some(1.0e-4),
            max_iterations: Some(2000),
            ..NscdSection::default()
        }),
        output: Some(OutputSection { every: Some(50), cycles: None }),
        settlement: None,
        materials: [("ballast", spec.density), ("elastomer", 1100.0), ("frame", 2400.0)]
            .into_iter()
            .map(|(name, density)| Material { name: name.into(), density })
            .collect(),
        contacts,
        bodies,
        springs,
    })
}

/// Stage 1b of a free-bank sample: the deposited sample without its mould, to be
/// run to equilibrium again (the grains slump into their own bank slope).
pub fn open_bank(sample: &Scene) -> Result<Scene> {
    let mut out = sample.clone();
    let before = out.bodies.len();
    out.bodies.retain(|b| !MOULD.contains(&b.name.as_str()));
    if out.bodies.len() == before {
        return Err(Error::Scene("open_bank: the sample has no mould walls (it was not made with a bank)".into()));
    }
    Ok(out)
}
