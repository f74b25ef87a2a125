//! The scene's `solid` section for the stages: its check when a simulation is built, and the
//! law loader the framework reaches through the checked scene.
//!
//! The section's type and the checks of its settings are the scene model's
//! ([`efsi_core::scene::solid`]). The VOF stage's plugin reads it once as a [`Solid`] and checks
//! it ([`check`], its [`StagePlugin::check_scene`](efsi_core::StagePlugin::check_scene)) when a
//! simulation is built — its ranges; its shape's dimension, that of the scene (a
//! two-dimensional shape in a Cartesian3D scene, a three-dimensional one in a planar or
//! axisymmetric scene, or a combination of both is refused, naming the shapes the scene takes);
//! its velocity's components, one per axis of the scene; and that it covers a cell of the
//! grid — each failure naming the setting's path (`solid.density`), puts back its settings in force, so that records hold the defaults too,
//! and keeps the [`Solid`] in the checked scene's [`Options`], from which every stage that
//! needs it reads it, with the law loader ([`Laws`]) through which the run loop identifies the
//! law library a checkpoint records.
//!
//! A solid without a law (a second fluid: a drop, a bubble) runs in every geometry; one with a
//! law adds the implicit-momentum stage (`momentum`) and the deformation stage, which run in
//! every geometry too.

pub use efsi_core::scene::solid::{LawSpec, SceneSolid, Shape, Solid, checked_json, json};

use efsi_core::plugin_api::{LawDescription, LawLoader, Laws};
use efsi_core::scene::Options;
use efsi_core::validate::{Checked, err};
use efsi_core::{Field, Region, Scene, Stagger};
use std::path::Path;

/// The solid of a checked scene, as [`check`] read it into `options`; an error if the scene
/// has none.
pub(crate) fn solid(options: &Options) -> Result<&Solid, String> {
    options
        .get::<Solid>()
        .ok_or_else(|| "the scene has no solid".to_string())
}

/// Check the `solid` section of `scene`, if it has one ([`Solid::validate`]), put back its
/// settings in force (defaults filled in) and keep the [`Solid`] in `options`, read once for
/// every stage that needs it, with the law loader ([`Laws`]).
pub fn check(scene: &mut Scene, options: &mut Options) -> Checked {
    let Some(solid) = scene.solid_spec()? else {
        return Ok(());
    };
    solid.validate(scene)?;
    covers_a_cell(scene, &solid.shape)?;
    scene.set_solid(&solid);
    options.insert(solid);
    options.insert(Laws(&LOADER));
    Ok(())
}

/// A solid that covers no cell of the scene's grid (outside the domain, far below a cell, an
/// empty intersection) would leave a run without one, its probes NaN: refused, by the cell
/// fractions the VOF stage starts from ([`crate::vof::fill_fraction`]).
fn covers_a_cell(scene: &Scene, shape: &Shape) -> Checked {
    let grid = scene.build_grid();
    let mut phi = Field::zeros(&grid);
    crate::vof::fill_fraction(&grid, shape, &mut phi);
    let most = Region::of(&grid, Stagger::Cell).max(0.0, |line| {
        phi.at(&line, [0, 0, 0]).iter().fold(0.0, |m, &f| f.max(m))
    });
    if most <= 0.0 {
        let cells = match grid.dims() {
            3 => format!("{}×{}×{}", grid.nx, grid.ny, grid.nz),
            _ => format!("{}×{}", grid.nx, grid.ny),
        };
        let cell = match grid.dims() {
            3 => format!("{:e} × {:e} × {:e}", grid.dx, grid.dy, grid.dz),
            _ => format!("{:e} × {:e}", grid.dx, grid.dy),
        };
        return err(
            "solid.shape",
            format!(
                "covers no cell of the {cells} grid (outside the domain, much smaller than a \
                 cell of {cell}, or empty): the run would have no solid"
            ),
        );
    }
    Ok(())
}

/// The law loader of `efsi-laws-host` as the framework's [`LawLoader`].
struct Loader;

/// The one [`Loader`].
static LOADER: Loader = Loader;

impl LawLoader for Loader {
    fn describe(&self, name: &str, dir: &Path) -> Result<LawDescription, String> {
        let library = efsi_laws_host::loader::resolve_law(name, dir).map_err(|e| e.to_string())?;
        let info = efsi_laws_host::describe(&library).map_err(|e| e.to_string())?;
        Ok(LawDescription {
            name: info.name,
            abi_version: info.abi_version,
            parameters: info
                .parameters
                .iter()
                .map(|p| {
                    format!(
                        "{} [{}] default {:e} range {}",
                        p.name,
                        p.unit,
                        p.default,
                        p.range_text()
                    )
                })
                .collect(),
            library,
        })
    }
}
