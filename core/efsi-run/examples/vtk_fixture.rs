//! Writes a small VTK fixture for the independent-reader test (`tests/python/test_vtk_fixture.py`).
//!
//! `cargo run -p efsi-run --example vtk_fixture -- OUTDIR` writes, for a planar and an
//! axisymmetric grid, two `.vtr` files (two output times) with the cell arrays `pressure`
//! (1 component), `velocity` (3) and `B` (6), one `.pvd` collection per grid, and
//! `expected.json`, which lists for every file what a reader must find in it: dimensions, extent,
//! node coordinates and every array's name, component count and values (shortest round-trip
//! decimal form, so they parse back to the very same `f64`). The cases `planar_f32_zlib` and
//! `axisymmetric_f32_zlib` write the same arrays as `Float32`, zlib-compressed
//! (`vtkZLibDataCompressor`), with point data and text field data (`geometry`, `units`);
//! `expected.json` records each file's format and its text field data (the point values are
//! the reader test's own averages of the cell values).

use efsi_core::{Geometry, Grid};
use efsi_run::output::vtk::{
    CellArray, PvdCollection, VtkCompression, VtkPrecision, VtrFormat, extent_string,
    node_coordinates, write_vtr_with,
};
use serde_json::{Value, json};
use std::path::Path;

/// Analytic cell-centre fields at time `t`: (pressure, velocity, B), cell-major.
fn fields(grid: &Grid, t: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = grid.cells();
    let (mut p, mut u, mut b) = (
        Vec::with_capacity(n),
        Vec::with_capacity(3 * n),
        Vec::with_capacity(6 * n),
    );
    for j in 0..grid.ny as isize {
        for i in 0..grid.nx as isize {
            let (x, y) = (grid.xc(i), grid.yc(j));
            p.push(x.sin() + 2.0 * y + t);
            u.extend([x.cos() * y + t, x * y - 0.25, -x + y * y]);
            for c in 0..6 {
                let c = c as f64;
                b.push(1.0 + (c + 1.0) * x + c.sqrt() * y.exp() + t / (c + 2.0));
            }
        }
    }
    (p, u, b)
}

fn write_case(
    dir: &Path,
    stem: &str,
    grid: &Grid,
    format: &VtrFormat,
    files: &mut Vec<Value>,
) -> Value {
    let notes = if format == &VtrFormat::default() {
        Vec::new()
    } else {
        efsi_run::output::fields::notes(grid.geometry).to_vec()
    };
    let mut pvd = PvdCollection::new(dir.join(format!("{stem}.pvd")));
    for (k, t) in [0.0, 0.1].into_iter().enumerate() {
        let name = format!("{stem}_{k:04}.vtr");
        let (p, u, b) = fields(grid, t);
        let arrays = [
            CellArray {
                name: "pressure",
                components: 1,
                values: &p,
            },
            CellArray {
                name: "velocity",
                components: 3,
                values: &u,
            },
            CellArray {
                name: "B",
                components: 6,
                values: &b,
            },
        ];
        write_vtr_with(&dir.join(&name), grid, t, &arrays, format, &notes)
            .expect("writing the .vtr");
        pvd.add(t, &name).expect("writing the .pvd");

        let [x, y, z] = node_coordinates(grid);
        let extent: Vec<usize> = extent_string(grid)
            .split(' ')
            .map(|s| s.parse().unwrap())
            .collect();
        files.push(json!({
            "file": name,
            "geometry": format!("{:?}", grid.geometry),
            "time": t,
            "float32": format.precision == VtkPrecision::Float32,
            "zlib": format.compression == VtkCompression::Zlib,
            "point_data": format.point_data,
            "notes": notes.iter().map(|(k, v)| json!({"name": k, "text": v})).collect::<Vec<_>>(),
            "dims": [x.len(), y.len(), z.len()],
            "extent": extent,
            "cells": grid.cells(),
            "x": x,
            "y": y,
            "z": z,
            "arrays": arrays.iter().map(|a| json!({
                "name": a.name,
                "components": a.components,
                "values": a.values,
            })).collect::<Vec<_>>(),
        }));
    }
    json!({
        "file": format!("{stem}.pvd"),
        "entries": pvd.entries().iter().map(|(t, f)| json!({"time": t, "file": f})).collect::<Vec<_>>(),
    })
}

fn main() {
    let Some(out) = std::env::args_os().nth(1) else {
        eprintln!("usage: vtk_fixture OUTDIR");
        std::process::exit(2);
    };
    let dir = Path::new(&out);
    std::fs::create_dir_all(dir).expect("creating OUTDIR");

    let planar = Grid::new(Geometry::Planar, 7, 5, (0.0, 1.4), (0.0, 1.0));
    let axi = Grid::new(Geometry::Axisymmetric, 6, 9, (0.0, 0.6), (-0.2, 0.7));
    let mut files = Vec::new();
    let small = VtrFormat {
        precision: VtkPrecision::Float32,
        compression: VtkCompression::Zlib,
        point_data: true,
    };
    let raw = VtrFormat::default();
    let collections = vec![
        write_case(dir, "planar", &planar, &raw, &mut files),
        write_case(dir, "axisymmetric", &axi, &raw, &mut files),
        write_case(dir, "planar_f32_zlib", &planar, &small, &mut files),
        write_case(dir, "axisymmetric_f32_zlib", &axi, &small, &mut files),
        // 2560 cells: B is 61 440 bytes as Float32, two zlib blocks (the last partial).
        write_case(
            dir,
            "planar_large_f32_zlib",
            &Grid::new(Geometry::Planar, 64, 40, (0.0, 1.6), (0.0, 1.0)),
            &small,
            &mut files,
        ),
    ];
    let expected = json!({ "files": files, "collections": collections });
    let text = serde_json::to_string_pretty(&expected).expect("serialising expected.json");
    std::fs::write(dir.join("expected.json"), text + "\n").expect("writing expected.json");
    println!("wrote the VTK fixture to {}", dir.display());
}
