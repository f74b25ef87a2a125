//! Geometric, direction-split, mass-conserving advection of the solid fraction φ_s, in planar,
//! axisymmetric and three-dimensional Cartesian geometry.
//!
//! # Equation
//!
//! The solid fraction is a passive, volume-preserving indicator (seed §2, Eq. 7):
//!
//! ```text
//!     ∂φ/∂t + ∇·(φ u) − φ ∇·u = 0,        ∇·u = 0,
//! ```
//!
//! on a prescribed MAC velocity (u on x-faces, v on y-faces, w on z-faces in three dimensions).
//! In axisymmetric geometry (`x = r`, `y = z`) the divergence is
//! `(1/r) ∂(r φ u)/∂r + ∂(φ v)/∂z`, and the conserved quantity is `Σ φ · r_c Δr Δz` (per
//! radian); in three dimensions it is `Σ φ Δx Δy Δz`.
//!
//! # Scheme (Weymouth & Yue 2010, the algorithm of Basilisk's `vof.h`)
//!
//! One step is one one-dimensional sweep per axis of the grid ([`Grid::dims`]): `x, y` then
//! `y, x` on alternate steps in two dimensions, `x, y, z` then `z, y, x` in three (each pair of
//! steps a symmetric, Strang-like composition). Before the first sweep the cell-centred
//! indicator `c_c = [φⁿ > ½]` is frozen for all the sweeps. A sweep along axis `d` does, for
//! every cell `I`,
//!
//! ```text
//!     φ* = φ + (F_{I−½e_d} − F_{I+½e_d} + c_c (U_{I+½e_d} − U_{I−½e_d})) / V_I,
//! ```
//!
//! where
//! - `V_I` is the cell volume: `Δx Δy` (planar, per unit depth), `r_c Δr Δz` (axisymmetric,
//!   per radian), `Δx Δy Δz` (three dimensions);
//! - `U` is the volume swept through a face during `Δt`, the discrete face flux
//!   `U = A_f u_f Δt` with the face area `A_f` (the product of the two other cell sizes; `r_f Δz`
//!   on r-faces and `r_c Δr` on z-faces in axisymmetric geometry) — the same fluxes whose per-cell
//!   sum is the discrete divergence, so that for a discretely divergence-free velocity
//!   `Σ_sweeps c_c (U_out − U_in) = 0` in every cell;
//! - `F = U · f_up` is the phase volume carried through the face: `f_up` is the exact fraction
//!   of the **fluxed region** — the slab of the upwind cell adjacent to the face whose volume is
//!   `|U|` — that lies below the upwind cell's PLIC interface. In Cartesian geometry (and along
//!   z) the slab has width `|u|Δt`; along r its width `w` solves `∫_slab r dA = r_f |u| Δt Δz`,
//!   i.e. `w = 2 r_f |s| / (r_f + √(r_f² − 2 r_f s))` with `s = u Δt`, and `f_up` is its
//!   r-weighted fraction (`∫ r dA` of the polygon below the line over `∫ r dA` of the slab).
//!   In two dimensions the interface is a line ([`super::plic`]: Youngs normals, planar `α`
//!   analytic, axisymmetric `α` by bracketed Newton); in three a plane ([`super::plic3d`]: the
//!   mixed Youngs–centred normal, the analytic plane–cuboid volume and its inverse, the slab's
//!   fraction [`Plane::slab_fraction`]). A full (empty) upwind cell gives `F = U` (`F = 0`)
//!   exactly.
//!
//! The phase volume `Σ φ V` changes by `Σ (F_in − F_out)` (which telescopes to the boundary
//! fluxes: zero at closed sides, equal and opposite at periodic sides) plus `Σ c_c·(∇·U)`,
//! which vanishes cell by cell for a discretely divergence-free velocity: **volume is conserved
//! to round-off**, in every geometry. Interfaces are reconstructed before each sweep from the
//! current φ.
//!
//! One sweep serves every geometry: its passes run over [`Region`] lines and shifts `unit(d)`
//! along the sweep's axis, and only the two cell-local operations — reconstructing a cell's
//! interface from its neighbourhood and the fraction of a slab below it — depend on the
//! geometry.
//!
//! # Boundaries
//!
//! Each side is [`VofSide::Closed`] (no flux through it, whatever the face velocity there; the
//! axis `r = 0` is closed) or [`VofSide::Periodic`] (paired with the opposite side; the face
//! velocity of the high side is taken equal to that of the low side). Ghost cells of φ are
//! filled by even reflection (closed) or wrap-around (periodic) before each reconstruction,
//! axis by axis, each axis over the ghosts of the axes before it, so edge and corner ghosts are
//! consistent.
//!
//! # Stability and boundedness
//!
//! The fluxed slab must fit in its upwind cell (`|U| ≤ V_up`) and Weymouth & Yue show that
//! the update keeps `0 ≤ φ ≤ 1` (to round-off) for Courant numbers `≤ ½` in each sweep. The
//! Courant number reported in [`AdvectStats::cfl`] is the flux form `max |U_f| / V_upwind`,
//! which equals `max_d |u_d|Δt/Δx_d` in Cartesian geometry and is larger than `|u|Δt/Δr` for
//! outward radial flow next to the axis (up to 2× in the first column). After each sweep φ is
//! clipped to `[0, 1]`, and a value within `WISP` = 1e-14 of 0 or 1 — round-off of a sweep
//! (values of 1e-38 to 1e-17 left beside an interface that passed), not a resolvable sliver —
//! is set to it: such wisps would otherwise stay, and a body's window, which covers every cell
//! where its fraction is not zero, would grow around them. The largest clipped amount and the
//! volume it added are reported, so a caller can check that the clipping stayed at round-off
//! (excursions ≤ 1e-12 at Courant ≤ ½), and the clipped volume is given back to the interface
//! cells: volume stays conserved to round-off.
//!
//! # Limits
//!
//! The split scheme's error is first order in the splitting and second order at best in
//! space: the shape error of a resolved interface converges at about second order (the
//! mixed normal in three dimensions), and filaments thinner than a cell break into droplets
//! (flotsam), as with every PLIC scheme; the volume stays exact.
//!
//! # References
//!
//! - G. D. Weymouth & D. K.-P. Yue (2010), *Conservative volume-of-fluid method for free-surface
//!   simulations on Cartesian grids*, J. Comput. Phys. 229:2853–2865.
//! - D. L. Youngs (1982), see [`super::plic`]; R. Scardovelli & S. Zaleski (2000), ibid.
//! - E. Aulisa, S. Manservisi, R. Scardovelli & S. Zaleski (2007), *Interface reconstruction
//!   with least-squares fit and split advection in three-dimensional Cartesian geometry*,
//!   J. Comput. Phys. 225:2301–2319 (the mixed normal, the 3-D test problems).
//! - W. J. Rider & D. B. Kothe (1998), *Reconstructing volume tracking*, J. Comput. Phys.
//!   141:112–152; D. Enright, R. Fedkiw, J. Ferziger & I. Mitchell (2002), *A hybrid particle
//!   level set method for improved interface capturing*, J. Comput. Phys. 183:83–116 (the
//!   two- and three-dimensional test problems).
//! - S. Popinet, Basilisk `src/vof.h` (the same scheme; the reference errors of the tests).

