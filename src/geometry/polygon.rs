//! Convex polygons, discs and compounds (rigid unions of convex polygons), in
//! the body frame with the centroid of the whole shape at the origin.

use super::{cross, Vec2};
use parry2d_f64::mass_properties::MassProperties;
use parry2d_f64::math::Vector as PVec;
use serde::{Deserialize, Serialize};

/// Why a shape was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// Fewer than 3 vertices (the count given).
    #[error("a polygon needs at least 3 vertices, got {0}")]
    TooFewVertices(usize),
    /// A vertex (its index) has a non-finite coordinate.
    #[error("vertex {0} is not finite")]
    NonFinite(usize),
    /// Two vertices (their indices) coincide or are collinear with a neighbour.
    #[error("degenerate polygon: vertices {0} and {1} coincide or are collinear with their neighbour")]
    Degenerate(usize, usize),
    /// The vertices turn clockwise (negative signed area).
    #[error("polygon vertices must be given counter-clockwise (signed area is negative)")]
    Clockwise,
    /// The turn at a vertex (its index) is clockwise: not convex.
    #[error("non-convex polygon: the turn at vertex {0} is clockwise")]
    NonConvex(usize),
    /// A disc or regular polygon radius (m) that is not positive and finite.
    #[error("radius must be positive and finite, got {0}")]
    BadRadius(f64),
    /// A regular polygon with fewer than 3 sides (the count given).
    #[error("a regular polygon needs at least 3 sides, got {0}")]
    BadSides(usize),
    /// A compound without parts.
    #[error("a compound needs at least one part")]
    NoParts,
    /// A compound with more than [`Compound::MAX_PARTS`] parts (the count given).
    #[error("a compound has at most {max} parts, got {0}", max = Compound::MAX_PARTS)]
    TooManyParts(usize),
    /// Part `index` of a compound is refused.
    #[error("parts[{index}]: {source}")]
    Part {
        /// Index of the part in the compound.
        index: usize,
        /// Why it was refused.
        source: Box<GeometryError>,
    },
    /// Part `.0` of a compound has `.1` vertices, more than [`Compound::MAX_PART_VERTICES`].
    #[error("parts[{0}]: a part has at most {max} vertices, got {1}", max = Compound::MAX_PART_VERTICES)]
    PartTooManyVertices(usize, usize),
    /// Parts `.1` and `.0` (`.0 < .1`) overlap by a depth `.2` (m).
    #[error("parts[{1}]: overlaps parts[{0}] by {2:e} m (parts may share edges but not overlap)")]
    PartsOverlap(usize, usize, f64),
}

/// A convex polygon in its body frame, centroid at the origin, vertices counter-clockwise
/// (except as a part of a [`Compound`], whose vertices are in the compound's body frame).
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
        // Distance from the centroid to the line of edge `k` (positive: the centroid is inside).
        let inradius = (0..n).map(|k| vertices[k].dot(&normals[k])).fold(f64::INFINITY, f64::min);
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

/// A rigid union of convex polygons (a non-convex body, e.g. a sleeper with
/// bars under it), in the body frame: the centroid of the whole union is the
/// origin.
///
/// Each part is a [`ConvexPolygon`] whose `vertices` and `normals` are in the
/// body frame (so, unlike a lone polygon, a part is *not* centred on the
/// origin); its `circumradius` is the largest distance from the **body**
/// centroid to its vertices (what a bounding box needs) and its `inradius` is
/// the part's **own** inradius about its own centroid `offsets[k]` (the size
/// scale of the shadow-overlap test). Parts may share edges but not overlap.
///
/// Contact detection runs part by part; the dynamics sees one rigid body.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Compound {
    /// The parts, vertices and normals in the body frame.
    pub parts: Vec<ConvexPolygon>,
    /// Centroid of each part in the body frame (m).
    pub offsets: Vec<Vec2>,
    /// Largest distance from the body centroid to a vertex of any part (m).
    pub circumradius: f64,
}

impl Compound {
    /// Largest number of parts (contact keys give a part index 8 bits).
    pub const MAX_PARTS: usize = 256;
    /// Largest number of vertices of one part (contact keys give a vertex or edge index 6 bits).
    pub const MAX_PART_VERTICES: usize = 64;

