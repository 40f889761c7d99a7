//! A loaded 3D track scene run on under another stopping rule: the start of a study from a seated state.
//!
//! A study of stopping rules from a fresh deposit ([`super::loaded_scene`]) measures mostly the seating: the
//! first cycles settle tens of micrometres while the rules differ by one or two per cycle. A loaded scene
//! written at the end of a long run (a run's `final_scene.toml`, time restarting at 0) starts where the
//! section has seated. [`reloaded_scene`] keeps everything of such a scene — grains, sleeper, load, sublayer,
//! time step, θ, sweep caps, mixing, gap and overlap rules — and changes only what a study varies: the
//! stopping rule (`[nscd] criterion` and `tolerance`) and the number of cycles (`[simulation] duration`, in
//! cycles of the scene's own loading frequency, `[output] cycles`).

use super::{refuse, LoadingSpec, SLEEPER};
use crate::error::Result;
use crate::scene::{Scene3, SceneFile};

/// Whether `scene` is a loaded track scene (it has the [`SLEEPER`]), as [`super::loaded_scene`] writes it,
/// rather than a deposited sample.
pub fn is_loaded(scene: &Scene3) -> bool {
    scene.bodies.iter().any(|b| b.name == SLEEPER)
}

/// `loaded` (a loaded track scene, [`is_loaded`]) for `spec.cycles` cycles of its own loading frequency (its
/// `[output] cycles` frequency), with `spec.criterion` and `spec.tolerance` as its stopping rule; everything
/// else of the scene kept, its `[nscd]` keys other than those two included. The other fields of `spec` are the
/// scene's own and must be [`LoadingSpec::default`]'s: one that differs is refused by name rather than ignored.
///
/// # Errors
/// [`crate::Error::Scene`]: `cycles`, `criterion` or `tolerance` out of range; another field of `spec` given
/// (named); a scene without the sleeper or without `[output] cycles` (`sample: …`); the result invalid as a
/// scene file.
pub fn reloaded_scene(loaded: &Scene3, spec: &LoadingSpec) -> Result<Scene3> {
    if !is_loaded(loaded) {
        return refuse(format!("sample: not a loaded scene: it has no body '{SLEEPER}'"));
    }
    let d = LoadingSpec::default();
    // Every field named, none left to `..`: a field added to `LoadingSpec` must be sorted here, kept or refused.
    let LoadingSpec {
        sleeper_width,
        sleeper_length,
        sleeper_height,
        sleeper_density,
        mean_pressure,
        amplitude_pressure,
        frequency,
        phase,
        stiffness_factor,
        cycles: _,
        dt,
        theta,
        criterion: _,
        tolerance: _,
        min_iterations,
        max_iterations,
        face_gaps,
        overlaps,
        anderson,
        output_every,
    } = spec;
    let given = [
        ("sleeper_width", *sleeper_width != d.sleeper_width),
        ("sleeper_length", *sleeper_length != d.sleeper_length),
        ("sleeper_height", *sleeper_height != d.sleeper_height),
        ("sleeper_density", *sleeper_density != d.sleeper_density),
        ("mean_pressure", *mean_pressure != d.mean_pressure),
        ("amplitude_pressure", *amplitude_pressure != d.amplitude_pressure),
        ("frequency", *frequency != d.frequency),
        ("phase", *phase != d.phase),
        ("stiffness_factor", *stiffness_factor != d.stiffness_factor),
        ("dt", *dt != d.dt),
        ("theta", *theta != d.theta),
        ("min_iterations", *min_iterations != d.min_iterations),
        ("max_iterations", *max_iterations != d.max_iterations),
        ("face_gaps", *face_gaps != d.face_gaps),
        ("overlaps", *overlaps != d.overlaps),
        ("anderson", *anderson != d.anderson),
        ("output_every", *output_every != d.output_every),
    ];
    if let Some((name, _)) = given.iter().find(|(_, differs)| *differs) {
        return refuse(format!(
            "{name}: the sample is a loaded scene, which keeps its own; only cycles, criterion and tolerance \
             apply to it"
        ));
    }
    spec.check()?;
    let Some(frequency) = loaded.output.as_ref().and_then(|o| o.cycles.as_ref()).map(|c| c.frequency) else {
        return refuse("sample: the loaded scene has no `[output] cycles`, so no cycle to count".into());
    };
    let mut out = loaded.clone();
    out.simulation.duration = spec.cycles as f64 / frequency;
    let nscd = out.nscd.get_or_insert_with(Default::default);
    nscd.criterion = Some(spec.criterion.clone());
    nscd.tolerance = Some(spec.tolerance);
    out.validate()?;
    Ok(out)
}