use super::plic::{axi_alpha, half_plane_moments, rect_alpha, rect_fraction, youngs_normal};
use super::plic3d::{Block, Plane, myc_normal};
use efsi_core::{Field, G, Grid, Line, Region, Stagger, unit};

/// What a side of the domain does to the transported fraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VofSide {
    /// No flux through the side (wall, symmetry plane, axis); ghosts by even reflection.
    Closed,
    /// Periodic with the opposite side (which must be periodic too).
    Periodic,
}

/// The side kinds of the sides of the domain (the z sides count on a three-dimensional grid
/// only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VofBoundaries {
    /// Low-x (low-r, the axis when `x0 = 0`) side.
    pub x_lo: VofSide,
    /// High-x (high-r) side.
    pub x_hi: VofSide,
    /// Low-y (low-z) side.
    pub y_lo: VofSide,
    /// High-y (high-z) side.
    pub y_hi: VofSide,
    /// Low-z side of a three-dimensional grid.
    pub z_lo: VofSide,
    /// High-z side of a three-dimensional grid.
    pub z_hi: VofSide,
}

impl VofBoundaries {
    /// All sides closed.
    pub fn closed() -> Self {
        Self::periodic_axes([false; 3])
    }

    /// Periodic in x and/or y, closed otherwise.
    pub fn periodic(x: bool, y: bool) -> Self {
        Self::periodic_axes([x, y, false])
    }

    /// Periodic along the axes `p[a]`, closed otherwise.
    pub fn periodic_axes(p: [bool; 3]) -> Self {
        let k = |p: bool| {
            if p {
                VofSide::Periodic
            } else {
                VofSide::Closed
            }
        };
        VofBoundaries {
            x_lo: k(p[0]),
            x_hi: k(p[0]),
            y_lo: k(p[1]),
            y_hi: k(p[1]),
            z_lo: k(p[2]),
            z_hi: k(p[2]),
        }
    }

    /// The low and high sides along axis `a`.
    pub fn along(&self, a: usize) -> (VofSide, VofSide) {
        match a {
            0 => (self.x_lo, self.x_hi),
            1 => (self.y_lo, self.y_hi),
            _ => (self.z_lo, self.z_hi),
        }
    }

    /// Check the sides against a grid: periodic sides come in pairs, the grid has at least two
    /// cells along each of its axes, and an axisymmetric grid is not periodic in `r`.
    pub fn validate(&self, grid: &Grid) -> Result<(), String> {
        for (a, name) in ["x", "y", "z"].into_iter().enumerate().take(grid.dims()) {
            let (lo, hi) = self.along(a);
            if (lo == VofSide::Periodic) != (hi == VofSide::Periodic) {
                return Err(format!(
                    "VOF boundaries: a periodic {name} side needs a periodic opposite side"
                ));
            }
        }
        if grid.is_axisymmetric() && self.x_lo == VofSide::Periodic {
            return Err("VOF boundaries: an axisymmetric grid cannot be periodic in r".into());
        }
        if grid.is_axisymmetric() && grid.x0 < 0.0 {
            return Err("VOF boundaries: an axisymmetric grid must have r ≥ 0".into());
        }
        let n = grid.n();
        if n[..grid.dims()].iter().any(|&n| n < 2) {
            return Err(if grid.is_3d() {
                "VOF advection needs at least 2 × 2 × 2 cells".into()
            } else {
                "VOF advection needs at least 2 × 2 cells".into()
            });
        }
        Ok(())
    }
}

/// Statistics of one [`VofAdvector::step`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdvectStats {
    /// Largest amount `|φ_clipped − φ|` removed by clipping φ to `[0, 1]` after a sweep
    /// (round-off, ≲ 1e-15, when the Courant number is ≤ ½).
    pub max_clipped: f64,
    /// Net volume `Σ (φ_clipped − φ) V` added by that clipping (the only departure from exact
    /// conservation besides round-off).
    pub clipped_volume: f64,
    /// Flux Courant number `max |U_f| / V_upwind` over the sweeps (see the module docs).
    pub cfl: f64,
}

