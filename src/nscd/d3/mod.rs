//! The 3D NSCD engine: rigid convex polyhedra, spheres and fixed walls (Moreau–Jean θ-method on six degrees of
//! freedom, [`system`]), its contact rows for the shared method ([`contact`], over [`super::method`]) and its
//! local law ([`cone`]); the detection is [`crate::space::detection`], the bodies [`crate::space::bodies`].

pub mod cone;
pub mod contact;
pub mod system;
