//! The planar MD engine: soft-contact dynamics of the 2D scenes of the NSCD
//! engine (convex polygons, discs, compounds, fixed bodies, imposed velocities,
//! harmonic loads, sublayer springs), so that one scene runs with both methods.
//! The bodies, loads, springs and the shadow-overlap detection are those of
//! [`crate::plane`]; the contact laws are the MD engine's ([`crate::md::contact`])
//! on the contact points the detection gives ([`law`]); time integration is
//! velocity Verlet ([`system`]).
//!
//! A 0.1 m granite square dropped on a fixed floor, linear law: at rest its two
//! corners share the weight, and the face sits at the static overlap `m g / k_n`.
//! ```
//! use ballast::md::planar::{PlanarParams, PlanarSystem, SoftLaw, SoftModel};
//! use ballast::plane::BodyInfo;
//! let mut sys = PlanarSystem::new(PlanarParams { dt: 2e-5, ..PlanarParams::default() }, 1);
//! let k_n = 1e8; // N/m, the pair's stiffness (thickness included)
//! sys.set_law(0, 0, SoftLaw { model: SoftModel::Linear, normal_stiffness: k_n, tangential_ratio: 0.5, restitution: 0.1, friction: 0.5 })?;
//! let (floor, q) = BodyInfo::polygon("floor", &[[-0.5, -0.1], [0.5, -0.1], [0.5, 0.0], [-0.5, 0.0]], 0, 2700.0, 1.0)?;
//! sys.bodies.push(floor.into_fixed(), q, [0.0; 3]);
//! let (block, q) = BodyInfo::polygon("block", &[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]], 0, 2700.0, 1.0)?;
//! let overlap = block.mass * 9.81 / k_n; // 27 kg: 2.6 µm
//! let block = sys.bodies.push(block, q, [0.0; 3]);
//! for _ in 0..5000 {
//!     sys.step()?;
//! }
//! let sunk = 0.05 - sys.bodies.q[block][1];
//! assert!((sunk - overlap).abs() < 1e-3 * overlap, "{sunk} m against {overlap} m");
//! # Ok::<(), ballast::Error>(())
//! ```

pub mod engine;
pub mod law;
pub mod stiffness;
pub mod system;

pub use law::{SoftLaw, SoftModel};
pub use system::{PlanarParams, PlanarStepStats, PlanarSystem};
