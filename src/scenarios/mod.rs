//! Ready-made scenes, built as scene values ([`Scene`] for the NSCD engine,
//! [`MdScene`](crate::scene::MdScene) for the MD one) and validated like a
//! scene file, so that they are saved with `to_toml_string` and rerun like any
//! hand-written scene: the pentagon deposit of the Saussine ballast tests
//! ([`deposit`]), the full Saussine et al. (2006) sample with its sublayer, side
//! walls or free bank, and loaded sleeper ([`saussine`]), the Karrech et al.
//! (2007) sphere sample ([`karrech`]), the cyclic triaxial box of David et al.
//! ([`luding`]), and the MD benchmark bed ([`md_bed`], built as a system).
//!
//! Impossible parameters (a non-positive radius, time step or width, a box too
//! narrow for the grains, spheres that cannot be placed…) are
//! [`Error::Scene`] with a one-line message naming the generator and the
//! parameter, never a panic, an endless loop or a scene that fails later.

pub mod deposit;
pub mod grains3d;
pub mod karrech;
pub mod luding;
pub mod md_bed;
pub mod saussine;
pub mod track3d;

pub use deposit::{pentagon_deposit, DepositSpec};

use crate::error::{Error, Result};
use crate::scene::SceneFile;
use crate::scene::{BodySpec, Scene};

/// `Err(Error::Scene(msg))`.
pub(crate) fn refuse<T>(msg: String) -> Result<T> {
    Err(Error::Scene(msg))
}

/// `v` if it is finite and > 0, else an error `{what} must be positive and finite, got {v}`.
pub(crate) fn positive(what: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        refuse(format!("{what} must be positive and finite, got {v}"))
    }
}

/// `v` if it is finite and ≥ 0, else an error naming `what`.
pub(crate) fn non_negative(what: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        refuse(format!("{what} must be non-negative and finite, got {v}"))
    }
}

/// `v` if it is a θ of the Moreau–Jean scheme, in [1/2, 1], else an error `{what} must be in [0.5, 1], got {v}`.
pub(crate) fn theta(what: &str, v: f64) -> Result<f64> {
    if (0.5..=1.0).contains(&v) {
        Ok(v)
    } else {
        refuse(format!("{what} must be in [0.5, 1], got {v}"))
    }
}

/// `v` if it is finite, else an error naming `what`.
pub(crate) fn finite(what: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        refuse(format!("{what} must be finite, got {v}"))
    }
}

/// Checks a grading `(circumradius m, count)` of generator `ctx`: every radius
/// positive and finite, at least one grain. Returns the number of grains and the
/// smallest and largest radius (m) of the classes that have grains.
pub(crate) fn grading(ctx: &str, grading: &[(f64, usize)]) -> Result<(usize, f64, f64)> {
    for (i, &(r, _)) in grading.iter().enumerate() {
        positive(&format!("{ctx}: grading[{i}] radius (m)"), r)?;
    }
    let n: usize = grading.iter().map(|g| g.1).sum();
    if n == 0 {
        return refuse(format!("{ctx}: grading: the grading has no grain (every count is 0)"));
    }
    let used = grading.iter().filter(|g| g.1 > 0).map(|g| g.0);
    let r_min = used.clone().fold(f64::INFINITY, f64::min);
    let r_max = used.fold(0.0, f64::max);
    Ok((n, r_min, r_max))
}

/// A body of `material` at `position` (m) with no shape yet and every optional key absent.
pub(crate) fn body(name: impl Into<String>, material: &str, position: [f64; 2]) -> BodySpec {
    BodySpec {
        name: name.into(),
        material: material.into(),
        polygon: None,
        regular: None,
        disc: None,
        parts: None,
        position,
        angle: None,
        velocity: None,
        spin: None,
        fixed: None,
        imposed: None,
        load: None,
    }
}

/// The rectangle `[x0, x1] × [y0, y1]` (m) as a counter-clockwise vertex list.
pub(crate) fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// A generated NSCD scene after the validation of a scene file.
pub(crate) fn validated(scene: Scene) -> Result<Scene> {
    scene.validate()?;
    Ok(scene)
}

/// An MD `[[material]]`: density (kg/m³), Young's modulus (Pa), Poisson's ratio.
pub(crate) fn md_material(name: &str, density: f64, young: f64, poisson: f64) -> crate::scene::md::MdMaterial {
    crate::scene::md::MdMaterial { name: name.into(), density, young, poisson }
}

/// An MD `[[body]]` sphere of `radius` (m) at `position` (m), at rest.
pub(crate) fn md_sphere(
    name: String,
    material: &str,
    radius: f64,
    position: crate::md::V3,
) -> crate::scene::md::SphereSpec {
    crate::scene::md::SphereSpec {
        name,
        material: material.into(),
        sphere: radius,
        position: xyz(position),
        velocity: None,
        spin: None,
    }
}

/// An MD plane `[[wall]]` through `point` (m) with `normal` into the spheres' side.
pub(crate) fn md_plane(
    name: String,
    material: &str,
    point: crate::md::V3,
    normal: crate::md::V3,
    servo: Option<crate::scene::md::ServoSpec>,
) -> crate::scene::md::WallSpec {
    crate::scene::md::WallSpec {
        name,
        material: material.into(),
        plane: Some(crate::scene::md::PlaneSpec { point: xyz(point), normal: xyz(normal) }),
        disc: None,
        cylinder: None,
        servo,
    }
}

/// The components of `v`.
pub(crate) fn xyz(v: crate::md::V3) -> [f64; 3] {
    [v[0], v[1], v[2]]
}
