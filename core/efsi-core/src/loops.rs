//! Loops over a grid location: the one way a stage visits cells, faces or corners.
//!
//! A [`Region`] is a box of grid indices at one location of the MAC grid ([`Stagger`]): the
//! interior of cell centres, of one face family or of the corners ([`Region::of`]), narrowed
//! along an axis where a stage needs fewer (the unknown faces of a wall-bounded direction,
//! [`Region::range`]). An index is the grid's [`Index`] `[i, j, k]`: a two-dimensional grid is
//! a three-dimensional one whose third axis has size one (`k = 0`, no ghosts across it), as in
//! Oceananigans' flat axes, and a three-dimensional grid ([`Grid::new_3d`]) has its planes and
//! z ghosts, so a kernel written over an `Index` and shifts along axes runs unchanged on both.
//! A region is visited as [`Line`]s — the runs of
//! indices along the first axis, which are contiguous in memory — so kernels work on slices
//! and vectorise:
//!
//! - [`Region::for_each`] writes one or more fields on each line (`&mut Field`, a pair or a
//!   triple): the kernel gets the line and the fields' values on it, exactly the line's length;
//! - [`Region::fold`] and [`Region::fold_mut`] reduce over the lines (a partial per line,
//!   folded in line order), [`Region::sum`] and [`Region::max`] are the common folds;
//! - [`Field::at`] reads a field on a line shifted by a grid offset (`u` at `I + x̂` is
//!   `u.at(&line, [1, 0, 0])`), [`Field::at_mut`] likewise for an output the loop does not
//!   own; both are bounds-checked slices, so no kernel writes an index by hand.
//!
//! The ghost layers and the fields' padded layout live here only: a stage never adds `G` or a
//! stride. On a three-dimensional grid the region's lines are its rows of every plane, in
//! storage order (`k` outer, then `j`), and the loops skip the padded rows between them. Parallel chunking is [`efsi_linalg::par`]'s: lines run in parallel when there is
//! enough work, each line's partial result is folded in line order, so every loop gives the
//! same bits on any number of threads. This module lives in efsi-core because it needs the
//! grid and the fields (which efsi-linalg, the solvers' crate, does not know); the row and
//! chunk engine below it is in efsi-linalg because the solvers' vectors need it too.

use crate::field::{Field, Stagger};
use crate::grid::{G, Grid};
use efsi_linalg::par::{self, Lanes};

/// A grid index `[i, j, k]` (ghosts are negative or past the interior). On a two-dimensional
/// grid `k` is always 0.
pub type Index = [isize; 3];

/// A shift by one along axis `a` (0, 1 or 2): `I + unit(a)` is the neighbour above `I`.
#[inline(always)]
pub const fn unit(a: usize) -> Index {
    let mut s = [0; 3];
    s[a] = 1;
    s
}

/// A box of grid indices `lo ≤ I < hi` (component-wise) at one grid location.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    lo: Index,
    hi: Index,
    /// The padded layout of the grid's fields: row stride, padded rows per plane, padded
    /// planes and ghost planes below `k = 0` (1 and 0 in two dimensions).
    stride: usize,
    rows: usize,
    planes: usize,
    gz: usize,
}

/// One run of a [`Region`] along the first axis: the indices `start + [n, 0, 0]` for
/// `n in 0..len`, contiguous in every field's storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Line {
    /// The first index of the run.
    pub start: Index,
    /// Its length.
    pub len: usize,
    /// Its ordinal among the region's lines (`0..`[`Region::lines`]), in storage order: the
    /// row of a compact vector that holds one value per index of the region.
    pub n: usize,
    /// Linear storage index of `start`, the row stride it was computed with and the plane
    /// size (0 on a two-dimensional grid, which has no neighbours along z).
    offset: usize,
    stride: usize,
    plane: usize,
    /// Length of the padded storage of the grid's fields.
    size: usize,
}

impl Line {
    /// The `n`-th index of the run.
    #[inline(always)]
    pub fn index(&self, n: usize) -> Index {
        [self.start[0] + n as isize, self.start[1], self.start[2]]
    }

    /// The storage index of the `n`-th index of the run in every field of the grid (for
    /// kernels that address storage shared by several fields, e.g. a per-face matrix).
    #[inline(always)]
    pub fn linear(&self, n: usize) -> usize {
        self.offset + n
    }

