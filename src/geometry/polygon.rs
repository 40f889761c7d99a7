//! Convex polygons and discs (body frame, centroid at the origin).

use super::{cross, Vec2};
use parry2d_f64::mass_properties::MassProperties;
use parry2d_f64::math::Vector as PVec;
use serde::{Deserialize, Serialize};

/// Why a shape was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    #[error("a polygon needs at least 3 vertices, got {0}")]
    TooFewVertices(usize),
    #[error("vertex {0} is not finite")]
    NonFinite(usize),
    #[error("degenerate polygon: vertices {0} and {1} coincide or are collinear with their neighbour")]
    Degenerate(usize, usize),
    #[error("polygon vertices must be given counter-clockwise (signed area is negative)")]
    Clockwise,
    #[error("non-convex polygon: the turn at vertex {0} is clockwise")]
    NonConvex(usize),
    #[error("radius must be positive and finite, got {0}")]
    BadRadius(f64),
    #[error("a regular polygon needs at least 3 sides, got {0}")]
    BadSides(usize),
}

/// A convex polygon in its body frame, centroid at the origin, vertices counter-clockwise.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ConvexPolygon {
    /// Vertices (m), counter-clockwise, centroid at the origin.
    pub vertices: Vec<Vec2>,
    /// Outward unit normal of edge `k` (from vertex `k` to vertex `k+1`).
    pub normals: Vec<Vec2>,
    /// Largest distance from the centroid to a vertex (m).
    pub circumradius: f64,
    /// Smallest distance from the centroid to an edge line (m).
    pub inradius: f64,
}

impl ConvexPolygon {
    /// Validates `vertices` (body frame, counter-clockwise, strictly convex) and
    /// re-centres them on the centroid. Returns the polygon and the centroid's
    /// position in the given frame (m).
    pub fn new(vertices: &[[f64; 2]]) -> Result<(Self, Vec2), GeometryError> {
        let n = vertices.len();
        if n < 3 {
            return Err(GeometryError::TooFewVertices(n));
        }
        let v: Vec<Vec2> = vertices.iter().map(|p| Vec2::new(p[0], p[1])).collect();
        if let Some(i) = v.iter().position(|p| !p.x.is_finite() || !p.y.is_finite()) {
            return Err(GeometryError::NonFinite(i));
        }
        let scale = v.iter().map(|p| p.norm()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let area2: f64 = (0..n).map(|i| cross(v[i], v[(i + 1) % n])).sum();
        // Relative threshold: a turn smaller than 1e-10 of the size² is collinear.
        let eps = 1e-10 * scale * scale;
        if area2 < 0.0 && area2.abs() > eps {
            return Err(GeometryError::Clockwise);
        }
        for i in 0..n {
            let (a, b, c) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
            if (b - a).norm() <= 1e-12 * scale {
                return Err(GeometryError::Degenerate((i + n - 1) % n, i));
            }
            let turn = cross(b - a, c - b);
            if turn.abs() <= eps {
                return Err(GeometryError::Degenerate(i, (i + 1) % n));
            }
            if turn < 0.0 {
                return Err(GeometryError::NonConvex(i));
            }
        }
        // A star polygon (winding twice) turns left everywhere; its area check fails
        // only through the total turning, so check that the edge angles sum to 2π.
        let total: f64 = (0..n)
            .map(|i| {
                let (a, b, c) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
                cross(b - a, c - b).atan2((b - a).dot(&(c - b)))
            })
            .sum();
        if (total - std::f64::consts::TAU).abs() > 1e-6 {
            return Err(GeometryError::NonConvex(0));
        }
        let pts: Vec<PVec> = v.iter().map(|p| PVec::new(p.x, p.y)).collect();
        let mp = MassProperties::from_convex_polygon(1.0, &pts);
        let c = Vec2::new(mp.local_com.x, mp.local_com.y);
        Ok((Self::from_centred(v.iter().map(|p| p - c).collect()), c))
    }

    /// Regular polygon with `sides` vertices on a circle of `radius` (m, circumradius),
    /// first vertex on +x.
    pub fn regular(sides: usize, radius: f64) -> Result<Self, GeometryError> {
        if sides < 3 {
            return Err(GeometryError::BadSides(sides));
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(GeometryError::BadRadius(radius));
        }
        let v = (0..sides)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / sides as f64;
                Vec2::new(radius * a.cos(), radius * a.sin())
            })
            .collect();
        Ok(Self::from_centred(v))
    }

    fn from_centred(vertices: Vec<Vec2>) -> Self {
        let n = vertices.len();
        let normals: Vec<Vec2> = (0..n)
            .map(|k| {
                let e = vertices[(k + 1) % n] - vertices[k];
                Vec2::new(e.y, -e.x).normalize()
            })
            .collect();
        let circumradius = vertices.iter().map(|p| p.norm()).fold(0.0, f64::max);
        let inradius = (0..n).map(|k| -vertices[k].dot(&normals[k])).fold(f64::INFINITY, f64::min).abs();
        Self { vertices, normals, circumradius, inradius }
    }

    /// Area (m²) and polar second moment of area about the centroid (m⁴).
    pub fn area_and_polar_moment(&self) -> (f64, f64) {
        let pts: Vec<PVec> = self.vertices.iter().map(|p| PVec::new(p.x, p.y)).collect();
        let mp = MassProperties::from_convex_polygon(1.0, &pts);
        let area = mp.mass();
        (area, mp.principal_inertia())
    }
}

