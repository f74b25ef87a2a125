//! Several bodies, each transported on its own: the volume fraction `φ_k` of body `k` in a
//! window of the grid that follows it.
//!
//! # Rule
//!
//! Each body's fraction obeys the transport equation of [`super::advect`],
//!
//! ```text
//!     ∂φ_k/∂t + ∇·(φ_k u) − φ_k ∇·u = 0,     k = 1 … K,
//! ```
//!
//! advanced by the same split PLIC step (the one kernel of [`VofAdvector`], planar,
//! axisymmetric and three-dimensional) on the same velocity. Bodies are never merged: a cell
//! holding two bodies holds two fractions, each reconstructed and fluxed with its own
//! interface, so two bodies that meet stay two fields and part again when the flow parts them.
//! The mixture of the materials in a cell is
//!
//! ```text
//!     ρ = (1 − Σ_k φ_k) ρ_f + Σ_k φ_k ρ_k,     μ = (1 − Σ_k φ_k) μ_f + Σ_k φ_k μ_k,
//! ```
//!
//! the bodies summed in the scene's order, and the state's solid fraction is `Σ_k φ_k`.
//!
//! # Storage: a window per body
//!
//! `φ_k` is held on a box of cells, its window ([`BodyWindow`]): the cells where `φ_k ≠ 0`
//! (its support) and a margin of [`MARGIN`] cells around them, clipped to the domain, and the
//! whole axis along a periodic axis. Memory and work scale with the bodies' extent, not with
//! the grid times the number of bodies; each window holds the work arrays of its step, sized
//! for the window, so the bodies step in parallel. Before every (sub-)step the window is moved
//! — a new box around the support, the values copied — when the support comes within
//! [`NEAR`] cells of a window side that is not a side of the domain.
//!
//! **Why a window step is the full-grid step, bit for bit.** One sweep at Courant number ≤ ½
//! moves phase only into the next cell along its axis, so a step of `d` sweeps grows the
//! support by at most one cell along each axis. With the support at least [`NEAR`] = 3 cells
//! inside every inner window side at the start of a step, every cut cell's 3×3(×3)
//! reconstruction block lies inside the window, and every cell of the window's edge, and its
//! outside neighbour, is empty: the full grid's flux through a window side is `F = 0` (empty
//! upwind cell), as the window's closed side gives, and its volume flux `U` enters the update
//! only through the indicator `c_c = 0` of empty cells. The advector takes its cell sizes and
//! radii from the parent grid at the same cells (`VofAdvector::lending_in`), and the step's
//! sums (clipped volume, the room of the give-back) add the same non-zero terms in the same
//! order, lines in storage order. A test asserts the equality (planar, axisymmetric, 3-D,
//! with window moves).
//!
//! # Limits
//!
//! The window of a body that spans the domain is the domain. The transport keeps each body's
//! `0 ≤ φ_k ≤ 1` and volume; it does not keep `Σ_k φ_k ≤ 1` in a cell that two bodies enter
//! together (each reconstructs its own interface as if the rest of the cell were fluid): bodies
//! must be kept a film apart, by the resolved fluid and, below a cell, by the contact stage's
//! repulsion ([`crate::contact`]); the probe `SolidOverlap` (`max_solid_fraction_sum`) shows
//! `max Σ_k φ_k` at every output, and `BodyContact` the cells two bodies share.
//!
//! # Elastic bodies
//!
//! Each body with a law keeps its own deformation `B_k`, weighted by this module's `φ_k`
//! (which the state's `BodyFractions` carries to the elastic stage), and its own law; the
//! cell's stress is the sum of the bodies' and the implicit system's tangent the sum of theirs
//! (the elastic stage's `bodies` module), so the histories of two bodies never mix, even where
//! they share a cell. Its deformation lives on a window of its own that contains this one
//! (this window grown by a margin: the elastic stage's `bodies` module, "Storage"), placed
//! anew when this one moves. Contact below a cell's gap is the contact stage's
//! ([`crate::contact`]).

use super::advect::{AdvectStats, VofAdvector, VofBoundaries, VofSide};
use efsi_core::body_fractions::BodyFraction;
use efsi_core::{Field, G, Grid, Region, Stagger};

/// Cells of margin a window keeps around its body's support when it is (re)placed: one more
/// than [`NEAR`], so a window placed anew moves again only once its support has grown two
/// cells toward an inner side. The step's equality with the full grid's asks for [`NEAR`] alone
/// (module docs); a wider margin would move the window less often at the price of a larger
/// window, which every step pays for here and in the elastic window around it.
pub const MARGIN: usize = NEAR + 1;