    /// The values at `I + shift` for the indices `I` of the line in `data`, an array laid out
    /// like the grid's fields (a work array from a pool, a solver's history): [`Field::at`]
    /// for storage that is not a [`Field`]. Bounds-checked.
    #[inline(always)]
    pub fn on<'a>(&self, data: &'a [f64], shift: Index) -> &'a [f64] {
        assert_eq!(data.len(), self.size, "an array of another grid");
        &data[self.span(shift)]
    }

    /// The entries at the line's columns shifted by `di` of a per-column array (one value per
    /// padded column `i ∈ [−G, nx + 1 + G)`, like the metric's radius factors): a
    /// bounds-checked slice of the line's length.
    #[inline(always)]
    pub fn cols<'a>(&self, v: &'a [f64], di: isize) -> &'a [f64] {
        let o = usize::try_from(self.start[0] + di + G).expect("column below the ghost layers");
        &v[o..o + self.len]
    }

    /// This line moved `j` rows and `k` planes on, numbered `n` (`k` is 0 on a two-dimensional
    /// grid, which has one plane).
    #[inline(always)]
    fn down(mut self, j: usize, k: usize, n: usize) -> Line {
        self.start[1] += j as isize;
        self.start[2] += k as isize;
        self.n = n;
        self.offset += j * self.stride + k * self.plane;
        self
    }

    /// The indices of the run, in order.
    pub fn indices(&self) -> impl Iterator<Item = Index> + '_ {
        (0..self.len).map(|n| self.index(n))
    }

    /// Checks that a field of row stride `stride` whose storage is `data` is laid out like the
    /// line's grid: the same row stride and padded length. Two loads and two comparisons, as
    /// it runs on every slice a kernel takes; a layout that differs only in how its rows split
    /// into planes (a grid with `ny` and `nz` exchanged) passes it.
    #[inline(always)]
    fn check(&self, data: &[f64], stride: usize) {
        assert!(
            stride == self.stride && data.len() == self.size,
            "field of another grid"
        );
    }

    /// The storage range of the run shifted by `s` in the grid's layout.
    #[inline(always)]
    fn span(&self, s: Index) -> std::ops::Range<usize> {
        let (stride, plane) = (self.stride, self.plane);
        assert!(
            s[2] == 0 || plane != 0,
            "a two-dimensional field has no third-axis neighbours"
        );
        let o = self.offset as isize + s[0] + s[1] * stride as isize + s[2] * plane as isize;
        let o = usize::try_from(o).expect("shift below the ghost layers");
        o..o + self.len
    }
}

impl Region {
    /// The interior of location `at` of `grid` (see the table in [`crate::grid`]).
    pub fn of(grid: &Grid, at: Stagger) -> Self {
        let [stride, rows, planes] = grid.padded();
        Region {
            lo: [0, 0, 0],
            hi: at.extent3(grid).map(|n| n as isize),
            stride,
            rows,
            planes,
            gz: grid.gz(),
        }
    }

    /// Every index of the padded storage of `grid`'s fields, ghosts included (for arrays
    /// defined everywhere, e.g. coefficients computed from a field whose ghosts are filled).
    pub fn whole(grid: &Grid) -> Self {
        let r = Region::of(grid, Stagger::Cell);
        let gz = r.gz as isize;
        Region {
            lo: [-G, -G, -gz],
            hi: [
                r.stride as isize - G,
                r.rows as isize - G,
                r.planes as isize - gz,
            ],
            ..r
        }
    }

    /// The same box with axis `a` restricted to `lo..hi` (which may reach into the ghosts).
    #[inline(always)]
    pub fn range(self, a: usize, lo: isize, hi: isize) -> Self {
        let mut r = self;
        r.lo[a] = lo;
        r.hi[a] = hi.max(lo);
        r
    }

    /// Lower corner (included).
    #[inline(always)]
    pub fn lo(&self) -> Index {
        self.lo
    }

    /// Upper corner (excluded).
    #[inline(always)]
    pub fn hi(&self) -> Index {
        self.hi
    }

    /// Number of indices along axis `a`.
    #[inline(always)]
    pub fn len(&self, a: usize) -> usize {
        (self.hi[a] - self.lo[a]).max(0) as usize
    }

