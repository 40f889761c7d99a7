//! The `[settlement]` table of `Simulation.settle`: the scene's own, with the keyword arguments in place of its
//! keys (`accelerate = (k_i, k, h)`, `law`, `body`, and any other key of the table in `settings`), read by the
//! library's serde form of the table (an unknown key or a bad value is a `SceneError` naming it).

use crate::errors::to_py;
use ballast_core::open::{Loaded, SettleRequest};
use ballast_core::scene::common::SettlementSection;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Map, Value};

/// The keyword arguments of `Simulation.settle` that shape its table.
pub struct Asked<'a, 'py> {
    /// `(k_i, k, h)`: cycles computed before the first fit, computed per fit, extrapolated by the first jump.
    pub accelerate: Option<(u64, u64, u64)>,
    /// `"shenton"` or `"linear"`.
    pub law: Option<String>,
    /// The settlement body's name.
    pub body: Option<String>,
    /// Any other keys of the table.
    pub settings: Option<&'a Bound<'py, PyDict>>,
    /// Cycles to reach.
    pub cycles: Option<u64>,
}

/// The scene's `[settlement]` table, if it has one.
fn scene_table(loaded: &Loaded) -> Option<SettlementSection> {
    match loaded {
        Loaded::Nscd(o) => o.scene.settlement.clone(),
        Loaded::PlanarMd(o, _) => o.scene.settlement.clone(),
        Loaded::Md(o) => o.scene.settlement.clone(),
        Loaded::Nscd3(o) => o.scene.settlement.clone(),
    }
}

/// The request of a settle call on `loaded`: the table `asked` makes of the scene's (or of none), and the
/// cycles.
pub fn request(py: Python<'_>, loaded: &Loaded, asked: Asked<'_, '_>) -> PyResult<SettleRequest> {
    let Asked { accelerate, law, body, settings, cycles } = asked;
    let own = scene_table(loaded);
    if own.is_none() && accelerate.is_none() {
        return Err(scene_error(
            "accelerate: the scene has no [settlement] table; give accelerate = (k_i, k, h)".into(),
        ));
    }
    if accelerate.is_none() && law.is_none() && body.is_none() && settings.is_none() {
        return Ok(SettleRequest { settlement: None, cycles });
    }
    let mut table = match own {
        Some(t) => serde_json::to_value(t).map_err(json_error)?,
        None => Value::Object(Map::new()),
    };
    let keys = table.as_object_mut().expect("a table serialises as an object");
    if let Some((initial, computed, extrapolated)) = accelerate {
        keys.insert("initial_cycles".into(), initial.into());
        keys.insert("computed_cycles".into(), computed.into());
        keys.insert("extrapolated_cycles".into(), extrapolated.into());
    }
    if let Some(law) = law {
        keys.insert("law".into(), law.into());
    }
    if let Some(body) = body {
        keys.insert("settlement_body".into(), body.into());
    }
    if let Some(settings) = settings {
        let text: String = py.import("json")?.call_method1("dumps", (settings,))?.extract()?;
        let Value::Object(given) = serde_json::from_str(&text).map_err(json_error)? else {
            unreachable!("a dict dumps as an object")
        };
        keys.extend(given);
    }
    let section: SettlementSection = serde_json::from_value(table)
        .map_err(|e| scene_error(format!("settlement: {}", e.to_string().replace('\n', " "))))?;
    Ok(SettleRequest { settlement: Some(section), cycles })
}

/// A `SceneError` with `message` (whose first word names the key).
fn scene_error(message: String) -> PyErr {
    to_py(ballast_core::Error::Scene(message))
}

/// A JSON error of the binding's own conversions, as a `ValueError`.
fn json_error(e: serde_json::Error) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(e.to_string())
}