/// The fewest cells between a body's support and an inner side of its window before a step:
/// closer, the window moves first (see the module docs for why 3 keeps a window step equal to
/// the full-grid step).
pub const NEAR: usize = 3;

/// One body's fraction on its window of the grid.
#[derive(Clone, Debug)]
pub struct BodyWindow {
    /// The parent cell of the window's cell `[0, 0, 0]`.
    lo: [usize; 3],
    /// The window as a grid: the shape of its fields (its coordinates are not used).
    grid: Grid,
    /// The advector on the window, with the parent's metric.
    advector: VofAdvector,
    /// `φ_k` on the window (ghosts by the window's sides).
    phi: Field,
    /// The face velocities copied onto the window, one per axis.
    vel: Vec<Field>,
    /// The advector's work arrays, sized for the window ([`super::advect::work_len`]): each
    /// body's own, so the bodies step in parallel.
    work: Vec<f64>,
    /// The sides of the parent grid.
    bounds: VofBoundaries,
}

/// The window sides: periodic along the parent's periodic axes (there the window spans the
/// axis), closed elsewhere.
fn window_bounds(bounds: VofBoundaries) -> VofBoundaries {
    let p = |a: usize| bounds.along(a).0 == VofSide::Periodic;
    VofBoundaries::periodic_axes([p(0), p(1), p(2)])
}

/// The interior cells of `phi` where it is not zero: the lowest and highest index along each
/// axis, or `None` if there is none.
fn support(grid: &Grid, phi: &Field) -> Option<([usize; 3], [usize; 3])> {
    let cells = Region::of(grid, Stagger::Cell);
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for n in 0..cells.lines() {
        let l = cells.line(n);
        for (f, idx) in phi.at(&l, [0; 3]).iter().zip(l.indices()) {
            if *f != 0.0 {
                for a in 0..3 {
                    let i = idx[a] as usize;
                    lo[a] = lo[a].min(i);
                    hi[a] = hi[a].max(i);
                }
            }
        }
    }
    (lo[0] != usize::MAX).then_some((lo, hi))
}

impl BodyWindow {
    /// The window of the body whose fraction on the whole of `parent` is `phi` (interior
    /// cells read); an error if the sides do not fit the grid.
    pub fn around(parent: &Grid, bounds: VofBoundaries, phi: &Field) -> Result<Self, String> {
        let (lo, hi) = support(parent, phi).unwrap_or(([0; 3], [0; 3]));
        let mut w = Self::placed(parent, bounds, lo, hi)?;
        w.copy_in(phi);
        Ok(w)
    }

    /// An empty window around the parent cells `lo..=hi` with [`MARGIN`] cells about them.
    fn placed(
        parent: &Grid,
        bounds: VofBoundaries,
        lo: [usize; 3],
        hi: [usize; 3],
    ) -> Result<Self, String> {
        let dims = parent.dims();
        let pn = parent.n();
        let mut wlo = [0usize; 3];
        let mut wn = [1usize; 3];
        for a in 0..dims {
            if bounds.along(a).0 == VofSide::Periodic {
                wn[a] = pn[a];
                continue;
            }
            let a0 = lo[a].saturating_sub(MARGIN);
            let a1 = (hi[a] + 1 + MARGIN).min(pn[a]);
            // At least two cells (the advector's least).
            let a0 = a0.min(pn[a].saturating_sub(2));
            wlo[a] = a0;
            wn[a] = (a1 - a0).max(2);
        }
        Self::at(parent, bounds, wlo, wn)
    }

    /// An empty window of `wn` cells whose cell `[0, 0, 0]` is the parent cell `wlo`.
    fn at(
        parent: &Grid,
        bounds: VofBoundaries,
        wlo: [usize; 3],
        wn: [usize; 3],
    ) -> Result<Self, String> {
        let dims = parent.dims();
        let pn = parent.n();
        if (0..dims).any(|a| wn[a] < 2 || wlo[a] + wn[a] > pn[a]) {
            return Err(format!(
                "a window of {wn:?} cells at {wlo:?} does not fit the grid of {pn:?} cells"
            ));
        }
        let h = parent.h();
        let span =
            |a: usize, o: f64| (o + wlo[a] as f64 * h[a], o + (wlo[a] + wn[a]) as f64 * h[a]);
        let grid = if parent.is_3d() {
            Grid::new_3d(
                wn,
                span(0, parent.x0),
                span(1, parent.y0),
                span(2, parent.z0),
            )
        } else {
            Grid::new(
                parent.geometry,
                wn[0],
                wn[1],
                span(0, parent.x0),
                span(1, parent.y0),
            )
        };
        let wb = window_bounds(bounds);
        let advector = VofAdvector::lending_in(&grid, wb, parent, wlo)?;
        Ok(BodyWindow {
            lo: wlo,
            phi: Field::zeros(&grid),
            vel: (0..dims).map(|_| Field::zeros(&grid)).collect(),
            work: Vec::new(),
            advector,
            grid,
            bounds,
        })
    }

