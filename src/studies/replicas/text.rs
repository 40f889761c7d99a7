//! One replica's start from any scene file's text, whatever its engine: the scene read as its kind
//! ([`SceneKind::of`]), perturbed as the studies perturb theirs ([`perturb_scene`] for the 2D scenes of
//! either engine, [`perturb_md_scene`] for 3D spheres, [`perturb_scene3`] for 3D polyhedra), and written
//! back as TOML. This is `ballast run --replica R --perturb DIST`: one replica of an ensemble started from
//! any state (a deposited sample, a loaded run's `final_scene.toml`), run alone.

use super::{perturb_md_scene, perturb_scene, perturb_scene3, ReplicaRecord, Start};
use crate::error::Result;
use crate::scene::{MdScene, Scene, Scene3, SceneFile, SceneKind};

/// The text of replica `start.replica` of the scene `text` (read as the file `name`, run on `engine` if it
/// is given, as [`crate::open::open_text`] would run it), and the record of what was done. Replica 0 gives
/// `text` unchanged; replica `r ≥ 1` moves every mobile body's position by a displacement of at most
/// `start.perturbation.distance_m` drawn from stream `r` of its seed, and the scene is written back
/// ([`SceneFile::to_toml_string`]: the same scene, its floats exact, its layout the writer's). The same text
/// and start give the same replica as the studies' replica `r` of that scene.
///
/// # Errors
/// [`crate::Error::Scene`] (one line naming the key) for an invalid scene or perturbation
/// (`perturbation.distance_m`).
pub fn perturbed_text(
    text: String,
    name: &str,
    engine: Option<&str>,
    start: &Start,
) -> Result<(String, ReplicaRecord)> {
    let (p, r) = (&start.perturbation, start.replica);
    p.check()?;
    if r == 0 {
        return Ok((text, ReplicaRecord::unmoved(p, 0)));
    }
    // The kind is that of the scene as run, so that an engine the scene cannot run on is refused here as
    // the run would refuse it; the scene itself is perturbed in its own file's form.
    match SceneKind::of(&text, name, engine)? {
        SceneKind::Md => moved(&text, name, |s: &mut MdScene| perturb_md_scene(s, p, r)),
        SceneKind::Nscd3 => moved(&text, name, |s: &mut Scene3| perturb_scene3(s, p, r)),
        SceneKind::Nscd | SceneKind::PlanarMd => moved(&text, name, |s: &mut Scene| perturb_scene(s, p, r)),
    }
}

/// The scene `text` read as an `S`, moved by `perturb`, written back; with the record of the move.
fn moved<S: SceneFile>(
    text: &str,
    name: &str,
    perturb: impl FnOnce(&mut S) -> Result<ReplicaRecord>,
) -> Result<(String, ReplicaRecord)> {
    let mut scene = S::from_toml_str_named(text, name)?;
    let record = perturb(&mut scene)?;
    Ok((scene.to_toml_string()?, record))
}
