//! `ballast`: granular mechanics under cyclic loading, for railway ballast settlement.
//!
//! - [`nscd`]: non-smooth contact dynamics of rigid 2D polygons (Moreau–Jean θ-method,
//!   nonlinear Gauss–Seidel with exact Coulomb friction, shadow-overlap detection,
//!   viscoelastic sublayer);
//! - [`scene`]: TOML scene files, their validation, and building a system from them;
//! - [`io`]: output files (`series.csv`, `final.json`).
//!
//! All quantities are SI and `f64`.
//!
//! ```
//! let scene = ballast::scene::Scene::load("examples/block_on_floor.toml")?;
//! let mut sys = scene.build()?; // nscd::System: plain serde data
//! for _ in 0..scene.steps() {
//!     let stats = sys.step()?; // contacts, iterations, criterion, overlaps, kinetic energy
//!     assert!(stats.max_overlap < 1e-6);
//! }
//! println!("{:?}", sys.bodies.q); // (x, y, θ) of every centre of mass
//! # Ok::<(), ballast::Error>(())
//! ```

pub mod clock;
pub mod error;
pub mod geometry;
pub mod io;
pub mod md;
pub mod nscd;
pub mod run;
pub mod scenarios;
pub mod scene;
pub mod team;

pub use error::{Error, Result};
