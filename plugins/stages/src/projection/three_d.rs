//! The projection on a three-dimensional grid: the seven-point variable-density matrix, the
//! right-hand side with the z-face velocity `w`, and the velocity correction — the planar
//! scheme of the module docs with the third axis.
//!
//! **Matrix.** `Σ_f (A_f/(ρ_f h_a)) (p_C − p_F)` over the six faces, `A_f` the face's area
//! (`h_y h_z`, `h_x h_z`, `h_x h_y`), `ρ_f` the average of the two cells' densities
//! ([`operators::face_density`]); a closed side (wall) has no coupling (homogeneous Neumann), a
//! periodic axis wraps, read from the density's ghost across the wrap, which must be filled.
//! **Right-hand side** `−(∇·V) dV/Δt` ([`operators::div`] with u, v, w). **Correction**
//! `V_a ← V_a − Δt (p_C − p_{C−e_a})/(h_a ρ_f)` on the unknown faces of each axis.
//!
//! The sides along every axis come from the [`BoundarySet`] ([`z_sides`] for z).

use efsi_core::loops::unit;
use efsi_core::{BoundarySet, Field, Grid, Region, Stagger, operators};
use efsi_linalg::par;

/// The z sides of the projection: whether z is periodic, and the first and one-past-last
/// unknown z-face (`0..nz` when periodic, `1..nz` between walls).
pub(crate) fn z_sides(bc: &BoundarySet, nz: usize) -> (bool, isize, isize) {
    let f = bc.normal_faces(2, nz);
    (bc.periodic(2), f.lo, f.hi)
}

/// Whether each axis of a three-dimensional grid wraps.
pub(crate) fn periodic_axes(bc: &BoundarySet, grid: &Grid) -> [bool; 3] {
    [bc.periodic(0), bc.periodic(1), z_sides(bc, grid.nz).0]
}

/// The unknown faces `lo..hi` of each axis.
pub(crate) fn unknown_faces(bc: &BoundarySet, grid: &Grid) -> [(isize, isize); 3] {
    let (x, y) = (bc.normal_faces(0, grid.nx), bc.normal_faces(1, grid.ny));
    let (_, zlo, zhi) = z_sides(bc, grid.nz);
    [(x.lo, x.hi), (y.lo, y.hi), (zlo, zhi)]
}

/// The projection's seven-point matrix on a three-dimensional grid (module docs) into the
/// diagonal and the east, north and top couplings of a matrix (`nx·ny·nz` values each, rows of
/// `nx`), lines of cells in parallel. `rho`'s ghosts across a periodic wrap must be filled.
pub(crate) fn assemble_3d_into(
    [diag, east, north, top]: [&mut [f64]; 4],
    grid: &Grid,
    periodic: [bool; 3],
    rho: &Field,
) {
    let n = [grid.nx, grid.ny, grid.nz];
    let h = grid.h();
    let cells = Region::of(grid, Stagger::Cell);
    let area = |ax: usize| (0..3).filter(|&b| b != ax).map(|b| h[b]).product::<f64>();
    let (nx, ny) = (n[0], n[1]);
    par::rows((&mut *east, &mut *north, &mut *top), nx).for_each(|r, (e, no, t)| {
        let line = cells.line(r);
        let at = [line.start[1] as usize, line.start[2] as usize];
        let rc = rho.at(&line, [0; 3]);
        for (ax, out) in [e, no, t].into_iter().enumerate() {
            let rn = rho.at(&line, unit(ax));
            let c = area(ax) / h[ax];
            for (i, o) in out.iter_mut().enumerate() {
                let last = if ax == 0 {
                    i + 1 == nx
                } else {
                    at[ax - 1] + 1 == n[ax]
                };
                *o = if !last || periodic[ax] {
                    c / operators::face_density(rc[i], rn[i])
                } else {
                    0.0
                };
            }
        }
    });
    let (east, north, top) = (&*east, &*north, &*top);
    let plane = nx * ny;
    par::rows(diag, nx).for_each(|r, row| {
        let (j, c) = (r % ny, r / ny);
        for (i, d) in row.iter_mut().enumerate() {
            let k = r * nx + i;
            let w = if i > 0 {
                east[k - 1]
            } else if periodic[0] {
                east[k + nx - 1]
            } else {
                0.0
            };
            let s = if j > 0 {
                north[k - nx]
            } else if periodic[1] {
                north[k + (ny - 1) * nx]
            } else {
                0.0
            };
            let b = if c > 0 {
                top[k - plane]
            } else if periodic[2] {
                top[k + (n[2] - 1) * plane]
            } else {
                0.0
            };
            *d = east[k] + north[k] + top[k] + w + s + b;
        }
    });
}

