//! What a 3D engine shares, as `plane/` is for the 2D ones: its bodies ([`bodies`]: positions, unit quaternions,
//! velocities with the spin in the principal frame) and its contact detection ([`detection`]: after LMGC90's
//! PRPRx for polyhedra, with spheres and half-spaces).

pub mod bodies;
pub mod detection;
