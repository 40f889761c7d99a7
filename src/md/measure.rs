//! Measurements on an MD state: the quantities of Karrech et al. Fig. 3
//! (apparent weight, coordination number, density, kinetic and potential energy)
//! and of David et al. §3 (wall stresses, deviatoric stress and strain).

use super::particles::V3;
use super::system::MdSystem;
use super::walls::{box_area, box_extent};
use nalgebra::Matrix3;

impl MdSystem {
    /// The unit vector against gravity (`+z` without gravity).
    pub fn up(&self) -> V3 {
        let g = self.settings.gravity;
        if g.norm() > 0.0 {
            -g.normalize()
        } else {
            V3::z()
        }
    }

    /// Gravitational potential energy (J) `Σ m |g| h`, `h` the height of the centre
    /// above [`MdSystem::gravity_reference`] along gravity (fixed for the run, so
    /// kinetic + potential energy is conserved without dissipation).
    pub fn gravitational_energy(&self) -> f64 {
        let g = self.settings.gravity;
        let gn = g.norm();
        if gn == 0.0 {
            return 0.0;
        }
        let up = -g / gn;
        let p = &self.particles;
        (0..p.len()).map(|i| p.m[i] * gn * (p.x[i].dot(&up) - self.gravity_reference)).sum()
    }

    /// Potential energy `E_p` (J): gravitational plus elastic (of the last evaluation).
    pub fn potential_energy(&self) -> f64 {
        self.gravitational_energy() + self.last.elastic_energy
    }

    /// Normal force (N) the spheres press on the wall named `name` with (positive
    /// when pressed): the apparent weight on a base.
    pub fn wall_load(&self, name: &str) -> Option<f64> {
        self.walls.iter().find(|w| w.name == name).map(|w| -w.normal_force())
    }

    /// Total weight of the spheres `Σ m |g|` (N).
    pub fn weight(&self) -> f64 {
        self.particles.m.iter().sum::<f64>() * self.settings.gravity.norm()
    }

    /// Packing fraction of the spheres in the slab `lo ≤ z·up ≤ hi` along `up`
    /// (unit), over a cross-section `area` (m²): exact volume of the sphere caps
    /// inside the slab divided by `area (hi − lo)`.
    pub fn packing_fraction(&self, up: V3, lo: f64, hi: f64, area: f64) -> f64 {
        let p = &self.particles;
        let cap = |r: f64, h: f64| -> f64 {
            // Volume of a sphere of radius r below a plane at height h from its bottom.
            let h = h.clamp(0.0, 2.0 * r);
            std::f64::consts::PI * h * h * (3.0 * r - h) / 3.0
        };
        let mut v = 0.0;
        for i in 0..p.len() {
            let z = p.x[i].dot(&up);
            let r = p.r[i];
            v += cap(r, hi - (z - r)) - cap(r, lo - (z - r));
        }
        v / (area * (hi - lo))
    }

    /// Stress tensor of the sample `σ = (1/V) Σ_c f_c ⊗ l_c` (Pa, compression
    /// positive) over volume `volume` (m³), from the contacts between spheres of
    /// the last evaluation (no kinetic part: quasi-static samples).
    pub fn stress(&self, volume: f64) -> Matrix3<f64> {
        self.virial / volume
    }

    /// Stress on the plane wall `name` (Pa, compression positive) over `area` (m²),
    /// or over the box face area if `area` is `None`.
    pub fn wall_stress(&self, name: &str, area: Option<f64>) -> Option<f64> {
        let w = self.walls.iter().find(|w| w.name == name)?;
        let axis = w.normal()?.iamax();
        let a = area.unwrap_or_else(|| box_area(&self.walls, axis));
        (a > 0.0).then(|| -w.normal_force() / a)
    }

    /// Box extents `(L_x, L_y, L_z)` (m) from the axis-aligned plane walls.
    pub fn box_extents(&self) -> Option<V3> {
        Some(V3::new(box_extent(&self.walls, 0)?, box_extent(&self.walls, 1)?, box_extent(&self.walls, 2)?))
    }

    /// Mean stress on the two box walls normal to `axis` (Pa, compression positive).
    pub fn box_stress(&self, axis: usize) -> Option<f64> {
        let area = box_area(&self.walls, axis);
        if area <= 0.0 {
            return None;
        }
        let mut sum = 0.0;
        let mut count = 0;
        for w in &self.walls {
            if let Some(n) = w.normal() {
                if n.iamax() == axis && (n[axis].abs() - 1.0).abs() < 1e-9 {
                    sum += -w.normal_force() / area;
                    count += 1;
                }
            }
        }
        (count == 2).then_some(0.5 * sum)
    }
}

/// Deviatoric stress `σ_D = 2 (σ_xx − σ_yy) / 3` (Pa) and strain
/// `ε_D = ε_xx − ε_yy` with `ε = 1 − L/L⁰` (David et al. §3.1), from the box
/// stresses and extents and the reference extents `l0`.
pub fn deviatoric(sxx: f64, syy: f64, l: V3, l0: V3) -> (f64, f64) {
    let exx = 1.0 - l[0] / l0[0];
    let eyy = 1.0 - l[1] / l0[1];
    (2.0 * (sxx - syy) / 3.0, exx - eyy)
}

impl MdSystem {
    /// Horizontal cross-section of the container (m²), if the walls make one: a
    /// cylinder along gravity (`π R²`, halved by each symmetry plane containing its
    /// axis), or a box of axis-aligned planes (`L_x L_y` for gravity along `z`).
    pub fn container_section(&self) -> Option<f64> {
        let up = self.up();
        for w in &self.walls {
            if let super::walls::Shape::Cylinder { axis_point, axis, radius } = w.shape {
                if axis.cross(&up).norm() < 1e-9 {
                    let halvings = self
                        .ghosts
                        .planes
                        .iter()
                        .filter(|p| {
                            p.normal.dot(&axis).abs() < 1e-9 && (axis_point - p.point).dot(&p.normal).abs() < 1e-12
                        })
                        .count();
                    return Some(std::f64::consts::PI * radius * radius / f64::from(1u32 << halvings));
                }
            }
        }
        let axis = up.iamax();
        let area = box_area(&self.walls, axis);
        (area > 0.0).then_some(area)
    }

    /// Packing fraction of the sample in its container (the "relative density" of
    /// Karrech et al. Fig. 3c): sphere volume over `section × height`, the height
    /// from the lowest sphere bottom to the highest sphere top along gravity (so a
    /// rough free surface lowers it, as the paper's footnote 2 says). `None`
    /// without a recognised container.
    pub fn packing_fraction_bulk(&self) -> Option<f64> {
        let section = self.container_section()?;
        let up = self.up();
        let p = &self.particles;
        if p.is_empty() {
            return None;
        }
        let lo = (0..p.len()).map(|i| p.x[i].dot(&up) - p.r[i]).fold(f64::INFINITY, f64::min);
        let hi = (0..p.len()).map(|i| p.x[i].dot(&up) + p.r[i]).fold(f64::NEG_INFINITY, f64::max);
        Some(p.volume() / (section * (hi - lo)))
    }
}

impl MdSystem {
    /// Kinetic energy of the servo walls `Σ ½ m_w ṡ²` (J).
    pub fn wall_kinetic_energy(&self) -> f64 {
        self.walls
            .iter()
            .map(|w| match w.motion {
                super::walls::Motion::Servo { mass, .. } => 0.5 * mass * w.s_dot * w.s_dot,
                super::walls::Motion::Fixed => 0.0,
            })
            .sum()
    }
}
