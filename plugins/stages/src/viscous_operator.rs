//! The one discretisation of `K_η = vol·∇·(2η D)` on the MAC grid, shared by the viscous stage,
//! the elastic stage's implicit system and the block multigrid preconditioner of both, written
//! once for two and three dimensions.
//!
//! **Operator.** `D = ½(∇V + ∇Vᵀ)`. With `e_a` the unit shift and `h_a` the cell size along
//! axis `a`, `V` the cell volume and `u_a` the velocity on the `a`-faces:
//!
//! - the normal stresses `2η ∂u_a/∂x_a` at cell centres with the cell coefficient `η`;
//! - the shear stress of each pair of axes `a < b`, `η_e (∂u_a/∂x_b + ∂u_b/∂x_a)`, on the
//!   edges along the remaining axis ([`SHEAR`]: xy on the corners of a two-dimensional grid,
//!   which are the edges along z of a three-dimensional one, yz on the edges along x, xz on
//!   those along y), with the edge coefficient `η_e`;
//! - their divergence on each component's staggered control volume, and in axisymmetric
//!   geometry (x = r) the hoop term `−2η u_r/r²` on the u-faces; the radius factors come from
//!   the grid's metric (all ones and no hoop term in planar and Cartesian geometry).
//!
//! `η` is an effective viscosity times a time: `θΔt μ` for the viscous step,
//! `θΔt μ + (Δt²/2) G_eff` for the elastic step's preconditioner (see [`crate::elastic`]). The
//! edge coefficient of a viscosity is the harmonic mean of the four cells around the edge
//! ([`edge_viscosity`]).
//!
//! **Coefficients**, assembled once per step ([`Coefficients`]): for each axis `a` the
//! normal-stress coefficient `c_a = 2η r V/h_a²` at cells (formed where it is read, as
//! `(s_a r) η` from one copy of the cell field and the factor `s_a`, `2V/h_a²` times the
//! field's scale, so one cell array serves every axis), for each pair one edge weight `g = r η_e V/(h_a h_b)` (an array per pair), and
//! the hoop term `h = η_f r V χ²` (the two cells' sum `η_f`, hoop factor `χ = 1/r`) per unknown
//! u-face (`r` the radius factor of the location; in two dimensions `V = h_x h_y`, per unit
//! depth). Per unknown `a`-face `I`:
//!
//! ```text
//!   (K u)_a[I] = c_a[I] (u_a[I+e_a] − u_a[I]) − c_a[I−e_a] (u_a[I] − u_a[I−e_a])
//!      + Σ_{b≠a} ( g_ab[I+e_b] (ρ_ab (u_a[I+e_b] − u_a[I]) + (u_b[I+e_b] − u_b[I+e_b−e_a]))
//!                − g_ab[I]     (ρ_ab (u_a[I] − u_a[I−e_b]) + (u_b[I] − u_b[I−e_a])) )
//!      − h[I] u_a[I],                                               ρ_ab = h_a/h_b,
//! ```
//!
//! the edge `I` of a pair being the one at the low faces of cell `I` along both its axes. The
//! coefficient of `u_b` in an `a`-row is that of `u_a` in the `b`-row: `−K` is symmetric
//! (positive semi-definite, the gradient of the dissipation `Σ 2η D:D dV`) by construction with
//! walls, periodic sides and the axis; the zero-gradient ghosts of an `Outflow` side make the
//! rows of the faces beside it non-symmetric (the tests check both statements on a dense copy
//! of the matrix, in two and three dimensions).
//!
//! **Products.** [`Coefficients::product`] computes `y = d∘x − K(V)` on the compact unknown
//! faces in one vectorised pass per component, lines in parallel, and returns `x·y` summed by
//! lines in order: bit-identical on any number of threads. [`Coefficients::diagonal`] gives the
//! matrix's diagonal; [`Coefficients::blocks`] its diagonal blocks (u–u, v–v, w–w) as five-
//! or seven-point stencils for the block multigrid ([`crate::block_multigrid`]).

use crate::faces::UnknownFaces;
use efsi_core::grid::Metric;
use efsi_core::operators::minus;
use efsi_core::{Field, Grid, Index, Line, Region, Stagger, unit};
use efsi_linalg::Stencil5;
use efsi_linalg::par;
use std::borrow::{Borrow, BorrowMut};

/// The shear stresses: each pair of axes `[a, b]` (`a < b`) and the edges its stress lives
/// on. A two-dimensional grid has the first only.
pub(crate) const SHEAR: [([usize; 2], Stagger); 3] = [
    ([0, 1], Stagger::Corner),
    ([1, 2], Stagger::XEdge),
    ([0, 2], Stagger::YEdge),
];

/// The shear pairs of a grid of `dims` axes.
pub(crate) fn shear_pairs(dims: usize) -> &'static [([usize; 2], Stagger)] {
    &SHEAR[..if dims == 3 { 3 } else { 1 }]
}

/// The index in [`SHEAR`] of the pair of axes `a ≠ b`.
fn pair(a: usize, b: usize) -> usize {
    match (a.min(b), a.max(b)) {
        (0, 1) => 0,
        (1, 2) => 1,
        (0, 2) => 2,
        _ => panic!("no shear pair of axes {a} and {b}"),
    }
}

/// `p + q`.
#[inline(always)]
fn add(p: Index, q: Index) -> Index {
    [p[0] + q[0], p[1] + q[1], p[2] + q[2]]
}

/// A coefficient on the cells, or on the edges of one shear pair: a field of the grid, or — in
/// a [compact](Coefficients::compact) operator, while it holds one value everywhere — that
/// value as one line, which every line of the grid reads (the same values, no array of the
/// grid's size). The field is made the first time the values differ, and kept.
struct Coef {
    field: Option<Field>,
    /// The one value, as many times as the longest line of the grid (empty: never uniform).
    line: Vec<f64>,
    uniform: bool,
}

impl Coef {
    /// A field of `grid`, zero.
    fn field(grid: &Grid) -> Self {
        Coef {
            field: Some(Field::zeros(grid)),
            line: Vec::new(),
            uniform: false,
        }
    }

    /// Zero everywhere, as one line: a field only once the values differ.
    fn compact(grid: &Grid) -> Self {
        Coef {
            field: None,
            line: vec![0.0; longest_line(grid)],
            uniform: true,
        }
    }

    /// The values at `I + shift` for the indices `I` of `l` ([`Field::at`]).
    #[inline(always)]
    fn at(&self, l: &Line, shift: Index) -> &[f64] {
        match &self.field {
            Some(f) if !self.uniform => f.at(l, shift),
            _ => &self.line[..l.len],
        }
    }

    /// The field, to write every value of (made now if it was uniform so far).
    fn field_mut(&mut self, grid: &Grid) -> &mut Field {
        self.uniform = false;
        self.field.get_or_insert_with(|| Field::zeros(grid))
    }