    /// Whether the box holds no index.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        (0..3).any(|a| self.len(a) == 0)
    }

    /// Number of indices.
    #[inline(always)]
    pub fn size(&self) -> usize {
        self.len(0) * self.len(1) * self.len(2)
    }

    /// Number of lines (runs along the first axis).
    #[inline(always)]
    pub fn lines(&self) -> usize {
        if self.is_empty() {
            0
        } else {
            self.len(1) * self.len(2)
        }
    }

    /// Line `n` (`0..`[`Region::lines`]) of the region, for a kernel that walks lines itself
    /// (e.g. filling the rows of a compact vector, [`efsi_linalg::par::rows`]).
    #[inline]
    pub fn line(&self, n: usize) -> Line {
        let ny = self.len(1);
        // One plane (every two-dimensional region): the line number is the row within it.
        let (j, k) = if self.len(2) == 1 && n < ny {
            (n, 0)
        } else {
            (n % ny, n / ny)
        };
        self.first_line().down(j, k, n)
    }

    /// Line 0 (the corner `lo`): the part of every line a loop computes once, before its lines
    /// ([`Line::down`] moves it to the others).
    #[inline(always)]
    fn first_line(&self) -> Line {
        let stride = self.stride;
        let row = self.padded_row(self.lo[1], self.lo[2]);
        Line {
            start: self.lo,
            len: self.len(0),
            n: 0,
            offset: row * stride + (self.lo[0] + G) as usize,
            stride,
            plane: self.plane(),
            size: stride * self.rows * self.planes,
        }
    }

    /// The plane size of the layout as a [`Line`] shifts by it (0 in two dimensions).
    #[inline(always)]
    fn plane(&self) -> usize {
        if self.gz == 0 {
            0
        } else {
            self.stride * self.rows
        }
    }

    /// The padded row (in storage order, counted over all planes) of index `[·, j, k]`.
    #[inline(always)]
    fn padded_row(&self, j: isize, k: isize) -> usize {
        (k + self.gz as isize) as usize * self.rows + (j + G) as usize
    }

    /// The line of padded row `r` of the storage, if that row is one of the region's: its rows
    /// and planes from line 0 and its number, `(j, k, n)`.
    #[inline(always)]
    fn line_of_row(&self, r: usize) -> Option<(usize, usize, usize)> {
        let (k, j) = (
            (r / self.rows) as isize - self.gz as isize,
            (r % self.rows) as isize - G,
        );
        ((self.lo[1]..self.hi[1]).contains(&j) && (self.lo[2]..self.hi[2]).contains(&k)).then(
            || {
                let (j, k) = ((j - self.lo[1]) as usize, (k - self.lo[2]) as usize);
                (j, k, k * self.len(1) + j)
            },
        )
    }

    /// Checks that the region fits the padded layout of a field (`stride × rows × planes`).
    fn check(&self) {
        let (stride, rows, gz) = (self.stride, self.rows, self.gz as isize);
        assert!(
            self.is_empty() || (self.lo[2] >= -gz && self.hi[2] <= self.planes as isize - gz),
            "{}",
            if gz == 0 {
                "a two-dimensional field has only k = 0"
            } else {
                "region outside the field's ghost planes"
            }
        );
        assert!(
            self.is_empty()
                || (self.lo[0] >= -G
                    && self.hi[0] + G <= stride as isize
                    && self.lo[1] >= -G
                    && self.hi[1] + G <= rows as isize),
            "region {:?}..{:?} outside the field's ghost layers",
            self.lo,
            self.hi
        );
    }

    /// Run `f(line, values)` over the lines, writing `fields` (a `&mut Field`, or a pair or
    /// triple of them) on each: `values` are the fields' slices on the line, in the same shape.
    /// Lines in parallel when there is enough work; each writes only its own indices, so the
    /// result is the serial loop's.
    pub fn for_each<F: FieldsMut>(&self, fields: F, f: impl Fn(Line, F::Lanes) + Sync + Send) {
        let Some((lanes, x, r0)) = self.lanes(fields) else {
            return;
        };
        let (rows, first) = (
            par::rows(lanes, self.stride).work(self.len(0)),
            self.first_line(),
        );
        if self.len(2) == 1 {
            rows.for_each(|n, l| f(first.down(n, 0, n), l.sub(x.clone())));
        } else {
            rows.for_each(|m, l| {
                if let Some((j, k, n)) = self.line_of_row(r0 + m) {
                    f(first.down(j, k, n), l.sub(x.clone()))
                }
            });
        }
    }

    /// The fields' storage from the region's first line's padded row to its last one's, the
    /// columns of a line within a row, and the padded row the storage starts at (`None` for
    /// an empty region). Within one plane every padded row of that range is a line of the
    /// region; across planes the rows between them are not (`Region::line_of_row`).
    #[allow(clippy::type_complexity)]
    fn lanes<F: FieldsMut>(&self, fields: F) -> Option<(F::Lanes, std::ops::Range<usize>, usize)> {
        if self.is_empty() {
            return None;
        }
        assert_eq!(
            fields.layout(),
            [self.stride, self.rows, self.planes],
            "fields of another grid"
        );
        self.check();
        let r0 = self.padded_row(self.lo[1], self.lo[2]);
        let r1 = self.padded_row(self.hi[1] - 1, self.hi[2] - 1) + 1;
        let x = (self.lo[0] + G) as usize..(self.hi[0] + G) as usize;
        let stride = self.stride;
        Some((fields.lanes(r0 * stride..r1 * stride), x, r0))
    }

    /// `combine(…combine(init, f(line₀, values₀))…)`: [`Region::for_each`] whose kernel also
    /// returns a partial result (a reduction over what it writes, in the same pass), folded in
    /// line order — the same bits on any number of threads.
    pub fn fold_mut<F: FieldsMut, A, P: Copy + Default + Send>(
        &self,
        fields: F,
        init: A,
        f: impl Fn(Line, F::Lanes) -> P + Sync + Send,
        combine: impl Fn(A, P) -> A,
    ) -> A {
        let Some((lanes, x, r0)) = self.lanes(fields) else {
            return init;
        };
        let (rows, first) = (
            par::rows(lanes, self.stride).work(self.len(0)),
            self.first_line(),
        );
        if self.len(2) == 1 {
            return rows.fold(
                init,
                |n, l| f(first.down(n, 0, n), l.sub(x.clone())),
                combine,
            );
        }
        // Across planes a padded row between two planes' lines contributes nothing.
        rows.fold(
            init,
            |m, l| {
                self.line_of_row(r0 + m)
                    .map(|(j, k, n)| f(first.down(j, k, n), l.sub(x.clone())))
            },
            |a, p| match p {
                Some(p) => combine(a, p),
                None => a,
            },
        )
    }

    /// `combine(…combine(init, f(line₀))…)` over the lines, each partial computed in parallel
    /// when there is enough work and folded in line order (the same bits on any number of
    /// threads).
    pub fn fold<A, P: Copy + Default + Send>(
        &self,
        init: A,
        f: impl Fn(Line) -> P + Sync + Send,
        combine: impl Fn(A, P) -> A,
    ) -> A {
        self.check();
        if self.is_empty() {
            return init;
        }
        let (first, ny) = (self.first_line(), self.len(1));
        let line = |n: usize| match self.len(2) {
            1 => first.down(n, 0, n),
            _ => first.down(n % ny, n / ny, n),
        };
        par::range(self.lines())
            .work(self.len(0))
            .fold(init, |n| f(line(n)), combine)
    }

    /// `Σ f(line)` component-wise, `N` sums at once, lines added in order.
    pub fn sum<const N: usize>(&self, f: impl Fn(Line) -> [f64; N] + Sync + Send) -> [f64; N]
    where
        [f64; N]: Default,
    {
        self.fold([0.0; N], f, par::add)
    }

    /// `max(init, max over lines of f(line))`.
    pub fn max(&self, init: f64, f: impl Fn(Line) -> f64 + Sync + Send) -> f64 {
        self.fold(init, f, f64::max)
    }
}

