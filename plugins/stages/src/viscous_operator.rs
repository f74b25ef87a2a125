//! The one discretisation of `K_η = vol·∇·(2η D)` on the MAC grid, shared by the viscous stage,
//! the elastic stage's implicit system and the block multigrid preconditioner of both.
//!
//! **Operator.** `D = ½(∇V + ∇Vᵀ)`; normal stresses `2η ∂u/∂x`, `2η ∂v/∂y` at cell centres with
//! the cell coefficient `η`, shear `η_k (∂u/∂y + ∂v/∂x)` at corners with the corner coefficient
//! `η_k`, their divergence on the staggered control volumes, and in axisymmetric geometry
//! (x = r) the hoop term `−2η u_r/r²` on the u-faces; the radius factors come from the grid's
//! metric (zero hoop factor in planar geometry). `η` is an effective viscosity times a time:
//! `θΔt μ` for the viscous step, `θΔt μ + (Δt²/2) G_eff` for the elastic step's preconditioner
//! (see [`crate::elastic`]). The corner coefficient of a viscosity is the harmonic mean of the
//! four cells' ([`corner_viscosity`]).
//!
//! **Coefficients**, assembled once per step ([`Coefficients`]): `a_c = 2η_c r_c Δy/Δx` on
//! cells for the u-equation's normal stress, `b_c = 2η_c r_c Δx/Δy` for the v-equation's, one
//! corner weight `g = r η_k`, and the hoop term `h = η_f r ΔxΔy χ²` (the two cells' sum
//! `η_f`, hoop factor `χ = 1/r`) per unknown u-face. Per u-face `(i, j)`:
//!
//! ```text
//!   (K u)_ij = a_i (u_{i+1} − u_i) − a_{i−1} (u_i − u_{i−1})
//!            + g_{j+1} (α (u_{j+1} − u_j) + (v_{i,j+1} − v_{i−1,j+1}))
//!            − g_j     (α (u_j − u_{j−1}) + (v_{ij} − v_{i−1,j}))     − h u_ij,     α = Δx/Δy,
//! ```
//!
//! and per v-face the transposed pattern with `b` and `β = Δy/Δx`. The coefficient of `v` in a
//! u-row is that of `u` in the v-row: `−K` is symmetric (positive semi-definite, the gradient of
//! the dissipation `Σ 2η D:D dV`) by construction with walls, periodic sides and the axis; the
//! zero-gradient ghosts of an `Outflow` side make the rows of the faces beside it non-symmetric
//! (a test checks both statements on a dense copy of the matrix).
//!
//! **Products.** [`Coefficients::apply`] computes `y = d∘x − K(u, v)` on the compact unknown
//! faces in one vectorised pass per component, rows in parallel, and returns `x·y` summed by rows
//! in order: bit-identical on any number of threads. [`Coefficients::diagonal`] gives the
//! matrix's diagonal, [`Coefficients::blocks`] its u–u and v–v blocks as five-point stencils for
//! the block multigrid ([`crate::block_multigrid`]).

use crate::faces::UnknownFaces;
use efsi_core::{Field, Grid, Line, Region, Stagger, unit};
use efsi_linalg::Stencil5;
use efsi_linalg::par;

/// The coefficients of `K_η` (see the module docs) for one grid and its unknown faces.
pub(crate) struct Coefficients {
    faces: UnknownFaces,
    /// `Δx/Δy`, `Δy/Δx`.
    alpha: f64,
    beta: f64,
    nx: usize,
    /// Normal-stress coefficients of the u- and v-equations at cells.
    cxx: Field,
    cyy: Field,
    /// Corner weights `r η_k`.
    gc: Field,
    /// The hoop term of each unknown face (zero on v-faces and in planar geometry).
    hoop: Vec<f64>,
}

impl Coefficients {
    /// Zero coefficients (`K = 0`) for `grid` and its unknown `faces`.
    pub(crate) fn new(grid: &Grid, faces: UnknownFaces) -> Self {
        Coefficients {
            hoop: vec![0.0; faces.len()],
            faces,
            alpha: grid.dx / grid.dy,
            beta: grid.dy / grid.dx,
            nx: grid.nx,
            cxx: Field::zeros(grid),
            cyy: Field::zeros(grid),
            gc: Field::zeros(grid),
        }
    }

    /// The hoop term per unknown face (compact; zero on v-faces).
    pub(crate) fn hoop(&self) -> &[f64] {
        &self.hoop
    }

