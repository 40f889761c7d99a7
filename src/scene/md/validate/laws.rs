//! The contact laws of an MD scene checked (`[[contact]]`: Hertz–Mindlin or linear, restitution, friction,
//! rolling), resolved into the pair laws of the materials ([`crate::md::law`]), and every pair of materials
//! that can touch checked to have one.

use super::*;

/// Every pair of materials that can touch has a law: spheres with spheres (of
/// one material: two spheres, or one and its symmetry image) and with walls
/// ([`md::law::first_uncovered`], which [`MdSystem::new`](crate::md::MdSystem::new) checks through too).
pub(super) fn check_laws_cover(
    scene: &MdScene,
    sphere_materials: &[usize],
    walls: &[Wall],
    planes: &[SymmetryPlane],
    pairs: &HashMap<(usize, usize), usize>,
) -> Result<()> {
    let wall_materials: Vec<usize> = walls.iter().map(|w| w.material as usize).collect();
    let has_law = |a: usize, b: usize| pairs.contains_key(&(a, b));
    let Some(u) =
        md::law::first_uncovered(scene.materials.len(), sphere_materials, &wall_materials, !planes.is_empty(), has_law)
    else {
        return Ok(());
    };
    let body = |i: usize| label("body", i, &scene.bodies[i].name);
    let what = match u.meeting {
        md::law::Meeting::Spheres(i, j) => format!("{} and {}", body(i), body(j)),
        md::law::Meeting::Image(i) => format!("{} and its symmetry image", body(i)),
        md::law::Meeting::Wall(i, k) => format!("{} and {}", body(i), label("wall", k, &scene.walls[k].name)),
    };
    err(format!(
        "contact: no [[contact]] between materials '{}' and '{}', which can touch ({what})",
        scene.materials[u.a].name, scene.materials[u.b].name
    ))
}

/// [`md::law::hertz_alpha_for_restitution`], remembered: each call integrates
/// impacts for some milliseconds, and scenes repeat their coefficients.
fn hertz_alpha(e: f64) -> f64 {
    static KNOWN: Mutex<Vec<(u64, f64)>> = Mutex::new(Vec::new());
    let mut known = KNOWN.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(&(_, alpha)) = known.iter().find(|(bits, _)| *bits == e.to_bits()) {
        return alpha;
    }
    let alpha = md::law::hertz_alpha_for_restitution(e);
    if known.len() < 64 {
        known.push((e.to_bits(), alpha));
    }
    alpha
}

/// The engine's law of a validated `[[contact]]`: a restitution coefficient
/// becomes the damping ratio of [`md::law::hertz_alpha_for_restitution`] or
/// [`md::law::linear_alpha_for_restitution`].
pub(super) fn pair_law(l: &CheckedLaw, materials: &[md::Material]) -> PairLaw {
    match l.model {
        CheckedModel::Hertz { restitution, alpha_n, alpha_t } => {
            let alpha_n = restitution.map_or(alpha_n, hertz_alpha);
            PairLaw::hertz(&materials[l.a], &materials[l.b], alpha_n, alpha_t.unwrap_or(alpha_n), l.mu_s)
        }
        CheckedModel::Linear { kn, kt, restitution, gamma_n, gamma_t } => {
            let normal = match restitution {
                Some(e) => Damping::Ratio(md::law::linear_alpha_for_restitution(e)),
                None => Damping::Coefficient(gamma_n),
            };
            PairLaw::linear(kn, kt, normal, Damping::Coefficient(gamma_t), l.mu_s, l.mu_d)
        }
    }
}

