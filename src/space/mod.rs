//! What a 3D engine shares, as `plane/` is for the 2D ones: its bodies ([`bodies`]: positions, unit quaternions,
//! velocities with the spin in the principal frame) its contact detection ([`detection`]: after LMGC90's
//! PRPRx for polyhedra, with spheres and half-spaces), its loads and imposed velocities ([`loads`]), the
//! sublayer springs of law (17) ([`springs`]) and the relaxation of a configuration ([`relax`]).

pub mod bodies;
pub mod detection;
pub mod loads;
pub mod relax;
pub mod springs;
