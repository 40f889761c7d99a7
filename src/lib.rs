//! `ballast`: granular mechanics under cyclic loading, for railway ballast settlement.
//!
//! - [`nscd`]: non-smooth contact dynamics of rigid 2D polygons (Moreau–Jean θ-method,
//!   nonlinear Gauss–Seidel with exact Coulomb friction, shadow-overlap detection,
//!   viscoelastic sublayer);
//! - [`scene`]: TOML scene files, their validation, and building a system from them;
//! - [`io`]: output files (`series.csv`, `final.json`).
//!
//! All quantities are SI and `f64`.

pub mod error;
pub mod geometry;
pub mod io;
pub mod nscd;
pub mod scenarios;
pub mod scene;

pub use error::{Error, Result};