    /// `v` everywhere, if the coefficient may be uniform (returns whether it is now).
    fn set_uniform(&mut self, v: f64) -> bool {
        if self.line.is_empty() {
            return false;
        }
        self.line.fill(v);
        self.uniform = true;
        true
    }
}

/// The longest line of `grid`'s padded storage.
fn longest_line(grid: &Grid) -> usize {
    grid.padded().into_iter().max().unwrap_or(0)
}

/// Whether every value of `f` (ghosts included) has the bits of the first.
fn uniform(f: &Field) -> Option<f64> {
    let d = f.data();
    let v = *d.first()?;
    d.iter().all(|x| x.to_bits() == v.to_bits()).then_some(v)
}

/// A diagonal `d` of [`Coefficients::product`] and [`Coefficients::diagonal`]: one value per
/// unknown face (compact, u then v then w), or one value for every face, given as one line of
/// it (at least as long as the grid's longest line).
#[derive(Clone, Copy)]
pub(crate) enum Diag<'a> {
    /// Per unknown face.
    Faces(&'a [f64]),
    /// The same value at every face, as one line.
    Uniform(&'a [f64]),
}

impl<'a> Diag<'a> {
    /// Its values on the faces of each axis, and whether each line reads the same line.
    fn parts(self, faces: &UnknownFaces) -> ([&'a [f64]; 3], bool) {
        match self {
            Diag::Faces(d) => (faces.split(d), false),
            Diag::Uniform(l) => ([l; 3], true),
        }
    }
}

impl<'a> From<&'a [f64]> for Diag<'a> {
    fn from(d: &'a [f64]) -> Self {
        Diag::Faces(d)
    }
}

impl<'a> From<&'a Vec<f64>> for Diag<'a> {
    fn from(d: &'a Vec<f64>) -> Self {
        Diag::Faces(d)
    }
}

/// The coefficients of `K_η` (see the module docs) for one grid and its unknown faces.
pub(crate) struct Coefficients {
    faces: UnknownFaces,
    dims: usize,
    /// `h_a/h_b`: the weight of a row's own component in a shear flux.
    ratio: [[f64; 3]; 3],
    /// The cell coefficient `η` (a copy, ghosts included): the normal-stress coefficient of
    /// axis `a` at a cell is `c_a = (s_a r) η`, formed where it is read ([`normal`](Self::normal))
    /// — one cell array instead of one per axis.
    cells: Coef,
    /// `s_a = 2 scale V/h_a²` (per unit radius factor) of each axis.
    normal_factor: [f64; 3],
    /// The grid's radius factors (`r` at cell centres for `c_a`).
    metric: Metric,
    /// Whether they are all ones (planar and three-dimensional grids).
    unit_metric: bool,
    /// The weight `g` of each shear pair ([`shear_pairs`]) on its edges.
    edge: Vec<Coef>,
    /// The hoop term of each unknown face (zero off the u-faces and in planar geometry; not
    /// stored, empty, in a compact operator off the axisymmetric geometry).
    hoop: Vec<f64>,
    /// Zeros, one line long: the hoop term of a compact operator that stores none.
    zeros: Vec<f64>,
}

impl Coefficients {
    /// Zero coefficients (`K = 0`) for `grid` and its unknown `faces`: a field per cell
    /// coefficient and shear pair, the hoop term per unknown face.
    pub(crate) fn new(grid: &Grid, faces: UnknownFaces) -> Self {
        Self::with(grid, faces, false)
    }

    /// [`new`](Self::new), storing no more than the coefficients need: where the viscosity
    /// is uniform (ghosts included) on a grid whose radius factors are all ones (planar,
    /// three-dimensional), the cell coefficient and each shear pair's weight are one value
    /// each ([`Coef`]); off the axisymmetric geometry no hoop term is stored (it is zero:
    /// [`hoop_diag`](Self::hoop_diag) gives zeros). The same products, bit for bit. Only
    /// [`set_viscosity_weights`](Self::set_viscosity_weights) keeps its coefficients uniform.
    pub(crate) fn compact(grid: &Grid, faces: UnknownFaces) -> Self {
        Self::with(grid, faces, true)
    }

    fn with(grid: &Grid, faces: UnknownFaces, compact: bool) -> Self {
        let dims = grid.dims();
        let h = grid.h();
        let unit_metric = !grid.is_axisymmetric();
        let coef = |grid| {
            if compact {
                Coef::compact(grid)
            } else {
                Coef::field(grid)
            }
        };
        Coefficients {
            hoop: vec![
                0.0;
                if compact && unit_metric {
                    0
                } else {
                    faces.len()
                }
            ],
            zeros: vec![0.0; if compact { longest_line(grid) } else { 0 }],
            faces,
            dims,
            ratio: std::array::from_fn(|a| std::array::from_fn(|b| h[a] / h[b])),
            cells: coef(grid),
            normal_factor: [0.0; 3],
            metric: grid.metric.clone(),
            unit_metric,
            edge: shear_pairs(dims).iter().map(|_| coef(grid)).collect(),
        }
    }

    /// The hoop term per unknown face (compact; zero off the u-faces) of an operator made
    /// with [`new`](Self::new).
    pub(crate) fn hoop(&self) -> &[f64] {
        &self.hoop
    }

