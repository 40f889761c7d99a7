//! The 3D NSCD engine: rigid convex polyhedra, spheres and fixed walls (Moreau–Jean θ-method on six degrees of
//! freedom, [`system`]), its contact rows for the shared method ([`contact`], over [`super::method`]) and its
//! local law ([`cone`]) with its Signorini condition on overlaps ([`overlaps`]); the detection is
//! [`crate::space::detection`], the bodies [`crate::space::bodies`]. The system is an [`crate::engine::Engine`] of
//! the run loop ([`engine`]) with its rows ([`rows`]), measures ([`measure`]) and snapshots ([`vtk`]).

pub mod cone;
pub mod contact;
pub mod engine;
pub mod measure;
pub mod overlaps;
pub mod rows;
pub mod spring;
pub mod system;
pub mod vtk;
