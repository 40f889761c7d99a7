//! The library's messages name the arguments and spec fields a caller gave (`threads`, `cycles`,
//! `perturbation.distance_m`, …); the command line speaks of its flags. [`as_flags`] turns the first into the
//! second for the one line an input error prints.

/// A library message's leading field, and the flag of the command line that sets it.
const FLAGS: [(&str, &str); 31] = [
    ("threads", "--threads"),
    ("checkpoint_every_s", "--checkpoint-every"),
    ("resume", "--resume"),
    ("engine", "--engine"),
    ("length.steps", "--steps"),
    ("length.duration", "--duration"),
    ("reference", "--reference"),
    ("from", "--from"),
    ("stiffness_factor", "--stiffness-factor"),
    ("inclination_deg", "--inclination"),
    ("sleeper_width", "--sleeper-width"),
    ("bars", "--bars"),
    ("dt", "--dt"),
    ("criterion", "--criterion"),
    ("tolerance", "--tolerance"),
    ("min_iterations", "--min-iterations"),
    ("cycles", "--cycles"),
    ("jobs", "--jobs"),
    ("perturbation.distance_m", "--perturb"),
    ("replicas", "--replicas"),
    ("sample", "--sample"),
    ("overlaps", "--overlaps"),
    ("model", "--model"),
    ("dt_fraction", "--dt-fraction"),
    ("policies", "--policies"),
    ("samples", "--samples"),
    ("factors", "--factors"),
    ("dts", "--dts"),
    ("task", "--task"),
    ("summarize", "--summarize-only"),
    ("guide", "--guide"),
];

/// `msg` with its leading `field:` replaced by the flag that sets the field, if it is one of the command
/// line's ([`FLAGS`]); any other message (a scene key such as `simulation.dt`, a file) as it is.
pub(crate) fn as_flags(msg: &str) -> String {
    for (field, flag) in FLAGS {
        if let Some(rest) = msg.strip_prefix(field).filter(|r| r.starts_with(':')) {
            return format!("{flag}{rest}");
        }
    }
    msg.to_string()
}

#[cfg(test)]
mod tests {
    use super::as_flags;

    /// A field of the library becomes its flag; a scene key, or a field that only starts like one, stays.
    #[test]
    fn leading_fields_become_flags() {
        assert_eq!(as_flags("threads: must be at least 1, got 0"), "--threads: must be at least 1, got 0");
        assert_eq!(as_flags("length.steps: must be at least 1"), "--steps: must be at least 1");
        assert_eq!(as_flags("perturbation.distance_m: must be a distance"), "--perturb: must be a distance");
        assert_eq!(as_flags("samples: must be at least 1"), "--samples: must be at least 1");
        assert_eq!(as_flags("simulation.dt: must be positive"), "simulation.dt: must be positive");
        assert_eq!(as_flags("cycles_x: no"), "cycles_x: no");
        assert_eq!(as_flags("scene.toml: bad"), "scene.toml: bad");
    }
}