    /// The window's first parent cell and its cells along each axis.
    pub fn extent(&self) -> ([usize; 3], [usize; 3]) {
        (self.lo, self.grid.n())
    }

    /// Add `scale·φ_k` into the interior cells of `out` (a field of the parent grid).
    pub fn add_into(&self, out: &mut Field, scale: f64) {
        let [nx, ny, nz] = self.grid.n();
        let o = self.lo.map(|v| v as isize);
        for k in 0..nz as isize {
            for j in 0..ny as isize {
                let from = self.phi.idx3([0, j, k]);
                let to = out.idx3([o[0], j + o[1], k + o[2]]);
                let row = &self.phi.data()[from..from + nx];
                for (t, f) in out.data_mut()[to..to + nx].iter_mut().zip(row) {
                    *t += scale * f;
                }
            }
        }
    }

    /// Copy the parent field `phi` into the window's interior.
    fn copy_in(&mut self, phi: &Field) {
        let [nx, ny, nz] = self.grid.n();
        let o = self.lo.map(|v| v as isize);
        for k in 0..nz as isize {
            for j in 0..ny as isize {
                for i in 0..nx as isize {
                    self.phi[[i, j, k]] = phi[[i + o[0], j + o[1], k + o[2]]];
                }
            }
        }
    }

    /// Whether the support has come within [`NEAR`] cells of a window side inside the domain.
    fn must_move(&self, parent: &Grid) -> Option<([usize; 3], [usize; 3])> {
        let (lo, hi) = support(&self.grid, &self.phi)?;
        let (n, pn) = (self.grid.n(), parent.n());
        let near = (0..parent.dims()).any(|a| {
            (self.lo[a] > 0 && lo[a] < NEAR) || (self.lo[a] + n[a] < pn[a] && hi[a] + NEAR >= n[a])
        });
        near.then(|| {
            (
                std::array::from_fn(|a| lo[a] + self.lo[a]),
                std::array::from_fn(|a| hi[a] + self.lo[a]),
            )
        })
    }

    /// Move the window around its support if it must ([`NEAR`]); whether it moved.
    pub fn follow(&mut self, parent: &Grid) -> Result<bool, String> {
        let Some((lo, hi)) = self.must_move(parent) else {
            return Ok(false);
        };
        let mut moved = Self::placed(parent, self.bounds, lo, hi)?;
        // The window's ghosts hold no values of their own: copy the old interior.
        let old = std::mem::take(&mut self.phi);
        moved.copy_window(&old, self.lo, self.grid.n());
        *self = moved;
        Ok(true)
    }

    /// Copy the interior of a window field `old` (first parent cell `old_lo`, `old_n` cells).
    fn copy_window(&mut self, old: &Field, old_lo: [usize; 3], old_n: [usize; 3]) {
        for k in 0..old_n[2] {
            for j in 0..old_n[1] {
                for i in 0..old_n[0] {
                    let v = old[[i as isize, j as isize, k as isize]];
                    if v == 0.0 {
                        continue;
                    }
                    let p = [i + old_lo[0], j + old_lo[1], k + old_lo[2]];
                    let w = [0, 1, 2].map(|a| p[a] as isize - self.lo[a] as isize);
                    self.phi[w] = v;
                }
            }
        }
    }

    /// Advance `φ_k` by `dt` on the parent's face velocities `vel` (one per axis), moving the
    /// window first if the body nears its side; `step_index` selects the sweep order.
    pub fn step(
        &mut self,
        parent: &Grid,
        vel: &[&Field],
        dt: f64,
        step_index: u64,
    ) -> Result<AdvectStats, String> {
        self.follow(parent)?;
        for (w, v) in self.vel.iter_mut().zip(vel) {
            copy_padded(v, w, self.lo);
        }
        self.work.resize(super::advect::work_len(&self.grid), 0.0);
        let dims = self.vel.len();
        let vel: [&Field; 3] = std::array::from_fn(|a| &self.vel[a.min(dims - 1)]);
        Ok(self.advector.step_in(
            &mut self.work,
            &self.grid,
            &mut self.phi,
            &vel[..dims],
            dt,
            step_index,
        ))
    }

