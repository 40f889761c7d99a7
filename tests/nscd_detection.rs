//! Contact detection: shadow overlap on configurations with known answers, and
//! against the exact penetration depth of random pentagon pairs.

use ballast::geometry::{ConvexPolygon, Vec2};
use ballast::nscd::narrow_phase::{detect, Placed};
use ballast::nscd::shadow_overlap::{ContactPoint, PolygonView};

struct World {
    v: Vec<Vec2>,
    n: Vec<Vec2>,
    c: Vec2,
    r: f64,
}

fn place(p: &ConvexPolygon, x: f64, y: f64, angle: f64) -> World {
    let (c, s) = (angle.cos(), angle.sin());
    let rot = |v: &Vec2| Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y);
    World {
        v: p.vertices.iter().map(|v| rot(v) + Vec2::new(x, y)).collect(),
        n: p.normals.iter().map(rot).collect(),
        c: Vec2::new(x, y),
        r: p.inradius,
    }
}

fn view(w: &World) -> Placed<'_> {
    Placed::Polygon(PolygonView { vertices: &w.v, normals: &w.n, centre: w.c, inradius: w.r })
}

fn contacts(a: &World, b: &World, alert: f64) -> Vec<ContactPoint> {
    let mut out = Vec::new();
    detect(view(a), view(b), alert, |c| out.push(c));
    out
}

fn square(side: f64) -> ConvexPolygon {
    let h = side / 2.0;
    ConvexPolygon::new(&[[-h, -h], [h, -h], [h, h], [-h, h]]).unwrap().0
}

/// Edge-to-edge: two contact points at the ends of the contact segment, gap = −overlap.
#[test]
fn face_to_face_overlap_gives_two_points_at_segment_ends() {
    let sq = square(1.0);
    let depth = 1e-3;
    let a = place(&sq, 0.3, 1.0 - depth, 0.0); // candidate above, shifted right
    let b = place(&sq, 0.0, 0.0, 0.0);
    let mut c = contacts(&a, &b, 1e-2);
    c.sort_by(|p, q| p.point.x.total_cmp(&q.point.x));
    assert_eq!(c.len(), 2, "{c:?}");
    // Segment [−0.2, 0.5] in x; points half-way through the overlap, y = 0.5 − depth/2.
    for (p, x) in c.iter().zip([-0.2, 0.5]) {
        assert!((p.point.x - x).abs() < 1e-12 && (p.point.y - (0.5 - depth / 2.0)).abs() < 1e-12, "{p:?}");
        assert!((p.gap + depth).abs() < 1e-12);
        assert!((p.normal - Vec2::new(0.0, 1.0)).norm() < 1e-12, "normal points to the candidate");
    }
}

/// One intruding corner: one contact, point half-way between the corner and its
/// projection on the edge, tangent along the edge.
#[test]
fn corner_intrusion_gives_one_point() {
    let sq = square(1.0);
    let depth = 2e-3;
    let half_diag = 0.5 * 2f64.sqrt();
    let b = place(&sq, 0.0, 0.0, 0.0);
    let a = place(&sq, 0.1, 0.5 + half_diag - depth, std::f64::consts::FRAC_PI_4);
    let c = contacts(&a, &b, 1e-2);
    assert_eq!(c.len(), 1, "{c:?}");
    assert!((c[0].gap + depth).abs() < 1e-12);
    assert!((c[0].point - Vec2::new(0.1, 0.5 - depth / 2.0)).norm() < 1e-12, "{:?}", c[0]);
    assert!((c[0].normal - Vec2::new(0.0, 1.0)).norm() < 1e-12);
    // Same configuration with the roles swapped: the normal flips, the gap does not.
    let c2 = contacts(&b, &a, 1e-2);
    assert_eq!(c2.len(), 1);
    assert!((c2[0].gap + depth).abs() < 1e-12 && (c2[0].normal + Vec2::new(0.0, 1.0)).norm() < 1e-12);
}

/// Open contacts are reported with their positive gap inside the alert distance only.
#[test]
fn separated_polygons_within_alert_only() {
    let sq = square(1.0);
    let b = place(&sq, 0.0, 0.0, 0.0);
    let a = place(&sq, 0.0, 1.0 + 5e-3, 0.0);
    let c = contacts(&a, &b, 1e-2);
    assert_eq!(c.len(), 2);
    assert!(c.iter().all(|p| (p.gap - 5e-3).abs() < 1e-12));
    assert!(contacts(&a, &b, 1e-3).is_empty());
}