    /// The coefficients of `scale·K_μ` for the cell viscosities `mu` (ghosts filled); the
    /// corner viscosities ([`corner_viscosity`]) are written to `corner`. Rows in parallel.
    pub(crate) fn set_viscosity(&mut self, g: &Grid, mu: &Field, scale: f64, corner: &mut Field) {
        corner_viscosity(g, mu, corner);
        self.set(g, mu, corner, scale);
    }

    /// [`set_viscosity`](Self::set_viscosity) without keeping the corner viscosities: each
    /// corner's harmonic mean goes straight into its weight (the same values, bit for bit, and
    /// no corner array). Rows in parallel.
    pub(crate) fn set_viscosity_weights(&mut self, g: &Grid, mu: &Field, scale: f64) {
        self.set_cells(g, mu, scale);
        let m = &g.metric;
        Region::of(g, Stagger::Corner).for_each(&mut self.gc, |l, gr| {
            let (sw, se) = (mu.at(&l, [-1, -1, 0]), mu.at(&l, [0, -1, 0]));
            let (nw, ne) = (mu.at(&l, [-1, 0, 0]), mu.at(&l, [0; 3]));
            let rx = m.rx_on(&l, 0);
            for n in 0..l.len {
                let mk = corner_mean([sw[n], se[n], nw[n], ne[n]]);
                gr[n] = scale * rx[n] * mk;
            }
        });
        self.set_hoop(g, mu, scale);
    }

    /// The coefficients of `scale·K_η` for the cell coefficients `eta` (ghosts filled) and the
    /// corner coefficients `eta_k`. Rows in parallel.
    pub(crate) fn set(&mut self, g: &Grid, eta: &Field, eta_k: &Field, scale: f64) {
        self.set_cells(g, eta, scale);
        let m = &g.metric;
        Region::of(g, Stagger::Corner).for_each(&mut self.gc, |l, gr| {
            let (ek, rx) = (eta_k.at(&l, [0; 3]), m.rx_on(&l, 0));
            for n in 0..l.len {
                gr[n] = scale * rx[n] * ek[n];
            }
        });
        self.set_hoop(g, eta, scale);
    }

    /// The normal-stress coefficients `cxx`, `cyy` of `scale·K_η` from the cell coefficients.
    fn set_cells(&mut self, g: &Grid, eta: &Field, scale: f64) {
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let (ax, ay) = (scale * 2.0 * dy / dx, scale * 2.0 * dx / dy);
        Region::whole(g).for_each((&mut self.cxx, &mut self.cyy), |l, (cx, cy)| {
            let (e, rc) = (eta.at(&l, [0; 3]), m.rc_on(&l, 0));
            for (((cx, cy), e), r) in cx.iter_mut().zip(cy.iter_mut()).zip(e).zip(rc) {
                *cx = ax * r * e;
                *cy = ay * r * e;
            }
        });
    }

    /// The hoop term of `scale·K_η` on each unknown u-face, from the cell coefficients.
    fn set_hoop(&mut self, g: &Grid, eta: &Field, scale: f64) {
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let faces = self.faces.u_region();
        let hoop = &mut self.hoop[..faces.size()];
        if !faces.is_empty() {
            par::rows(&mut *hoop, faces.len(0)).for_each(|n, hs| {
                let l = faces.line(n);
                let (ew, ec) = (eta.at(&l, [-1, 0, 0]), eta.at(&l, [0; 3]));
                let (rx, hx) = (m.rx_on(&l, 0), m.hoop_x_on(&l, 0));
                for (c, h) in hs.iter_mut().enumerate() {
                    let x = hx[c];
                    *h = scale * dx * dy * rx[c] * (ew[c] + ec[c]) * x * x;
                }
            });
        }
    }

