//! The exact cell fractions of the three-dimensional shapes (`efsi_stages::vof::shapes3d`):
//! their sums against the analytic volumes, per-cell values against midpoint sums, and the
//! additivity of the sphere's quadrature.

use efsi_core::{Field, Grid, Region, Stagger};
use efsi_stages::vof::shapes3d::{Cuboid, volume_in};
use efsi_stages::vof::{Axis, Shape, fill_fraction, phase_volume};
use std::f64::consts::PI;

fn cube(n: usize) -> Grid {
    Grid::new_3d([n; 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0))
}

fn total(grid: &Grid, shape: &Shape) -> f64 {
    let mut phi = Field::zeros(grid);
    fill_fraction(grid, shape, &mut phi);
    phase_volume(grid, &phi)
}

#[test]
fn sphere_volume_is_exact_at_every_resolution() {
    let r = 0.15;
    let exact = 4.0 / 3.0 * PI * r * r * r;
    for n in [8, 16, 32, 64] {
        let v = total(
            &cube(n),
            &Shape::Sphere {
                center: (0.35, 0.35, 0.35),
                radius: r,
            },
        );
        println!("sphere n = {n}: relative error {:.2e}", (v - exact) / exact);
        assert!(
            ((v - exact) / exact).abs() < 1e-13,
            "n = {n}: {v} vs {exact}"
        );
    }
}

#[test]
fn ellipsoid_cylinder_and_half_space_volumes_are_exact() {
    let g = cube(24);
    let (a, b, c) = (0.3, 0.17, 0.23);
    let v = total(
        &g,
        &Shape::Ellipsoid {
            center: (0.47, 0.52, 0.49),
            semi_axes: (a, b, c),
        },
    );
    let exact = 4.0 / 3.0 * PI * a * b * c;
    assert!(
        ((v - exact) / exact).abs() < 1e-13,
        "ellipsoid {v} vs {exact}"
    );
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let v = total(
            &g,
            &Shape::Cylinder {
                axis,
                center: (0.51, 0.46, 0.53),
                radius: 0.21,
                length: 0.63,
            },
        );
        let exact = PI * 0.21 * 0.21 * 0.63;
        assert!(
            ((v - exact) / exact).abs() < 1e-13,
            "{axis:?}: {v} vs {exact}"
        );
    }
    // x + y + z < 1 in the unit cube: the corner tetrahedron, 1/6.
    let v = total(
        &g,
        &Shape::HalfSpace {
            normal: (1.0, 1.0, 1.0),
            offset: 1.0,
        },
    );
    assert!((v - 1.0 / 6.0).abs() < 1e-14, "half-space {v}");
}

#[test]
fn a_box_on_the_cell_faces_is_exact_cell_by_cell() {
    let g = cube(16);
    let shape = Shape::Box {
        min: (0.25, 0.125, 0.5),
        max: (0.75, 0.5, 0.875),
    };
    let mut phi = Field::zeros(&g);
    fill_fraction(&g, &shape, &mut phi);
    Region::of(&g, Stagger::Cell).for_each(&mut phi, |l, phi| {
        for (f, [i, j, k]) in phi.iter().zip(l.indices()) {
            let inside = (4..12).contains(&i) && (2..8).contains(&j) && (8..14).contains(&k);
            assert_eq!(*f, if inside { 1.0 } else { 0.0 }, "[{i}, {j}, {k}]");
        }
    });
    assert_eq!(phase_volume(&g, &phi), 0.5 * 0.375 * 0.375);
    // Off the faces: the overlap volumes, exact to round-off.
    let v = total(
        &g,
        &Shape::Box {
            min: (0.23, 0.111, 0.5071),
            max: (0.7713, 0.52, 0.8802),
        },
    );
    assert!((v - 0.5413 * 0.409 * 0.3731).abs() < 1e-15, "{v}");
}

#[test]
fn slotted_sphere_volume_to_the_recursion_tolerance() {
    let (r, c) = (0.15, (0.5, 0.75, 0.5));
    let sphere = Shape::Sphere {
        center: c,
        radius: r,
    };
    let slot = Cuboid {
        lo: [0.475, 0.5, 0.0],
        hi: [0.525, 0.725, 1.0],
    };
    let shape = Shape::Difference(
        Box::new(sphere.clone()),
        Box::new(Shape::Box {
            min: (0.475, 0.5, 0.0),
            max: (0.525, 0.725, 1.0),
        }),
    );
    // The slot's part of the sphere from one box, where only the sphere's boundary crosses.
    // The cells on the slot's rim (two boundaries) are resolved to sub-boxes of h/2^10: an
    // error ≲ 1e-6 of a cell each, some 10² of them.
    let exact = 4.0 / 3.0 * PI * r * r * r - volume_in(&sphere, slot);
    for n in [32, 64] {
        let v = total(&cube(n), &shape);
        println!(
            "slotted sphere n = {n}: error {:.2e} of a cell",
            (v - exact) * (n as f64).powi(3)
        );
        assert!(
            (v - exact).abs() < 5e-5 / (n as f64).powi(3),
            "n = {n}: {v} vs {exact}"
        );
    }
}

