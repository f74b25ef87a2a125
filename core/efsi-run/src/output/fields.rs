//! The arrays of the VTK field files: what each one holds ([`describe`], also in `run.json`'s
//! `vtk_arrays` and the README's output table) and how it is made from the state
//! ([`arrays`]).
//!
//! Every array is cell data at the cell centres (and, with `output.vtk.point_data`, also point
//! data at the nodes). The geometry decides the axes: planar runs lie in the X–Y plane (X = x,
//! Y = y, Z out of plane); axisymmetric runs write the r–z half-plane at θ = 0 in the X–Z
//! plane: X = r, Z = z (the axis), Y = θ (the hoop direction), so a rotation about Z revolves
//! the slice into the body. Units are the scene's; the ones named here are those of a scene in
//! SI units (m, kg, s), as the shipped solid cases are.

use efsi_core::field::Field;
use efsi_core::grid::{Geometry, Grid};
use efsi_core::scene::{VTK_FIELDS, VtkOptions};

use efsi_core::state::State;

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

/// Every array the files of a run with `geometry` can hold, in [`VTK_FIELDS`] order, as
/// written with `point_data` or not.
pub fn describe(geometry: Geometry, point_data: bool) -> Vec<ArrayDoc> {
    let axi = geometry == Geometry::Axisymmetric;
    let location = if point_data { "cell and point" } else { "cell" };
    let tensor = |t: &'static str| -> Vec<&'static str> {
        match (axi, t) {
            (false, "B") => vec!["B̃xx", "B̃yy", "B̃zz (out of plane)", "B̃xy", "0", "0"],
            (true, "B") => vec!["B̃rr", "B̃θθ", "B̃zz", "0", "0", "B̃rz"],
            (false, _) => vec!["τxx", "τyy", "τzz (out of plane)", "τxy", "0", "0"],
            (true, _) => vec!["τrr", "τθθ", "τzz", "0", "0", "τrz"],
        }
    };
    VTK_FIELDS
        .iter()
        .map(|&name| {
            let (components, meaning, unit) = match name {
                "velocity" => (
                    if axi {
                        vec!["u_r", "0", "u_z"]
                    } else {
                        vec!["u_x", "u_y", "0"]
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
                "solid_fraction" => (
                    vec!["φ"],
                    "solid volume fraction φ of the cell, 0 (fluid) to 1 (solid); present with a solid",
                    "1",
                ),
                "B" => (
                    tensor("B"),
                    "B̃ = φ^{1/2} B, not B: the left Cauchy–Green tensor B = F Fᵀ of the solid weighted by the square root of the solid fraction (divide by √φ for B; I in a solid at rest, 0 in the fluid); the shear component is the mean of the cell's four corners; present with a solid that has a law",
                    "1",
                ),
                _ => (
                    tensor("stress"),
                    "the elastic extra stress only, τ(B̃) − τ(φ^{1/2} I): the law's stress less its isotropic rest stress; without the pressure and the viscous stress (the Cauchy stress is −p I + 2μD + this); the shear component is the mean of the cell's four corners; present with a solid that has a law",
                    "Pa",
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
        .collect()
}

/// The names of the arrays a file of `state` holds under `options`: those asked for (all by
/// default) that the state has, in [`VTK_FIELDS`] order.
pub fn present(state: &State, options: &VtkOptions) -> Vec<&'static str> {
    VTK_FIELDS
        .iter()
        .copied()
        .filter(|name| {
            options
                .fields
                .as_ref()
                .is_none_or(|f| f.iter().any(|x| x == name))
        })
        .filter(|&name| match name {
            "solid_fraction" => state.phi.is_some(),
            "B" | "stress" => state.phi.is_some() && state.deformation.is_some(),
            _ => true,
        })
        .collect()
}

/// The `run.json` section `vtk`: the files' format, text field data and the arrays they hold,
/// each described ([`describe`]).
pub fn summary(grid: &Grid, state: &State, options: &VtkOptions) -> serde_json::Value {
    let names = present(state, options);
    let docs: Vec<ArrayDoc> = describe(grid.geometry, options.point_data)
        .into_iter()
        .filter(|d| names.contains(&d.name))
        .collect();
    let notes: serde_json::Map<String, serde_json::Value> = notes(grid.geometry)
        .iter()
        .map(|(k, v)| (k.to_string(), serde_json::Value::from(*v)))
        .collect();
    serde_json::json!({
        "precision": options.precision,
        "compression": options.compression,
        "point_data": options.point_data,
        "field_data": notes,
        "arrays": docs,
    })
}

/// The arrays `options` asks for (all the state has, by default), in [`VTK_FIELDS`] order:
/// `(name, components, values)`, cell-major.
pub fn arrays(
    grid: &Grid,
    state: &State,
    options: &VtkOptions,
) -> Vec<(&'static str, usize, Vec<f64>)> {
    let wanted = present(state, options);
    let (nx, ny) = (grid.nx, grid.ny);
    let n = nx * ny;
    let cells = || (0..ny as isize).flat_map(move |j| (0..nx as isize).map(move |i| (i, j)));
    let scalar = |f: &Field| cells().map(|c| f[c]).collect::<Vec<f64>>();
    let mut out = Vec::new();
    for name in wanted {
        match name {
            "velocity" => {
                // Axisymmetric output is the r–z slice in the X–Z plane (u_z goes to Z).
                let vy = if grid.is_axisymmetric() { 2 } else { 1 };
                let mut vel = vec![0.0; 3 * n];
                for (k, (i, j)) in cells().enumerate() {
                    let (a, b) = efsi_core::ops::centre_velocity(&state.u, &state.v, i, j);
                    vel[3 * k] = a;
                    vel[3 * k + vy] = b;
                }
                out.push((name, 3, vel));
            }
            "pressure" => out.push((name, 1, scalar(&state.p))),
            "density" => out.push((name, 1, scalar(&state.rho))),
            "viscosity" => out.push((name, 1, scalar(&state.mu))),
            "divergence" => out.push((
                name,
                1,
                cells()
                    .map(|(i, j)| efsi_core::ops::div(grid, &state.u, &state.v, i, j))
                    .collect(),
            )),
            "solid_fraction" => {
                if let Some(phi) = &state.phi {
                    out.push((name, 1, scalar(phi)));
                }
            }
            "B" | "stress" => {
                if let (Some(d), Some(phi)) = (&state.deformation, &state.phi) {
                    let t = if name == "B" {
                        tensor(grid, &d.b, Some(phi))
                    } else {
                        tensor(grid, &d.stress, None)
                    };
                    out.push((name, 6, t));
                }
            }
            _ => {}
        }
    }
    out
}

/// A staggered tensor (11, 22, 33 at centres, 12 at corners) at the cell centres as a VTK
/// symmetric tensor (XX, YY, ZZ, XY, YZ, XZ), weighted by `φ^{1/2}` if `phi` is given. Planar:
/// 1 = X, 2 = Y, 3 = Z. Axisymmetric (the r–z slice in the X–Z plane): r = X, z = Z, θ = Y.
fn tensor(grid: &Grid, t: &[Field; 4], phi: Option<&Field>) -> Vec<f64> {
    let (nx, ny) = (grid.nx, grid.ny);
    let mut out = vec![0.0; 6 * nx * ny];
    let (c11, c22, c33, c12) = if grid.is_axisymmetric() {
        (0, 2, 1, 5)
    } else {
        (0, 1, 2, 3)
    };
    for j in 0..ny as isize {
        for i in 0..nx as isize {
            let k = 6 * (j as usize * nx + i as usize);
            let w = phi.map_or(1.0, |p| p[(i, j)].clamp(0.0, 1.0).sqrt());
            let t12 =
                0.25 * (t[3][(i, j)] + t[3][(i + 1, j)] + t[3][(i, j + 1)] + t[3][(i + 1, j + 1)]);
            out[k + c11] = w * t[0][(i, j)];
            out[k + c22] = w * t[1][(i, j)];
            out[k + c33] = w * t[2][(i, j)];
            out[k + c12] = w * t12;
        }
    }
    out
}
