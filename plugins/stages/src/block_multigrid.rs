//! A block multigrid preconditioner for implicit momentum systems whose stiff part acts like a
//! viscosity.
//!
//! **Matrix.** On the compact unknown faces ([`UnknownFaces`]: u first, then v, then in three
//! dimensions w) it takes `A = M − K_η`, `K_η = vol·∇·(2η D)` with the coefficients of the one
//! viscous operator ([`crate::viscous_operator`]) — `η = θΔt μ` for the viscous step, plus
//! `(Δt²/2) G_eff` for the elastic step, whose implicit tangent acts like an extra viscosity
//! `GΔt/2` (see [`crate::elastic`]). The preconditioner keeps the diagonal blocks of `A`, one
//! per velocity component ([`Coefficients::blocks`]): symmetric M-matrices, five-point on a
//! two-dimensional grid and seven-point on a three-dimensional one (the coupling between
//! components through the shear stress is dropped, and left to the Krylov solver), with the
//! diagonal the caller gives: the operator's own, or the mass plus every coupling of the row,
//! wall ones included ([`Coefficients::diagonal`]), so the blocks are diagonally dominant.
//!
//! **Cycle.** One multigrid V(1,1)-cycle per block ([`Multigrid`], the mass carried whole to the
//! coarse levels): symmetric positive definite, so it serves conjugate gradients as well as
//! BiCGSTAB. Rows run in parallel with fixed results ([`efsi_linalg::par`]): the same bits
//! on any number of threads. [`ViscousBlocks::new`] allocates the hierarchies; later set-ups and
//! applications allocate nothing.
//!
//! **Window.** Where the stiff part acts on a small region (the elastic step's solid, two
//! dimensions), the multigrid works on a window of each block and the Jacobi diagonal on the rest
//! ([`ViscousBlocks::setup_in`]). The window is the principal submatrix of the solid's faces
//! grown by a margin (the unknowns outside held at zero, [`Stencil5::window_into`]). Outside,
//! the rows are the mass `a` plus the viscous couplings; a disturbance running along a row's
//! strongest coupling `c` decays by `λ` per cell (`λ + 1/λ = 2 + a/c`, the least `a/c` of the
//! rows outside), and the margin is the distance over which it decays by [`WINDOW_DECAY`]. With
//! four equal couplings taking the share `q` of the diagonal (`a/c = 4(1 − q)/q`) that is 2
//! cells at `q` = 0.03 (the sphere impact's air has 0.02–0.03) and 16 at 0.92 (the soft-wall
//! cavity's fluid); more where one direction carries most of the coupling; the whole block
//! where the mass vanishes. The Krylov solver still iterates on the whole system,
//! so the window changes the cost of an iteration, not the answer (to the solver's tolerance);
//! the margin is chosen so that the iteration count stays that of the whole-grid preconditioner.

use crate::faces::UnknownFaces;
use crate::viscous_operator::Coefficients;
use efsi_core::{BoundarySet, Grid};
use efsi_linalg::{Multigrid, Preconditioner, Stencil5};

/// Multigrid on the diagonal blocks of `M − K_η` (one per axis; see the module docs), on the
/// whole of each block or, in two dimensions, on a window of it ([`ViscousBlocks::setup_in`]).
pub(crate) struct ViscousBlocks {
    faces: UnknownFaces,
    /// Each axis' block (u–u, v–v, w–w).
    a: Vec<Stencil5>,
    /// The window of each block the multigrid works on, and its matrix (the storage of a
    /// whole block, reused).
    w: Vec<BlockWindow>,
    s: Vec<Stencil5>,
    mg: Vec<Multigrid>,
}

/// A rectangle of a block's unknowns: first `(i0, j0)`, `nx × ny` of them; `whole` when it is
/// the block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct BlockWindow {
    i0: usize,
    j0: usize,
    nx: usize,
    ny: usize,
    whole: bool,
}

impl BlockWindow {
    fn whole(a: &Stencil5) -> Self {
        BlockWindow {
            i0: 0,
            j0: 0,
            nx: a.nx,
            ny: a.ny,
            whole: true,
        }
    }

    /// The unknowns `[i0, i1] × [j0, j1]` (block indices, may reach outside) of block `a`;
    /// the whole block along a periodic direction; `None` where the rectangle misses the
    /// block.
    fn clamped(a: &Stencil5, (i0, i1): (isize, isize), (j0, j1): (isize, isize)) -> Option<Self> {
        let clamp = |lo: isize, hi: isize, n: usize, periodic: bool| {
            let (lo, hi) = (
                lo.max(0) as usize,
                (hi.max(-1) + 1).min(n as isize) as usize,
            );
            if periodic {
                Some((0, n))
            } else {
                (lo < hi).then_some((lo, hi - lo))
            }
        };
        let (i0, nx) = clamp(i0, i1, a.nx, a.periodic_x)?;
        let (j0, ny) = clamp(j0, j1, a.ny, a.periodic_y)?;
        Some(BlockWindow {
            i0,
            j0,
            nx,
            ny,
            whole: nx == a.nx && ny == a.ny,
        })
    }
}