impl AdvectStats {
    fn merge(&mut self, o: AdvectStats) {
        self.max_clipped = self.max_clipped.max(o.max_clipped);
        self.clipped_volume += o.clipped_volume;
        self.cfl = self.cfl.max(o.cfl);
    }
}

/// A fraction within this of 0 or 1 after a sweep is round-off and is set to 0 or 1 (its volume
/// given back to the interface cells; module docs, "Stability and boundedness"): some fifty
/// ulps of 1, above the round-off of a sweep's sums of order-one fluxes and far below a
/// resolvable sliver. A larger threshold would magnify round-off differences between mirrored
/// cells (one cleaned, its mirror not) into an asymmetry of its own size.
const WISP: f64 = 1e-14;

/// The cell geometries of the kernels (a const-generic parameter): what a cell's interface is
/// and how a slab of it is cut.
const PLANAR: u8 = 0;
const AXI: u8 = 1;
const CUBE: u8 = 2;

/// The VOF PLIC advection kernel: owns its scratch arrays (allocated once in [`Self::new`]).
///
/// Every pass of a sweep (indicator, reconstruction, face fluxes, update) runs over the lines
/// of a grid region in parallel ([`Region`]); each line writes only its own entries and
/// returns its own partial statistics, which are folded in line order, so the result is the
/// same bit for bit on any number of threads.
#[derive(Clone, Debug)]
pub struct VofAdvector {
    bounds: VofBoundaries,
    /// [`PLANAR`], [`AXI`] or [`CUBE`].
    kind: u8,
    /// Cells and cell size along each axis (`nz = 1`, `dz = 1` in two dimensions).
    n: [usize; 3],
    h: [f64; 3],
    /// Area of a face normal to each axis without its radius factor: the product of the two
    /// other cell sizes.
    area: [f64; 3],
    /// Values per padded array of the grid.
    cells: usize,
    /// The grid's cell centres.
    interior: Region,
    /// The work arrays of a step ([`Work`], [`work_len`] values) when the advector owns
    /// them; empty when its stage lends them from the pipeline's pool ([`Self::step_in`]).
    own: Vec<f64>,
    /// Per padded column ([`efsi_core::Line::cols`]): `1/V`, the radius of the left edge, the face radius.
    inv_vol: Vec<f64>,
    r_left: Vec<f64>,
    r_face: Vec<f64>,
    r_centre: Vec<f64>,
}

/// Values of the work arrays a step on `grid` needs ([`Work`]): the indicator, the interface
/// (a normal component per axis and its constant), two face fluxes and the divergence sum, one
/// padded array each. Nothing in them carries over between steps.
pub(crate) fn work_len(grid: &Grid) -> usize {
    (5 + grid.dims()) * grid.padded().iter().product::<usize>()
}

/// A step's work arrays, cut from one block of [`work_len`] values.
struct Work<'a> {
    /// Frozen indicator `c_c = [φⁿ > ½]` (interior cells).
    cc: &'a mut [f64],
    /// Interface per padded cell: normal x, normal y, normal z (empty in two dimensions), and
    /// its constant α (cell-local coordinates).
    plane: [&'a mut [f64]; 4],
    /// Phase flux `F` and volume flux `U` per face of the current sweep.
    flux: &'a mut [f64],
    vflux: &'a mut [f64],
    /// Net volume outflux per cell summed over the sweeps of the step (`∇·u Δt V`, ≈ 0).
    divsum: &'a mut [f64],
}

impl<'a> Work<'a> {
    fn cut(block: &'a mut [f64], cells: usize, dims: usize) -> Self {
        let (cc, rest) = block[..(5 + dims) * cells].split_at_mut(cells);
        let (mx, rest) = rest.split_at_mut(cells);
        let (my, rest) = rest.split_at_mut(cells);
        let (mz, rest) = rest.split_at_mut(if dims == 3 { cells } else { 0 });
        let (al, rest) = rest.split_at_mut(cells);
        let (flux, rest) = rest.split_at_mut(cells);
        let (vflux, divsum) = rest.split_at_mut(cells);
        Work {
            cc,
            plane: [mx, my, mz, al],
            flux,
            vflux,
            divsum,
        }
    }
}

/// One line's share of the clipping statistics of an update (folded in line order).
#[derive(Clone, Copy, Debug, Default)]
struct RowStats {
    max_clipped: f64,
    /// Clipped volume.
    volume: f64,
}

/// The fluxed slab of a face's upwind cell in two dimensions: the cell size, and the cell's
/// PLIC line and the radius of its left edge (0 in planar geometry).
struct Slab {
    dx: f64,
    dy: f64,
    line: [f64; 3],
    r_left: f64,
}

impl Slab {
    /// Fraction (r-weighted in axisymmetric geometry) of the fluxed slab of the upwind cell
    /// below its line; `w` is the slab width, `pos` whether the flow is towards `+d` (slab at
    /// the high side of the cell).
    #[inline(always)]
    fn fraction<const K: u8, const D: usize>(&self, w: f64, pos: bool) -> f64 {
        let (dx, dy) = (self.dx, self.dy);
        let [mx, my, al] = self.line;
        // Slab origin in cell-local coordinates and its size.
        let (ox, oy, sw, sh) = match (D, pos) {
            (0, true) => (dx - w, 0.0, w, dy),
            (0, false) => (0.0, 0.0, w, dy),
            (_, true) => (0.0, dy - w, dx, w),
            (_, false) => (0.0, 0.0, dx, w),
        };
        let a = al - mx * ox - my * oy;
        if K == AXI {
            let r0 = self.r_left + ox;
            let (area, m1) = half_plane_moments(mx, my, a, sw, sh);
            let slab = (r0 + 0.5 * sw) * sw * sh;
            ((r0 * area + m1) / slab).clamp(0.0, 1.0)
        } else {
            rect_fraction(mx, my, a, sw, sh)
        }
    }
}

