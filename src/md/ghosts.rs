//! Symmetry planes by mirror images ("ghosts"), for a quarter sample (Karrech et
//! al. 2007 §2.3: `u_x = 0` at `x = 0`, `u_y = 0` at `y = 0`).
//!
//! A symmetry plane stands for the mirror half of the sample: each sphere near it
//! has an image across it (position, velocity mirrored; spin, a pseudovector,
//! mirrored with the opposite sign), and real spheres touch images as they touch
//! real spheres, friction included. A sphere touching its own image feels the
//! force of the full-sample contact with `R* = r/2`, `m* = m/2`, and no tangential
//! slip (the images move symmetrically), so it cannot cross the plane. With two
//! perpendicular planes, spheres near both also get the image through both (the
//! opposite quadrant). Forces are applied to real spheres only; a pair across a
//! plane is computed once from each side, mirror images of each other.

use super::particles::{Particles, V3};
use serde::{Deserialize, Serialize};

/// A symmetry plane through `point` with unit normal `normal` (into the sample).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SymmetryPlane {
    /// A point of the plane (m).
    pub point: V3,
    /// Unit normal pointing into the sample (the real spheres' side).
    pub normal: V3,
}

impl SymmetryPlane {
    /// Signed distance of `x` to the plane (m), positive on the sample's side.
    #[inline]
    pub fn distance(&self, x: &V3) -> f64 {
        (x - self.point).dot(&self.normal)
    }

    fn mirror_point(&self, x: &V3) -> V3 {
        x - self.normal * (2.0 * self.distance(x))
    }

    fn mirror_vector(&self, v: &V3) -> V3 {
        v - self.normal * (2.0 * v.dot(&self.normal))
    }

    fn mirror_spin(&self, w: &V3) -> V3 {
        -self.mirror_vector(w)
    }
}

/// The current images: for ghost `g`, `origin[g]` is the real sphere and
/// `mask[g]` the set of planes (bit `s` for plane `s`) it is mirrored through;
/// `x`, `v`, `w` its mirrored state.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Ghosts {
    /// The symmetry planes; plane `s` is bit `s` of [`Self::mask`].
    pub planes: Vec<SymmetryPlane>,
    /// Index of the real sphere each image mirrors.
    pub origin: Vec<u32>,
    /// Planes each image is mirrored through (bit `s` for plane `s`; two bits for the
    /// image through both planes).
    pub mask: Vec<u32>,
    /// `mask << 32 | origin`, the stable key of each ghost in the neighbour list.
    pub key: Vec<u64>,
    /// Centre of each image (m).
    pub x: Vec<V3>,
    /// Velocity of each image (m/s), the mirrored velocity of its sphere.
    pub v: Vec<V3>,
    /// Spin of each image (rad/s), mirrored as a pseudovector (opposite sign of the mirrored vector).
    pub w: Vec<V3>,
}

impl Ghosts {
    /// Copies `src` into `self`, reusing `self`'s buffers (no allocation once the sizes match): the backup of
    /// an MD step ([`crate::md::MdSystem`]). The destructuring names every field, so a field added to the
    /// struct does not compile until it is copied here too (a field forgotten would be a silent replay bug).
    pub(crate) fn copy_from(&mut self, src: &Ghosts) {
        let Ghosts { planes, origin, mask, key, x, v, w } = src;
        self.planes.clone_from(planes);
        self.origin.clone_from(origin);
        self.mask.clone_from(mask);
        self.key.clone_from(key);
        self.x.clone_from(x);
        self.v.clone_from(v);
        self.w.clone_from(w);
    }

    /// No image yet.
    pub fn new(planes: Vec<SymmetryPlane>) -> Self {
        Ghosts { planes, ..Default::default() }
    }

    /// Number of images.
    pub fn len(&self) -> usize {
        self.origin.len()
    }

    /// True if there are no images.
    pub fn is_empty(&self) -> bool {
        self.origin.is_empty()
    }

    /// Chooses the images: spheres closer than `reach` (m) to a plane (to both
    /// planes for the double image).
    pub fn select(&mut self, x: &[V3], reach: f64) {
        self.origin.clear();
        self.mask.clear();
        self.key.clear();
        let np = self.planes.len();
        if np == 0 {
            return;
        }
        for (i, p) in x.iter().enumerate() {
            let mut near = 0u32;
            for (s, plane) in self.planes.iter().enumerate() {
                if plane.distance(p) < reach {
                    near |= 1 << s;
                }
            }
            for mask in 1u32..(1 << np) {
                if mask & near == mask {
                    self.origin.push(i as u32);
                    self.mask.push(mask);
                    self.key.push((mask as u64) << 32 | i as u64);
                }
            }
        }
    }

    /// The centre of image `g` for its original at `x` (m): `x` mirrored through
    /// the image's planes in order, the same operations as [`Ghosts::update`].
    pub fn image_of(&self, g: usize, x: &V3) -> V3 {
        let mut x = *x;
        for (s, plane) in self.planes.iter().enumerate() {
            if self.mask[g] & (1 << s) != 0 {
                x = plane.mirror_point(&x);
            }
        }
        x
    }

    /// Mirrors the current state of the originals into the images.
    pub fn update(&mut self, p: &Particles) {
        let n = self.len();
        self.x.resize(n, V3::zeros());
        self.v.resize(n, V3::zeros());
        self.w.resize(n, V3::zeros());
        for g in 0..n {
            let i = self.origin[g] as usize;
            let (mut x, mut v, mut w) = (p.x[i], p.v[i], p.w[i]);
            for (s, plane) in self.planes.iter().enumerate() {
                if self.mask[g] & (1 << s) != 0 {
                    x = plane.mirror_point(&x);
                    v = plane.mirror_vector(&v);
                    w = plane.mirror_spin(&w);
                }
            }
            self.x[g] = x;
            self.v[g] = v;
            self.w[g] = w;
        }
    }
}