#[test]
fn sphere_quadrature_is_additive() {
    // A cell's volume against the sum over its octants (other break points, other nodes), for
    // cells cut in every way by the sphere: the quadrature error, not the geometry's.
    let sphere = Shape::Sphere {
        center: (0.0, 0.0, 0.0),
        radius: 1.0,
    };
    let h = 0.37;
    let mut worst = 0.0f64;
    for i in -3..3 {
        for j in -3..3 {
            for k in -3..3 {
                let lo = [
                    i as f64 * h + 0.013,
                    j as f64 * h - 0.021,
                    k as f64 * h + 0.007,
                ];
                let b = Cuboid {
                    lo,
                    hi: lo.map(|x| x + h),
                };
                let whole = volume_in(&sphere, b);
                let m: [f64; 3] = std::array::from_fn(|a| lo[a] + 0.5 * h);
                let mut parts = 0.0;
                for o in 0..8 {
                    let mut q = b;
                    for a in 0..3 {
                        if o >> a & 1 == 0 {
                            q.hi[a] = m[a];
                        } else {
                            q.lo[a] = m[a];
                        }
                    }
                    parts += volume_in(&sphere, q);
                }
                worst = worst.max((whole - parts).abs() / b.volume());
            }
        }
    }
    println!("sphere quadrature: octant sums agree to {worst:.2e} of the cell");
    assert!(worst < 1e-14, "{worst:e}");
}

#[test]
fn cut_cells_match_midpoint_sums() {
    // Per-cell fractions against a 64³ midpoint sum in each cell (error ≲ 1e-3).
    let shapes = [
        Shape::Sphere {
            center: (0.43, 0.61, 0.52),
            radius: 0.27,
        },
        Shape::Ellipsoid {
            center: (0.43, 0.61, 0.52),
            semi_axes: (0.31, 0.22, 0.4),
        },
        // The caps on planes between sample layers, where the midpoint sum is exact in y.
        Shape::Cylinder {
            axis: Axis::Y,
            center: (0.43, 0.609375, 0.52),
            radius: 0.27,
            length: 0.5,
        },
        Shape::Union(vec![
            Shape::Sphere {
                center: (0.43, 0.61, 0.52),
                radius: 0.27,
            },
            Shape::HalfSpace {
                normal: (0.3, 1.0, -0.4),
                offset: 0.3,
            },
        ]),
    ];
    let g = cube(4);
    for s in &shapes {
        let mut phi = Field::zeros(&g);
        fill_fraction(&g, s, &mut phi);
        let m = 64;
        let cells = (0..4).flat_map(|k| (0..4).flat_map(move |j| (0..4).map(move |i| [i, j, k])));
        for [i, j, k] in cells {
            let mut inside = 0usize;
            for c in 0..m {
                for b in 0..m {
                    for a in 0..m {
                        let p = |x0: f64, n| x0 + (n as f64 + 0.5) * 0.25 / m as f64;
                        if s.contains3(p(g.xf(i), a), p(g.yf(j), b), p(g.zf(k), c)) {
                            inside += 1;
                        }
                    }
                }
            }
            let f = inside as f64 / (m * m * m) as f64;
            assert!(
                (phi[[i, j, k]] - f).abs() < 2e-3,
                "{s:?} [{i}, {j}, {k}]: {} vs {f}",
                phi[[i, j, k]]
            );
        }
    }
}

#[test]
fn shapes_deserialize_and_mixed_dimensions_are_refused() {
    let s: Shape = ron::from_str(
        "Difference(Sphere(center: (0.5, 0.75, 0.5), radius: 0.15), \
         Box(min: (0.475, 0.5, 0.0), max: (0.525, 0.725, 1.0)))",
    )
    .unwrap();
    assert_eq!(s.dims(), 3);
    assert!(s.validate().is_ok());
    let c: Shape =
        ron::from_str("Cylinder(axis: Z, center: (0.5, 0.5, 0.5), radius: 0.1, length: 0.4)")
            .unwrap();
    assert!(c.contains3(0.55, 0.5, 0.69) && !c.contains3(0.55, 0.5, 0.71));
    let mixed = Shape::Union(vec![
        c,
        Shape::Disk {
            center: (0.5, 0.5),
            radius: 0.1,
        },
    ]);
    let (at, m) = mixed.check().unwrap_err();
    assert_eq!(at, "[1]");
    assert!(m.contains("2-D shape combined with a 3-D"), "{m}");
    let bad = Shape::Ellipsoid {
        center: (0.0, 0.0, 0.0),
        semi_axes: (1.0, 0.0, 1.0),
    };
    assert_eq!(bad.check().unwrap_err().0, ".semi_axes");
    assert!(ron::from_str::<Shape>("Sphere(center: (0.5, 0.5), radius: 0.1)").is_err());
}