    /// `dm` plus the sum of every coupling of each row into `diag`, where `dm` holds the mass
    /// plus the hoop term ([`hoop`](Self::hoop)) of each unknown face: the diagonal of
    /// `diag(dm) − K` away from the boundaries; beside a wall the wall's coupling counts once
    /// whatever its ghost rule (a reflected no-slip ghost doubles it in the matrix), which keeps
    /// the blocks diagonally dominant. Jacobi and the block multigrid use it. Rows in parallel.
    pub(crate) fn diagonal(&self, dm: &[f64], diag: &mut [f64]) {
        let (uf, vf) = (self.faces.u_region(), self.faces.v_region());
        let (cxx, cyy, gc) = (&self.cxx, &self.cyy, &self.gc);
        let (alpha, beta) = (self.alpha, self.beta);
        let (dm_u, dm_v) = dm.split_at(uf.size());
        let (dg_u, dg_v) = diag.split_at_mut(uf.size());
        if !uf.is_empty() {
            par::rows((&mut *dg_u, dm_u), uf.len(0)).for_each(|n, (dgs, dm)| {
                let l = uf.line(n);
                let (cw, ce) = (cxx.at(&l, [-1, 0, 0]), cxx.at(&l, [0; 3]));
                let (gs, gn) = (gc.at(&l, [0; 3]), gc.at(&l, unit(1)));
                for c in 0..l.len {
                    dgs[c] = dm[c] + (ce[c] + cw[c]) + alpha * (gn[c] + gs[c]);
                }
            });
        }
        if !vf.is_empty() {
            par::rows((&mut *dg_v, dm_v), vf.len(0)).for_each(|n, (dgs, dm)| {
                let l = vf.line(n);
                let (cs, cn) = (cyy.at(&l, [0, -1, 0]), cyy.at(&l, [0; 3]));
                let (gw, ge) = (gc.at(&l, [0; 3]), gc.at(&l, unit(0)));
                for c in 0..l.len {
                    dgs[c] = dm[c] + (cn[c] + cs[c]) + beta * (ge[c] + gw[c]);
                }
            });
        }
    }

    /// The u–u and v–v blocks of `diag(d) − K` — `d` the full diagonal ([`diagonal`](Self::diagonal))
    /// — as five-point stencils (couplings `≥ 0`, zero across a closed boundary).
    pub(crate) fn blocks(&self, diag: &[f64], au: &mut Stencil5, av: &mut Stencil5) {
        let (uf, vf) = (self.faces.u_region(), self.faces.v_region());
        let (px, py) = (au.periodic_x, au.periodic_y);
        let (nur, ny) = (au.nx, au.ny);
        for j in 0..uf.lines() {
            let l = uf.line(j);
            let (ce, gn) = (self.cxx.at(&l, [0; 3]), self.gc.at(&l, unit(1)));
            for c in 0..nur {
                let kc = j * nur + c;
                au.east[kc] = if c + 1 < nur || px { ce[c] } else { 0.0 };
                au.north[kc] = if j + 1 < ny || py {
                    self.alpha * gn[c]
                } else {
                    0.0
                };
                au.diag[kc] = diag[kc];
            }
        }
        let nu = nur * ny;
        let (nx, nvr) = (self.nx, av.ny);
        for jr in 0..vf.lines() {
            let l = vf.line(jr);
            let (cn, ge) = (self.cyy.at(&l, [0; 3]), self.gc.at(&l, unit(0)));
            for i in 0..nx {
                let kc = jr * nx + i;
                av.east[kc] = if i + 1 < nx || px {
                    self.beta * ge[i]
                } else {
                    0.0
                };
                av.north[kc] = if jr + 1 < nvr || py { cn[i] } else { 0.0 };
                av.diag[kc] = diag[nu + kc];
            }
        }
    }

    /// `y = d∘x − K(u, v)` on the unknown faces, with `u`, `v` the fields (ghosts filled) and `x`
    /// their compact vector of unknowns, or the fields' own values when `None` (rows in
    /// parallel; each row writes its own entries). Returns `x·y`, summed by rows in order (the
    /// same on any number of threads).
    pub(crate) fn apply(
        &self,
        u: &Field,
        v: &Field,
        d: &[f64],
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        let nu = self.faces.nu();
        let (yu, yv) = y.split_at_mut(nu);
        let (du, dv) = d.split_at(nu);
        let (xu, xv) = match x {
            Some(x) => {
                let (a, b) = x.split_at(nu);
                (Some(a), Some(b))
            }
            None => (None, None),
        };
        let (uf, vf) = (self.faces.u_region(), self.faces.v_region());
        let mut xy = 0.0;
        if !uf.is_empty() {
            let n = uf.len(0);
            xy = par::rows(&mut *yu, n).fold(
                0.0,
                |j, y| {
                    let x = xu.map(|x| &x[j * n..(j + 1) * n]);
                    self.u_line(&uf.line(j), u, v, &du[j * n..], x, y)
                },
                |s, p| s + p,
            );
        }
        let mut xy_v = 0.0;
        if !vf.is_empty() {
            let n = vf.len(0);
            xy_v = par::rows(&mut *yv, n).fold(
                0.0,
                |j, y| {
                    let x = xv.map(|x| &x[j * n..(j + 1) * n]);
                    self.v_line(&vf.line(j), u, v, &dv[j * n..], x, y)
                },
                |s, p| s + p,
            );
        }
        xy + xy_v
    }