impl VofAdvector {
    /// An advector for `grid` with the given sides.
    ///
    /// # Panics
    /// If [`VofBoundaries::validate`] fails (use [`Self::try_new`] to get the message instead).
    pub fn new(grid: &Grid, bounds: VofBoundaries) -> Self {
        Self::try_new(grid, bounds).unwrap_or_else(|e| panic!("{e}"))
    }

    /// An advector for `grid` with the given sides, or why the sides do not fit the grid.
    pub fn try_new(grid: &Grid, bounds: VofBoundaries) -> Result<Self, String> {
        let mut a = Self::lending(grid, bounds)?;
        a.own = vec![0.0; work_len(grid)];
        Ok(a)
    }

    /// An advector without work arrays of its own: its steps borrow them
    /// ([`Self::step_in`]).
    pub(crate) fn lending(grid: &Grid, bounds: VofBoundaries) -> Result<Self, String> {
        Self::lending_in(grid, bounds, grid, [0; 3])
    }

    /// An advector for the box of cells `window` of the grid `parent`, whose cell `[0, 0, 0]`
    /// is the parent's cell `lo` ([`super::bodies`]): the shape of its fields is `window`'s,
    /// its cell sizes and metric (the radii of an axisymmetric grid) are the parent's at the
    /// same cells, so a step on the window computes, cell by cell, what a step on the parent
    /// does there. Without work arrays of its own ([`Self::step_in`]).
    pub(crate) fn lending_in(
        window: &Grid,
        bounds: VofBoundaries,
        parent: &Grid,
        lo: [usize; 3],
    ) -> Result<Self, String> {
        let grid = window;
        bounds.validate(grid)?;
        let axi = grid.is_axisymmetric();
        let kind = if grid.is_3d() {
            CUBE
        } else if axi {
            AXI
        } else {
            PLANAR
        };
        let cells = grid.padded().iter().product();
        // The padded columns, in storage order, as the parent's columns.
        let padded_row = Region::whole(grid).line(0);
        let columns = || padded_row.indices().map(|[i, _, _]| i + lo[0] as isize);
        let [dx, dy, dz] = parent.h();
        Ok(VofAdvector {
            bounds,
            kind,
            n: grid.n(),
            h: parent.h(),
            area: [dy * dz, dx * dz, dx * dy],
            cells,
            interior: Region::of(grid, Stagger::Cell),
            own: Vec::new(),
            inv_vol: columns()
                .map(|i| 1.0 / (parent.cell_volume(i) * dz))
                .collect(),
            r_left: columns()
                .map(|i| if axi { parent.xf(i) } else { 0.0 })
                .collect(),
            r_face: columns().map(|i| parent.metric.rx(i)).collect(),
            r_centre: columns().map(|i| parent.metric.rc(i)).collect(),
        })
    }

    /// The sides this advector was built with.
    pub fn boundaries(&self) -> VofBoundaries {
        self.bounds
    }

    /// Advance `phi` (cell-centred) by `dt` on the face velocities `vel`, one per axis of the
    /// grid (u on x-faces, v on y-faces, w on z-faces). `step_index` selects the sweep order
    /// (even: x first).
    ///
    /// Ghost cells of `phi` are overwritten. No heap allocation.
    pub fn step(
        &mut self,
        grid: &Grid,
        phi: &mut Field,
        vel: &[&Field],
        dt: f64,
        step_index: u64,
    ) -> AdvectStats {
        let mut own = std::mem::take(&mut self.own);
        let st = self.step_in(&mut own, grid, phi, vel, dt, step_index);
        self.own = own;
        st
    }

    /// [`step`](Self::step) in the borrowed work arrays `work` (at least [`work_len`]
    /// values; their contents on entry do not matter).
    pub(crate) fn step_in(
        &mut self,
        work: &mut [f64],
        grid: &Grid,
        phi: &mut Field,
        vel: &[&Field],
        dt: f64,
        step_index: u64,
    ) -> AdvectStats {
        let dims = grid.dims();
        assert_eq!(vel.len(), dims, "one velocity component per axis");
        debug_assert!(grid.n() == self.n, "grid mismatch");
        debug_assert_eq!(phi.data().len(), self.cells);
        let mut w = Work::cut(work, self.cells, dims);
        let src = &*phi;
        self.interior
            .for_each(self.interior.storage(w.cc), |l, cc| {
                for (c, f) in cc.iter_mut().zip(src.at(&l, [0; 3])) {
                    *c = if *f > 0.5 { 1.0 } else { 0.0 };
                }
            });
        let mut stats = AdvectStats::default();
        let mut order = [0, 1, 2];
        let order = &mut order[..dims];
        if !step_index.is_multiple_of(2) {
            order.reverse();
        }
        for (n, &d) in order.iter().enumerate() {
            let pass = Pass {
                first: n == 0,
                last: n == dims - 1,
            };
            let v = vel[d];
            let s = match (self.kind, d) {
                (PLANAR, 0) => self.sweep::<PLANAR, 0>(&mut w, phi, v, dt, pass),
                (PLANAR, _) => self.sweep::<PLANAR, 1>(&mut w, phi, v, dt, pass),
                (AXI, 0) => self.sweep::<AXI, 0>(&mut w, phi, v, dt, pass),
                (AXI, _) => self.sweep::<AXI, 1>(&mut w, phi, v, dt, pass),
                (_, 0) => self.sweep::<CUBE, 0>(&mut w, phi, v, dt, pass),
                (_, 1) => self.sweep::<CUBE, 1>(&mut w, phi, v, dt, pass),
                (_, _) => self.sweep::<CUBE, 2>(&mut w, phi, v, dt, pass),
            };
            stats.merge(s);
        }
        stats
    }

