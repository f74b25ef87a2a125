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
//! every geometry too, for one body or several (each elastic body with its own deformation and
//! law).

pub use efsi_core::scene::bodies::{Bodies, Body, SceneBodies};
pub use efsi_core::scene::solid::{LawSpec, SceneSolid, Shape, Solid, checked_json, json};

use efsi_core::plugin_api::{LawDescription, LawLoader, Laws};
use efsi_core::scene::Options;
use efsi_core::validate::{Checked, err};
use efsi_core::{Field, Grid, Region, Scene, Stagger};
use std::path::Path;

/// The solid of a checked scene, as [`check`] read it into `options`; an error if the scene
/// has none.
pub(crate) fn solid(options: &Options) -> Result<&Solid, String> {
    options
        .get::<Solid>()
        .ok_or_else(|| "the scene has no solid".to_string())
}

/// Check the `solid` or `solids` section of `scene`, if it has one, put back its settings in
/// force (defaults filled in) and keep the [`Bodies`] in `options`, read once for every stage
/// that needs them, with the law loader ([`Laws`]); a scene of one body (`solid:`, or a
/// `solids` list of one) also keeps it as the [`Solid`], which the elastic stages read.
///
/// A scene of several bodies is further refused when a body covers no cell and when two bodies
/// overlap at t = 0 ([`overlap`]). Bodies with a law keep their own deformation each (the
/// elastic stage's per-body deformation).
pub fn check(scene: &mut Scene, options: &mut Options) -> Checked {
    let Some(bodies) = scene.bodies_spec()? else {
        return Ok(());
    };
    if !bodies.listed {
        let solid = &bodies.list[0].solid;
        check_solid(scene, solid, "solid")?;
        scene.set_solid(solid);
        options.insert(solid.clone());
    } else {
        let many = bodies.list.len() > 1;
        for (k, body) in bodies.list.iter().enumerate() {
            let at = Body::path(true, k);
            check_solid(scene, &body.solid, &at)
                .map_err(|(f, m)| (f, format!("body \"{}\": {m}", body.name)))?;
        }
        overlap(scene, &bodies.list)?;
        scene.set_bodies(&bodies.list);
        if !many {
            options.insert(bodies.list[0].solid.clone());
        }
    }
    options.insert(bodies);
    options.insert(Laws(&LOADER));
    Ok(())
}

/// The bodies of a checked scene, as [`check`] read them into `options`; an error if the scene
/// has none.
pub(crate) fn bodies(options: &Options) -> Result<&Bodies, String> {
    options
        .get::<Bodies>()
        .ok_or_else(|| "the scene has no solid".to_string())
}

/// The checks of one body's settings that need the scene's geometry and grid: its velocity
/// in a Cartesian3D scene, and that it covers a cell; `at` is its path (`solid`,
/// `solids[1]`).
fn check_solid(scene: &Scene, solid: &Solid, at: &str) -> Checked {
    solid.validate(scene).map_err(|(f, m)| {
        let rest = f.strip_prefix("solid").unwrap_or(&f);
        (format!("{at}{rest}"), m)
    })?;
    covers_a_cell(scene, &solid.shape).map_err(|(f, m)| {
        let rest = f.strip_prefix("solid").unwrap_or(&f);
        (format!("{at}{rest}"), m)
    })
}

/// The largest cell fraction of the intersection of two bodies at t = 0 that is not an
/// overlap: the exact fractions of [`crate::vof::fill_fraction`] are exact to round-off where
/// one boundary crosses a cell, and to ≲ 1e-10 of the cell where two do (the recursive split
/// of [`crate::vof::shapes`]), so two bodies that touch, or pass within a cell of each other,
/// stay below it.
pub const OVERLAP_TOLERANCE: f64 = 1e-9;