impl ViscousBlocks {
    /// The blocks of `grid` under `bc`, hierarchies allocated (with a unit placeholder matrix).
    pub(crate) fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        let periodic = [0, 1, 2].map(|a| a < grid.dims() && bc.periodic(a));
        Self::on(grid, UnknownFaces::new(grid, bc), periodic)
    }

    /// The blocks of the unknown `faces` of `grid`, each axis `periodic` or not, hierarchies
    /// allocated (with a unit placeholder matrix).
    pub(crate) fn on(grid: &Grid, faces: UnknownFaces, periodic: [bool; 3]) -> Self {
        let shape = |a: usize| {
            let r = faces.region(a);
            Stencil5::new_3d(r.len(0), r.len(1), r.len(2), periodic)
        };
        let a: Vec<Stencil5> = (0..grid.dims()).map(shape).collect();
        let mut b = ViscousBlocks {
            faces,
            w: a.iter().map(BlockWindow::whole).collect(),
            s: (0..grid.dims()).map(shape).collect(),
            mg: (0..grid.dims())
                .map(|_| Multigrid::new(1).with_w_cycle(false).with_excess_scale(1.0))
                .collect(),
            a,
        };
        for (a, mg) in b.a.iter_mut().zip(&mut b.mg) {
            a.diag.fill(1.0);
            if !a.is_empty() {
                mg.setup(a);
            }
        }
        b
    }

    /// Take the blocks of `diag(diagonal) − K` from the coefficients `k` and refresh the
    /// hierarchies, on the whole of each block.
    pub(crate) fn setup(&mut self, k: &Coefficients, diagonal: &[f64]) {
        self.setup_in(k, diagonal, None);
    }

    /// [`setup`](Self::setup) with the multigrid on a window of each block and the Jacobi
    /// diagonal elsewhere (`solid`: the cells `[i0, i1] × [j0, j1]` the stiff part acts on,
    /// grid indices; `None`: multigrid everywhere; a three-dimensional grid uses the whole
    /// blocks). The window is the faces of those cells grown by the margin over which an
    /// increment decays by [`WINDOW_DECAY`] in the rows outside ([`margin`]); the whole block
    /// where that reaches its edges. Nothing is allocated: a window reuses the whole block's
    /// storage.
    pub(crate) fn setup_in(
        &mut self,
        k: &Coefficients,
        diagonal: &[f64],
        solid: Option<((isize, isize), (isize, isize))>,
    ) {
        k.blocks(diagonal, &mut self.a);
        let (ulo, vlo) = (self.faces.ux.lo, self.faces.vy.lo);
        let solid = solid.filter(|_| self.a.len() == 2);
        // The faces of the cells grown by m: cell i's u-faces are i and i + 1, its v-faces j
        // and j + 1 (block indices count from the first unknown face).
        let faces = |m: isize, ((i0, i1), (j0, j1)): ((isize, isize), (isize, isize))| {
            let (i0, i1, j0, j1) = (i0 - m, i1 + m, j0 - m, j1 + m);
            [
                ((i0 - ulo, i1 + 1 - ulo), (j0, j1)),
                ((i0, i1), (j0 - vlo, j1 + 1 - vlo)),
            ]
        };
        let parts = self
            .a
            .iter()
            .zip(&mut self.w)
            .zip(&mut self.s)
            .zip(&mut self.mg);
        for (b, (((a, w), s), mg)) in parts.enumerate() {
            if a.is_empty() {
                continue;
            }
            // The solid's own faces, grown by the margin their surroundings need; the whole
            // block without a solid, or where none of its faces are in this block.
            let grown = |c| {
                let (x, y) = faces(0, c)[b];
                let m = margin(outside_decay(a, BlockWindow::clamped(a, x, y)?));
                let (x, y) = faces(m, c)[b];
                BlockWindow::clamped(a, x, y)
            };
            *w = solid.and_then(grown).unwrap_or(BlockWindow::whole(a));
            if w.whole {
                mg.setup(a);
            } else {
                a.window_into((w.i0, w.j0), (w.nx, w.ny), s);
                mg.setup(s);
            }
        }
    }
}