    /// Fill the ghost layers of `phi` (even reflection at closed sides, wrap at periodic ones),
    /// axis by axis: the ghosts along axis `a` over the interior of the later axes and the
    /// ghosts of the earlier ones, so edge and corner ghosts are consistent.
    pub fn fill_ghosts(&self, phi: &mut Field) {
        let dims = if self.kind == CUBE { 3 } else { 2 };
        for a in 0..dims {
            let n = self.n[a] as isize;
            let per = self.bounds.along(a).0 == VofSide::Periodic;
            let mut across = self.interior;
            for b in 0..a {
                across = across.range(b, -G, self.n[b] as isize + G);
            }
            if a == 0 {
                // Lines run along x: each row's ghosts at both ends in one pass.
                let rows = across.range(0, 0, n);
                let data = phi.data_mut();
                for k in 0..rows.lines() {
                    let first = rows.line(k).linear(0);
                    for g in 1..=G {
                        let (lo, hi) = if per { (n - g, g - 1) } else { (g - 1, n - g) };
                        data[first - g as usize] = data[first + lo as usize];
                        data[first + (n - 1 + g) as usize] = data[first + hi as usize];
                    }
                }
                continue;
            }
            let step = phi.offset(unit(a));
            for g in 1..=G {
                // Ghost `−g` from `lo`, ghost `n − 1 + g` from `hi`.
                let (lo, hi) = if per { (n - g, g - 1) } else { (g - 1, n - g) };
                for (ghost, from) in [(-g, lo), (n - 1 + g, hi)] {
                    let plane = across.range(a, ghost, ghost + 1);
                    let shift = (from - ghost) * step;
                    let data = phi.data_mut();
                    for k in 0..plane.lines() {
                        let l = plane.line(k);
                        let to = l.linear(0);
                        let src = to.checked_add_signed(shift).expect("inside the storage");
                        data.copy_within(src..src + l.len, to);
                    }
                }
            }
        }
    }

    /// Reconstruct the interface of every cut cell of `cells`, lines in parallel.
    fn reconstruct<const K: u8>(&self, plane: &mut [&mut [f64]; 4], phi: &Field, cells: Region) {
        let [dx, dy, _] = self.h;
        let r_left = &self.r_left;
        let [mx, my, mz, al] = plane;
        if K == CUBE {
            let h = self.h;
            let out = (
                (cells.storage(mx), cells.storage(my)),
                (cells.storage(mz), cells.storage(al)),
            );
            cells.for_each(out, |l, ((mx, my), (mz, al))| {
                let c: [[[&[f64]; 3]; 3]; 3] = std::array::from_fn(|c| {
                    std::array::from_fn(|b| {
                        std::array::from_fn(|a| {
                            phi.at(&l, [a as isize - 1, b as isize - 1, c as isize - 1])
                        })
                    })
                });
                for k in 0..l.len {
                    let f = c[1][1][1][k];
                    if f <= 0.0 || f >= 1.0 {
                        continue;
                    }
                    let b: Block = c.map(|c| c.map(|b| b.map(|a| a[k])));
                    let p = Plane::new(myc_normal(&b, h), f, h);
                    (mx[k], my[k], mz[k], al[k]) = (p.n[0], p.n[1], p.n[2], p.alpha);
                }
            });
            return;
        }
        let out = (cells.storage(mx), cells.storage(my), cells.storage(al));
        cells.for_each(out, |l, (mx, my, al)| {
            let c = |di: isize, dj: isize| phi.at(&l, [di, dj, 0]);
            let (s, m, n) = (
                [c(-1, -1), c(0, -1), c(1, -1)],
                [c(-1, 0), c(0, 0), c(1, 0)],
                [c(-1, 1), c(0, 1), c(1, 1)],
            );
            let rl = l.cols(r_left, 0);
            for k in 0..l.len {
                let f = m[1][k];
                if f <= 0.0 || f >= 1.0 {
                    continue;
                }
                let b = [
                    [s[0][k], s[1][k], s[2][k]],
                    [m[0][k], m[1][k], m[2][k]],
                    [n[0][k], n[1][k], n[2][k]],
                ];
                let (x, y) = youngs_normal(&b, dx, dy);
                let alpha = if K == AXI {
                    axi_alpha(x, y, f, rl[k], dx, dy)
                } else {
                    rect_alpha(x, y, f, dx, dy)
                };
                (mx[k], my[k], al[k]) = (x, y, alpha);
            }
        });
    }

