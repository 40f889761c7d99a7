//! Validation of a parsed MD scene: every value is checked (finite, in range,
//! names resolved, every pair of materials that can touch has a law, no
//! contradictory keys) and resolved into what building an
//! [`MdSystem`](crate::md::MdSystem) needs. Each error is one line naming the
//! section or the entry and the field, as for NSCD scenes, e.g.
//! `body[3] 's3': sphere: must be positive and finite, got -0.001` or
//! `contact[1].normal_stiffness: not a key of model 'hertz' (only of 'linear')`.
//! The resolved scene is then checked against its own dynamics
//! ([`super::safety`]): initial overlaps, background damping, time step.

mod laws;

use super::format::{MdContact, MdScene, ServoSpec, WallSpec};
use super::safety::{self, Resolved};
use crate::error::Result;
use crate::md::system::DEFAULT_SKIN_FRACTION;
use crate::md::{
    self, Damping, Drive, GearSet, History1, Integrator, LawTable, MdSettings, Motion, PairLaw, Shape, SymmetryPlane,
    Wall, V3,
};
use crate::scene::validate::{err, finite, label, non_negative, num, positive, MAX_LENGTH, MIN_SIZE};
use crate::scene::SceneFile;
use laws::{check_contact, check_laws_cover, pair_law};
use std::collections::HashMap;
use std::sync::Mutex;

/// Two unit vectors are perpendicular (symmetry planes) or along an axis (box
/// walls) within this tolerance.
const ANGLE_TOLERANCE: f64 = 1e-9;

/// The model of a contact law and its parameters, as given ([`pair_law`] then
/// maps a restitution to a damping ratio, remembered: some milliseconds for `hertz`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum CheckedModel {
    /// Hertz–Mindlin: `α_n` from `restitution` if given, else `alpha_n`;
    /// `α_t = alpha_t`, or `α_n` if `None`.
    Hertz { restitution: Option<f64>, alpha_n: f64, alpha_t: Option<f64> },
    /// Linear spring–dashpot: stiffnesses (N/m); the normal dashpot from
    /// `restitution` if given, else the coefficient `gamma_n` (kg/s); tangential
    /// dashpot `gamma_t` (kg/s).
    Linear { kn: f64, kt: f64, restitution: Option<f64>, gamma_n: f64, gamma_t: f64 },
}

/// A contact law resolved by validation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CheckedLaw {
    /// Material indices.
    pub a: usize,
    pub b: usize,
    pub model: CheckedModel,
    /// Static and dynamic friction coefficients.
    pub mu_s: f64,
    pub mu_d: f64,
}

/// Everything validation resolved.
#[derive(Debug, Clone)]
pub(crate) struct CheckedMd {
    pub settings: MdSettings,
    pub materials: Vec<md::Material>,
    /// Material index of each sphere.
    pub sphere_materials: Vec<usize>,
    /// The laws, restitution coefficients turned into damping ratios.
    pub laws: LawTable,
    pub walls: Vec<Wall>,
    pub planes: Vec<SymmetryPlane>,
    pub threads: Option<usize>,
}

/// `ctx: must be finite, got [x, y, z]` unless every component is finite.
fn finite3(ctx: &str, v: [f64; 3]) -> Result<V3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(V3::from(v))
    } else {
        err(format!("{ctx}: must be finite, got {}", show3(v)))
    }
}

fn show3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// A finite point whose coordinates are within [`MAX_LENGTH`].
fn point(ctx: &str, v: [f64; 3]) -> Result<V3> {
    let p = finite3(ctx, v)?;
    if p.iter().all(|x| x.abs() <= MAX_LENGTH) {
        Ok(p)
    } else {
        err(format!("{ctx}: coordinates must be within ±{MAX_LENGTH:e} m, got {}", show3(v)))
    }
}

/// A non-zero finite vector, normalised.
fn direction(ctx: &str, v: [f64; 3]) -> Result<V3> {
    let d = finite3(ctx, v)?;
    let n = d.norm();
    if n > 0.0 && n.is_finite() {
        Ok(d / n)
    } else {
        err(format!("{ctx}: must be a non-zero vector, got {}", show3(v)))
    }
}

/// A positive length (m) no larger than [`MAX_LENGTH`].
fn length(ctx: &str, v: f64) -> Result<f64> {
    positive(ctx, v)?;
    if v > MAX_LENGTH {
        return err(format!("{ctx}: must be at most {MAX_LENGTH:e} m, got {}", num(v)));
    }
    Ok(v)
}