    /// [`apply`](Self::apply) on one line of unknown u-faces: `y = d∘x − K(u, v)` there
    /// (`x` the line's unknowns, or `u` itself), returning `x·y`.
    #[inline(always)]
    fn u_line(
        &self,
        l: &Line,
        u: &Field,
        v: &Field,
        d: &[f64],
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        let n = y.len();
        let alpha = self.alpha;
        let (uc, ue, uw) = (
            &u.at(l, [0; 3])[..n],
            &u.at(l, unit(0))[..n],
            &u.at(l, [-1, 0, 0])[..n],
        );
        let (un, us) = (&u.at(l, unit(1))[..n], &u.at(l, [0, -1, 0])[..n]);
        let (vc, vw) = (&v.at(l, [0; 3])[..n], &v.at(l, [-1, 0, 0])[..n]);
        let (vn, vnw) = (&v.at(l, unit(1))[..n], &v.at(l, [-1, 1, 0])[..n]);
        let (ac, aw) = (
            &self.cxx.at(l, [0; 3])[..n],
            &self.cxx.at(l, [-1, 0, 0])[..n],
        );
        let (gs, gn) = (&self.gc.at(l, [0; 3])[..n], &self.gc.at(l, unit(1))[..n]);
        let dr = &d[..n];
        let xr = &x.unwrap_or(uc)[..n];
        for c in 0..n {
            let f_s = gs[c] * (alpha * (uc[c] - us[c]) + (vc[c] - vw[c]));
            let f_n = gn[c] * (alpha * (un[c] - uc[c]) + (vn[c] - vnw[c]));
            let k = ac[c] * (ue[c] - uc[c]) - aw[c] * (uc[c] - uw[c]) + (f_n - f_s);
            y[c] = dr[c] * xr[c] - k;
        }
        let y = &*y;
        par::sum4(n, |c| xr[c] * y[c])
    }

    /// [`apply`](Self::apply) on one line of unknown v-faces.
    #[inline(always)]
    fn v_line(
        &self,
        l: &Line,
        u: &Field,
        v: &Field,
        d: &[f64],
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        let n = y.len();
        let beta = self.beta;
        let (vc, ve, vw) = (
            &v.at(l, [0; 3])[..n],
            &v.at(l, unit(0))[..n],
            &v.at(l, [-1, 0, 0])[..n],
        );
        let (vn, vs) = (&v.at(l, unit(1))[..n], &v.at(l, [0, -1, 0])[..n]);
        let (uc, us) = (&u.at(l, [0; 3])[..n], &u.at(l, [0, -1, 0])[..n]);
        let (ue, use_) = (&u.at(l, unit(0))[..n], &u.at(l, [1, -1, 0])[..n]);
        let (bc, bs) = (
            &self.cyy.at(l, [0; 3])[..n],
            &self.cyy.at(l, [0, -1, 0])[..n],
        );
        let (gw, ge) = (&self.gc.at(l, [0; 3])[..n], &self.gc.at(l, unit(0))[..n]);
        let dr = &d[..n];
        let xr = &x.unwrap_or(vc)[..n];
        for c in 0..n {
            let f_w = gw[c] * ((uc[c] - us[c]) + beta * (vc[c] - vw[c]));
            let f_e = ge[c] * ((ue[c] - use_[c]) + beta * (ve[c] - vc[c]));
            let k = bc[c] * (vn[c] - vc[c]) - bs[c] * (vc[c] - vs[c]) + (f_e - f_w);
            y[c] = dr[c] * xr[c] - k;
        }
        let y = &*y;
        par::sum4(n, |c| xr[c] * y[c])
    }
}

/// Corner viscosities: the harmonic mean of the four cells around each corner (zero if any is
/// inviscid), corner rows in parallel. The corner carries the shear stress
/// `μ (∂u/∂y + ∂v/∂x)`; across an interface the two phases shear in series, whose effective
/// viscosity is the harmonic mean — the arithmetic mean would let the more viscous phase drag
/// the other along (an O(1) error in the first cell beside an interface, first order overall).
pub(crate) fn corner_viscosity(grid: &Grid, mu: &Field, out: &mut Field) {
    Region::of(grid, Stagger::Corner).for_each(out, |l, o| {
        let (sw, se) = (mu.at(&l, [-1, -1, 0]), mu.at(&l, [0, -1, 0]));
        let (nw, ne) = (mu.at(&l, [-1, 0, 0]), mu.at(&l, [0; 3]));
        for n in 0..l.len {
            o[n] = corner_mean([sw[n], se[n], nw[n], ne[n]]);
        }
    });
}

