//! The NSCD engine: non-smooth contact dynamics of rigid 2D convex polygons and
//! discs (Moreau–Jean), following Saussine, Cholet, Gautier, Dubois, Bohatier,
//! Moreau, *Modelling ballast behaviour under dynamic loading. Part 1*, CMAME
//! 195 (2006) 2841–2859, §2.
//!
//! Data flow of a step: [`stepper`] (θ-method) → [`detection`] ([`broad_phase`]
//! grid, [`shadow_overlap`] / [`narrow_phase`]) → [`contact`] rows → [`nlgs`]
//! ([`coulomb`] local solver, [`sublayer`] springs). The method of the step's solve
//! — Gauss–Seidel, its policies ([`criterion`]), the check pass and the split of two
//! halves swept side by side ([`split`]) — is [`method`], generic over the contact's
//! dimension; this folder brings the 2D rows and the finishers on the 2D law
//! ([`apgd`], `interior`).
//!
//! A system built in code: [`System::new`] with the parameters
//! ([`NscdParams::default`]: θ = 1/2, g = 9.81 m/s² down, the scenes' NLGS
//! settings) and the number of materials, whose pairs are frictionless and
//! plastic until [`System::set_law`] says otherwise; bodies from
//! [`BodyInfo::polygon`] (vertices where they are in the world; mass `ρ t A` and
//! inertia `ρ t J` computed, the centroid returned to push the body at) and its
//! siblings ([`bodies`]). Here a 0.1 m granite square resting on a fixed floor:
//! once at rest, the floor carries its weight, so the normal forces of its
//! contacts (mean forces over the last step, [`System::contact_forces`]) sum to
//! `m g`. At rest the impulses of a step balance the weight over the step to
//! the NLGS tolerance (1e-4, relative, on the impulses), so the check allows
//! 1e-3 of the weight.
//! ```
//! use ballast::nscd::{BodyInfo, ContactLaw, NscdParams, System};
//! let mut sys = System::new(NscdParams { dt: 1e-3, ..NscdParams::default() }, 1);
//! sys.set_law(0, 0, ContactLaw { friction: 0.5, ..ContactLaw::default() });
//! let (floor, q) = BodyInfo::polygon("floor", &[[-0.5, -0.1], [0.5, -0.1], [0.5, 0.0], [-0.5, 0.0]], 0, 2700.0, 1.0)?;
//! sys.bodies.push(floor.into_fixed(), q, [0.0; 3]);
//! let (block, q) = BodyInfo::polygon("block", &[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]], 0, 2700.0, 1.0)?;
//! let weight = block.mass * 9.81; // ρ a² t g = 27 kg × 9.81 m/s²
//! let block = sys.bodies.push(block, q, [0.0; 3]);
//! sys.params.alert_distance = sys.bodies.default_alert_distance(); // as a scene's: 0.5 mm here
//! for _ in 0..100 {
//!     sys.step()?;
//! }
//! let carried: f64 = sys.contact_forces().filter(|c| c.candidate == block || c.antagonist == block).map(|c| c.r_n).sum();
//! assert!((carried - weight).abs() < 1e-3 * weight, "{carried} N for a weight of {weight} N");
//! assert!(sys.bodies.q[block][1] - 0.05 > -1e-6); // resting on the floor, overlap below 1 µm
//! # Ok::<(), ballast::Error>(())
//! ```

pub mod apgd;
pub mod contact;
pub mod coulomb;
pub mod d3;
pub mod engine;
#[cfg(feature = "faer")]
pub mod interior;
pub mod measure;
pub mod method;
pub mod nlgs;
pub mod stepper;
pub mod sublayer;
pub mod system;

// The bodies, loads and detection shared with the 2D MD engine ([`crate::plane`]),
// under their former paths.
pub use crate::plane::{bodies, broad_phase, detection, loads, narrow_phase, relax, shadow_overlap};
// The method's convergence policies and split, under their former paths.
pub use method::{criterion, split};

pub use bodies::{Bodies, BodyInfo};
pub use contact::ContactLaw;
pub use criterion::{Measure, Policy};
pub use loads::{Harmonic, Imposed, Load};
pub use nlgs::NlgsSettings;
pub use sublayer::Spring;
pub use system::{ContactInfo, NscdParams, StepStats, System};
