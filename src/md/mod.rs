//! The MD engine: soft-contact molecular dynamics (discrete elements) of 3D
//! spheres, following Karrech et al., *A computational procedure for the
//! prediction of settlement in granular materials under cyclic loading*, CMAME 197
//! (2007) 80–94, §2, and David, García-Rojo, Herrmann, Luding, *Hysteresis and
//! creep in powders and grains*, §§2–3.
//!
//! Data flow of a step: [`integrator`] (velocity Verlet or Gear predictor) →
//! [`neighbours`] (linked cells → Verlet list with skin, rebuilt when needed;
//! [`ghosts`] for symmetry planes) → [`contact`] forces with the pair's [`law`]
//! (Hertz–Mindlin or linear spring–dashpot, tangential memory) → [`walls`] →
//! integrator (second kick or corrector) → servo walls. [`measure`] turns a state
//! into the papers' quantities.
//!
//! [`planar`] runs the same contact laws on the 2D bodies of [`crate::plane`]
//! (the NSCD engine's scenes) with the shadow-overlap detection.
//!
//! A system built in code: spheres pushed with [`Particles::add_sphere`] (mass
//! `ρ 4/3 π r³` and inertia `2/5 m r²` computed), walls ([`Wall::new`]), a law for
//! every pair of materials that can touch ([`LawTable`], [`PairLaw`]; a pair left
//! out is refused by [`MdSystem::new`]) and [`MdSettings`] (its
//! [`Default`]: velocity Verlet, g = 9.81 m/s² down along `−z`, no background
//! damping; give the time step and a skin of the spheres' scale). Here a sphere
//! set on a plane sinks into it, rings down under the Hertz contact's damping
//! and rests at the static overlap of `F_n = 4/3 E* √R δ^{3/2} = m g`,
//! `δ = (m g / (4/3 E* √R))^{2/3}` (24 µm here). The contact's period is some
//! 8 ms and its damping ratio 0.5, so after 50 ms the ringing has decayed below
//! 1e-6 of the overlap; the check allows 1e-3 of it (the time step, 1/800 of
//! the period, errs by less).
//! ```
//! use ballast::md::{law::e_star, Ghosts, LawTable, Material, MdSettings, MdSystem, Motion, PairLaw, Particles, Shape, Wall, V3};
//! let rock = Material { density: 2000.0, young: 1e7, poisson: 0.25 }; // kg/m³, Pa
//! let (r, g) = (0.01, 9.81); // m, m/s²
//! let mut spheres = Particles::default();
//! let s = spheres.add_sphere(0, rock.density, r, V3::new(0.0, 0.0, r), V3::zeros())?; // touching the plane
//! let floor = Shape::Plane { point: V3::zeros(), normal: V3::z() };
//! let walls = vec![Wall::new("floor", 0, floor, Motion::Fixed)];
//! let mut laws = LawTable::named(&["rock"]);
//! laws.set(0, 0, PairLaw::hertz(&rock, &rock, 0.5, 0.5, 0.5)); // damping ratios α_n, α_t; friction
//! let settings = MdSettings { dt: 1e-5, skin: 0.1 * r, ..MdSettings::default() };
//! let mut sys = MdSystem::new(settings, spheres, walls, laws, Ghosts::new(Vec::new()))?;
//! for _ in 0..5000 {
//!     sys.step()?; // 50 ms
//! }
//! let m = sys.particles.m[s];
//! let expected = (m * g / (4.0 / 3.0 * e_star(&rock, &rock) * r.sqrt())).powf(2.0 / 3.0);
//! let overlap = r - sys.particles.x[s].z;
//! assert!((overlap - expected).abs() < 1e-3 * expected, "{overlap:e} m against {expected:e} m");
//! assert!(sys.particles.kinetic_energy() < 1e-12 * m * g * r); // at rest
//! # Ok::<(), ballast::Error>(())
//! ```

pub mod contact;
pub mod contacts;
pub mod engine;
pub mod ghosts;
pub mod integrator;
pub mod law;
pub mod measure;
pub mod neighbours;
pub mod particles;
pub mod planar;
pub mod relax;
pub mod rows;
pub mod system;
pub mod vtk;
pub mod walls;

pub use contacts::{MdContactInfo, MdContactKind};
pub use ghosts::{Ghosts, SymmetryPlane};
pub use integrator::{GearSet, Integrator};
pub use law::{Damping, LawTable, Material, Model, PairLaw};
pub use particles::{sphere_mass, Particles, V3};
pub use system::{MdSettings, MdStepStats, MdSystem};
pub use walls::{Drive, History1, Motion, Shape, Wall};