/// The harmonic mean of the four cell viscosities around a corner, zero if any is inviscid
/// ([`corner_viscosity`]).
#[inline(always)]
fn corner_mean(q: [f64; 4]) -> f64 {
    if q.iter().all(|&x| x > 0.0) {
        4.0 / q.iter().map(|x| 1.0 / x).sum::<f64>()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::BoundarySet;
    use efsi_core::grid::Geometry;
    use efsi_core::scene::{Boundaries, Boundary};

    /// A 7 × 5 grid in `geometry` and its boundaries (x_min, x_max, y_min, y_max).
    fn setup(geometry: Geometry, sides: [Boundary; 4]) -> (Grid, BoundarySet) {
        let grid = Grid::new(geometry, 7, 5, (0.0, 1.0), (0.0, 0.6));
        let [x_min, x_max, y_min, y_max] = sides;
        let b = Boundaries::planar(x_min, x_max, y_min, y_max);
        let bc = BoundarySet::new(&b, &grid);
        (grid, bc)
    }

    /// A viscosity field varying over three decades, ghosts included.
    fn viscosity(grid: &Grid) -> Field {
        let mut mu = Field::zeros(grid);
        let n = mu.data().len();
        for (k, m) in mu.data_mut().iter_mut().enumerate() {
            *m = 10f64.powf(3.0 * ((k * 7919) % n) as f64 / n as f64 - 1.5);
        }
        mu
    }

    /// The dense matrix of `diag(dm) − K` on the compact unknowns, column by column.
    fn matrix(grid: &Grid, bc: &BoundarySet, k: &Coefficients, dm: &[f64]) -> Vec<Vec<f64>> {
        let faces = UnknownFaces::new(grid, bc);
        let n = faces.len();
        let (mut u, mut v) = (Field::zeros(grid), Field::zeros(grid));
        let mut cols = Vec::new();
        for c in 0..n {
            let mut x = vec![0.0; n];
            x[c] = 1.0;
            u.fill(0.0);
            v.fill(0.0);
            faces.scatter(&x, &mut u, &mut v);
            bc.fill_velocity(grid, &mut u, &mut v, 0.0, true);
            let mut y = vec![0.0; n];
            let xy = k.apply(&u, &v, dm, Some(&x), &mut y);
            assert_eq!(xy, y[c]);
            cols.push(y);
        }
        cols
    }

    fn check(geometry: Geometry, sides: [Boundary; 4]) {
        let label = format!("{geometry:?} {sides:?}");
        let (grid, bc) = setup(geometry, sides);
        let faces = UnknownFaces::new(&grid, &bc);
        let n = faces.len();
        let mut mu = viscosity(&grid);
        bc.fill_scalar(&grid, &mut mu, false);
        let mut k = Coefficients::new(&grid, faces);
        let mut corner = Field::zeros(&grid);
        k.set_viscosity(&grid, &mu, 0.3, &mut corner);
        let dm: Vec<f64> = k.hoop().iter().map(|h| 1.0 + h).collect();
        let a = matrix(&grid, &bc, &k, &dm);
        let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        // Beside an outflow side (x_max here) the zero-gradient ghosts make the rows of its
        // last column of faces non-symmetric; everywhere else the matrix is symmetric.
        let nur = (faces.ux.hi - faces.ux.lo) as usize;
        let outflow = matches!(bc.get(efsi_core::scene::Side::XMax), Boundary::Outflow);
        let last_column = |c: usize| {
            outflow
                && if c < faces.nu() {
                    c % nur == nur - 1
                } else {
                    (c - faces.nu()) % grid.nx == grid.nx - 1
                }
        };
        for i in (0..n).filter(|&i| !last_column(i)) {
            for j in (0..n).filter(|&j| !last_column(j)) {
                assert!(
                    (a[i][j] - a[j][i]).abs() <= 1e-13 * scale,
                    "{label}: A[{i}][{j}] = {} but A[{j}][{i}] = {}",
                    a[i][j],
                    a[j][i]
                );
            }
        }
        let diag = check_diagonal(&label, &grid, &faces, &k, &dm, &a, scale);
        check_blocks(&grid, &bc, &faces, &k, &diag, &a, scale);
        check_definite(&a);
    }

    /// The diagonal is the matrix's own away from the boundaries (and never below it); returns
    /// it.
    fn check_diagonal(
        label: &str,
        grid: &Grid,
        faces: &UnknownFaces,
        k: &Coefficients,
        dm: &[f64],
        a: &[Vec<f64>],
        scale: f64,
    ) -> Vec<f64> {
        let n = faces.len();
        let nur = (faces.ux.hi - faces.ux.lo) as usize;
        let nvr = (faces.vy.hi - faces.vy.lo) as usize;
        let mut diag = vec![0.0; n];
        k.diagonal(dm, &mut diag);
        let inner = |a: usize, n: usize| a >= 1 && a + 2 <= n;
        let mut checked = 0;
        for c in 0..n {
            let interior = if c < faces.nu() {
                inner(c % nur, nur) && inner(c / nur, grid.ny)
            } else {
                let q = c - faces.nu();
                inner(q % grid.nx, grid.nx) && inner(q / grid.nx, nvr)
            };
            if interior {
                assert!(
                    (diag[c] - a[c][c]).abs() <= 1e-13 * scale,
                    "{label}: diagonal {c}"
                );
                checked += 1;
            }
            assert!(diag[c] >= a[c][c] - 1e-13 * scale || c >= faces.nu() || !interior);
        }
        assert!(checked >= 10, "{label}: {checked} interior rows");
        diag
    }

    /// The blocks' couplings are the matrix's entries.
    fn check_blocks(
        grid: &Grid,
        bc: &BoundarySet,
        faces: &UnknownFaces,
        k: &Coefficients,
        diag: &[f64],
        a: &[Vec<f64>],
        scale: f64,
    ) {
        let nur = (faces.ux.hi - faces.ux.lo) as usize;
        let nvr = (faces.vy.hi - faces.vy.lo) as usize;
        let mut au = Stencil5::new(nur, grid.ny, bc.periodic(0), bc.periodic(1));
        let mut av = Stencil5::new(grid.nx, nvr, bc.periodic(0), bc.periodic(1));
        k.blocks(diag, &mut au, &mut av);
        let nu = faces.nu();
        let wrap = |c: usize, n: usize| if c + 1 < n { c + 1 } else { 0 };
        for j in 0..grid.ny {
            for c in 0..nur {
                let q = j * nur + c;
                if au.east[q] != 0.0 {
                    let e = j * nur + wrap(c, nur);
                    assert!((au.east[q] + a[q][e]).abs() <= 1e-13 * scale, "u east {q}");
                }
                if au.north[q] != 0.0 {
                    let nq = wrap(j, grid.ny) * nur + c;
                    assert!(
                        (au.north[q] + a[q][nq]).abs() <= 1e-13 * scale,
                        "u north {q}"
                    );
                }
            }
        }
        for jr in 0..nvr {
            for i in 0..grid.nx {
                let q = nu + jr * grid.nx + i;
                if av.east[q - nu] != 0.0 {
                    let e = nu + jr * grid.nx + wrap(i, grid.nx);
                    assert!(
                        (av.east[q - nu] + a[q][e]).abs() <= 1e-13 * scale,
                        "v east {q}"
                    );
                }
                if av.north[q - nu] != 0.0 {
                    let nq = nu + wrap(jr, nvr) * grid.nx + i;
                    assert!(
                        (av.north[q - nu] + a[q][nq]).abs() <= 1e-13 * scale,
                        "v north {q}"
                    );
                }
            }
        }
    }

    /// Positive definite with a positive mass: `xᵀAx > 0` for a few vectors.
    fn check_definite(a: &[Vec<f64>]) {
        let n = a.len();
        for seed in 1..5u64 {
            let x: Vec<f64> = (0..n)
                .map(|c| ((c as u64 * 2654435761 + seed * 97) % 1000) as f64 / 500.0 - 1.0)
                .collect();
            let q: f64 = (0..n)
                .map(|i| x[i] * (0..n).map(|j| a[j][i] * x[j]).sum::<f64>())
                .sum();
            assert!(q > 0.0);
        }
    }

    #[test]
    fn the_matrix_is_symmetric_and_its_diagonal_and_blocks_are_its_own() {
        use Boundary::*;
        check(Geometry::Planar, [NoSlip, NoSlip, NoSlip, NoSlip]);
        check(Geometry::Planar, [Periodic, Periodic, NoSlip, FreeSlip]);
        check(Geometry::Planar, [NoSlip, Outflow, Periodic, Periodic]);
        check(Geometry::Axisymmetric, [Axis, NoSlip, NoSlip, FreeSlip]);
    }
}
