//! The arrays of the VTK field files: what each one holds ([`describe`], also in `run.json`'s
//! `vtk_arrays` and the table of `docs/outputs.md`) and how it is made from the state
//! ([`arrays`]).
//!
//! Every array is cell data at the cell centres (and, with `output.vtk.point_data`, also point
//! data at the nodes). The geometry decides the axes: planar runs lie in the X–Y plane (X = x,
//! Y = y, Z out of plane); axisymmetric runs write the r–z half-plane at θ = 0 in the X–Z
//! plane: X = r, Z = z (the axis), Y = θ (the hoop direction), so a rotation about Z revolves
//! the slice into the body. Units are the scene's; the ones named here are those of a scene in
//! SI units (m, kg, s), as the shipped solid cases are.

use crate::output::spec::{SliceSpec, VTK_FIELDS, VtkOptions};
use efsi_core::field::Field;
use efsi_core::grid::{Geometry, Grid};
use efsi_core::{OutputDecl, OutputKind, Region, Stagger, operators};

use crate::output::vtk::Produce;
use efsi_core::state::State;
use std::io;

/// What one array of the VTK files holds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ArrayDoc {
    /// The array's name in the file.
    pub name: &'static str,
    /// Where the values sit (`cell`, or `cell and point` with point data).
    pub location: &'static str,
    /// Its components, in the file's order (VTK's: vectors X, Y, Z; symmetric tensors XX, YY,
    /// ZZ, XY, YZ, XZ), each named by the physical component it holds.
    pub components: Vec<&'static str>,
    /// What it is.
    pub meaning: &'static str,
    /// Its unit (SI scene).
    pub unit: &'static str,
}

/// The text field data of every file: `geometry` (the axes) and `units`.
pub fn notes(geometry: Geometry) -> [(&'static str, &'static str); 2] {
    [
        (
            "geometry",
            match geometry {
                Geometry::Planar => {
                    "planar: X = x, Y = y, Z out of the plane (one cell layer at Z = 0)"
                }
                Geometry::Cartesian3D => "three-dimensional: X = x, Y = y, Z = z",
                Geometry::Axisymmetric => {
                    "axisymmetric: the r-z half-plane at theta = 0; X = r (radius), Z = z (the axis), Y = theta (hoop direction); revolve about Z for the body"
                }
            },
        ),
        (
            "units",
            "the scene's units; for a scene in SI: coordinates m, TIME s, velocity m/s, pressure Pa, density kg/m^3, viscosity Pa s, divergence 1/s, stress Pa; solid_fraction and B dimensionless",
        ),
    ]
}

/// Every array the files of a run with `geometry` can hold, as written with `point_data` or
/// not: the shared fields' ([`VTK_FIELDS`] order), then the arrays among the stages' `outputs`
/// ([`efsi_core::StagePlugin::outputs`]).
pub fn describe(geometry: Geometry, point_data: bool, outputs: &[OutputDecl]) -> Vec<ArrayDoc> {
    let location = if point_data { "cell and point" } else { "cell" };
    let stage = outputs.iter().filter_map(|o| {
        let components = match o.kind {
            OutputKind::Array { components, .. } => components(geometry),
            OutputKind::Field(_) => vec![o.name],
            OutputKind::Quantity(_) => return None,
        };
        Some(ArrayDoc {
            name: o.name,
            location,
            components,
            meaning: o.meaning,
            unit: o.unit,
        })
    });
    VTK_FIELDS
        .iter()
        .map(|&name| {
            let (components, meaning, unit) = match name {
                "velocity" => (
                    match geometry {
                        Geometry::Axisymmetric => vec!["u_r", "0", "u_z"],
                        Geometry::Planar => vec!["u_x", "u_y", "0"],
                        Geometry::Cartesian3D => vec!["u_x", "u_y", "u_z"],
                    },
                    "fluid and solid velocity, the mean of the two faces' normal components at the cell centre",
                    "m/s",
                ),
                "pressure" => (
                    vec!["p"],
                    "pressure of the projection (gravity's hydrostatic part included; defined up to a constant in a closed domain)",
                    "Pa",
                ),
                "density" => (vec!["ρ"], "density of the cell's mixture, φ ρ_s + (1 − φ) ρ_f", "kg/m³"),
                "viscosity" => (vec!["μ"], "dynamic viscosity of the cell's mixture", "Pa·s"),
                "divergence" => (
                    vec!["∇·u"],
                    "discrete divergence of the velocity (the projection's residual; ≈ 0)",
                    "1/s",
                ),
                _ => (
                    vec!["φ"],
                    "solid volume fraction φ of the cell, 0 (fluid) to 1 (solid); present with a solid",
                    "1",
                ),
            };
            ArrayDoc {
                name,
                location,
                components,
                meaning,
                unit,
            }
        })
        .chain(stage)
        .collect()
}

