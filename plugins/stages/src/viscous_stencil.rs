//! The implicit viscous operator `θΔt K_v` with its coefficients precomputed, for a Krylov
//! solver that applies it many times per step (the elastic stage's BiCGSTAB).
//!
//! `K_v = vol·∇·(2μD)` is the viscous stage's operator ([`crate::viscous`]; normal stresses with
//! the cell viscosity, shear with the corner viscosity, the hoop term), written as differences
//! of neighbouring velocities times coefficients that hold the viscosity, the metric factors,
//! the grid spacings and `θΔt`: the same sums in another order (equal to round-off), without the
//! six divisions per face of the direct form, which made it 3–4× slower. Per u-face `(i, j)`:
//!
//! ```text
//!   a_x[i](u_{i+1} − u_i) − a_x[i−1](u_i − u_{i−1})                       a_x = θΔt dy r_c 2μ/dx
//!   + c_y[j+1](u_{j+1} − u_j) + c[j+1](v_{i,j+1} − v_{i−1,j+1})           c_y = θΔt dx r_x μ_k/dy
//!   − c_y[j](u_j − u_{j−1}) − c[j](v_{i,j} − v_{i−1,j}) − h u_{ij}        c = θΔt r_x μ_k
//! ```
//!
//! (corners indexed by their column and row, `h = θΔt dx dy r_x (μ_{i−1} + μ_i) χ²` with the
//! grid's hoop factor `χ`, `1/r` axisymmetric and 0 planar), and per
//! v-face the transposed pattern with `a_y = θΔt dx r_c 2μ/dy` and `c_x = θΔt dy r_x μ_k/dx`.
//! The apply runs over rows in parallel, each row writing its own entries: bit-identical on any
//! number of threads.

use efsi_core::{Field, Grid, bc::UnknownFaces};
use efsi_linalg::par;

/// `θΔt K_v` on the compact unknown faces, coefficients set once per step.
pub(crate) struct ViscousStencil {
    faces: UnknownFaces,
    nx: usize,
    ax: Field,
    ay: Field,
    c: Field,
    cx: Field,
    cy: Field,
    h: Field,
}

impl ViscousStencil {
    /// Zero coefficients for `grid` and its unknown `faces`.
    pub(crate) fn new(grid: &Grid, faces: UnknownFaces) -> Self {
        ViscousStencil {
            faces,
            nx: grid.nx,
            ax: Field::zeros(grid),
            ay: Field::zeros(grid),
            c: Field::zeros(grid),
            cx: Field::zeros(grid),
            cy: Field::zeros(grid),
            h: Field::zeros(grid),
        }
    }

    /// The coefficients of `td·K_v` for the cell viscosities `mu` (ghosts filled) and the corner
    /// viscosities `mc`.
    pub(crate) fn setup(&mut self, g: &Grid, td: f64, mu: &Field, mc: &Field) {
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let (nx, ny) = (g.nx as isize, g.ny as isize);
        for j in -1..=ny {
            for i in -1..=nx {
                let k = mu.idx(i, j);
                let v = mu.data()[k];
                self.ax.data_mut()[k] = td * dy * m.rc(i) * 2.0 * v / dx;
                self.ay.data_mut()[k] = td * dx * m.rc(i) * 2.0 * v / dy;
            }
        }
        for j in 0..=ny {
            for i in 0..=nx {
                let k = mc.idx(i, j);
                let v = mc.data()[k];
                self.c.data_mut()[k] = td * m.rx(i) * v;
                self.cx.data_mut()[k] = td * dy * m.rx(i) * v / dx;
                self.cy.data_mut()[k] = td * dx * m.rx(i) * v / dy;
            }
        }
        for j in 0..ny {
            for i in self.faces.ux.lo..self.faces.ux.hi {
                let k = mu.idx(i, j);
                let hp = m.hoop_x(i);
                self.h.data_mut()[k] =
                    td * dx * dy * m.rx(i) * (mu.data()[k - 1] + mu.data()[k]) * hp * hp;
            }
        }
    }

    /// `y = mass·x − θΔt K_v (u, v)` on the compact unknown faces, where `(u, v)` holds `x` on
    /// the unknown faces and the homogeneous boundary values in the ghosts; rows in parallel.
    pub(crate) fn apply(&self, mass: &[f64], x: &[f64], u: &Field, v: &Field, y: &mut [f64]) {
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let nur = (ux.hi - ux.lo).max(0) as usize;
        let nx = self.nx;
        let nu = self.faces.nu();
        let s = u.stride();
        let (ud, vd) = (u.data(), v.data());
        let (ax, ay, c, cx, cy, h) = (
            self.ax.data(),
            self.ay.data(),
            self.c.data(),
            self.cx.data(),
            self.cy.data(),
            self.h.data(),
        );
        let (yu, yv) = y.split_at_mut(nu);
        par::for_each_row(yu, nur, |j, row| {
            let k0 = u.idx(ux.lo, j as isize);
            for (o, y) in row.iter_mut().enumerate() {
                let k = k0 + o;
                let kn = k + s;
                let ku = ax[k] * (ud[k + 1] - ud[k]) - ax[k - 1] * (ud[k] - ud[k - 1])
                    + cy[kn] * (ud[kn] - ud[k])
                    + c[kn] * (vd[kn] - vd[kn - 1])
                    - cy[k] * (ud[k] - ud[k - s])
                    - c[k] * (vd[k] - vd[k - 1])
                    - h[k] * ud[k];
                let q = j * nur + o;
                *y = mass[q] * x[q] - ku;
            }
        });
        par::for_each_row(yv, nx, |jr, row| {
            let k0 = v.idx(0, vy.lo + jr as isize);
            for (i, y) in row.iter_mut().enumerate() {
                let k = k0 + i;
                let ke = k + 1;
                let kv = ay[k] * (vd[k + s] - vd[k]) - ay[k - s] * (vd[k] - vd[k - s])
                    + c[ke] * (ud[ke] - ud[ke - s])
                    + cx[ke] * (vd[ke] - vd[k])
                    - c[k] * (ud[k] - ud[k - s])
                    - cx[k] * (vd[k] - vd[k - 1]);
                let q = nu + jr * nx + i;
                *y = mass[q] * x[q] - kv;
            }
        });
    }
}
