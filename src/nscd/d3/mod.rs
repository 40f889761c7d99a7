//! The 3D NSCD engine: rigid convex polyhedra and spheres (Moreau–Jean θ-method on six degrees of freedom), its
//! rows for the shared method ([`super::method`]) and its local law ([`cone`]).

pub mod cone;