/// The names of the arrays a file of `state` holds under `options`: those asked for (all by
/// default) that the state has, in [`describe`]'s order.
pub fn present(
    grid: &Grid,
    state: &State,
    options: &VtkOptions,
    outputs: &[OutputDecl],
) -> Vec<&'static str> {
    let wanted = |name: &str| {
        options
            .fields
            .as_ref()
            .is_none_or(|f| f.iter().any(|x| x == name))
    };
    let stage = outputs.iter().filter_map(|o| {
        let there = match o.kind {
            OutputKind::Array { values, .. } => values(grid, state).is_some(),
            OutputKind::Field(f) => f(state).is_some(),
            OutputKind::Quantity(_) => false,
        };
        (there && wanted(o.name)).then_some(o.name)
    });
    VTK_FIELDS
        .iter()
        .copied()
        .filter(|name| wanted(name))
        .filter(|&name| name != "solid_fraction" || state.phi.is_some())
        .chain(stage)
        .collect()
}

/// The `run.json` section `vtk`: the files' format, text field data and the arrays they hold,
/// each described ([`describe`]); with plane slices (`slices`, their intervals resolved), each
/// one's plane, interval, collection and arrays under `slices`.
pub fn summary(
    grid: &Grid,
    state: &State,
    options: &VtkOptions,
    slices: &[SliceSpec],
    outputs: &[OutputDecl],
) -> serde_json::Value {
    let names = present(grid, state, options, outputs);
    let docs: Vec<ArrayDoc> = describe(grid.geometry, options.point_data, outputs)
        .into_iter()
        .filter(|d| names.contains(&d.name))
        .collect();
    let notes: serde_json::Map<String, serde_json::Value> = notes(grid.geometry)
        .iter()
        .map(|(k, v)| (k.to_string(), serde_json::Value::from(*v)))
        .collect();
    let mut json = serde_json::json!({
        "precision": options.precision,
        "compression": options.compression,
        "point_data": options.point_data,
        "field_data": notes,
        "arrays": docs,
    });
    if !slices.is_empty() {
        json["slices"] = slices
            .iter()
            .map(|s| {
                let wanted = VtkOptions {
                    fields: s.fields.clone(),
                    ..options.clone()
                };
                let name = s.stem();
                serde_json::json!({
                    "name": name,
                    "normal": crate::output::slice::axis_name(s.normal.index()),
                    "at": s.at,
                    "every": s.every,
                    "collection": format!("slices/{name}.pvd"),
                    "arrays": present(grid, state, &wanted, outputs),
                })
            })
            .collect();
    }
    json
}

/// The text field data of a plane slice's files: `geometry` (the plane and its axes), `slice`
/// (how its values are made) and `units`.
pub fn slice_notes(normal: usize, at: f64) -> [(&'static str, String); 3] {
    let axis = crate::output::slice::axis_name(normal);
    [
        (
            "geometry",
            format!(
                "the plane {axis} = {at:?} of a three-dimensional run: X = x, Y = y, Z = z (one \
                 cell layer along {axis})"
            ),
        ),
        (
            "slice",
            format!(
                "cell values interpolated linearly along {axis} between the two cell layers \
                 whose centres bracket the plane (the layer next to a wall within half a cell of it)"
            ),
        ),
        ("units", notes(Geometry::Cartesian3D)[1].1.to_string()),
    ]
}

/// The arrays `options` asks for (all the state has, by default), in [`describe`]'s order:
/// `(name, components, values)`, cell-major ([`producers`] gathered).
pub fn arrays(
    grid: &Grid,
    state: &State,
    options: &VtkOptions,
    outputs: &[OutputDecl],
) -> Vec<(&'static str, usize, Vec<f64>)> {
    producers(grid, state, options, outputs)
        .into_iter()
        .map(|(name, components, produce)| {
            let mut values = Vec::with_capacity(components * grid.cells());
            produce(&mut |v| {
                values.extend_from_slice(v);
                Ok(())
            })
            .expect("gathering into memory cannot fail");
            (name, components, values)
        })
        .collect()
}

/// A producer of one array's values ([`Produce`]), boxed.
pub type Producer<'a> = Box<Produce<'a>>;

/// The arrays of [`arrays`], each as a producer that hands its values over a line of cells
/// at a time (a stage's array whole), in VTK's order: `(name, components, producer)` — what a
/// field file is written from without holding its arrays.
pub fn producers<'a>(
    grid: &'a Grid,
    state: &'a State,
    options: &VtkOptions,
    outputs: &'a [OutputDecl],
) -> Vec<(&'static str, usize, Producer<'a>)> {
    let mut out: Vec<(&'static str, usize, Producer<'a>)> = Vec::new();
    for name in present(grid, state, options, outputs) {
        let field = |f: &'a Field| -> Producer<'a> { Box::new(move |sink| scalar(grid, f, sink)) };
        let array: Option<(usize, Producer<'a>)> = match name {
            "velocity" => Some((3, Box::new(move |sink| velocity(grid, state, sink)))),
            "pressure" => Some((1, field(&state.p))),
            "density" => Some((1, field(&state.rho))),
            "viscosity" => Some((1, field(&state.mu))),
            "divergence" => Some((1, Box::new(move |sink| divergence(grid, state, sink)))),
            "solid_fraction" => state.phi.as_ref().map(|phi| (1, field(phi))),
            _ => stage_array(grid, state, outputs, name),
        };
        if let Some((components, produce)) = array {
            out.push((name, components, produce));
        }
    }
    out
}

