//! The solid's constitutive law: resolved by name through the law loader, and shared by the
//! elastic and deformation sub-steps of the implicit-momentum stage (loaded and checked once).

use efsi_core::Scene;
use efsi_core::scene::Options;
use efsi_laws_host::ConstitutiveLaw;

/// The law named by the scene's solid: a plugin library found and checked by
/// [`efsi_laws_host::load_law`] (missing file, ABI, parameters, finite-difference check of the
/// tangent) — every law, test laws included, goes through the loader. A 3-D scene loads it with
/// [`efsi_laws_host::load_law_3d`], which refuses a version-1 library (in-plane tensors only)
/// naming the version.
/// `options` are the scene's checked sections, which hold its solid.
pub fn resolve_law(scene: &Scene, options: &Options) -> Result<Box<dyn ConstitutiveLaw>, String> {
    let spec = crate::solid::solid(options)?
        .law
        .as_ref()
        .ok_or("the solid has no law")?;
    load_spec(scene, spec, "solid")
}

/// The law `spec` of the body at `path` (`solid`, `solids[1]`) through the loader: the 3-D
/// loader in a Cartesian3D scene, paths relative to the scene's folder; errors name
/// `<path>.law`.
fn load_spec(
    scene: &Scene,
    spec: &crate::solid::LawSpec,
    path: &str,
) -> Result<Box<dyn ConstitutiveLaw>, String> {
    let dir = scene
        .source_dir
        .clone()
        .unwrap_or_else(|| std::path::PathBuf::from("."));
    let load = if scene.geometry == efsi_core::Geometry::Cartesian3D {
        efsi_laws_host::load_law_3d
    } else {
        efsi_laws_host::load_law
    };
    let law = load(&spec.name, &spec.parameters, &dir).map_err(|e| format!("{path}.law: {e}"))?;
    Ok(Box::new(law))
}

/// The solid's law as the elastic and deformation sub-steps share it: loaded and
/// checked once, by whichever of them is built first ([`efsi_core::Resources`]).
struct SharedLaw(std::sync::Arc<dyn ConstitutiveLaw>);

/// The law of `scene` from the pipeline's shared values, loaded there by the first stage
/// that asks.
pub(super) fn shared_law(
    scene: &Scene,
    options: &Options,
    shared: &mut efsi_core::Resources,
) -> Result<std::sync::Arc<dyn ConstitutiveLaw>, String> {
    let law = shared
        .get_or_try_insert_with(|| resolve_law(scene, options).map(|l| SharedLaw(l.into())))?;
    Ok(law.0.clone())
}

/// The laws of the elastic bodies of a scene of several, one per body in the order of
/// [`super::bodies::elastic_bodies`], loaded and checked once per pipeline.
struct SharedLaws(Vec<std::sync::Arc<dyn ConstitutiveLaw>>);

/// The law of each elastic body of `bodies`: the single solid's [`shared_law`], or each body's
/// own (its `solids[k].law`), loaded by the first stage that asks.
pub(super) fn shared_laws(
    scene: &Scene,
    options: &Options,
    bodies: &[super::bodies::ElasticBody],
    shared: &mut efsi_core::Resources,
) -> Result<Vec<std::sync::Arc<dyn ConstitutiveLaw>>, String> {
    if bodies.len() == 1 && bodies[0].index.is_none() {
        return Ok(vec![shared_law(scene, options, shared)?]);
    }
    let laws = shared.get_or_try_insert_with(|| {
        bodies
            .iter()
            .map(|b| body_law(scene, b).map(std::sync::Arc::from))
            .collect::<Result<Vec<_>, String>>()
            .map(SharedLaws)
    })?;
    Ok(laws.0.clone())
}

/// The law of one body of several, through the loader as [`resolve_law`]'s.
fn body_law(
    scene: &Scene,
    b: &super::bodies::ElasticBody,
) -> Result<Box<dyn ConstitutiveLaw>, String> {
    let spec = b
        .solid
        .law
        .as_ref()
        .ok_or_else(|| format!("{}: the body has no law", b.path))?;
    load_spec(scene, spec, &b.path)
}