/// Checks one `[[contact]]` between materials `a` and `b`.
pub(super) fn check_contact(i: usize, c: &MdContact, a: usize, b: usize) -> Result<CheckedLaw> {
    let ctx = |field: &str| format!("contact[{i}].{field}");
    let model = match c.model.as_str() {
        "hertz" => md::Model::Hertz,
        "linear" => md::Model::Linear,
        other => {
            return err(format!(
                "{}: unknown model '{}', expected 'hertz' or 'linear'",
                ctx("model"),
                crate::error::clip(other)
            ))
        }
    };
    // Keys of the other model.
    let (foreign, other): (&[(&str, bool)], &str) = match model {
        md::Model::Hertz => (
            &[
                ("static_friction", c.static_friction.is_some()),
                ("dynamic_friction", c.dynamic_friction.is_some()),
                ("normal_stiffness", c.normal_stiffness.is_some()),
                ("tangential_stiffness", c.tangential_stiffness.is_some()),
                ("normal_damping", c.normal_damping.is_some()),
                ("tangential_damping", c.tangential_damping.is_some()),
            ],
            "linear",
        ),
        md::Model::Linear => (
            &[
                ("normal_damping_ratio", c.normal_damping_ratio.is_some()),
                ("tangential_damping_ratio", c.tangential_damping_ratio.is_some()),
            ],
            "hertz",
        ),
    };
    if let Some((key, _)) = foreign.iter().find(|(_, given)| *given) {
        let hint = if key.ends_with("_friction") { ": give friction" } else { "" };
        return err(format!(
            "{}: not a key of model '{}' (only of '{other}'){hint}",
            ctx(key),
            crate::error::clip(&c.model)
        ));
    }
    // Friction: one coefficient, or static and dynamic.
    let (mu_s, mu_d) = match (c.friction, c.static_friction, c.dynamic_friction) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            let key = if c.static_friction.is_some() { "static_friction" } else { "dynamic_friction" };
            return err(format!(
                "{}: give either friction or static_friction and dynamic_friction, not both",
                ctx(key)
            ));
        }
        (Some(mu), None, None) => {
            let mu = non_negative(&ctx("friction"), mu)?;
            (mu, mu)
        }
        (None, Some(s), Some(d)) => {
            let s = non_negative(&ctx("static_friction"), s)?;
            let d = non_negative(&ctx("dynamic_friction"), d)?;
            if d > s {
                return err(format!(
                    "{}: must not exceed static_friction = {}, got {}",
                    ctx("dynamic_friction"),
                    num(s),
                    num(d)
                ));
            }
            (s, d)
        }
        (None, Some(_), None) => {
            return err(format!("{}: missing, required with static_friction", ctx("dynamic_friction")))
        }
        (None, None, Some(_)) => {
            return err(format!("{}: missing, required with dynamic_friction", ctx("static_friction")))
        }
        (None, None, None) => {
            return err(format!(
                "{}: missing, give friction (or static_friction and dynamic_friction)",
                ctx("friction")
            ))
        }
    };
    let restitution = match c.restitution {
        Some(e) if e > 0.0 && e <= 1.0 => Some(e),
        Some(e) => return err(format!("{}: must be in (0, 1], got {}", ctx("restitution"), num(e))),
        None => None,
    };
    let model = match model {
        md::Model::Hertz => {
            if restitution.is_some() && c.normal_damping_ratio.is_some() {
                return err(format!(
                    "{}: give either restitution or normal_damping_ratio, not both",
                    ctx("normal_damping_ratio")
                ));
            }
            let alpha_n = non_negative(&ctx("normal_damping_ratio"), c.normal_damping_ratio.unwrap_or(0.0))?;
            let alpha_t = match c.tangential_damping_ratio {
                Some(r) => Some(non_negative(&ctx("tangential_damping_ratio"), r)?),
                None => None,
            };
            CheckedModel::Hertz { restitution, alpha_n, alpha_t }
        }
        md::Model::Linear => {
            let Some(kn) = c.normal_stiffness else {
                return err(format!("{}: missing, required by model 'linear'", ctx("normal_stiffness")));
            };
            let Some(kt) = c.tangential_stiffness else {
                return err(format!("{}: missing, required by model 'linear'", ctx("tangential_stiffness")));
            };
            let kn = positive(&ctx("normal_stiffness"), kn)?;
            let kt = positive(&ctx("tangential_stiffness"), kt)?;
            if restitution.is_some() && c.normal_damping.is_some() {
                return err(format!("{}: give either restitution or normal_damping, not both", ctx("normal_damping")));
            }
            let gamma_n = non_negative(&ctx("normal_damping"), c.normal_damping.unwrap_or(0.0))?;
            let gamma_t = non_negative(&ctx("tangential_damping"), c.tangential_damping.unwrap_or(0.0))?;
            CheckedModel::Linear { kn, kt, restitution, gamma_n, gamma_t }
        }
    };
    Ok(CheckedLaw { a, b, model, mu_s, mu_d })
}