/// The axis (0, 1, 2) a unit vector lies along, if any.
fn axis_of(n: &V3) -> Option<usize> {
    let a = n.iamax();
    ((n[a].abs() - 1.0).abs() < ANGLE_TOLERANCE).then_some(a)
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Checks the whole scene, one section after the other, and resolves names,
/// shapes, laws and defaults; then the scene as a whole against its dynamics
/// ([`super::safety`]).
pub(crate) fn check(scene: &MdScene) -> Result<CheckedMd> {
    let sim = &scene.simulation;
    crate::scene::common::check_simulation(sim, "md", 3)?;
    let defaults = MdSettings::default();
    let gravity = V3::from(sim.gravity_or(defaults.gravity.into()));
    let ms = scene.md.clone().unwrap_or_default();
    let (integrator, background_damping, background_rotational_damping) = check_md(&ms, &defaults)?;
    crate::scene::common::check_output(scene.output.as_ref(), false, |_| None)?;
    if scene.settlement.is_some() {
        scene.acceleration()?;
    }
    let planes = check_symmetry(scene)?;
    let (names, materials) = check_materials(scene)?;
    let (pairs, laws) = check_contacts(scene, &names)?;
    let (sphere_materials, diameters) = check_bodies(scene, &names, &materials)?;
    let walls = check_walls(scene, &names)?;
    check_laws_cover(scene, &sphere_materials, &walls, &planes, &pairs)?;
    let skin = ms.skin.unwrap_or(DEFAULT_SKIN_FRACTION * diameters / scene.bodies.len() as f64);
    let settings =
        MdSettings { dt: sim.dt, gravity, integrator, skin, background_damping, background_rotational_damping };
    let mut table = LawTable::named(&scene.materials.iter().map(|m| m.name.as_str()).collect::<Vec<_>>());
    for l in &laws {
        table.set(l.a, l.b, pair_law(l, &materials));
    }
    safety::check(&Resolved {
        scene,
        settings: &settings,
        densities: materials.iter().map(|m| m.density).collect(),
        sphere_materials: &sphere_materials,
        laws: &table,
        walls: &walls,
        planes: &planes,
    })?;
    Ok(CheckedMd { settings, materials, sphere_materials, laws: table, walls, planes, threads: ms.threads })
}

/// Checks `[md]`: the integrator, the skin, the background damping (kg/s) and
/// the threads; defaults from [`MdSettings::default`].
fn check_md(ms: &super::format::MdSection, defaults: &MdSettings) -> Result<(Integrator, f64, f64)> {
    let integrator = match ms.integrator.as_deref().unwrap_or("verlet") {
        "verlet" => {
            if ms.gear.is_some() {
                return err("md.gear: only with integrator = \"gear\"".into());
            }
            Integrator::Verlet
        }
        "gear" => {
            let name = ms.gear.as_deref().unwrap_or("karrech");
            match GearSet::from_name(name) {
                Some(set) => Integrator::Gear(set),
                None => {
                    return err(format!(
                        "md.gear: unknown set '{}', expected one of 'karrech', 'gear3', 'gear4', 'gear5', 'gear6'",
                        crate::error::clip(name)
                    ))
                }
            }
        }
        other => {
            return err(format!(
                "md.integrator: unknown integrator '{}', expected 'verlet' or 'gear'",
                crate::error::clip(other)
            ))
        }
    };
    if let Some(s) = ms.skin {
        length("md.skin", s)?;
    }
    let background_damping =
        non_negative("md.background_damping", ms.background_damping.unwrap_or(defaults.background_damping))?;
    let background_rotational_damping = non_negative(
        "md.background_rotational_damping",
        ms.background_rotational_damping.unwrap_or(defaults.background_rotational_damping),
    )?;
    if ms.threads == Some(0) {
        return err("md.threads: must be at least 1, got 0".into());
    }

    Ok((integrator, background_damping, background_rotational_damping))
}

/// Checks `[[symmetry]]`: at most two planes, perpendicular.
fn check_symmetry(scene: &MdScene) -> Result<Vec<SymmetryPlane>> {
    if scene.symmetry.len() > 2 {
        return err(format!("symmetry: at most 2 symmetry planes, got {}", scene.symmetry.len()));
    }
    let mut planes = Vec::with_capacity(scene.symmetry.len());
    for (i, s) in scene.symmetry.iter().enumerate() {
        let point = point(&format!("symmetry[{i}].point"), s.point)?;
        let normal = direction(&format!("symmetry[{i}].normal"), s.normal)?;
        planes.push(SymmetryPlane { point, normal });
    }
    if let [a, b] = planes.as_slice() {
        let dot = a.normal.dot(&b.normal);
        if dot.abs() > ANGLE_TOLERANCE {
            return err(format!(
                "symmetry[1].normal: two symmetry planes must be perpendicular, the normals' dot product is {}",
                num(dot)
            ));
        }
    }

    Ok(planes)
}

/// Checks `[[material]]`: unique non-empty names, moduli in range; the index of each name.
fn check_materials(scene: &MdScene) -> Result<(HashMap<&str, usize>, Vec<md::Material>)> {
    let mut names: HashMap<&str, usize> = HashMap::new();
    let mut materials = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        if m.name.is_empty() {
            return err(format!("material[{i}].name: must not be empty"));
        }
        if let Some(j) = names.insert(m.name.as_str(), i) {
            return err(format!(
                "material[{i}].name: duplicate material '{}' (also material[{j}])",
                crate::error::clip(&m.name)
            ));
        }
        let ctx = |field: &str| format!("{}: {field}", label("material", i, &m.name));
        positive(&ctx("density"), m.density)?;
        positive(&ctx("young"), m.young)?;
        if !(m.poisson > -1.0 && m.poisson < 0.5) {
            return err(format!("{}: must be in (-1, 0.5), got {}", ctx("poisson"), num(m.poisson)));
        }
        materials.push(md::Material { density: m.density, young: m.young, poisson: m.poisson });
    }
    Ok((names, materials))
}