/// An array laid out like the grid's fields but not held by a [`Field`] (a work array from a
/// pool), for a [`Region`] loop to write ([`Region::storage`]).
pub struct Storage<'a> {
    data: &'a mut [f64],
    layout: [usize; 3],
}

impl Region {
    /// `data`, laid out like the fields of the region's grid, as an output of
    /// [`Region::for_each`] (its length is checked against the layout).
    pub fn storage<'a>(&self, data: &'a mut [f64]) -> Storage<'a> {
        let layout = [self.stride, self.rows, self.planes];
        assert_eq!(
            data.len(),
            layout.iter().product::<usize>(),
            "an array of another grid"
        );
        Storage { data, layout }
    }
}

impl<'a> FieldsMut for Storage<'a> {
    type Lanes = &'a mut [f64];
    fn layout(&self) -> [usize; 3] {
        self.layout
    }
    fn lanes(self, r: std::ops::Range<usize>) -> Self::Lanes {
        &mut self.data[r]
    }
}

/// Fields a [`Region`] loop writes: `&mut Field` or a [`Storage`], or a pair or triple of them
/// (of one grid).
pub trait FieldsMut {
    /// The fields' storage, as [`Lanes`] (one slice per field).
    type Lanes: Lanes;
    /// Row stride and number of padded rows (equal for all the fields).
    fn shape(&self) -> (usize, usize) {
        let [s, r, _] = self.layout();
        (s, r)
    }
    /// Row stride, padded rows per plane and padded planes (equal for all the fields).
    fn layout(&self) -> [usize; 3];
    /// The storage range `r` of each field.
    fn lanes(self, r: std::ops::Range<usize>) -> Self::Lanes;
}