/// `b = −(∇·V) dV/Δt` per cell of a three-dimensional grid (rows of `nx`).
pub(crate) fn divergence_rhs_3d(grid: &Grid, vel: [&Field; 3], dt: f64, b: &mut [f64]) {
    let cells = Region::of(grid, Stagger::Cell);
    let scale = -grid.dx * grid.dy * grid.dz / dt;
    par::rows(b, grid.nx).for_each(|r, row| {
        operators::div(grid, &vel, &cells.line(r), row);
        for v in row.iter_mut() {
            *v *= scale;
        }
    });
}

/// `V_a ← V_a − Δt (p_C − p_{C−e_a})/(h_a ρ_f)` on the faces `faces[a]` of each axis
/// (`p`'s and `rho`'s ghosts filled).
pub(crate) fn subtract_gradient_3d(
    grid: &Grid,
    faces: [(isize, isize); 3],
    p: &Field,
    rho: &Field,
    dt: f64,
    vel: [&mut Field; 3],
) {
    let h = grid.h();
    let staggers = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
    for (ax, u) in vel.into_iter().enumerate() {
        let (lo, hi) = faces[ax];
        let c = dt / h[ax];
        let below = [-unit(ax)[0], -unit(ax)[1], -unit(ax)[2]];
        let region = Region::of(grid, staggers[ax]).range(ax, lo.max(0), hi.max(0));
        region.for_each(u, |line, u| {
            let (pc, pb) = (p.at(&line, [0; 3]), p.at(&line, below));
            let (rc, rb) = (rho.at(&line, [0; 3]), rho.at(&line, below));
            for (t, u) in u.iter_mut().enumerate() {
                *u -= c * (pc[t] - pb[t]) / operators::face_density(rc[t], rb[t]);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_linalg::{Multigrid, Pcg, Stencil5};

    /// The projection's seven-point matrix on a three-dimensional grid into `a` (reshaped; module
    /// docs).
    fn assemble_3d(a: &mut Stencil5, grid: &Grid, periodic: [bool; 3], rho: &Field) {
        a.reshape_3d(grid.nx, grid.ny, grid.nz, periodic);
        let Stencil5 {
            diag,
            east,
            north,
            top,
            ..
        } = a;
        assemble_3d_into([diag, east, north, top], grid, periodic, rho);
    }

    /// Copy every stored value of `f` outside the interior along a periodic axis from its
    /// image inside (`i mod n`, axis by axis): the wrap the boundary set fills on planar grids.
    fn wrap(f: &mut Field, n: [usize; 3], periodic: [bool; 3]) {
        for ax in 0..3 {
            if !periodic[ax] {
                continue;
            }
            let len = f.data().len();
            for q in 0..len {
                let mut i = f.index_of(q);
                if i[ax] >= 0 && i[ax] < n[ax] as isize {
                    continue;
                }
                i[ax] = i[ax].rem_euclid(n[ax] as isize);
                let src = f.idx3(i);
                let v = f.data()[src];
                f.data_mut()[q] = v;
            }
        }
    }

    /// Set `f` at every index of `region` to `value(x)` at its position `x` (cell centre or
    /// face centre, from the stagger's offsets).
    fn set(f: &mut Field, grid: &Grid, at: Stagger, value: impl Fn([f64; 3]) -> f64) {
        let h = grid.h();
        let off = match at {
            Stagger::XFace => [0.0, 0.5, 0.5],
            Stagger::YFace => [0.5, 0.0, 0.5],
            Stagger::ZFace => [0.5, 0.5, 0.0],
            _ => [0.5; 3],
        };
        let region = Region::of(grid, at);
        for l in 0..region.lines() {
            let line = region.line(l);
            for i in line.indices() {
                let x = [0, 1, 2].map(|a| (i[a] as f64 + off[a]) * h[a]);
                let q = f.idx3(i);
                f.data_mut()[q] = value(x);
            }
        }
    }

    /// Project a rough velocity on a 3-D grid with a sphere 1000 times denser than the rest:
    /// afterwards `max |∇·V|·Δt` is at the solver's tolerance, from O(1) before.
    #[test]
    fn projects_to_zero_divergence_in_3d() {
        for periodic in [
            [true, false, true],
            [false, false, false],
            [true, true, true],
        ] {
            let n = [12, 10, 8];
            let grid = Grid::new_3d(n, (0.0, 1.2), (0.0, 1.0), (0.0, 0.8));
            let mut rho = Field::zeros(&grid);
            set(&mut rho, &grid, Stagger::Cell, |[x, y, z]| {
                let r2 = (x - 0.6).powi(2) + (y - 0.5).powi(2) + (z - 0.4).powi(2);
                if r2 < 0.09 { 1000.0 } else { 1.0 }
            });
            wrap(&mut rho, n, periodic);
            let (mut u, mut v, mut w) = (
                Field::zeros(&grid),
                Field::zeros(&grid),
                Field::zeros(&grid),
            );
            set(&mut u, &grid, Stagger::XFace, |[x, y, z]| {
                (7.0 * x + 3.0 * y * z).sin()
            });
            set(&mut v, &grid, Stagger::YFace, |[x, y, z]| {
                (5.0 * y - 2.0 * x + z).cos()
            });
            set(&mut w, &grid, Stagger::ZFace, |[x, y, z]| {
                (4.0 * z * x + y).sin()
            });
            // Closed sides: zero normal velocity on the wall faces.
            let faces = n.map(|m| m as isize);
            let staggers = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
            for (ax, f) in [&mut u, &mut v, &mut w].into_iter().enumerate() {
                if periodic[ax] {
                    continue;
                }
                let region = Region::of(&grid, staggers[ax]);
                for l in 0..region.lines() {
                    for i in region.line(l).indices() {
                        if i[ax] == 0 || i[ax] == faces[ax] {
                            let q = f.idx3(i);
                            f.data_mut()[q] = 0.0;
                        }
                    }
                }
            }
            for f in [&mut u, &mut v, &mut w] {
                wrap(f, n, periodic);
            }
            let dt = 0.01;
            let cells = n[0] * n[1] * n[2];
            let max_div =
                |u: &Field, v: &Field, w: &Field| operators::max_abs_div(&grid, &[u, v, w]);
            let before = max_div(&u, &v, &w) * dt;
            let mut a = Stencil5::new(0, 0, false, false);
            assemble_3d(&mut a, &grid, periodic, &rho);
            let mut b = vec![0.0; cells];
            divergence_rhs_3d(&grid, [&u, &v, &w], dt, &mut b);
            // Closed box: the right-hand side on the range (zero sum).
            let mean = b.iter().sum::<f64>() / cells as f64;
            b.iter_mut().for_each(|x| *x -= mean);
            let mut mg = Multigrid::new(2);
            mg.setup(&a);
            let mut x = vec![0.0; cells];
            let maxabs = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let tol = 1e-12 * maxabs(&b);
            let st = Pcg::new(cells).solve(&mut a, &mg, &b, &mut x, tol, 100, maxabs);
            assert!(st.converged && st.iterations <= 15, "{periodic:?}: {st:?}");
            let mut p = Field::zeros(&grid);
            let region = Region::of(&grid, Stagger::Cell);
            for l in 0..region.lines() {
                let line = region.line(l);
                for (t, i) in line.indices().enumerate() {
                    let q = p.idx3(i);
                    p.data_mut()[q] = x[l * n[0] + t];
                }
            }
            wrap(&mut p, n, periodic);
            let faces = [0, 1, 2].map(|ax| {
                if periodic[ax] {
                    (0, faces[ax])
                } else {
                    (1, faces[ax])
                }
            });
            subtract_gradient_3d(&grid, faces, &p, &rho, dt, [&mut u, &mut v, &mut w]);
            for f in [&mut u, &mut v, &mut w] {
                wrap(f, n, periodic);
            }
            let after = max_div(&u, &v, &w) * dt;
            assert!(before > 1e-2, "{periodic:?}: {before}");
            assert!(
                after < 1e-10,
                "{periodic:?}: max|∇·V|Δt {before:e} → {after:e}"
            );
        }
    }
}