/// Refuse bodies that overlap at t = 0: for every pair, the exact cell fractions of the
/// intersection of their shapes ([`Shape::Intersection`]) exceed [`OVERLAP_TOLERANCE`] in
/// some cell. This is a geometric test (resolved to the fractions' accuracy, not to the
/// grid): bodies that share a cell without overlapping pass, and their fractions then sum to
/// at most 1 in every cell (to round-off), the bound the transport keeps. The fractions are
/// those of the cells of the two shapes' common bounding box (`bounds`, a cell more on every
/// side); a pair whose boxes share no cell of the grid cannot overlap in one.
pub fn overlap(scene: &Scene, bodies: &[Body]) -> Checked {
    let grid = scene.build_grid();
    let boxes: Vec<Bounds> = bodies.iter().map(|b| bounds(&b.solid.shape)).collect();
    for (k, b) in bodies.iter().enumerate() {
        for (j, a) in bodies[..k].iter().enumerate() {
            let common = std::array::from_fn(|x| {
                (
                    boxes[j][x].0.max(boxes[k][x].0),
                    boxes[j][x].1.min(boxes[k][x].1),
                )
            });
            let Some(most) = largest_fraction(&grid, &common, || {
                Shape::Intersection(vec![a.solid.shape.clone(), b.solid.shape.clone()])
            }) else {
                continue;
            };
            if most > OVERLAP_TOLERANCE {
                return err(
                    &format!("solids[{k}].shape"),
                    format!(
                        "body \"{}\" overlaps body \"{}\" (solids[{j}]) at t = 0 (up to {:.3} \
                         of a cell): bodies must start apart",
                        b.name, a.name, most
                    ),
                );
            }
        }
    }
    Ok(())
}

/// A solid that covers no cell of the scene's grid (outside the domain, far below a cell, an
/// empty intersection) would leave a run without one, its probes NaN: refused, by the cell
/// fractions the VOF stage starts from ([`crate::vof::fill_fraction`]).
fn covers_a_cell(scene: &Scene, shape: &Shape) -> Checked {
    let grid = scene.build_grid();
    let most = largest_fraction(&grid, &bounds(shape), || shape.clone()).unwrap_or(0.0);
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

/// A box `lo < x_a < hi` along x, y and z (infinite sides where unbounded; empty when some
/// `lo ≥ hi`).
type Bounds = [(f64, f64); 3];

/// A box that holds every point of `shape`: the shape's own for a disk, a ball, an ellipsoid,
/// a rectangle, a box and a cylinder (a two-dimensional shape unbounded along z); the whole
/// space for a half-plane or a half-space; the hull of the parts' for a union, their common
/// box for an intersection, the first shape's for a difference.
fn bounds(shape: &Shape) -> Bounds {
    const ALL: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);
    const NONE: Bounds = [(f64::INFINITY, f64::NEG_INFINITY); 3];
    let around = |c: f64, r: f64| (c - r, c + r);
    match shape {
        Shape::Disk { center, radius } => {
            [around(center.0, *radius), around(center.1, *radius), ALL]
        }
        Shape::Rectangle { min, max } => [(min.0, max.0), (min.1, max.1), ALL],
        Shape::HalfPlane { .. } | Shape::HalfSpace { .. } => [ALL; 3],
        Shape::Sphere { center, radius } => [
            around(center.0, *radius),
            around(center.1, *radius),
            around(center.2, *radius),
        ],
        Shape::Ellipsoid { center, semi_axes } => [
            around(center.0, semi_axes.0),
            around(center.1, semi_axes.1),
            around(center.2, semi_axes.2),
        ],
        Shape::Box { min, max } => [(min.0, max.0), (min.1, max.1), (min.2, max.2)],
        Shape::Cylinder {
            axis,
            center,
            radius,
            length,
        } => {
            let along = axis.index();
            let c = [center.0, center.1, center.2];
            std::array::from_fn(|a| around(c[a], if a == along { 0.5 * length } else { *radius }))
        }
        Shape::Union(v) => v.iter().map(bounds).fold(NONE, |h, b| {
            std::array::from_fn(|a| (h[a].0.min(b[a].0), h[a].1.max(b[a].1)))
        }),
        Shape::Intersection(v) => v.iter().map(bounds).fold([ALL; 3], |h, b| {
            std::array::from_fn(|a| (h[a].0.max(b[a].0), h[a].1.min(b[a].1)))
        }),
        Shape::Difference(a, _) => bounds(a),
    }
}