impl<'a> FieldsMut for &'a mut Field {
    type Lanes = &'a mut [f64];
    fn layout(&self) -> [usize; 3] {
        [self.stride(), self.rows(), self.planes()]
    }
    fn lanes(self, r: std::ops::Range<usize>) -> Self::Lanes {
        &mut self.data_mut()[r]
    }
}

impl<A: FieldsMut, B: FieldsMut> FieldsMut for (A, B) {
    type Lanes = (A::Lanes, B::Lanes);
    fn layout(&self) -> [usize; 3] {
        assert_eq!(
            self.0.layout(),
            self.1.layout(),
            "fields of different grids"
        );
        self.0.layout()
    }
    fn lanes(self, r: std::ops::Range<usize>) -> Self::Lanes {
        (self.0.lanes(r.clone()), self.1.lanes(r))
    }
}

impl<A: FieldsMut, B: FieldsMut, C: FieldsMut> FieldsMut for (A, B, C) {
    type Lanes = (A::Lanes, B::Lanes, C::Lanes);
    fn layout(&self) -> [usize; 3] {
        assert!(
            self.0.layout() == self.1.layout() && self.0.layout() == self.2.layout(),
            "fields of different grids"
        );
        self.0.layout()
    }
    fn lanes(self, r: std::ops::Range<usize>) -> Self::Lanes {
        (
            self.0.lanes(r.clone()),
            self.1.lanes(r.clone()),
            self.2.lanes(r),
        )
    }
}

impl Field {
    /// The values at `I + shift` for the indices `I` of `line`: a bounds-checked slice of the
    /// line's length (a shift may reach the ghost layers, not past them).
    #[inline(always)]
    pub fn at(&self, line: &Line, shift: Index) -> &[f64] {
        line.check(self.data(), self.stride());
        &self.data()[line.span(shift)]
    }

    /// [`Field::at`], mutable: for an output that a line owns but the loop was not given.
    #[inline(always)]
    pub fn at_mut(&mut self, line: &Line, shift: Index) -> &mut [f64] {
        line.check(self.data(), self.stride());
        let r = line.span(shift);
        &mut self.data_mut()[r]
    }
}

impl std::ops::Index<Index> for Field {
    type Output = f64;
    #[inline(always)]
    fn index(&self, i: Index) -> &f64 {
        &self.data()[self.idx3(i)]
    }
}