    /// One sweep along `D` with the face velocity `vel` normal to it. The `last` sweep of a
    /// step also takes back the net divergence of the step's correction terms: `c_c ∇·u` is
    /// what the split needs between its sweeps, but summed over the step, `c_c (∇·u) Δt`, it is
    /// not zero for a velocity that is divergence-free only to the projection's tolerance, and
    /// it changed the phase's volume by ~3e-12 per step (3.7e-9 over the soft-wall run).
    /// Without it the step is in flux form: conservative to round-off. (A cell whose net
    /// divergence exceeds that residual, 1e-8 of its volume per step, keeps the correction.)
    fn sweep<const K: u8, const D: usize>(
        &mut self,
        w: &mut Work,
        phi: &mut Field,
        vel: &Field,
        dt: f64,
        pass: Pass,
    ) -> AdvectStats {
        self.fill_ghosts(phi);
        // Cells in the interior, plus the ghost layer that can be upwind of a periodic face.
        let g = if self.bounds.along(D).0 == VofSide::Periodic {
            1
        } else {
            0
        };
        let n = self.n[D] as isize;
        let cells = self.interior.range(D, -g, n + g);
        self.reconstruct::<K>(&mut w.plane, phi, cells);
        let cfl = self.fluxes::<K, D>(w, phi, vel, dt);
        let mut st = self.update::<D>(w, phi, pass);
        st.cfl = cfl;
        // Give the clipped volume back (round-off overshoots of ~1e-13 per cell add up over
        // thousands of cells and steps): to the interface cells, in proportion to their room
        // `φ(1 − φ)`.
        if st.clipped_volume != 0.0 {
            self.give_back(phi, st.clipped_volume);
        }
        st
    }

    /// The phase flux `F` and volume flux `U` of every face normal to `D` into `w.flux`,
    /// `w.vflux` (face `I` shares the storage index of cell `I`, its high neighbour), lines in
    /// parallel; returns the sweep's CFL number `max |U|/V` of the upwind cells.
    fn fluxes<const K: u8, const D: usize>(
        &mut self,
        w: &mut Work,
        phi: &Field,
        vel: &Field,
        dt: f64,
    ) -> f64 {
        let (lo_side, hi_side) = self.bounds.along(D);
        let periodic = lo_side == VofSide::Periodic;
        let nd = self.n[D] as isize;
        // The faces normal to D; the high periodic face of a sweep across lines is the low one
        // (copied below), that of a sweep along them is copied on its line.
        let all = self
            .interior
            .range(D, 0, nd + if D != 0 && periodic { 0 } else { 1 });
        let [mx, my, mz, al] = &w.plane;
        let face = Face {
            h: self.h,
            area: self.area[D],
            plane: [&**mx, &**my, &**mz, &**al],
            c: phi,
            r_area: if D == 0 { &self.r_face } else { &self.r_centre },
            r_left: &self.r_left,
            inv_vol: &self.inv_vol,
        };
        let out = (all.storage(w.vflux), all.storage(w.flux));
        let cfl = all.fold_mut(
            out,
            0.0f64,
            |l, (u, f)| {
                let v = vel.at(&l, [0; 3]);
                let face = face.on::<D>(&l);
                let mut cfl = 0.0f64;
                for n in 0..l.len {
                    let p = l.index(n)[D];
                    if D == 0 && p == nd && periodic {
                        (u[n], f[n]) = (u[0], f[0]);
                        continue;
                    }
                    let closed = (p == 0 && lo_side == VofSide::Closed)
                        || (p == nd && hi_side == VofSide::Closed);
                    let sv = v[n] * dt;
                    (u[n], f[n]) = if closed || sv == 0.0 {
                        (0.0, 0.0)
                    } else {
                        face.flux::<K, D>(n, sv, &mut cfl)
                    };
                }
                cfl
            },
            f64::max,
        );
        if D != 0 && periodic {
            let across = phi.offset(unit(D)) * nd;
            let low = self.interior.range(D, 0, 1);
            for k in 0..low.lines() {
                let l = low.line(k);
                let (from, to) = (l.linear(0), l.linear(0).wrapping_add_signed(across));
                w.vflux.copy_within(from..from + l.len, to);
                w.flux.copy_within(from..from + l.len, to);
            }
        }
        cfl
    }

    /// `φ += (F_low − F_high + c_c (U_high − U_low))/V` along `D`, clipped to `[0, 1]` (the
    /// statistics of the clipping returned), lines in parallel; the divergence of the sweeps
    /// before the last is summed in `w.divsum` for the last one.
    fn update<const D: usize>(&mut self, w: &mut Work, phi: &mut Field, pass: Pass) -> AdvectStats {
        let o = unit(D);
        let inv_vol = &self.inv_vol;
        let (f, uu, cc) = (&*w.flux, &*w.vflux, &*w.cc);
        let cells = self.interior;
        let line = |l: Line, (phi, div): (&mut [f64], &mut [f64])| {
            let (f0, f1, u0, u1) = (l.on(f, [0; 3]), l.on(f, o), l.on(uu, [0; 3]), l.on(uu, o));
            let (cc, iv) = (l.on(cc, [0; 3]), l.cols(inv_vol, 0));
            let mut st = RowStats::default();
            for n in 0..l.len {
                let d = u1[n] - u0[n];
                let mut val = phi[n] + (f0[n] - f1[n] + cc[n] * d) * iv[n];
                if pass.last {
                    // Only the projection's residual (a volume change below 1e-8 of the
                    // cell per step): a genuinely compressing field keeps W&Y's
                    // treatment, which keeps a full cell full.
                    let net = (div[n] + d) * iv[n];
                    if net.abs() <= 1e-8 {
                        val -= cc[n] * net;
                    }
                } else if pass.first {
                    div[n] = d;
                } else {
                    div[n] += d;
                }
                debug_assert!(val.is_finite(), "VOF: non-finite φ at {:?}", l.index(n));
                let clipped = if val < WISP {
                    0.0
                } else if val > 1.0 - WISP {
                    1.0
                } else {
                    val
                };
                if clipped != val {
                    st.max_clipped = st.max_clipped.max((clipped - val).abs());
                    st.volume += (clipped - val) / iv[n];
                    val = clipped;
                }
                phi[n] = val;
            }
            st
        };
        cells.fold_mut(
            (phi, cells.storage(w.divsum)),
            AdvectStats::default(),
            line,
            |mut st, r: RowStats| {
                st.max_clipped = st.max_clipped.max(r.max_clipped);
                st.clipped_volume += r.volume;
                st
            },
        )
    }