/// The least ratio `a/c` over the rows of `a` outside the window `w` (`a`: the row's diagonal
/// less its couplings, its mass; `c`: its largest coupling) — the decay of the slowest
/// disturbance there, one that runs along the most strongly coupled direction. Infinite when
/// no row outside couples.
fn outside_decay(a: &Stencil5, w: BlockWindow) -> f64 {
    let mut r = f64::INFINITY;
    for j in 0..a.ny {
        let inside_j = (w.j0..w.j0 + w.ny).contains(&j);
        for i in 0..a.nx {
            if inside_j && (w.i0..w.i0 + w.nx).contains(&i) {
                continue;
            }
            let k = j * a.nx + i;
            let c = [a.east[k], a.north[k], a.west(k, i), a.south(k, j)];
            let cmax = c[0].max(c[1]).max(c[2]).max(c[3]);
            if cmax > 0.0 {
                r = r.min((a.diag[k] - (c[0] + c[1] + c[2] + c[3])) / cmax);
            }
        }
    }
    r
}

/// The factor by which an increment is let decay between the solid and the edge of the
/// multigrid's window (module docs).
pub(crate) const WINDOW_DECAY: f64 = 1e-4;

/// The margin, in cells, over which a disturbance in rows of mass-to-coupling ratio at least
/// `r` ([`outside_decay`]) decays by [`WINDOW_DECAY`] away from its source: the decaying root
/// `λ` of the one-dimensional recurrence along the strongest coupling, `λ + 1/λ = 2 + r` (a
/// row with four equal couplings taking the share `q` of its diagonal has `r = 4(1 − q)/q`).
/// Unbounded when nothing decays (`r ≤ 0`, or not a number).
fn margin(r: f64) -> isize {
    if r.is_infinite() {
        return 1;
    }
    if r.is_nan() || r <= 0.0 {
        return isize::MAX / 4;
    }
    let r = 2.0 + r;
    let lambda = 2.0 / (r + (r * r - 4.0).sqrt());
    (WINDOW_DECAY.ln() / lambda.ln()).ceil().max(1.0) as isize
}

impl ViscousBlocks {
    /// The cycle of block `b` (if the grid has that axis) on its part `r` of a residual, into
    /// `z`: multigrid on its window, Jacobi outside it.
    fn apply_block(&self, b: usize, r: &[f64], z: &mut [f64]) {
        let Some(a) = self.a.get(b).filter(|a| !a.is_empty()) else {
            return;
        };
        let (w, m) = (self.w[b], &self.mg[b]);
        if w.whole {
            m.apply(r, z);
        } else {
            // Jacobi outside the window, multigrid inside (it overwrites the window).
            efsi_linalg::par::chunks(&mut *z).for_each(|o, z| {
                let (r, d) = (&r[o..o + z.len()], &a.diag[o..o + z.len()]);
                for ((z, r), d) in z.iter_mut().zip(r).zip(d) {
                    *z = r / d;
                }
            });
            m.apply_window(r, z, a.nx, w.j0 * a.nx + w.i0);
        }
    }
}

