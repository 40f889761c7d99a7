//! The integration tests: one binary, one module per file of `tests/`.
//!
//! Each file used to be its own test binary. Fifty binaries, each compiling the crate's generics at the test
//! profile's optimisation and linking, took 413 s of compile units, about 3.5 min of a clean build on 2 cores;
//! as modules of one binary they build in 48 s.
//! `cargo test --test integration cycles::` runs one file's tests. Two files stay binaries of their own
//! (`Cargo.toml`, `[[test]]`): `threads.rs`, whose timing beside a busy thread must not share the cores with
//! other tests, and `loom_team.rs`, built only with the `loom` feature.

// Helpers shared by the files (each file uses some of them).
mod common;
mod fixtures;
mod md_common;
mod scratch;
mod track3d_common;

mod cli;
mod compare;
mod cycles;
mod deposit_quality;
mod figures;
mod figures_cli;
mod fuzz_inputs;
mod generators;
mod landing_stages;
mod library_api;
mod md_cli;
mod md_contact;
mod md_contact_forces;
mod md_mechanics;
mod md_planar;
mod md_planar_scene;
mod md_ready_tests;
mod md_safety;
mod md_scene;
mod nlgs_measure;
mod nscd3d;
mod nscd3d_drives;
mod nscd3d_overlaps;
mod nscd3d_relax;
mod nscd3d_run;
mod nscd_anderson;
mod nscd_compound;
mod nscd_detection;
mod nscd_interior;
mod nscd_mechanics;
mod nscd_method;
mod nscd_solver;
mod nscd_sublayer;
mod readme_commands;
mod replicas;
mod resume_solver;
mod run_loop;
mod saussine;
mod saussine_studies;
mod scene3d;
mod scene_errors;
mod settlement_driver;
mod settlement_fit;
mod settlement_md;
mod settlement_relax;
mod settlement_rollback;
mod settlement_scene;
mod studies;
mod track3d;
mod track3d_replicas;
mod vtk;
mod write_back;