    /// The hoop term as a diagonal of [`product`](Self::product): per unknown face, or zeros
    /// where a [compact](Self::compact) operator stores none.
    pub(crate) fn hoop_diag(&self) -> Diag<'_> {
        if self.hoop.is_empty() && !self.zeros.is_empty() {
            Diag::Uniform(&self.zeros)
        } else {
            Diag::Faces(&self.hoop)
        }
    }

    /// Whether the hoop term is zero at every face (no hoop term is stored).
    pub(crate) fn hoop_free(&self) -> bool {
        self.hoop.is_empty() && !self.zeros.is_empty()
    }

    /// The longest line of the grid, for a uniform diagonal ([`Diag::Uniform`]).
    pub(crate) fn line_len(&self) -> usize {
        self.zeros.len()
    }

    /// The coefficients of `scale·K_μ` for the cell viscosities `mu` (ghosts filled); the edge
    /// viscosities ([`edge_viscosity`]) are written to `edges`, one field per shear pair
    /// ([`shear_pairs`]). Lines in parallel.
    pub(crate) fn set_viscosity_edges<F: BorrowMut<Field>>(
        &mut self,
        g: &Grid,
        mu: &Field,
        scale: f64,
        edges: &mut [F],
    ) {
        assert_eq!(edges.len(), self.edge.len(), "one field per shear pair");
        self.set_cells(g, mu, scale);
        for (p, e) in edges.iter_mut().enumerate() {
            let (axes, at) = SHEAR[p];
            let e: &mut Field = e.borrow_mut();
            edge_viscosity(g, mu, axes, at, e);
            self.set_edge(g, p, e, scale);
        }
        self.set_hoop(g, mu, scale);
    }

    /// [`set_viscosity_edges`](Self::set_viscosity_edges) on a two-dimensional grid, whose one
    /// shear pair lives on the corners (`corner`).
    #[cfg(test)]
    pub(crate) fn set_viscosity(&mut self, g: &Grid, mu: &Field, scale: f64, corner: &mut Field) {
        self.set_viscosity_edges(g, mu, scale, std::slice::from_mut(corner));
    }

    /// [`set_viscosity_edges`](Self::set_viscosity_edges) without keeping the edge viscosities:
    /// each edge's harmonic mean goes straight into its weight (the same values, bit for bit,
    /// and no edge array). A line of edges whose four rows of cells hold one viscosity (a
    /// uniform fluid, or a line away from an interface) takes that viscosity's mean once
    /// instead of per edge: the same value, without its divisions. Lines in parallel.
    pub(crate) fn set_viscosity_weights(&mut self, g: &Grid, mu: &Field, scale: f64) {
        self.set_cells(g, mu, scale);
        // One viscosity everywhere and radius factors of one: each pair's weight is the one
        // value every edge of it takes below (`s · 1 · mk`, the radius factor one).
        let one = (self.cells.uniform && self.unit_metric).then(|| self.cells.line[0]);
        for (e, &(axes, at)) in self.edge.iter_mut().zip(shear_pairs(self.dims)) {
            let s = depth(g, axes, scale);
            if let Some(m) = one
                && e.set_uniform(s * harmonic_mean([m; 4]))
            {
                continue;
            }
            let lo = edge_cells(axes);
            Region::of(g, at).for_each(e.field_mut(g), |l, gr| {
                let len = l.len;
                let cell = |m: usize| &mu.at(&l, lo[m])[..len];
                let [sw, se, nw, ne] = [cell(0), cell(1), cell(2), cell(3)];
                let (r, gr) = (&edge_radius(g, at, &l)[..len], &mut gr[..len]);
                let one = sw.first().copied().filter(|&m| {
                    [sw, se, nw, ne]
                        .iter()
                        .all(|row| row.iter().all(|&x| x == m))
                });
                if let Some(m) = one {
                    let mk = harmonic_mean([m; 4]);
                    for n in 0..len {
                        gr[n] = s * r[n] * mk;
                    }
                } else {
                    for n in 0..len {
                        let mk = harmonic_mean([sw[n], se[n], nw[n], ne[n]]);
                        gr[n] = s * r[n] * mk;
                    }
                }
            });
        }
        self.set_hoop(g, mu, scale);
    }

    /// The coefficients of `scale·K_η` for the cell coefficients `eta` (ghosts filled) and the
    /// edge coefficients `eta_e`, one field per shear pair ([`shear_pairs`]). Lines in
    /// parallel.
    pub(crate) fn set_edges<F: Borrow<Field> + Sync>(
        &mut self,
        g: &Grid,
        eta: &Field,
        eta_e: &[F],
        scale: f64,
    ) {
        assert_eq!(eta_e.len(), self.edge.len(), "one field per shear pair");
        self.set_cells(g, eta, scale);
        for (p, ek) in eta_e.iter().enumerate() {
            self.set_edge(g, p, ek.borrow(), scale);
        }
        self.set_hoop(g, eta, scale);
    }

    /// The weights of shear pair `p` of `scale·K_η` from its edge coefficients `eta_e`.
    fn set_edge(&mut self, g: &Grid, p: usize, eta_e: &Field, scale: f64) {
        let (axes, at) = SHEAR[p];
        let s = depth(g, axes, scale);
        Region::of(g, at).for_each(self.edge[p].field_mut(g), |l, gr| {
            let (ek, r) = (eta_e.at(&l, [0; 3]), edge_radius(g, at, &l));
            for n in 0..l.len {
                gr[n] = s * r[n] * ek[n];
            }
        });
    }

    /// The normal-stress coefficients `c_a` of `scale·K_η` from the cell coefficients: their
    /// factors `s_a` and a copy of `eta`.
    fn set_cells(&mut self, g: &Grid, eta: &Field, scale: f64) {
        let h = g.h();
        for (a, ca) in self.normal_factor.iter_mut().enumerate().take(self.dims) {
            // 2 scale V/h_a², as 2 scale (Π_{b≠a} h_b)/h_a.
            let area = (0..self.dims)
                .filter(|&b| b != a)
                .fold(scale * 2.0, |s, b| s * h[b]);
            *ca = area / h[a];
        }
        let one = (!self.cells.line.is_empty())
            .then(|| uniform(eta))
            .flatten();
        if !one.is_some_and(|v| self.cells.set_uniform(v)) {
            self.cells.field_mut(g).copy_from(eta);
        }
    }

    /// What the normal-stress coefficient `c_a = (s_a r) η` of axis `a` at the cells of line
    /// `l` shifted by `shift` along `a` (0 or −1) is made of: `s_a`, then `η` and `r` there
    /// (`r` `None` where the metric is all ones: `s_a · 1` is `s_a`, so `c_a = s_a η` exactly).
    #[inline(always)]
    fn normal(&self, a: usize, l: &Line, shift: isize) -> (f64, &[f64], Option<&[f64]>) {
        let mut at = [0; 3];
        at[a] = shift;
        let r = (!self.unit_metric).then(|| &self.metric.rc_on(l, at[0])[..l.len]);
        (self.normal_factor[a], &self.cells.at(l, at)[..l.len], r)
    }

    /// The hoop term of `scale·K_η` on each unknown u-face, from the cell coefficients.
    fn set_hoop(&mut self, g: &Grid, eta: &Field, scale: f64) {
        if self.hoop_free() {
            return;
        }
        let (m, h) = (&g.metric, g.h());
        let faces = self.faces.u_region();
        let hoop = &mut self.hoop[..faces.size()];
        let sv = h[..self.dims].iter().fold(scale, |s, h| s * h);
        if !faces.is_empty() {
            par::rows(&mut *hoop, faces.len(0)).for_each(|n, hs| {
                let l = faces.line(n);
                let (ew, ec) = (eta.at(&l, [-1, 0, 0]), eta.at(&l, [0; 3]));
                let (rx, hx) = (m.rx_on(&l, 0), m.hoop_x_on(&l, 0));
                for (c, h) in hs.iter_mut().enumerate() {
                    let x = hx[c];
                    *h = sv * rx[c] * (ew[c] + ec[c]) * x * x;
                }
            });
        }
    }

    /// `dm` plus the sum of every coupling of each row into `diag`, where `dm` holds the mass
    /// plus the hoop term ([`hoop`](Self::hoop)) of each unknown face: the diagonal of
    /// `diag(dm) − K` away from the boundaries; beside a wall the wall's coupling counts once
    /// whatever its ghost rule (a reflected no-slip ghost doubles it in the matrix), which keeps
    /// the blocks diagonally dominant. Jacobi and the block multigrid use it. Lines in parallel.
    pub(crate) fn diagonal<'d>(&self, dm: impl Into<Diag<'d>>, diag: &mut [f64]) {
        let (dms, same) = dm.into().parts(&self.faces);
        for (a, dg) in self.faces.split_mut(diag).into_iter().enumerate() {
            let r = self.faces.region(a);
            if r.is_empty() {
                continue;
            }
            let dm = dms[a];
            par::rows(dg, r.len(0)).for_each(|n, dgs| {
                let l = r.line(n);
                let dm = if same { dm } else { &dm[n * l.len..] };
                let ((ca, ehi, rhi), (_, elo, rlo)) =
                    (self.normal(a, &l, 0), self.normal(a, &l, -1));
                match (rhi, rlo) {
                    (Some(rhi), Some(rlo)) => {
                        for k in 0..l.len {
                            let (chi, clo) = (ca * rhi[k] * ehi[k], ca * rlo[k] * elo[k]);
                            dgs[k] = dm[k] + (chi + clo);
                        }
                    }
                    _ => {
                        for k in 0..l.len {
                            dgs[k] = dm[k] + (ca * ehi[k] + ca * elo[k]);
                        }
                    }
                }
                for b in (0..self.dims).filter(|&b| b != a) {
                    let (g, rho) = (&self.edge[pair(a, b)], self.ratio[a][b]);
                    let (glo, ghi) = (g.at(&l, [0; 3]), g.at(&l, unit(b)));
                    for k in 0..l.len {
                        dgs[k] += rho * (ghi[k] + glo[k]);
                    }
                }
            });
        }
    }

    /// The diagonal blocks (u–u, v–v and, in three dimensions, w–w) of `diag(d) − K` — `d` the
    /// full diagonal ([`diagonal`](Self::diagonal)) — as five- or seven-point stencils, one
    /// per axis in `out` (shaped like the unknown faces of that axis; couplings `≥ 0`, zero
    /// across a closed boundary): along the block's own axis `a` the normal stress's `c_a`,
    /// across it along `b` the shear's `ρ_ab g_ab`.
    pub(crate) fn blocks(&self, diag: &[f64], out: &mut [Stencil5]) {
        assert_eq!(out.len(), self.dims, "one block per axis");
        let ds = self.faces.split(diag);
        for (a, s) in out.iter_mut().enumerate() {
            let r = self.faces.region(a);
            let periodic = [s.periodic_x, s.periodic_y, s.periodic_z];
            let nr = r.len(0);
            for n in 0..r.lines() {
                let l = r.line(n);
                let o = n * nr;
                s.diag[o..o + nr].copy_from_slice(&ds[a][o..o + nr]);
                for d in 0..self.dims {
                    let out = &mut [&mut s.east, &mut s.north, &mut s.top][d][o..o + nr];
                    let last = |i: usize| {
                        let at = if d == 0 {
                            i
                        } else {
                            (l.start[d] - r.lo()[d]) as usize
                        };
                        at + 1 == r.len(d) && !periodic[d]
                    };
                    if d == a {
                        // The line's own normal-stress coefficients.
                        let (ca, eta, radius) = self.normal(a, &l, 0);
                        for (i, x) in out.iter_mut().enumerate() {
                            let own = radius.map_or(ca, |r| ca * r[i]) * eta[i];
                            *x = if last(i) { 0.0 } else { own };
                        }
                    } else {
                        let w = self.ratio[a][d];
                        let g = &self.edge[pair(a, d)].at(&l, unit(d))[..nr];
                        for (i, (x, g)) in out.iter_mut().zip(g).enumerate() {
                            *x = if last(i) { 0.0 } else { w * g };
                        }
                    }
                }
            }
        }
    }

    /// `y = d∘x − K(u, v)` on a two-dimensional grid ([`product`](Self::product) with the
    /// velocity `[u, v]`).
    #[cfg(test)]
    pub(crate) fn apply(
        &self,
        u: &Field,
        v: &Field,
        d: &[f64],
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        self.product(&[u, v], d, x, y)
    }

    /// `y = d∘x − K(V)` on the unknown faces, with `vel` the velocity (one field per axis,
    /// ghosts filled) and `x` its compact vector of unknowns, or the fields' own values when
    /// `None` (lines in parallel; each line writes its own entries). Returns `x·y`, summed by
    /// lines in order, component after component (the same on any number of threads).
    pub(crate) fn product<'d, F: Borrow<Field> + Sync>(
        &self,
        vel: &[F],
        d: impl Into<Diag<'d>>,
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        assert_eq!(vel.len(), self.dims, "one velocity component per axis");
        let (ds, same) = d.into().parts(&self.faces);
        let xs = x.map(|x| self.faces.split(x));
        let mut xy = [0.0; 3];
        for (a, y) in self.faces.split_mut(y).into_iter().enumerate() {
            let r = self.faces.region(a);
            if r.is_empty() {
                continue;
            }
            let (n, d) = (r.len(0), ds[a]);
            let x = xs.map(|x| x[a]);
            xy[a] = par::rows(y, n).fold(
                0.0,
                |j, y| {
                    let x = x.map(|x| &x[j * n..(j + 1) * n]);
                    let (l, d) = (r.line(j), if same { d } else { &d[j * n..] });
                    // The component, the grid's axis count and whether the metric is all ones
                    // count as constants: the shifts along the axes are then known to the
                    // compiler, which addresses the stencil's neighbours from fewer pointers.
                    match (self.unit_metric, self.dims, a) {
                        (true, 2, 0) => self.line::<0, 1, true, F>(&l, vel, d, x, y),
                        (true, 2, _) => self.line::<1, 1, true, F>(&l, vel, d, x, y),
                        (true, _, 0) => self.line::<0, 2, true, F>(&l, vel, d, x, y),
                        (true, _, 1) => self.line::<1, 2, true, F>(&l, vel, d, x, y),
                        (true, ..) => self.line::<2, 2, true, F>(&l, vel, d, x, y),
                        (false, 2, 0) => self.line::<0, 1, false, F>(&l, vel, d, x, y),
                        (false, 2, _) => self.line::<1, 1, false, F>(&l, vel, d, x, y),
                        (false, _, 0) => self.line::<0, 2, false, F>(&l, vel, d, x, y),
                        (false, _, 1) => self.line::<1, 2, false, F>(&l, vel, d, x, y),
                        (false, ..) => self.line::<2, 2, false, F>(&l, vel, d, x, y),
                    }
                },
                |s, p| s + p,
            );
        }
        (1..self.dims).fold(xy[0], |s, a| s + xy[a])
    }

    /// [`product`](Self::product) on one line of unknown `A`-faces of a grid of `S + 1` axes,
    /// whose shear pairs are with the `S` other axes: `y = d∘x − K(V)` there (`x` the line's
    /// unknowns, or `u_A` itself), returning `x·y`; `U`: the metric is all ones.
    #[inline(always)]
    fn line<const A: usize, const S: usize, const U: bool, F: Borrow<Field>>(
        &self,
        l: &Line,
        vel: &[F],
        d: &[f64],
        x: Option<&[f64]>,
        y: &mut [f64],
    ) -> f64 {
        let (a, n) = (A, y.len());
        let across: [usize; S] = std::array::from_fn(|m| if S == 1 { a ^ 1 } else { others(a)[m] });
        let u = vel[a].borrow();
        let (uc, ulo, uhi) = (
            &u.at(l, [0; 3])[..n],
            &u.at(l, minus(a))[..n],
            &u.at(l, unit(a))[..n],
        );
        // c_a at the cells above and below each face, `(s_a r) η` as the coefficients define it
        // (`s_a η` where r is one, the same value).
        let ca = self.normal_factor[a];
        let (ehi, elo) = (
            &self.cells.at(l, [0; 3])[..n],
            &self.cells.at(l, minus(a))[..n],
        );
        let (rhi, rlo): (&[f64], &[f64]) = if U {
            (&[], &[])
        } else {
            (
                &self.metric.rc_on(l, 0)[..n],
                &self.metric.rc_on(l, minus(a)[0])[..n],
            )
        };
        let dr = &d[..n];
        let xr = &x.unwrap_or(uc)[..n];
        // The normal stresses and the first shear pair; each further pair adds its fluxes in a
        // pass of its own (the sum in the same order), the last one forming `y`.
        for (m, &b) in across.iter().enumerate() {
            let Shear {
                rho,
                glo,
                ghi,
                own_lo,
                own_hi,
                lo,
                lo_m,
                hi,
                hi_m,
            } = Shear::new(self, a, b, l, vel, n);
            let last = m + 1 == S;
            for k in 0..n {
                let f_lo = glo[k] * (rho * (uc[k] - own_lo[k]) + (lo[k] - lo_m[k]));
                let f_hi = ghi[k] * (rho * (own_hi[k] - uc[k]) + (hi[k] - hi_m[k]));
                let s = if m == 0 {
                    let (chi, clo) = if U {
                        (ca * ehi[k], ca * elo[k])
                    } else {
                        (ca * rhi[k] * ehi[k], ca * rlo[k] * elo[k])
                    };
                    chi * (uhi[k] - uc[k]) - clo * (uc[k] - ulo[k])
                } else {
                    y[k]
                } + (f_hi - f_lo);
                y[k] = if last { dr[k] * xr[k] - s } else { s };
            }
        }
        let y = &*y;
        par::sum4(n, |k| xr[k] * y[k])
    }
}