/// A 2D body shape in its body frame (centroid at the origin).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Shape {
    Polygon(ConvexPolygon),
    /// A disc of the given radius (m).
    Disc(f64),
}

impl Shape {
    /// A disc of `radius` (m).
    pub fn disc(radius: f64) -> Result<Self, GeometryError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(GeometryError::BadRadius(radius));
        }
        Ok(Shape::Disc(radius))
    }

    /// Area (m²) and polar second moment of area about the centroid (m⁴).
    pub fn area_and_polar_moment(&self) -> (f64, f64) {
        match self {
            Shape::Polygon(p) => p.area_and_polar_moment(),
            Shape::Disc(r) => {
                let mp = MassProperties::from_ball(1.0, *r);
                (mp.mass(), mp.principal_inertia())
            }
        }
    }

    /// Radius of the smallest centred circle that contains the shape (m).
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Shape::Polygon(p) => p.circumradius,
            Shape::Disc(r) => *r,
        }
    }

    /// Radius of the largest centred circle inside the shape (m): the depth of
    /// overlap beyond which a contact is certainly a blow-up.
    pub fn inner_radius(&self) -> f64 {
        match self {
            Shape::Polygon(p) => p.inradius,
            Shape::Disc(r) => *r,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_mass_properties_match_closed_form() {
        // Unit square: A = 1, J = (a^4)/6 = 1/6 about the centroid.
        let (p, c) = ConvexPolygon::new(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap();
        assert!((c - Vec2::new(0.5, 0.5)).norm() < 1e-14);
        let (a, j) = p.area_and_polar_moment();
        assert!((a - 1.0).abs() < 1e-12);
        assert!((j - 1.0 / 6.0).abs() < 1e-12);
        assert!((p.inradius - 0.5).abs() < 1e-12);
    }

    #[test]
    fn disc_mass_properties_match_closed_form() {
        let (a, j) = Shape::disc(2.0).unwrap().area_and_polar_moment();
        assert!((a - std::f64::consts::PI * 4.0).abs() < 1e-12);
        // J = π r^4 / 2
        assert!((j - std::f64::consts::PI * 16.0 / 2.0).abs() < 1e-10);
    }

    #[test]
    fn bad_polygons_are_refused() {
        let cw = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
        assert_eq!(ConvexPolygon::new(&cw).unwrap_err(), GeometryError::Clockwise);
        let dart = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.3], [1.0, 2.0]];
        assert!(matches!(ConvexPolygon::new(&dart), Err(GeometryError::NonConvex(_))));
        let flat = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        assert!(matches!(ConvexPolygon::new(&flat), Err(GeometryError::Degenerate(..))));
        let dup = [[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(ConvexPolygon::new(&dup), Err(GeometryError::Degenerate(..))));
        let star: Vec<[f64; 2]> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                [a.cos(), a.sin()]
            })
            .collect();
        assert!(ConvexPolygon::new(&star).is_err());
    }
}
