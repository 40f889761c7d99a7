//! A 3D system for the diagnosis examples: a scene's, or the state of a run's checkpoint with the scene's `[nscd]`
//! settings, as `ballast run --resume --change-solver` takes them.

use ballast::nscd::d3::system::System3;
use ballast::run::checkpoint::{read_checked, Checkpoint};
use ballast::scene::{Scene3, SceneFile};

/// The system of the scene at `scene`; with `run`, the state of `run/checkpoint.json` (its warm start included)
/// with the scene's `[nscd]` settings.
pub fn system(scene: &str, run: Option<&str>) -> Result<System3, Box<dyn std::error::Error>> {
    let built = Scene3::load(scene)?.build()?;
    let Some(dir) = run else {
        return Ok(built);
    };
    let (_, checkpoint): (_, Checkpoint<System3, serde_json::Value>) = read_checked(std::path::Path::new(dir))?;
    let mut sys = checkpoint.system;
    sys.params.nlgs = built.params.nlgs;
    Ok(sys)
}