/// The axes other than `a` of a three-dimensional grid.
#[inline(always)]
fn others(a: usize) -> [usize; 2] {
    match a {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// The values one shear pair `(a, b)` contributes to a line of `a`-faces `I`
/// ([`Coefficients::product`]): the weights on the edges `I` and `I + e_b`, `u_a` at `I ∓ e_b`,
/// and `u_b` at the ends of both edges' other side.
struct Shear<'a> {
    rho: f64,
    glo: &'a [f64],
    ghi: &'a [f64],
    own_lo: &'a [f64],
    own_hi: &'a [f64],
    /// `u_b[I]`, `u_b[I − e_a]`, `u_b[I + e_b]`, `u_b[I + e_b − e_a]`.
    lo: &'a [f64],
    lo_m: &'a [f64],
    hi: &'a [f64],
    hi_m: &'a [f64],
}

impl<'a> Shear<'a> {
    #[inline(always)]
    fn new<F: Borrow<Field>>(
        k: &'a Coefficients,
        a: usize,
        b: usize,
        l: &Line,
        vel: &'a [F],
        n: usize,
    ) -> Self {
        let (ua, ub, g) = (vel[a].borrow(), vel[b].borrow(), &k.edge[pair(a, b)]);
        let up = unit(b);
        Shear {
            rho: k.ratio[a][b],
            glo: &g.at(l, [0; 3])[..n],
            ghi: &g.at(l, up)[..n],
            own_lo: &ua.at(l, minus(b))[..n],
            own_hi: &ua.at(l, up)[..n],
            lo: &ub.at(l, [0; 3])[..n],
            lo_m: &ub.at(l, minus(a))[..n],
            hi: &ub.at(l, up)[..n],
            hi_m: &ub.at(l, add(up, minus(a)))[..n],
        }
    }
}

/// `scale` times the cell size along the axis a shear pair `axes` leaves out (three
/// dimensions; `scale` itself in two).
fn depth(g: &Grid, axes: [usize; 2], scale: f64) -> f64 {
    let h = g.h();
    (0..g.dims())
        .filter(|c| !axes.contains(c))
        .fold(scale, |s, c| s * h[c])
}

/// The radius factor on the edges `at` of `l`: at x-faces where the edges sit on them, else at
/// cell centres (all ones off the axisymmetric geometry).
#[inline(always)]
fn edge_radius<'g>(g: &'g Grid, at: Stagger, l: &Line) -> &'g [f64] {
    if at.nodal()[0] == 1 {
        g.metric.rx_on(l, 0)
    } else {
        g.metric.rc_on(l, 0)
    }
}