    /// `φ −= volume·φ(1 − φ)/Σ φ(1 − φ)V` on the interior: `volume` given back to the
    /// interface cells in proportion to their room (nothing if there is none).
    fn give_back(&self, phi: &mut Field, volume: f64) {
        let inv_vol = &self.inv_vol;
        let [room] = self.interior.sum(|l| {
            let (c, iv) = (phi.at(&l, [0; 3]), l.cols(inv_vol, 0));
            let mut room = 0.0;
            for (c, iv) in c.iter().zip(iv) {
                room += c * (1.0 - c) / iv;
            }
            [room]
        });
        if room > 0.0 {
            let scale = volume / room;
            self.interior.for_each(phi, |_, phi| {
                for c in phi {
                    *c -= scale * *c * (1.0 - *c);
                }
            });
        }
    }
}

/// Where a sweep stands in its step: the first sweep starts the step's divergence sum, the
/// last takes it back.
#[derive(Clone, Copy, Debug)]
struct Pass {
    first: bool,
    last: bool,
}

/// What the flux of a face reads: the cell size, the face area without its radius factor, the
/// reconstructed interfaces and the volume fractions `c`, and the metric per padded column.
struct Face<'a> {
    h: [f64; 3],
    area: f64,
    plane: [&'a [f64]; 4],
    c: &'a Field,
    /// `r_f` (x-faces) or `r_c` (the other faces): the face area's radius factor.
    r_area: &'a [f64],
    r_left: &'a [f64],
    inv_vol: &'a [f64],
}