impl Preconditioner for ViscousBlocks {
    /// The blocks' cycles, side by side when there are threads to spare (each block's own
    /// loops keep their fixed order, so the bits do not depend on the threads).
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let [r0, r1, r2] = self.faces.split(r);
        let [z0, z1, z2] = self.faces.split_mut(z);
        if rayon::current_num_threads() > 1 {
            rayon::join(
                || self.apply_block(0, r0, z0),
                || {
                    rayon::join(
                        || self.apply_block(1, r1, z1),
                        || self.apply_block(2, r2, z2),
                    )
                },
            );
        } else {
            self.apply_block(0, r0, z0);
            self.apply_block(1, r1, z1);
            self.apply_block(2, r2, z2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::grid::Geometry;
    use efsi_core::scene::{Boundaries, Boundary};
    use efsi_core::{BoundarySet, Field};

    #[test]
    fn the_margin_grows_as_the_rows_couple_more_and_is_unbounded_without_mass() {
        // Four equal couplings taking 3 % of the diagonal (the sphere's air, r = 4(1 − q)/q):
        // 2 cells; a third: 5 cells; 92 % (a viscous fluid): 16 cells; no mass: everything;
        // no coupling: 1.
        let r = |q: f64| 4.0 * (1.0 - q) / q;
        assert_eq!(margin(r(0.03)), 2);
        assert_eq!(margin(r(1.0 / 3.0)), 5);
        assert_eq!(margin(r(0.92)), 16);
        assert_eq!(margin(0.0), isize::MAX / 4);
        assert_eq!(margin(f64::NAN), isize::MAX / 4);
        assert_eq!(margin(f64::INFINITY), 1);
        let m: Vec<isize> = [1e9, 1e3, 10.0, 1.0, 0.1, 0.01].map(margin).to_vec();
        assert!(m.windows(2).all(|w| w[0] <= w[1]), "{m:?}");
        // The decay it promises: λ^margin ≤ WINDOW_DECAY, and one cell fewer is not enough.
        for r in [100.0, 8.0, 1.0, 0.3] {
            let x = 2.0 + r;
            let lambda = 2.0 / (x + (x * x - 4.0f64).sqrt());
            let m = margin(r) as i32;
            assert!(lambda.powi(m) <= WINDOW_DECAY && lambda.powi(m - 1) > WINDOW_DECAY);
        }
    }

    /// Blocks of a 40 × 30 planar box with walls, mass `mass` per face and viscosity 1.
    fn blocks(mass: f64) -> (ViscousBlocks, Coefficients, Vec<f64>) {
        let grid = Grid::new(Geometry::Planar, 40, 30, (0.0, 1.0), (0.0, 0.75));
        let b = Boundaries::planar(
            Boundary::NoSlip,
            Boundary::NoSlip,
            Boundary::NoSlip,
            Boundary::NoSlip,
        );
        let bc = BoundarySet::new(&b, &grid);
        let faces = UnknownFaces::new(&grid, &bc);
        let mut k = Coefficients::new(&grid, faces);
        let mut mu = Field::zeros(&grid);
        mu.fill(1.0);
        let mut corner = Field::zeros(&grid);
        k.set_viscosity(&grid, &mu, 1.0, &mut corner);
        let dm: Vec<f64> = k.hoop().iter().map(|h| mass + h).collect();
        let mut diag = vec![0.0; faces.len()];
        k.diagonal(&dm, &mut diag);
        (ViscousBlocks::new(&grid, &bc), k, diag)
    }

    #[test]
    fn the_window_is_jacobi_outside_multigrid_inside_and_whole_where_nothing_decays() {
        let solid = Some(((10, 15), (8, 12)));
        // Rows whose mass is 1e3 times their couplings: a window, Jacobi outside it.
        let (mut b, k, diag) = blocks(1e3);
        b.setup_in(&k, &diag, solid);
        assert!(!b.w[0].whole && !b.w[1].whole);
        // Cells 10..=15 × 8..=12 grown by the margin (2 cells here): the u-faces 8..=18,
        // counted from the first unknown one (face 1; the wall's face 0 is known), of rows
        // 6..=14.
        assert_eq!((b.w[0].i0, b.w[0].nx, b.w[0].j0, b.w[0].ny), (7, 11, 6, 9));
        let n = diag.len();
        let r: Vec<f64> = (0..n).map(|c| ((c * 37) % 11) as f64 - 5.0).collect();
        let mut z = vec![0.0; n];
        b.apply(&r, &mut z);
        let nu = b.a[0].len();
        for (a, w, off) in [(&b.a[0], b.w[0], 0), (&b.a[1], b.w[1], nu)] {
            // Inside: the cycle of the window's own matrix, bit for bit.
            let mut sub = Stencil5::new(0, 0, false, false);
            a.window_into((w.i0, w.j0), (w.nx, w.ny), &mut sub);
            let mut mg = Multigrid::new(1).with_w_cycle(false).with_excess_scale(1.0);
            mg.setup(&sub);
            let at = |i: usize, j: usize| off + (w.j0 + j) * a.nx + w.i0 + i;
            let rw: Vec<f64> = (0..w.ny)
                .flat_map(|j| (0..w.nx).map(move |i| (i, j)))
                .map(|(i, j)| r[at(i, j)])
                .collect();
            let mut zw = vec![0.0; rw.len()];
            mg.apply(&rw, &mut zw);
            for j in 0..w.ny {
                for i in 0..w.nx {
                    assert_eq!(z[at(i, j)].to_bits(), zw[j * w.nx + i].to_bits());
                }
            }
            // Outside: Jacobi.
            for q in 0..a.len() {
                let (i, j) = (q % a.nx, q / a.nx);
                let inside = (w.i0..w.i0 + w.nx).contains(&i) && (w.j0..w.j0 + w.ny).contains(&j);
                if !inside {
                    assert_eq!(z[off + q], r[off + q] / a.diag[q], "face {}", off + q);
                }
            }
        }
        // One and two threads: the same bits (the two blocks' cycles run side by side).
        let pool = |t: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        };
        let (mut z1, mut z2) = (vec![0.0; n], vec![0.0; n]);
        pool(1).install(|| b.apply(&r, &mut z1));
        pool(2).install(|| b.apply(&r, &mut z2));
        assert!(z1.iter().zip(&z2).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert!(z1.iter().zip(&z).all(|(a, b)| a.to_bits() == b.to_bits()));
        // Light rows (viscosity dominant): the margin reaches the edges, the whole block.
        let (mut b, k, diag) = blocks(1e-6);
        b.setup_in(&k, &diag, solid);
        assert!(b.w[0].whole && b.w[1].whole);
        // A solid whose faces miss a block entirely leaves that block whole.
        let (mut b, k, diag) = blocks(1e3);
        b.setup_in(&k, &diag, Some(((10, 15), (-1, -1))));
        assert!(b.w[1].whole, "{:?}", b.w[1]);
    }
}