/// The shifts from an edge of the pair `[a, b]` to its four cells, in the order of the
/// harmonic mean's sum: `−e_a−e_b`, `−e_b`, `−e_a`, `0`.
fn edge_cells([a, b]: [usize; 2]) -> [Index; 4] {
    [add(minus(a), minus(b)), minus(b), minus(a), [0; 3]]
}

/// Edge viscosities of the shear pair `axes` on its edges `at`: the harmonic mean of the four
/// cells around each edge (zero if any is inviscid), lines in parallel. The edge carries the
/// shear stress `μ (∂u_a/∂x_b + ∂u_b/∂x_a)`; across an interface the two phases shear in
/// series, whose effective viscosity is the harmonic mean — the arithmetic mean would let the
/// more viscous phase drag the other along (an O(1) error in the first cell beside an
/// interface, first order overall).
pub(crate) fn edge_viscosity(
    grid: &Grid,
    mu: &Field,
    axes: [usize; 2],
    at: Stagger,
    out: &mut Field,
) {
    let lo = edge_cells(axes);
    Region::of(grid, at).for_each(out, |l, o| {
        let cell = |m: usize| mu.at(&l, lo[m]);
        let q = [cell(0), cell(1), cell(2), cell(3)];
        for n in 0..l.len {
            o[n] = harmonic_mean([q[0][n], q[1][n], q[2][n], q[3][n]]);
        }
    });
}