/// [`Face`] on one line of faces normal to `D`: the values of the faces' two cells, `[low
/// neighbour, own (high) cell]`, and the face area's radius factor.
struct FaceLine<'a> {
    h: [f64; 3],
    area: f64,
    c: [&'a [f64]; 2],
    plane: [[&'a [f64]; 4]; 2],
    r_left: [&'a [f64]; 2],
    inv_vol: [&'a [f64]; 2],
    r_area: &'a [f64],
}

impl<'a> Face<'a> {
    /// The values a line of faces normal to `D` reads.
    #[inline(always)]
    fn on<const D: usize>(&self, l: &Line) -> FaceLine<'a> {
        let lo = efsi_core::operators::minus(D);
        // The z component of a two-dimensional interface is absent (an empty array).
        let at = |a: &'a [f64], s: efsi_core::Index| if a.is_empty() { a } else { l.on(a, s) };
        FaceLine {
            h: self.h,
            area: self.area,
            c: [self.c.at(l, lo), self.c.at(l, [0; 3])],
            plane: [
                self.plane.map(|a| at(a, lo)),
                self.plane.map(|a| at(a, [0; 3])),
            ],
            r_left: [l.cols(self.r_left, lo[0]), l.cols(self.r_left, 0)],
            inv_vol: [l.cols(self.inv_vol, lo[0]), l.cols(self.inv_vol, 0)],
            r_area: l.cols(self.r_area, 0),
        }
    }
}

impl FaceLine<'_> {
    /// The volume flux `U` and phase flux `F` of the line's `n`-th face for the displacement
    /// `sv = vel·Δt ≠ 0`, raising `cfl` to the upwind cell's `|U|/V`.
    #[inline(always)]
    fn flux<const K: u8, const D: usize>(&self, n: usize, sv: f64, cfl: &mut f64) -> (f64, f64) {
        let pos = sv > 0.0;
        // The upwind cell: the low neighbour along D (0) or the face's own cell (1).
        let up = usize::from(!pos);
        let r = self.r_area[n];
        let w = if K == AXI && D == 0 {
            let disc = (r * r - 2.0 * r * sv).max(0.0);
            2.0 * r * sv.abs() / (r + disc.sqrt())
        } else {
            sv.abs()
        };
        let (area, w) = (r * self.area, w.min(self.h[D]));
        let big_u = area * sv;
        if big_u == 0.0 {
            return (big_u, 0.0);
        }
        *cfl = cfl.max(big_u.abs() * self.inv_vol[up][n]);
        let cu = self.c[up][n];
        let frac = if cu <= 0.0 {
            0.0
        } else if cu >= 1.0 {
            1.0
        } else {
            let p = &self.plane[up];
            if K == CUBE {
                let plane = Plane {
                    n: [p[0][n], p[1][n], p[2][n]],
                    alpha: p[3][n],
                };
                plane.slab_fraction(self.h, D, w, pos)
            } else {
                let slab = Slab {
                    dx: self.h[0],
                    dy: self.h[1],
                    line: [p[0][n], p[1][n], p[3][n]],
                    r_left: self.r_left[up][n],
                };
                slab.fraction::<K, D>(w, pos)
            }
        };
        (big_u, big_u * frac)
    }
}

/// The phase volume `Σ φ V` over the interior (per radian in axisymmetric geometry, per unit
/// depth in planar), summed in storage order with Neumaier's compensated summation so it can
/// be compared to round-off.
pub fn phase_volume(grid: &Grid, phi: &Field) -> f64 {
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    let cells = Region::of(grid, Stagger::Cell);
    for n in 0..cells.lines() {
        let l = cells.line(n);
        for (c, [i, _, _]) in phi.at(&l, [0; 3]).iter().zip(l.indices()) {
            let x = c * grid.cell_volume(i) * grid.dz;
            let t = sum + x;
            comp += if sum.abs() >= x.abs() {
                (sum - t) + x
            } else {
                (x - t) + sum
            };
            sum = t;
        }
    }
    sum + comp
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::Geometry;

    fn grid(geom: Geometry, n: usize) -> Grid {
        Grid::new(geom, n, n, (0.0, 1.0), (0.0, 1.0))
    }

    #[test]
    fn ghosts_wrap_and_reflect() {
        let g = grid(Geometry::Planar, 4);
        let mut phi = Field::zeros(&g);
        for j in 0..4 {
            for i in 0..4 {
                phi[(i, j)] = (10 * j + i) as f64;
            }
        }
        let a = VofAdvector::new(&g, VofBoundaries::periodic(true, false));
        a.fill_ghosts(&mut phi);
        assert_eq!(phi[(-1, 2)], phi[(3, 2)]);
        assert_eq!(phi[(-2, 2)], phi[(2, 2)]);
        assert_eq!(phi[(4, 1)], phi[(0, 1)]);
        assert_eq!(phi[(5, 1)], phi[(1, 1)]);
        assert_eq!(phi[(1, -1)], phi[(1, 0)]);
        assert_eq!(phi[(1, -2)], phi[(1, 1)]);
        assert_eq!(phi[(2, 4)], phi[(2, 3)]);
        assert_eq!(phi[(-1, -1)], phi[(3, 0)], "corner ghosts are consistent");
    }

    #[test]
    fn ghosts_wrap_and_reflect_in_three_dimensions() {
        let g = Grid::new_3d([4, 3, 5], (0.0, 1.0), (0.0, 0.75), (0.0, 1.25));
        let mut phi = Field::zeros(&g);
        for k in 0..5 {
            for j in 0..3 {
                for i in 0..4 {
                    phi[[i, j, k]] = (100 * k + 10 * j + i) as f64;
                }
            }
        }
        let a = VofAdvector::new(&g, VofBoundaries::periodic_axes([true, false, true]));
        a.fill_ghosts(&mut phi);
        // x: wrap; y: reflect; z: wrap.
        assert_eq!(phi[[-1, 1, 2]], phi[[3, 1, 2]]);
        assert_eq!(phi[[5, 1, 2]], phi[[1, 1, 2]]);
        assert_eq!(phi[[2, -2, 2]], phi[[2, 1, 2]]);
        assert_eq!(phi[[2, 3, 2]], phi[[2, 2, 2]]);
        assert_eq!(phi[[2, 1, -1]], phi[[2, 1, 4]]);
        assert_eq!(phi[[2, 1, 6]], phi[[2, 1, 1]]);
        // Edge and corner ghosts: the composition of the three.
        assert_eq!(phi[[-1, -1, 2]], phi[[3, 0, 2]]);
        assert_eq!(phi[[-2, 4, -2]], phi[[2, 1, 3]]);
        assert_eq!(phi[[4, -1, 5]], phi[[0, 0, 0]]);
    }

    #[test]
    fn uniform_translation_of_a_full_block_is_exact() {
        // A band of full cells moved by exactly one cell per two steps (CFL ½) along x, periodic:
        // after 2·n steps it is back where it started, bit for bit up to round-off.
        for geom in [Geometry::Planar] {
            let n = 16;
            let g = grid(geom, n);
            let mut phi = Field::zeros(&g);
            for j in 0..n as isize {
                for i in 3..7 {
                    phi[(i, j)] = 1.0;
                }
                phi[(7, j)] = 0.3;
            }
            let phi0 = phi.clone();
            let u = Field::filled(&g, 1.0);
            let v = Field::zeros(&g);
            let mut a = VofAdvector::new(&g, VofBoundaries::periodic(true, true));
            let dt = 0.5 * g.dx;
            for s in 0..2 * n as u64 {
                let st = a.step(&g, &mut phi, &[&u, &v], dt, s);
                assert!((st.cfl - 0.5).abs() < 1e-14);
                assert!(st.max_clipped < 1e-14);
            }
            for j in 0..n as isize {
                for i in 0..n as isize {
                    assert!((phi[(i, j)] - phi0[(i, j)]).abs() < 1e-13, "({i},{j})");
                }
            }
        }
    }

    #[test]
    fn closed_sides_stop_the_flux() {
        let g = grid(Geometry::Axisymmetric, 8);
        let mut phi = Field::filled(&g, 1.0);
        let u = Field::filled(&g, 0.3);
        let v = Field::filled(&g, -0.7);
        let mut a = VofAdvector::new(&g, VofBoundaries::closed());
        let v0 = phase_volume(&g, &phi);
        let st = a.step(&g, &mut phi, &[&u, &v], 0.05, 0);
        // Not divergence-free, but a full domain stays full: F = U everywhere and c_c = 1.
        assert!(st.max_clipped == 0.0);
        assert!((phase_volume(&g, &phi) - v0).abs() < 1e-15);
    }

    #[test]
    fn validation_rejects_bad_sides() {
        let g = grid(Geometry::Axisymmetric, 8);
        assert!(VofBoundaries::periodic(true, false).validate(&g).is_err());
        assert!(VofBoundaries::periodic(false, true).validate(&g).is_ok());
        let mut b = VofBoundaries::closed();
        b.y_lo = VofSide::Periodic;
        assert!(b.validate(&g).is_err());
    }
}