/// Disc–disc and polygon–disc gaps are distances between surfaces.
#[test]
fn disc_gaps_are_surface_distances() {
    let mut out = Vec::new();
    let d1 = Placed::Disc { centre: Vec2::new(0.0, 0.0), radius: 1.0 };
    let d2 = Placed::Disc { centre: Vec2::new(3.0, 4.0), radius: 3.9 };
    detect(d2, d1, 1.0, |c| out.push(c));
    assert_eq!(out.len(), 1);
    assert!((out[0].gap - 0.1).abs() < 1e-12 && (out[0].normal - Vec2::new(0.6, 0.8)).norm() < 1e-12);
    // Disc above the face of a square, and near its corner.
    let sq = square(2.0);
    let b = place(&sq, 0.0, 0.0, 0.0);
    out.clear();
    detect(Placed::Disc { centre: Vec2::new(0.5, 1.4), radius: 0.5 }, view(&b), 1.0, |c| out.push(c));
    assert!((out[0].gap + 0.1).abs() < 1e-12 && (out[0].normal - Vec2::new(0.0, 1.0)).norm() < 1e-12);
    out.clear();
    detect(Placed::Disc { centre: Vec2::new(1.3, 1.4), radius: 0.3 }, view(&b), 1.0, |c| out.push(c));
    assert!((out[0].gap - 0.2).abs() < 1e-12 && (out[0].normal - Vec2::new(0.6, 0.8)).norm() < 1e-12);
}

/// For slightly overlapping convex polygons the penetration depth is the smallest
/// shadow overlap over all edge normals (separating axis theorem). The descent
/// from the line of centres must find it, on random pentagon pairs of mixed sizes.
#[test]
fn shadow_overlap_depth_matches_exact_penetration_on_random_pentagons() {
    let mut seed = 99u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let sat = |a: &World, b: &World| {
        let mut m = f64::INFINITY;
        for (k, n) in a.n.iter().enumerate() {
            let minb = b.v.iter().map(|v| v.dot(n)).fold(f64::INFINITY, f64::min);
            m = m.min(a.v[k].dot(n) - minb);
        }
        for (k, n) in b.n.iter().enumerate() {
            let mina = a.v.iter().map(|v| v.dot(n)).fold(f64::INFINITY, f64::min);
            m = m.min(b.v[k].dot(n) - mina);
        }
        m
    };
    let mut checked = 0;
    for _ in 0..5000 {
        let ra = 0.005 + 0.005 * rnd();
        let rb = 0.005 + 0.005 * rnd();
        let pa = ConvexPolygon::regular(5, ra).unwrap();
        let pb = ConvexPolygon::regular(5, rb).unwrap();
        let dir = std::f64::consts::TAU * rnd();
        let (aa, ab) = (std::f64::consts::TAU * rnd(), std::f64::consts::TAU * rnd());
        let b = place(&pb, 0.0, 0.0, ab);
        // Bring A along `dir` until it touches B, then push it in by a small depth.
        let (mut lo, mut hi) = (0.0, ra + rb);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            let a = place(&pa, mid * dir.cos(), mid * dir.sin(), aa);
            if sat(&a, &b) > 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let dist = lo - 1e-4 * rnd() * ra;
        let a = place(&pa, dist * dir.cos(), dist * dir.sin(), aa);
        let depth = sat(&a, &b);
        let c = contacts(&a, &b, 1e-6);
        assert!(!c.is_empty() && c.len() <= 2);
        let deepest = c.iter().map(|p| -p.gap).fold(f64::NEG_INFINITY, f64::max);
        // Exact geometry: only round-off separates the two depths.
        assert!((deepest - depth).abs() < 1e-12, "depth {deepest} vs exact {depth}");
        for p in &c {
            assert!((p.normal.norm() - 1.0).abs() < 1e-12);
            // The normal points from B towards A.
            assert!(p.normal.dot(&(a.c - b.c)) > 0.0);
        }
        checked += 1;
    }
    assert_eq!(checked, 5000);
}