/// The index of the material named `name`, or an error in `ctx`.
fn material_index(names: &HashMap<&str, usize>, ctx: &str, name: &str) -> Result<usize> {
    match names.get(name) {
        Some(&m) => Ok(m),
        None => err(format!("{ctx}: unknown material '{}'", crate::error::clip(name))),
    }
}

/// Checks `[[contact]]`: known materials, one law per pair; the pairs and their laws.
#[allow(clippy::type_complexity)]
fn check_contacts(
    scene: &MdScene,
    names: &HashMap<&str, usize>,
) -> Result<(HashMap<(usize, usize), usize>, Vec<CheckedLaw>)> {
    let mut pairs: HashMap<(usize, usize), usize> = HashMap::new();
    let mut laws = Vec::with_capacity(scene.contacts.len());
    for (i, c) in scene.contacts.iter().enumerate() {
        let a = material_index(names, &format!("contact[{i}].between"), &c.between[0])?;
        let b = material_index(names, &format!("contact[{i}].between"), &c.between[1])?;
        if let Some(j) = pairs.insert((a.min(b), a.max(b)), i) {
            return err(format!(
                "contact[{i}].between: duplicate law for materials '{}' and '{}' (also contact[{j}])",
                c.between[0], c.between[1]
            ));
        }
        laws.push(check_contact(i, c, a, b)?);
    }

    Ok((pairs, laws))
}

/// Checks `[[body]]`: names, materials, radii, state, masses; the material of
/// each sphere and the sum of the diameters (m).
fn check_bodies(
    scene: &MdScene,
    names: &HashMap<&str, usize>,
    materials: &[md::Material],
) -> Result<(Vec<usize>, f64)> {
    if scene.bodies.is_empty() {
        return err("body: the scene has no [[body]] (no sphere)".into());
    }
    let mut body_names: HashMap<&str, usize> = HashMap::new();
    let mut sphere_materials = Vec::with_capacity(scene.bodies.len());
    let mut diameters = 0.0;
    for (i, b) in scene.bodies.iter().enumerate() {
        let name = label("body", i, &b.name);
        let ctx = |field: &str| format!("{name}: {field}");
        if !b.name.is_empty() {
            if let Some(j) = body_names.insert(b.name.as_str(), i) {
                return err(format!("{}: duplicate body name (also body[{j}])", ctx("name")));
            }
        }
        let m = material_index(names, &ctx("material"), &b.material)?;
        let r = length(&ctx("sphere"), b.sphere)?;
        if r < MIN_SIZE {
            return err(format!("{}: must be at least {MIN_SIZE:e} m, got {}", ctx("sphere"), num(r)));
        }
        point(&ctx("position"), b.position)?;
        finite3(&ctx("velocity"), b.velocity())?;
        finite3(&ctx("spin"), b.spin())?;
        let mass = md::particles::sphere_mass(materials[m].density, r);
        if !(mass.is_finite() && mass > 0.0) {
            return err(format!("{}: mass {mass:e} kg (density*4/3*pi*r^3) is not positive and finite", ctx("sphere")));
        }
        sphere_materials.push(m);
        diameters += 2.0 * r;
    }

    Ok((sphere_materials, diameters))
}