/// The cell values of `f` to `sink`, a line of cells at a time in VTK's order (i fastest, then
/// j, then k; k = 0 only in two dimensions).
fn scalar(
    grid: &Grid,
    f: &Field,
    sink: &mut dyn FnMut(&[f64]) -> io::Result<()>,
) -> io::Result<()> {
    let cells = Region::of(grid, Stagger::Cell);
    for n in 0..cells.lines() {
        sink(&f.at(&cells.line(n), [0; 3])[..grid.nx])?;
    }
    Ok(())
}

/// The velocity at the cell centres as 3-vectors, each component the mean of its two faces
/// ([`operators::centre_avg`]); an axisymmetric run's `(u_r, 0, u_z)` (the r–z slice lies in
/// the X–Z plane). To `sink` a line of cells at a time, in VTK's order.
fn velocity(
    grid: &Grid,
    state: &State,
    sink: &mut dyn FnMut(&[f64]) -> io::Result<()>,
) -> io::Result<()> {
    let (cells, nx) = (Region::of(grid, Stagger::Cell), grid.nx);
    let slot = |a: usize| usize::from(a == 1 && grid.is_axisymmetric()) + a;
    let mut out = vec![0.0; 3 * nx];
    let mut centre = vec![0.0; nx];
    for n in 0..cells.lines() {
        let line = cells.line(n);
        for (a, f) in state.velocity().iter().enumerate() {
            operators::centre_avg(f, a, &line, &mut centre);
            for (i, c) in centre.iter().enumerate() {
                out[3 * i + slot(a)] = *c;
            }
        }
        sink(&out)?;
    }
    Ok(())
}

/// The discrete divergence of the velocity per cell ([`operators::div`]), to `sink` a line of
/// cells at a time, in VTK's order.
fn divergence(
    grid: &Grid,
    state: &State,
    sink: &mut dyn FnMut(&[f64]) -> io::Result<()>,
) -> io::Result<()> {
    let cells = Region::of(grid, Stagger::Cell);
    let mut row = vec![0.0; grid.nx];
    for n in 0..cells.lines() {
        operators::div(grid, &state.velocity(), &cells.line(n), &mut row);
        sink(&row)?;
    }
    Ok(())
}

/// A stage's array or field `name` among `outputs`, if the state has it: `(components,
/// producer)` (an array is made whole when it is produced).
fn stage_array<'a>(
    grid: &'a Grid,
    state: &'a State,
    outputs: &'a [OutputDecl],
    name: &str,
) -> Option<(usize, Producer<'a>)> {
    match outputs.iter().find(|o| o.name == name).map(|o| o.kind) {
        Some(OutputKind::Array { components, values }) => {
            values(grid, state)?;
            let produce: Producer<'a> = Box::new(move |sink| match values(grid, state) {
                Some(v) => sink(&v),
                None => Ok(()),
            });
            Some((components(grid.geometry).len(), produce))
        }
        Some(OutputKind::Field(f)) => {
            let f = f(state)?;
            Some((1, Box::new(move |sink| scalar(grid, f, sink))))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `efsi describe-output` prints for a three-dimensional run: the velocity's three
    /// components and the axes.
    #[test]
    fn three_dimensional_files_are_described_with_their_axes() {
        let grid = Grid::new_3d([2, 3, 4], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let state = State::new(&grid, 1.0, 0.1, &Default::default());
        let s = summary(&grid, &state, &VtkOptions::default(), &[], &[]);
        assert_eq!(
            s["arrays"][0]["components"],
            serde_json::json!(["u_x", "u_y", "u_z"])
        );
        assert_eq!(
            s["field_data"]["geometry"],
            "three-dimensional: X = x, Y = y, Z = z"
        );
        let names: Vec<&str> = s["arrays"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a["name"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            ["velocity", "pressure", "density", "viscosity", "divergence"]
        );
    }
}