    /// The phase volume `Σ φ_k V` (per radian in axisymmetric geometry), summed in the
    /// storage order of the parent with compensated summation ([`super::phase_volume`]).
    pub fn volume(&self, parent: &Grid) -> f64 {
        super::phase_volume(parent, &self.on_parent(parent))
    }

    /// `φ_k` on the whole parent grid (interior cells; zero ghosts).
    pub fn on_parent(&self, parent: &Grid) -> Field {
        let mut f = Field::zeros(parent);
        self.add_into(&mut f, 1.0);
        f
    }

    /// Append the window to `out`: its first parent cell and its cells along each axis (six
    /// numbers), then `φ_k` on its interior cells in storage order (x fastest).
    pub fn save_into(&self, out: &mut Vec<f64>) {
        let n = self.grid.n();
        out.extend(self.lo.iter().chain(&n).map(|&v| v as f64));
        for k in 0..n[2] as isize {
            for j in 0..n[1] as isize {
                for i in 0..n[0] as isize {
                    out.push(self.phi[[i, j, k]]);
                }
            }
        }
    }

    /// The window [`Self::save_into`] wrote at the start of `data`, and the number of values
    /// it took; an error if they do not describe a window of `parent`.
    pub fn restore(
        parent: &Grid,
        bounds: VofBoundaries,
        data: &[f64],
    ) -> Result<(Self, usize), String> {
        let head = data
            .get(..6)
            .ok_or("a body's window record is shorter than its six numbers of extent")?;
        let int = |v: f64| {
            (v >= 0.0 && v.fract() == 0.0 && v < 1e12)
                .then_some(v as usize)
                .ok_or_else(|| format!("{v} is not a cell count of a window"))
        };
        let lo = [int(head[0])?, int(head[1])?, int(head[2])?];
        let n = [int(head[3])?, int(head[4])?, int(head[5])?];
        let mut w = Self::at(parent, bounds, lo, n)?;
        let cells = w.cells();
        let values = data
            .get(6..6 + cells)
            .ok_or_else(|| format!("a window of {cells} cells is cut short"))?;
        let mut it = values.iter();
        for k in 0..n[2] as isize {
            for j in 0..n[1] as isize {
                for i in 0..n[0] as isize {
                    w.phi[[i, j, k]] = *it.next().expect("counted");
                }
            }
        }
        Ok((w, 6 + cells))
    }

    /// Copy the window and `φ_k` on it into `into` (the state's copy of the bodies' fractions,
    /// [`efsi_core::body_fractions`]), reusing its storage.
    pub fn publish(&self, into: &mut BodyFraction) {
        let n = self.grid.n();
        let phi = &self.phi;
        let cells = (0..n[2] as isize).flat_map(move |k| {
            (0..n[1] as isize).flat_map(move |j| (0..n[0] as isize).map(move |i| phi[[i, j, k]]))
        });
        into.set(self.lo, n, cells);
    }

    /// Cells of the window (its interior): the storage it scales with.
    pub fn cells(&self) -> usize {
        self.grid.n().iter().product()
    }
}

/// The windows of `count` bodies that [`BodyWindow::save_into`] wrote one after the other in
/// `data` (the VOF stage's record of a scene of several bodies, in its snapshots and
/// checkpoints); an error if the record does not hold exactly that.
pub fn windows_of(
    parent: &Grid,
    bounds: VofBoundaries,
    count: usize,
    data: &[f64],
) -> Result<Vec<BodyWindow>, String> {
    let mut windows = Vec::with_capacity(count);
    let mut rest = data;
    for _ in 0..count {
        let (w, used) = BodyWindow::restore(parent, bounds, rest)?;
        windows.push(w);
        rest = &rest[used..];
    }
    if !rest.is_empty() {
        return Err(format!(
            "{} values beyond the windows of the {count} bodies",
            rest.len()
        ));
    }
    Ok(windows)
}

/// Copy the padded window of `from` (a parent field) whose cell `[0, 0, 0]` is the parent cell
/// `lo` into `to` (a window field), ghosts included: row by row.
fn copy_padded(from: &Field, to: &mut Field, lo: [usize; 3]) {
    let (stride, rows, planes, gz) = (to.stride(), to.rows(), to.planes(), to.gz() as isize);
    let o = lo.map(|v| v as isize);
    for k in 0..planes as isize {
        for j in 0..rows as isize {
            let (kk, jj) = (k - gz, j - G);
            let src = from.idx3([-G + o[0], jj + o[1], kk + o[2]]);
            let dst = to.idx3([-G, jj, kk]);
            to.data_mut()[dst..dst + stride].copy_from_slice(&from.data()[src..src + stride]);
        }
    }
}