/// The cells of `grid` that meet the box `b`, a cell more on every side (clipped to the
/// grid): the first cell and the cells along each axis; `None` if no cell meets it.
fn cells_of(grid: &Grid, b: &Bounds) -> Option<([usize; 3], [usize; 3])> {
    let n = grid.n();
    let (mut lo, mut count) = ([0; 3], [1; 3]);
    for a in 0..grid.dims() {
        let face = |i: usize| match a {
            0 => grid.xf(i as isize),
            1 => grid.yf(i as isize),
            _ => grid.zf(i as isize),
        };
        let first = (0..n[a]).find(|&i| face(i + 1) > b[a].0)?;
        let last = (0..n[a]).rev().find(|&i| face(i) < b[a].1)?;
        if first > last {
            return None;
        }
        lo[a] = first.saturating_sub(1);
        count[a] = (last + 2).min(n[a]) - lo[a];
    }
    Some((lo, count))
}

/// The largest cell fraction of the shape `shape()` (whose points lie in the box `b`) over the
/// cells of `grid` that meet `b` ([`cells_of`], on a window of the grid); `None` if none does.
fn largest_fraction(grid: &Grid, b: &Bounds, shape: impl FnOnce() -> Shape) -> Option<f64> {
    let (lo, n) = cells_of(grid, b)?;
    let window = grid.window(lo, n);
    let mut phi = Field::zeros(&window);
    crate::vof::fill_fraction(&window, &shape(), &mut phi);
    Some(Region::of(&window, Stagger::Cell).max(0.0, |line| {
        phi.at(&line, [0, 0, 0]).iter().fold(0.0, |m, &f| f.max(m))
    }))
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

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::Geometry;

    #[test]
    fn a_shapes_box_holds_it_and_its_cells_are_those_the_box_meets_and_one_more() {
        let disk = |x: f64, y: f64| Shape::Disk {
            center: (x, y),
            radius: 0.125,
        };
        let (a, b) = (disk(0.25, 0.25), disk(0.75, 0.625));
        let all = (f64::NEG_INFINITY, f64::INFINITY);
        let union = bounds(&Shape::Union(vec![a.clone(), b.clone()]));
        assert_eq!(union, [(0.125, 0.875), (0.125, 0.75), all]);
        let both = bounds(&Shape::Intersection(vec![a.clone(), b.clone()]));
        assert!(both[0].0 >= both[0].1, "{both:?}");
        let cut = Shape::Difference(Box::new(a.clone()), Box::new(b.clone()));
        assert_eq!(bounds(&cut), bounds(&a));
        let half = Shape::HalfPlane {
            normal: (1.0, 0.0),
            offset: 0.5,
        };
        assert_eq!(bounds(&half), [all; 3]);
        let c = Shape::Cylinder {
            axis: efsi_core::scene::solid::Axis::Y,
            center: (0.5, 0.5, 0.5),
            radius: 0.125,
            length: 0.5,
        };
        assert_eq!(bounds(&c), [(0.375, 0.625), (0.25, 0.75), (0.375, 0.625)]);
        // On 16 × 16 cells of 1/16: x in (0.125, 0.875) meets cells 2..=13, y in (0.125,
        // 0.75) cells 2..=11; a cell more on every side.
        let grid = Grid::new(Geometry::Planar, 16, 16, (0.0, 1.0), (0.0, 1.0));
        assert_eq!(cells_of(&grid, &union), Some(([1, 1, 0], [14, 12, 1])));
        // Clipped to the grid; none for an empty box or one beside the domain.
        let whole = [all; 3];
        assert_eq!(cells_of(&grid, &whole), Some(([0; 3], [16, 16, 1])));
        assert_eq!(cells_of(&grid, &both), None);
        assert_eq!(cells_of(&grid, &[(1.5, 2.0), (0.0, 1.0), all]), None);
        // The largest fraction on the box's cells is the whole grid's: a full cell inside.
        assert_eq!(largest_fraction(&grid, &union, || a.clone()), Some(1.0));
        assert_eq!(largest_fraction(&grid, &both, || a.clone()), None);
    }
}