/// The harmonic mean of the four cell viscosities around an edge, zero if any is inviscid
/// ([`edge_viscosity`]).
#[inline(always)]
fn harmonic_mean(q: [f64; 4]) -> f64 {
    if q.iter().all(|&x| x > 0.0) {
        4.0 / q.iter().map(|x| 1.0 / x).sum::<f64>()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viscous::VelocityGhosts;
    use crate::viscous::box_ghosts::BoxGhosts;
    use efsi_core::BoundarySet;
    use efsi_core::bc::WallTime;
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
        let mut s = [
            Stencil5::new(nur, grid.ny, bc.periodic(0), bc.periodic(1)),
            Stencil5::new(grid.nx, nvr, bc.periodic(0), bc.periodic(1)),
        ];
        k.blocks(diag, &mut s);
        let [au, av] = s;
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

    /// The dense matrix of `diag(dm) − K` of a grid whose ghosts `walls` fills, column by
    /// column (`a[c]` is the product with the `c`-th unit vector).
    fn dense(grid: &Grid, walls: &BoxGhosts, k: &Coefficients, dm: &[f64]) -> Vec<Vec<f64>> {
        let faces = UnknownFaces::with_ranges(grid, &walls.ranges(grid));
        let n = faces.len();
        let mut vel: Vec<Field> = (0..grid.dims()).map(|_| Field::zeros(grid)).collect();
        (0..n)
            .map(|c| {
                let mut x = vec![0.0; n];
                x[c] = 1.0;
                vel.iter_mut().for_each(|f| f.fill(0.0));
                faces.scatter_to(&x, &mut vel);
                walls.fill(grid, &mut vel, WallTime::Homogeneous);
                let mut y = vec![0.0; n];
                let xy = k.product(&vel, dm, Some(&x), &mut y);
                assert_eq!(xy, y[c]);
                y
            })
            .collect()
    }

    /// Whether the symmetric part of `a` plus `shift` on the diagonal has a Cholesky factor
    /// (all pivots positive).
    fn cholesky(a: &[Vec<f64>], shift: f64) -> bool {
        let n = a.len();
        let mut l = vec![vec![0.0; n]; n];
        for j in 0..n {
            for i in j..n {
                let mut s = 0.5 * (a[i][j] + a[j][i]) + if i == j { shift } else { 0.0 };
                for q in 0..j {
                    s -= l[i][q] * l[j][q];
                }
                if i == j {
                    if s <= 0.0 {
                        return false;
                    }
                    l[j][j] = s.sqrt();
                } else {
                    l[i][j] = s / l[j][j];
                }
            }
        }
        true
    }

    /// A three-dimensional box grid of `n` cells, unequal cell sizes along the axes.
    fn box_grid(n: [usize; 3]) -> Grid {
        Grid::new_3d(n, (0.0, 1.0), (0.0, 0.9), (0.0, 0.6))
    }

    #[test]
    fn the_three_dimensional_matrix_is_symmetric_and_positive_semi_definite() {
        for periodic in [[true; 3], [false, true, false], [false; 3]] {
            let grid = box_grid([4, 4, 3]);
            let walls = BoxGhosts { periodic };
            let faces = UnknownFaces::with_ranges(&grid, &walls.ranges(&grid));
            let mut mu = viscosity(&grid);
            walls.fill_scalar(&grid, &mut mu);
            let mut k = Coefficients::new(&grid, faces);
            k.set_viscosity_weights(&grid, &mu, 0.3);
            // −K alone: symmetric, positive semi-definite.
            let n = faces.len();
            let a = dense(&grid, &walls, &k, &vec![0.0; n]);
            let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            let a_ = |c: usize| a[c][c];
            for i in 0..n {
                for j in 0..n {
                    assert!(
                        (a[i][j] - a[j][i]).abs() <= 1e-13 * scale,
                        "{periodic:?}: A[{i}][{j}] = {} but A[{j}][{i}] = {}",
                        a[i][j],
                        a[j][i]
                    );
                }
            }
            assert!(
                cholesky(&a, 1e-10 * scale),
                "{periodic:?}: not semi-definite"
            );
            // With a wall anywhere nothing moves freely: definite. (Periodic on every side a
            // uniform translation is free: singular, checked below.)
            if periodic != [true; 3] {
                assert!(cholesky(&a, 0.0), "{periodic:?}: not definite");
            }
            // −K's diagonal is its own, except beside a wall parallel to the face, whose
            // reflected ghost doubles the coupling in the matrix and not in the diagonal.
            let mut diag = vec![0.0; n];
            k.diagonal(&vec![0.0; n], &mut diag);
            let size = grid.n().map(|n| n as isize);
            let mut own = 0;
            faces.for_each_axis(|c, a, q| {
                let i = mu.index_of(q);
                let beside =
                    (0..3).any(|b| b != a && !periodic[b] && (i[b] == 0 || i[b] == size[b] - 1));
                assert!(
                    diag[c] <= a_(c) + 1e-13 * scale,
                    "{periodic:?}: diagonal {c}"
                );
                if !beside {
                    assert!((diag[c] - a_(c)).abs() <= 1e-13 * scale, "diagonal {c}");
                    own += 1;
                }
            });
            assert!(own >= n / 8, "{periodic:?}: {own} rows away from walls");
            if periodic == [true; 3] {
                // A uniform translation along each axis is in the kernel.
                for t in 0..3 {
                    let [x0, x1, _] = faces.split(&a[0]).map(<[f64]>::len);
                    let part = |c: usize| usize::from(c >= x0) + usize::from(c >= x0 + x1);
                    let ones: Vec<f64> =
                        (0..n).map(|c| f64::from(u8::from(part(c) == t))).collect();
                    for row in 0..n {
                        let r: f64 = (0..n).map(|c| a[c][row] * ones[c]).sum();
                        assert!(r.abs() <= 1e-12 * scale, "translation {t}, row {row}: {r}");
                    }
                }
            }
            check_blocks_3d(&faces, periodic, &k, &diag, &a, scale);
            // Keeping the edge viscosities gives the same operator, bit for bit.
            let mut kept = Coefficients::new(&grid, faces);
            let mut edges: Vec<Field> = (0..3).map(|_| Field::zeros(&grid)).collect();
            kept.set_viscosity_edges(&grid, &mu, 0.3, &mut edges);
            assert!(dense(&grid, &walls, &kept, &vec![0.0; n]) == a);
        }
    }

    /// The seven-point blocks of a three-dimensional grid: their diagonal is `diag`, and each
    /// coupling to the next face along an axis is the matrix `a`'s entry (negated), zero
    /// across a wall.
    fn check_blocks_3d(
        faces: &UnknownFaces,
        periodic: [bool; 3],
        k: &Coefficients,
        diag: &[f64],
        a: &[Vec<f64>],
        scale: f64,
    ) {
        let mut s: Vec<Stencil5> = (0..3)
            .map(|b| {
                let r = faces.region(b);
                Stencil5::new_3d(r.len(0), r.len(1), r.len(2), periodic)
            })
            .collect();
        k.blocks(diag, &mut s);
        let mut off = 0;
        for (b, s) in s.iter().enumerate() {
            let n = [s.nx, s.ny, s.nz];
            for q in 0..s.len() {
                let at = [q % n[0], (q / n[0]) % n[1], q / (n[0] * n[1])];
                assert_eq!(s.diag[q], diag[off + q], "block {b}, diagonal {q}");
                for (d, c) in [&s.east, &s.north, &s.top].into_iter().enumerate() {
                    if at[d] + 1 == n[d] && !periodic[d] {
                        assert_eq!(c[q], 0.0, "block {b}, across a wall along {d} at {q}");
                        continue;
                    }
                    let mut next = at;
                    next[d] = (at[d] + 1) % n[d];
                    let p = (next[2] * n[1] + next[1]) * n[0] + next[0];
                    let entry = a[off + q][off + p];
                    assert!(
                        c[q] >= 0.0 && (c[q] + entry).abs() <= 1e-13 * scale,
                        "block {b}, coupling along {d} at {q}: {} vs {entry}",
                        c[q]
                    );
                }
            }
            off += s.len();
        }
    }

    #[test]
    fn a_two_dimensional_field_extruded_in_z_gives_the_planar_operator_plane_by_plane() {
        use Boundary::*;
        for (sides, periodic) in [
            ([NoSlip, NoSlip, NoSlip, NoSlip], [false, false, true]),
            ([Periodic, Periodic, NoSlip, NoSlip], [true, false, true]),
        ] {
            let (g2, bc) = setup(Geometry::Planar, sides.clone());
            let nz = 3;
            // dz = 1: the planar operator is per unit depth.
            let g3 = Grid::new_3d([g2.nx, g2.ny, nz], (0.0, 1.0), (0.0, 0.6), (0.0, nz as f64));
            let walls = BoxGhosts { periodic };
            let (f2, f3) = (
                UnknownFaces::new(&g2, &bc),
                UnknownFaces::with_ranges(&g3, &walls.ranges(&g3)),
            );
            let value = |i: isize, j: isize, c: usize| {
                ((i * 7919 + j * 104_729 + c as isize * 31) % 1013) as f64 / 500.0 - 1.0
            };
            let mut v2: Vec<Field> = (0..2).map(|_| Field::zeros(&g2)).collect();
            let mut v3: Vec<Field> = (0..3).map(|_| Field::zeros(&g3)).collect();
            let (mut mu2, mut mu3) = (viscosity(&g2), Field::zeros(&g3));
            for (c, f) in v2.iter_mut().enumerate() {
                for q in 0..f.data().len() {
                    let [i, j, _] = f.index_of(q);
                    f.data_mut()[q] = value(i, j, c);
                }
            }
            for q in 0..mu3.data().len() {
                let [i, j, _] = mu3.index_of(q);
                mu3.data_mut()[q] = mu2[(i, j)];
            }
            for (c, f) in v3.iter_mut().enumerate().take(2) {
                for q in 0..f.data().len() {
                    let [i, j, _] = f.index_of(q);
                    f.data_mut()[q] = value(i, j, c);
                }
            }
            let [u, v] = &mut v2[..] else { unreachable!() };
            bc.fill_velocity(&g2, u, v, 0.0, true);
            bc.fill_scalar(&g2, &mut mu2, false);
            walls.fill(&g3, &mut v3, WallTime::Homogeneous);
            walls.fill_scalar(&g3, &mut mu3);
            let (mut k2, mut k3) = (Coefficients::new(&g2, f2), Coefficients::new(&g3, f3));
            k2.set_viscosity_weights(&g2, &mu2, 0.3);
            k3.set_viscosity_weights(&g3, &mu3, 0.3);
            let (mut y2, mut y3) = (vec![0.0; f2.len()], vec![0.0; f3.len()]);
            k2.product(&v2, &vec![1.0; f2.len()], None, &mut y2);
            k3.product(&v3, &vec![1.0; f3.len()], None, &mut y3);
            let (p2, p3) = (f2.split(&y2), f3.split(&y3));
            for a in 0..2 {
                let (r2, r3) = (f2.region(a), f3.region(a));
                assert_eq!(
                    (r3.len(0), r3.len(1), r3.len(2)),
                    (r2.len(0), r2.len(1), nz)
                );
                let line = r2.size();
                for k in 0..nz {
                    assert!(
                        p3[a][k * line..(k + 1) * line] == *p2[a],
                        "{sides:?}: component {a}, plane {k}"
                    );
                }
            }
            assert!(p3[2].iter().all(|&y| y == 0.0), "no w from a planar field");
            assert!(p2[0].iter().any(|&y| y != 0.0));
        }
    }

    /// `c Π_d t_d(2π x_d)`, `t_d` = sin where `sin[d]`, else cos: a periodic product whose
    /// derivatives are products of the same kind.
    #[derive(Clone, Copy)]
    struct Trig {
        c: f64,
        sin: [bool; 3],
    }

    impl Trig {
        fn at(&self, x: [f64; 3]) -> f64 {
            let k = 2.0 * std::f64::consts::PI;
            (0..3).fold(self.c, |p, d| {
                p * if self.sin[d] {
                    (k * x[d]).sin()
                } else {
                    (k * x[d]).cos()
                }
            })
        }
        fn d(&self, a: usize) -> Trig {
            let k = 2.0 * std::f64::consts::PI;
            let mut t = *self;
            t.c *= if self.sin[a] { k } else { -k };
            t.sin[a] = !self.sin[a];
            t
        }
    }

    /// The largest error of `K(V)/vol` against `∇·(2η D(V))` over the faces of a periodic unit
    /// cube of `n³` cells, for a smooth periodic velocity and viscosity.
    fn manufactured_error(n: usize) -> (f64, f64) {
        let grid = Grid::new_3d([n; 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let t = |c, s: [u8; 3]| Trig {
            c,
            sin: s.map(|s| s == 1),
        };
        let vel_exact = [t(1.0, [1, 0, 1]), t(0.7, [0, 1, 0]), t(-0.4, [1, 1, 0])];
        let bump = t(0.5, [1, 1, 1]);
        let eta = |x: [f64; 3]| 1.0 + bump.at(x);
        // ∂_b(η (∂_b V_a + ∂_a V_b)), summed over b.
        let force = |a: usize, x: [f64; 3]| {
            (0..3)
                .map(|b| {
                    let s = vel_exact[a].d(b).at(x) + vel_exact[b].d(a).at(x);
                    let ds = vel_exact[a].d(b).d(b).at(x) + vel_exact[b].d(a).d(b).at(x);
                    bump.d(b).at(x) * s + eta(x) * ds
                })
                .sum::<f64>()
        };
        let h = grid.h();
        let pos = |[i, j, k]: Index, nodal: usize| {
            let mut x = [i, j, k].map(|i| i as f64 + 0.5);
            x[nodal] -= 0.5;
            [0, 1, 2].map(|d| x[d] * h[d])
        };
        let mut mu = Field::zeros(&grid);
        for q in 0..mu.data().len() {
            let i = mu.index_of(q);
            mu.data_mut()[q] = eta([0, 1, 2].map(|d| (i[d] as f64 + 0.5) * h[d]));
        }
        let vel: Vec<Field> = (0..3)
            .map(|a| {
                let mut f = Field::zeros(&grid);
                for q in 0..f.data().len() {
                    f.data_mut()[q] = vel_exact[a].at(pos(f.index_of(q), a));
                }
                f
            })
            .collect();
        let ranges = BoxGhosts {
            periodic: [true; 3],
        }
        .ranges(&grid);
        let faces = UnknownFaces::with_ranges(&grid, &ranges);
        let mut k = Coefficients::new(&grid, faces);
        k.set_viscosity_weights(&grid, &mu, 1.0);
        let mut y = vec![0.0; faces.len()];
        k.product(&vel, &vec![0.0; faces.len()], None, &mut y);
        let vol = h.iter().product::<f64>();
        let (mut err, mut size) = (0.0f64, 0.0f64);
        faces.for_each_axis(|c, a, q| {
            let f = force(a, pos(vel[a].index_of(q), a));
            err = err.max((-y[c] / vol - f).abs());
            size = size.max(f.abs());
        });
        (err, size)
    }

    #[test]
    fn the_three_dimensional_operator_is_second_order_for_a_smooth_field() {
        let (e16, size) = manufactured_error(16);
        let (e32, _) = manufactured_error(32);
        let order = (e16 / e32).log2();
        assert!(
            order > 1.9 && order < 2.1,
            "order {order} ({e16:e}, {e32:e})"
        );
        assert!(e32 < 0.01 * size, "{e32:e} of {size:e}");
    }

    /// The weights of lines of one viscosity (taken once per line) are those of the per-edge
    /// harmonic means, bit for bit, beside lines that mix two viscosities.
    #[test]
    fn uniform_lines_take_the_per_edge_weights() {
        let grid = box_grid([6, 5, 4]);
        let walls = BoxGhosts {
            periodic: [false; 3],
        };
        let faces = UnknownFaces::with_ranges(&grid, &walls.ranges(&grid));
        // 0.7 everywhere but a block of 0.02 (lines through it mix the two).
        let mut mu = Field::filled(&grid, 0.7);
        for q in 0..mu.data().len() {
            let i = mu.index_of(q);
            if (1..3).contains(&i[0]) && (2..4).contains(&i[1]) && i[2] == 1 {
                mu.data_mut()[q] = 0.02;
            }
        }
        let mut fast = Coefficients::new(&grid, faces);
        fast.set_viscosity_weights(&grid, &mu, 0.3);
        let mut edges: Vec<Field> = (0..3).map(|_| Field::zeros(&grid)).collect();
        let mut slow = Coefficients::new(&grid, faces);
        slow.set_viscosity_edges(&grid, &mu, 0.3, &mut edges);
        for (f, s) in fast.edge.iter().zip(&slow.edge) {
            let (f, s) = (f.field.as_ref().unwrap(), s.field.as_ref().unwrap());
            assert!(
                f.data()
                    .iter()
                    .zip(s.data())
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
            // Both kinds of line are there: the weights take more than one value.
            let (lo, hi) = s
                .data()
                .iter()
                .filter(|&&g| g > 0.0)
                .fold((f64::MAX, 0.0f64), |(l, h), &g| (l.min(g), h.max(g)));
            assert!(lo < hi, "one weight only: {lo} {hi}");
        }
    }

    /// A compact operator ([`Coefficients::compact`]) gives the full one's products and
    /// diagonal bit for bit — with one viscosity everywhere (one value per coefficient, no
    /// hoop term stored) and with two (fields made at the first call) — in three dimensions
    /// and in the plane; it stores no array while the viscosity is uniform.
    #[test]
    fn the_compact_operator_gives_the_full_ones_bits() {
        let planar = Grid::new(Geometry::Planar, 7, 5, (0.0, 1.0), (0.0, 0.8));
        for grid in [box_grid([5, 4, 3]), planar] {
            let walls = BoxGhosts {
                periodic: [false, true, false],
            };
            let faces = UnknownFaces::with_ranges(&grid, &walls.ranges(&grid));
            let n = faces.len();
            let mut two = viscosity(&grid);
            walls.fill_scalar(&grid, &mut two);
            for mu in [Field::filled(&grid, 0.7), two] {
                let mut full = Coefficients::new(&grid, faces);
                let mut compact = Coefficients::compact(&grid, faces);
                full.set_viscosity_weights(&grid, &mu, 0.3);
                compact.set_viscosity_weights(&grid, &mu, 0.3);
                let one = mu.data().iter().all(|&m| m == 0.7);
                assert_eq!(compact.cells.field.is_none(), one);
                assert!(compact.edge.iter().all(|e| e.field.is_none() == one));
                assert!(compact.hoop.is_empty());
                let mut vel: Vec<Field> = (0..grid.dims()).map(|_| Field::zeros(&grid)).collect();
                let x: Vec<f64> = (0..n)
                    .map(|c| ((c * 2654435761) % 1000) as f64 / 500.0 - 1.0)
                    .collect();
                faces.scatter_to(&x, &mut vel);
                walls.fill(&grid, &mut vel, WallTime::Homogeneous);
                let dm: Vec<f64> = (0..n).map(|c| 1.0 + (c % 7) as f64).collect();
                let (mut y1, mut y2) = (vec![0.0; n], vec![0.0; n]);
                let xy1 = full.product(&vel, &dm, Some(&x), &mut y1);
                let xy2 = compact.product(&vel, &dm, Some(&x), &mut y2);
                assert_eq!(xy1.to_bits(), xy2.to_bits());
                assert!(y1.iter().zip(&y2).all(|(a, b)| a.to_bits() == b.to_bits()));
                let (h1, h2) = (full.hoop().to_vec(), compact.hoop_diag());
                full.product(&vel, &h1, None, &mut y1);
                compact.product(&vel, h2, None, &mut y2);
                assert!(y1.iter().zip(&y2).all(|(a, b)| a.to_bits() == b.to_bits()));
                full.diagonal(&dm, &mut y1);
                compact.diagonal(&dm, &mut y2);
                assert!(y1.iter().zip(&y2).all(|(a, b)| a.to_bits() == b.to_bits()));
                // A uniform diagonal as one line, against the same values per face.
                let line = vec![2.5; compact.line_len()];
                full.diagonal(&vec![2.5; n], &mut y1);
                compact.diagonal(Diag::Uniform(&line), &mut y2);
                assert!(y1.iter().zip(&y2).all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
    }
}