impl std::ops::IndexMut<Index> for Field {
    #[inline(always)]
    fn index_mut(&mut self, i: Index) -> &mut f64 {
        let n = self.idx3(i);
        &mut self.data_mut()[n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Geometry;

    /// `u` scaled by `factor` in place and summed in one fused pass on `t` threads: the sum's
    /// bits and the scaled field.
    fn scaled_and_summed(cells: &Region, u: &Field, factor: f64, t: usize) -> (u64, Field) {
        let mut v = u.clone();
        let s = pool(t).install(|| {
            cells.fold_mut(
                &mut v,
                0.0,
                |_, v| {
                    v.iter_mut().fold(0.0, |s, v| {
                        *v *= factor;
                        s + *v
                    })
                },
                |a, p| a + p,
            )
        });
        (s.to_bits(), v)
    }

    fn pool(t: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    }

    #[test]
    fn regions_have_a_size_one_third_axis_and_lines_along_the_first() {
        let g = Grid::new(Geometry::Planar, 5, 3, (0.0, 1.0), (0.0, 1.0));
        let r = Region::of(&g, Stagger::XFace);
        assert_eq!((r.lo(), r.hi()), ([0, 0, 0], [6, 3, 1]));
        assert_eq!((r.size(), r.lines(), r.len(2)), (18, 3, 1));
        let r = Region::of(&g, Stagger::YFace).range(1, 1, 3);
        assert_eq!(
            (r.lines(), r.line(1).start, r.line(1).len),
            (2, [0, 2, 0], 5)
        );
        assert!(Region::of(&g, Stagger::Cell).range(0, 2, 1).is_empty());
        let mut f = Field::zeros(&g);
        f[[4, 2, 0]] = 7.0;
        assert_eq!(f[(4, 2)], 7.0);
        let l = Region::of(&g, Stagger::Cell).line(2);
        assert_eq!(f.at(&l, [0, 0, 0])[4], 7.0);
        assert_eq!(f.at(&l, [1, 0, 0])[3], 7.0, "u at I + x̂");
        assert_eq!(f.at(&l, [0, 1, 0]), &[0.0; 5], "a row of ghosts above");
        assert_eq!(l.indices().nth(4), Some([4, 2, 0]));
        assert_eq!(unit(1), [0, 1, 0]);
    }

    #[test]
    fn for_each_writes_the_region_only_and_hides_the_ghosts() {
        let g = Grid::new(Geometry::Planar, 70, 60, (0.0, 1.0), (0.0, 1.0));
        let (mut a, mut b) = (Field::filled(&g, -1.0), Field::zeros(&g));
        let r = Region::of(&g, Stagger::XFace).range(0, 1, 70);
        r.for_each((&mut a, &mut b), |l, (a, b)| {
            for (n, (a, b)) in a.iter_mut().zip(b).enumerate() {
                let [i, j, _] = l.index(n);
                *a = (i * 1000 + j) as f64;
                *b = l.n as f64;
            }
        });
        for j in -G..60 + 1 + G {
            for i in -G..70 + 1 + G {
                let inside = (1..70).contains(&i) && (0..60).contains(&j);
                let want = if inside { (i * 1000 + j) as f64 } else { -1.0 };
                assert_eq!(a[(i, j)], want, "({i}, {j})");
                assert_eq!(b[(i, j)], if inside { j as f64 } else { 0.0 });
            }
        }
    }

    #[test]
    fn reductions_are_the_same_on_one_and_two_threads_and_fold_in_line_order() {
        let g = Grid::new(Geometry::Planar, 301, 257, (0.0, 1.0), (0.0, 1.0));
        let mut u = Field::zeros(&g);
        Region::of(&g, Stagger::XFace).for_each(&mut u, |l, u| {
            for (n, u) in u.iter_mut().enumerate() {
                let [i, j, _] = l.index(n);
                *u = ((i * 7919 + j * 104_729) % 1013) as f64 / 17.0 - 20.0;
            }
        });
        let cells = Region::of(&g, Stagger::Cell);
        let div = |l: Line| {
            let (w, e) = (u.at(&l, [0, 0, 0]), u.at(&l, unit(0)));
            let s = w.iter().zip(e).fold(0.0, |s, (w, e)| s + (e - w) * (e + w));
            [s, s.abs()]
        };
        let (one, two) = (
            pool(1).install(|| cells.sum(div)),
            pool(2).install(|| cells.sum(div)),
        );
        assert_eq!(one.map(f64::to_bits), two.map(f64::to_bits));
        let serial = (0..cells.lines()).fold([0.0; 2], |s, n| par::add(s, div(cells.line(n))));
        assert_eq!(one, serial, "line partials added in line order");
        let m = pool(2).install(|| cells.max(0.0, |l| div(l)[1]));
        assert_eq!(
            m,
            (0..257).map(|n| div(cells.line(n))[1]).fold(0.0, f64::max)
        );
        // A fused update and reduction gives the same bits on one and two threads.
        let fused = |t| scaled_and_summed(&cells, &u, 0.5, t);
        assert_eq!(fused(1), fused(2));
    }

    #[test]
    #[should_panic(expected = "outside the field's ghost layers")]
    fn a_region_past_the_ghosts_is_refused() {
        let g = Grid::new(Geometry::Planar, 4, 4, (0.0, 1.0), (0.0, 1.0));
        let mut f = Field::zeros(&g);
        Region::of(&g, Stagger::Cell)
            .range(1, -3, 4)
            .for_each(&mut f, |_, _| {});
    }

    #[test]
    #[should_panic(expected = "out of range")]
    fn a_shift_past_the_storage_is_refused() {
        let g = Grid::new(Geometry::Planar, 4, 4, (0.0, 1.0), (0.0, 1.0));
        let f = Field::zeros(&g);
        let top = Region::of(&g, Stagger::Corner).line(4);
        let _ = f.at(&top, [0, 3, 0]);
    }

    #[test]
    #[should_panic(expected = "no third-axis neighbours")]
    fn a_third_axis_shift_is_refused_in_two_dimensions() {
        let g = Grid::new(Geometry::Planar, 4, 4, (0.0, 1.0), (0.0, 1.0));
        let f = Field::zeros(&g);
        let _ = f.at(&Region::of(&g, Stagger::Cell).line(0), unit(2));
    }

    #[test]
    fn three_dimensional_fields_round_trip_indices_and_strides() {
        let g = Grid::new_3d([5, 4, 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let f = Field::zeros(&g);
        assert_eq!((f.stride(), f.rows(), f.planes()), (10, 9, 8));
        assert_eq!(f.data().len(), 10 * 9 * 8);
        let mut seen = vec![false; f.data().len()];
        for k in -G..3 + 1 + G {
            for j in -G..4 + 1 + G {
                for i in -G..5 + 1 + G {
                    let n = f.idx3([i, j, k]);
                    assert_eq!(f.index_of(n), [i, j, k]);
                    assert!(!std::mem::replace(&mut seen[n], true), "one slot per index");
                    for a in 0..3 {
                        let mut s = [i, j, k];
                        s[a] += 1;
                        if s[a] < [5, 4, 3][a] + 1 + G {
                            let step = f.idx3(s) as isize - n as isize;
                            assert_eq!(step, f.offset(unit(a)), "axis {a}");
                        }
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "every slot is an index");
        assert_eq!(f.offset(unit(2)), (10 * 9) as isize);
        assert_eq!(f.idx3([0, 0, 0]), f.idx(0, 0));
        // Locations: z-faces and the edges along x and y have nz + 1 planes.
        let ext = |at| Region::of(&g, at).hi();
        assert_eq!(ext(Stagger::Cell), [5, 4, 3]);
        assert_eq!(ext(Stagger::ZFace), [5, 4, 4]);
        assert_eq!(ext(Stagger::Corner), [6, 5, 3]);
        assert_eq!(ext(Stagger::XEdge), [5, 5, 4]);
        assert_eq!(ext(Stagger::YEdge), [6, 4, 4]);
        let g2 = Grid::new(Geometry::Planar, 5, 4, (0.0, 1.0), (0.0, 1.0));
        assert_eq!(Region::of(&g2, Stagger::ZFace).hi(), [5, 4, 1]);
    }

    /// A 3-D field holding a different value at every index, ghosts included.
    fn labelled(g: &Grid) -> Field {
        let mut f = Field::zeros(g);
        for n in 0..f.data().len() {
            let [i, j, k] = f.index_of(n);
            f.data_mut()[n] = ((i * 7919 + j * 104_729 + k * 1_299_709) % 1013) as f64 / 17.0;
        }
        f
    }

    #[test]
    fn three_dimensional_loops_visit_the_region_in_storage_order_and_shift_along_z() {
        let g = Grid::new_3d([9, 7, 6], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let src = labelled(&g);
        let r = Region::of(&g, Stagger::ZFace)
            .range(0, -1, 8)
            .range(1, 2, 7)
            .range(2, -1, 5);
        assert_eq!((r.lines(), r.size()), (5 * 6, 9 * 5 * 6));
        let (mut a, mut b) = (Field::filled(&g, -1.0), Field::zeros(&g));
        for t in [1, 2] {
            pool(t).install(|| {
                r.for_each((&mut a, &mut b), |l, (a, b)| {
                    let (below, here) = (src.at(&l, [0, 0, -1]), src.at(&l, [0; 3]));
                    for n in 0..l.len {
                        a[n] = here[n] - below[n];
                        b[n] = l.n as f64;
                    }
                })
            });
        }
        for n in 0..a.data().len() {
            let [i, j, k] = a.index_of(n);
            let inside = (-1..8).contains(&i) && (2..7).contains(&j) && (-1..5).contains(&k);
            if inside {
                assert_eq!(a[[i, j, k]], src[[i, j, k]] - src[[i, j, k - 1]]);
                assert_eq!(
                    b[[i, j, k]],
                    ((k + 1) * 5 + j - 2) as f64,
                    "k-major line order"
                );
            } else {
                assert_eq!((a.data()[n], b.data()[n]), (-1.0, 0.0), "[{i}, {j}, {k}]");
            }
        }
    }

    #[test]
    fn every_loop_hands_its_kernel_the_lines_region_line_builds() {
        let g3 = Grid::new_3d([9, 7, 6], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let g2 = Grid::new(Geometry::Planar, 5, 4, (0.0, 1.0), (0.0, 1.0));
        let regions = [
            (
                &g3,
                Region::of(&g3, Stagger::YFace)
                    .range(1, 1, 6)
                    .range(2, -1, 4),
            ),
            (&g2, Region::of(&g2, Stagger::XFace).range(1, 1, 3)),
        ];
        for (g, r) in regions {
            let (f, [lo0, lo1, lo2], ny) = (Field::zeros(g), r.lo(), r.len(1));
            for n in 0..r.lines() {
                let l = r.line(n);
                let j = lo1 + (n % ny) as isize;
                assert_eq!(l.start, [lo0, j, lo2 + (n / ny) as isize]);
                assert_eq!((l.n, l.len, l.linear(0)), (n, r.len(0), f.idx3(l.start)));
            }
            let seen = r.sum(|l| {
                assert_eq!(l, r.line(l.n));
                [1.0, l.n as f64]
            });
            let lines = r.lines();
            assert_eq!(seen, [lines as f64, (lines * (lines - 1) / 2) as f64]);
            let mut out = Field::zeros(g);
            let written = r.fold_mut(
                &mut out,
                0,
                |l, _| usize::from(l == r.line(l.n)),
                |a, p| a + p,
            );
            assert_eq!(written, lines);
        }
    }

    #[test]
    #[should_panic(expected = "field of another grid")]
    fn a_field_of_another_grid_is_refused() {
        let g = Grid::new(Geometry::Planar, 4, 5, (0.0, 1.0), (0.0, 1.0));
        let other = Field::zeros(&Grid::new(Geometry::Planar, 5, 4, (0.0, 1.0), (0.0, 1.0)));
        let _ = other.at(&Region::of(&g, Stagger::Cell).line(0), [0; 3]);
    }

    #[test]
    fn three_dimensional_reductions_are_the_same_on_one_and_two_threads() {
        // Enough lines and planes for the parallel path and several rows between planes.
        let g = Grid::new_3d([61, 40, 30], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let u = labelled(&g);
        let cells = Region::of(&g, Stagger::Cell);
        let f = |l: Line| {
            let (c, up) = (u.at(&l, [0; 3]), u.at(&l, unit(2)));
            let s = c
                .iter()
                .zip(up)
                .fold(0.0, |s, (c, up)| s + c * up - 0.1 * c);
            [s, s.abs()]
        };
        let (one, two) = (
            pool(1).install(|| cells.sum(f)),
            pool(2).install(|| cells.sum(f)),
        );
        assert_eq!(one.map(f64::to_bits), two.map(f64::to_bits));
        let serial = (0..cells.lines()).fold([0.0; 2], |s, n| par::add(s, f(cells.line(n))));
        assert_eq!(one, serial, "line partials added in line order");
        let fused = |t| scaled_and_summed(&cells, &u, 0.75, t);
        let (f1, f2) = (fused(1), fused(2));
        assert_eq!(f1, f2);
        let want = (0..cells.lines()).fold(0.0, |s, n| {
            s + u
                .at(&cells.line(n), [0; 3])
                .iter()
                .fold(0.0, |s, v| s + v * 0.75)
        });
        assert_eq!(f64::from_bits(f1.0), want, "fused partials in line order");
    }

    #[test]
    #[should_panic(expected = "outside the field's ghost planes")]
    fn a_region_past_the_z_ghosts_is_refused() {
        let g = Grid::new_3d([4, 4, 4], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let mut f = Field::zeros(&g);
        Region::of(&g, Stagger::Cell)
            .range(2, -3, 4)
            .for_each(&mut f, |_, _| {});
    }
}