    /// Validates `parts` (each a vertex list in one common frame, counter-clockwise,
    /// strictly convex, checked like [`ConvexPolygon::new`]; the error names the
    /// part index), checks that no two parts overlap (a shared edge is allowed),
    /// and re-centres the union on its centroid. Returns the compound and the
    /// union centroid's position in the given frame (m).
    ///
    /// Overlap test: separating axes over the edge normals of both parts. Two
    /// parts pass when along some axis their penetration depth is at most
    /// `1e-9` times the larger part size (circumradius about its own centroid),
    /// so parts that share an edge, given with rounded coordinates, pass, and the
    /// overlap area this lets through is below `1e-9 ×` size × edge length.
    pub fn new(parts: &[Vec<[f64; 2]>]) -> Result<(Self, Vec2), GeometryError> {
        if parts.is_empty() {
            return Err(GeometryError::NoParts);
        }
        if parts.len() > Self::MAX_PARTS {
            return Err(GeometryError::TooManyParts(parts.len()));
        }
        let mut centred = Vec::with_capacity(parts.len());
        for (index, p) in parts.iter().enumerate() {
            let (poly, c) = ConvexPolygon::new(p).map_err(|e| GeometryError::Part { index, source: Box::new(e) })?;
            if p.len() > Self::MAX_PART_VERTICES {
                return Err(GeometryError::PartTooManyVertices(index, p.len()));
            }
            centred.push((poly, c));
        }
        // Pairwise overlap, in the given frame.
        for j in 1..centred.len() {
            for i in 0..j {
                let (pi, ci) = &centred[i];
                let (pj, cj) = &centred[j];
                let depth = penetration(pi, *ci, pj, *cj);
                if depth > 1e-9 * pi.circumradius.max(pj.circumradius) {
                    return Err(GeometryError::PartsOverlap(i, j, depth));
                }
            }
        }
        // Union centroid: area-weighted mean of the part centroids.
        let areas: Vec<f64> = centred.iter().map(|(p, _)| p.area_and_polar_moment().0).collect();
        let total: f64 = areas.iter().sum();
        let c = centred.iter().zip(&areas).fold(Vec2::zeros(), |acc, ((_, ck), a)| acc + ck * *a) / total;
        let mut out = Self { parts: Vec::with_capacity(parts.len()), offsets: Vec::new(), circumradius: 0.0 };
        for (poly, ck) in centred {
            let off = ck - c;
            let vertices: Vec<Vec2> = poly.vertices.iter().map(|v| v + off).collect();
            let circumradius = vertices.iter().map(|p| p.norm()).fold(0.0, f64::max);
            out.circumradius = out.circumradius.max(circumradius);
            out.parts.push(ConvexPolygon { vertices, normals: poly.normals, circumradius, inradius: poly.inradius });
            out.offsets.push(off);
        }
        Ok((out, c))
    }

    /// Area (m²) and polar second moment of area about the union centroid (m⁴):
    /// the sums over the parts, each part's own moment moved to the union
    /// centroid by the parallel-axis theorem `J = Σ (J_k + A_k |c_k|²)`.
    pub fn area_and_polar_moment(&self) -> (f64, f64) {
        let (mut area, mut polar) = (0.0, 0.0);
        for (p, off) in self.parts.iter().zip(&self.offsets) {
            let pts: Vec<PVec> = p.vertices.iter().map(|v| PVec::new(v.x - off.x, v.y - off.y)).collect();
            let mp = MassProperties::from_convex_polygon(1.0, &pts);
            let a = mp.mass();
            area += a;
            polar += mp.principal_inertia() + a * off.norm_squared();
        }
        (area, polar)
    }

    /// Smallest inradius of the parts (m).
    pub fn min_inradius(&self) -> f64 {
        self.parts.iter().map(|p| p.inradius).fold(f64::INFINITY, f64::min)
    }
}

/// Penetration depth (m) of two convex polygons given centred with their
/// centroids `ca`, `cb`: the smallest, over the edge normals of both, of the
/// overlap of their projections (≤ 0 when an axis separates them).
fn penetration(a: &ConvexPolygon, ca: Vec2, b: &ConvexPolygon, cb: Vec2) -> f64 {
    let mut depth = f64::INFINITY;
    for (p, cp, q, cq) in [(a, ca, b, cb), (b, cb, a, ca)] {
        for (v, n) in p.vertices.iter().zip(&p.normals) {
            let edge = (v + cp).dot(n);
            let deepest = q.vertices.iter().map(|w| (w + cq).dot(n)).fold(f64::INFINITY, f64::min);
            depth = depth.min(edge - deepest);
        }
    }
    depth
}

/// A 2D body shape in its body frame (centroid at the origin).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Shape {
    /// A convex polygon.
    Polygon(ConvexPolygon),
    /// A disc of the given radius (m).
    Disc(f64),
    /// A rigid union of convex polygons.
    Compound(Compound),
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
            Shape::Compound(c) => c.area_and_polar_moment(),
        }
    }

    /// Mass (kg) and polar moment of inertia about the centroid (kg·m²) of the
    /// shape as a prism of `thickness` (m) out of the plane and `density`
    /// (kg/m³): `ρ t A` and `ρ t J` ([`Shape::area_and_polar_moment`]). Scenes and
    /// [`crate::nscd::BodyInfo::new`] both compute their masses here.
    pub fn mass_properties(&self, density: f64, thickness: f64) -> (f64, f64) {
        let (area, polar) = self.area_and_polar_moment();
        (density * thickness * area, density * thickness * polar)
    }

    /// Radius of the smallest centred circle that contains the shape (m).
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Shape::Polygon(p) => p.circumradius,
            Shape::Disc(r) => *r,
            Shape::Compound(c) => c.circumradius,
        }
    }

    /// Radius of the largest centred circle inside the shape (m): the depth of
    /// overlap beyond which a contact is certainly a blow-up. For a compound, the
    /// smallest inradius of its parts (each about its own centroid).
    pub fn inner_radius(&self) -> f64 {
        match self {
            Shape::Polygon(p) => p.inradius,
            Shape::Disc(r) => *r,
            Shape::Compound(c) => c.min_inradius(),
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
        // A 0.1 × 0.02 rectangle: the nearest edge line is 0.01 from the centroid.
        let (p, _) = ConvexPolygon::new(&[[0.0, 0.0], [0.1, 0.0], [0.1, 0.02], [0.0, 0.02]]).unwrap();
        assert!((p.inradius - 0.01).abs() < 1e-15, "{}", p.inradius);
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