/// Checks `[[wall]]`: names, materials, shapes, servo motions (a stress on the
/// box area needs a closed box).
fn check_walls(scene: &MdScene, names: &HashMap<&str, usize>) -> Result<Vec<Wall>> {
    let mut wall_names: HashMap<&str, usize> = HashMap::new();
    let mut walls = Vec::with_capacity(scene.walls.len());
    for (i, w) in scene.walls.iter().enumerate() {
        if w.name.is_empty() {
            return err(format!("wall[{i}].name: must not be empty"));
        }
        if let Some(j) = wall_names.insert(w.name.as_str(), i) {
            return err(format!("wall[{i}].name: duplicate wall '{}' (also wall[{j}])", crate::error::clip(&w.name)));
        }
        let name = label("wall", i, &w.name);
        let m = material_index(names, &format!("{name}: material"), &w.material)?;
        walls.push(check_wall(&name, w, m as u32)?);
    }
    // A stress on the box area needs a closed box around the wall's axis.
    for (i, (w, spec)) in walls.iter().zip(&scene.walls).enumerate() {
        if let Motion::Servo { drive: Drive::Stress(_, None), .. } = w.motion {
            let ctx = format!("{}: servo.area", label("wall", i, &spec.name));
            let Some(axis) = w.normal().as_ref().and_then(axis_of) else {
                return err(format!("{ctx}: omitted, but the wall's normal is not along x, y or z: give area"));
            };
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let closed = |k: usize| md::walls::box_extent(&walls, k).is_some_and(|e| e > 0.0);
            if !(closed(a) && closed(b)) {
                return err(format!(
                    "{ctx}: omitted, but no plane or disc walls with normals ±{} and ±{} close a box around the {} \
                     axis: give area",
                    AXES[a], AXES[b], AXES[axis]
                ));
            }
        }
    }

    Ok(walls)
}

/// Checks one `[[wall]]` (labelled `name`) of material `material`.
fn check_wall(name: &str, w: &WallSpec, material: u32) -> Result<Wall> {
    let ctx = |field: &str| format!("{name}: {field}");
    let given = [w.plane.is_some(), w.disc.is_some(), w.cylinder.is_some()];
    match given.iter().filter(|&&g| g).count() {
        0 => return err(format!("{}: missing, give exactly one of plane, disc, cylinder", ctx("shape"))),
        1 => {}
        _ => return err(format!("{}: give exactly one of plane, disc, cylinder, not several", ctx("shape"))),
    }
    let shape = if let Some(p) = &w.plane {
        Shape::Plane { point: point(&ctx("plane.point"), p.point)?, normal: direction(&ctx("plane.normal"), p.normal)? }
    } else if let Some(d) = &w.disc {
        Shape::Disc {
            point: point(&ctx("disc.point"), d.point)?,
            normal: direction(&ctx("disc.normal"), d.normal)?,
            radius: length(&ctx("disc.radius"), d.radius)?,
        }
    } else {
        let c = w.cylinder.as_ref().expect("one shape");
        Shape::Cylinder {
            axis_point: point(&ctx("cylinder.axis_point"), c.axis_point)?,
            axis: direction(&ctx("cylinder.axis"), c.axis)?,
            radius: length(&ctx("cylinder.radius"), c.radius)?,
        }
    };
    let motion = match &w.servo {
        None => Motion::Fixed,
        Some(_) if w.cylinder.is_some() => {
            return err(format!("{}: only plane and disc walls can be servo walls, not a cylinder", ctx("servo")))
        }
        Some(s) => check_servo(&ctx("servo"), s)?,
    };
    Ok(Wall::new(&w.name, material, shape, motion))
}

/// Checks a `servo` table (context `ctx`).
fn check_servo(ctx: &str, s: &ServoSpec) -> Result<Motion> {
    let f = |field: &str| format!("{ctx}.{field}");
    let mass = positive(&f("mass"), s.mass)?;
    let viscosity = non_negative(&f("viscosity"), s.viscosity)?;
    let amplitude = finite(&f("amplitude"), s.amplitude.unwrap_or(0.0))?;
    let period = non_negative(&f("period"), s.period.unwrap_or(0.0))?;
    let drive = match (s.stress, s.force) {
        (Some(_), Some(_)) => return err(format!("{ctx}: give either stress or force, not both")),
        (None, None) => return err(format!("{ctx}: missing stress or force, give exactly one")),
        (Some(base), None) => {
            let base = finite(&f("stress"), base)?;
            let area = match s.area {
                Some(a) => Some(positive(&f("area"), a)?),
                None => None,
            };
            Drive::Stress(History1 { base, amplitude, period }, area)
        }
        (None, Some(base)) => {
            if s.area.is_some() {
                return err(format!("{}: only with stress, not with force", f("area")));
            }
            Drive::Force(History1 { base: finite(&f("force"), base)?, amplitude, period })
        }
    };
    Ok(Motion::Servo { mass, viscosity, drive })
}
