//! Data-parallel loops (rayon) whose results do not depend on the number of threads.
//!
//! Three loops, each with a `for_each` and a `fold`: [`rows`] (slices cut into rows of a given
//! length — the grid loops of `efsi_core::loops` are built on it), [`chunks`] (rows of
//! [`REDUCE_CHUNK`] elements: the solvers' vector updates and reductions) and [`range`] (plain
//! indices, for kernels that write through their own means). What they run over is one slice
//! or a pair or triple of them, mutable or shared ([`Lanes`]), plus, where each row needs its
//! own scratch or partial, one item per row ([`per_row`]).
//!
//! A `for_each` writes disjoint rows from read-only inputs, bit-identical to the serial loop by
//! construction. A `fold` computes one partial per row (in parallel when there is enough work)
//! and folds the partials in row order — the same summation tree whatever the pool size, so a
//! solve run on one thread and on many gives bit-identical iterates. Whether a loop is split,
//! and how finely, depends only on its amount of work ([`PAR_MIN`]), never on its results.
//! [`dot`] and [`dot2`] are the fixed-order inner products; `SharedSlice` is the one unsafe
//! view, kept for the red–black smoother.

use rayon::prelude::*;

/// Length of the fixed chunks of a reduction (a multiple of 4).
pub const REDUCE_CHUNK: usize = 4096;

/// Below this many elements a loop runs serially (a fork costs a few microseconds). Small
/// enough that the multigrid's coarse levels and the vector operations on them still fork on
/// two threads, large enough that a fork is paid for; the choice only moves time, never bits
/// (`tests/tests/parallel.rs`).
pub const PAR_MIN: usize = 2048;

/// `f(n, item)` for every item of `items` (`n` its position), the items in parallel (rayon's
/// own split: for a handful of independent tasks, each writing only its own data — the bodies
/// of a scene); the error of the first item in the items' order that fails, whichever thread
/// saw it first. Allocates nothing of its own.
pub fn try_each<I, E, F>(items: I, f: F) -> Result<(), E>
where
    I: IndexedParallelIterator,
    E: Send,
    F: Fn(usize, I::Item) -> Result<(), E> + Sync + Send,
{
    let first = items
        .enumerate()
        .map(|(n, x)| f(n, x).err().map(|e| (n, e)))
        .reduce(
            || None,
            |a, b| match (a, b) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
        );
    first.map_or(Ok(()), |(_, e)| Err(e))
}

/// Four-lane dot product of two equal-length slices (vectorises).
#[inline]
pub(crate) fn dot_serial(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let n4 = a.len() / 4 * 4;
    for k in (0..n4).step_by(4) {
        s[0] += a[k] * b[k];
        s[1] += a[k + 1] * b[k + 1];
        s[2] += a[k + 2] * b[k + 2];
        s[3] += a[k + 3] * b[k + 3];
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for k in n4..a.len() {
        t += a[k] * b[k];
    }
    t
}

/// `Σ a_k b_k`, summed in fixed chunks of [`REDUCE_CHUNK`] added in order (blocks of
/// `MAX_PARTS` chunks summed first on vectors longer than one block): the result is the same
/// bit for bit whatever the number of threads.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let big = REDUCE_CHUNK * MAX_PARTS;
    if a.len() > big {
        return rows((a, b), big)
            .serial()
            .map(|(a, b)| dot(a, b))
            .fold(0.0, |s, v| s + v);
    }
    chunks((a, b)).fold(0.0, |_, (a, b)| dot_serial(a, b), |s, v| s + v)
}

/// `(Σ a_k b_k, Σ a_k c_k)` in one pass, each summed as [`dot`] sums it (the same bits as
/// two calls, on any number of threads).
pub fn dot2(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let add = |s: (f64, f64), v: (f64, f64)| (s.0 + v.0, s.1 + v.1);
    let big = REDUCE_CHUNK * MAX_PARTS;
    if a.len() > big {
        return rows((a, b, c), big)
            .serial()
            .map(|(a, b, c)| dot2(a, b, c))
            .fold((0.0, 0.0), add);
    }
    chunks((a, b, c)).fold(
        (0.0, 0.0),
        |_, (a, b, c)| (dot_serial(a, b), dot_serial(a, c)),
        add,
    )
}

/// Largest number of chunk partials a reduction keeps on the stack at once.
const MAX_PARTS: usize = 512;

/// Four-lane sum of `f(k)` for `k in 0..n` (vectorises when `f` does), for the partials of a
/// [`Rows::fold`] or [`Chunks::fold`].
#[inline(always)]
pub fn sum4(n: usize, f: impl Fn(usize) -> f64) -> f64 {
    let mut s = [0.0f64; 4];
    let n4 = n / 4 * 4;
    for k in (0..n4).step_by(4) {
        s[0] += f(k);
        s[1] += f(k + 1);
        s[2] += f(k + 2);
        s[3] += f(k + 3);
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for k in n4..n {
        t += f(k);
    }
    t
}

/// Run `f` — serial work between parallel loops — while another thread of the pool, if one
/// is free, spins until it is done, so that the parallel loop after it finds that thread
/// awake. A rayon worker with nothing to do falls asleep after some tens of microseconds,
/// and waking it costs about as long again, so a parallel loop that follows a serial stretch
/// of that length would pay the wake-up on top of its own work. This is the "active wait"
/// that OpenMP runtimes apply between parallel regions, for the stretches where it pays (the
/// multigrid's serial coarse levels).
/// The spinning thread yields every few dozen rounds, so that on an oversubscribed machine it
/// does not take the core from the thread doing `f`. On one thread it is just `f()`.
pub fn serial_warm<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_num_threads() < 2 {
        return f();
    }
    let done = std::sync::atomic::AtomicBool::new(false);
    let (r, ()) = rayon::join(
        || {
            let r = f();
            done.store(true, std::sync::atomic::Ordering::Release);
            r
        },
        || {
            // Spin, yielding now and then: on an oversubscribed machine (more threads than
            // free cores) the thread doing the work gets the core instead.
            let mut n = 0u32;
            while !done.load(std::sync::atomic::Ordering::Acquire) {
                n = n.wrapping_add(1);
                if n.is_multiple_of(64) {
                    std::thread::yield_now();
                } else {
                    std::hint::spin_loop();
                }
            }
        },
    );
    r
}

/// `dst ← src` (equal lengths), in parallel chunks when long.
pub fn copy(dst: &mut [f64], src: &[f64]) {
    chunks((dst, src)).for_each(|_, (d, s)| d.copy_from_slice(s));
}

/// Slices split together into rows: one slice, or a pair or triple of equal-length slices,
/// each mutable or shared. A kernel of [`rows`], [`chunks`] and their folds receives one row of
/// each, in the same shape (`&mut [f64]`, `(&mut [f64], &[f64])`, …).
pub trait Lanes: Send + Sized {
    /// The common length (asserted equal for a tuple).
    fn len(&self) -> usize;
    /// Whether the slices are empty.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The two halves at `mid`.
    fn split_at(self, mid: usize) -> (Self, Self);
    /// The sub-slices `r` of each slice (bounds-checked).
    fn sub(self, r: std::ops::Range<usize>) -> Self;
    /// Consecutive rows of `n` elements (the last may be shorter), in order.
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self>;
    /// The same rows as a parallel iterator.
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self>;
}

impl<T: Send> Lanes for &mut [T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
    fn sub(self, r: std::ops::Range<usize>) -> Self {
        &mut self[r]
    }
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self> {
        self.chunks_mut(n)
    }
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self> {
        self.par_chunks_mut(n)
    }
}

impl<T: Sync> Lanes for &[T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        <[T]>::split_at(self, mid)
    }
    fn sub(self, r: std::ops::Range<usize>) -> Self {
        &self[r]
    }
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self> {
        self.chunks(n)
    }
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self> {
        self.par_chunks(n)
    }
}

impl<A: Lanes, B: Lanes> Lanes for (A, B) {
    fn len(&self) -> usize {
        assert_eq!(self.0.len(), self.1.len(), "lanes of unequal length");
        self.0.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let ((a0, a1), (b0, b1)) = (self.0.split_at(mid), self.1.split_at(mid));
        ((a0, b0), (a1, b1))
    }
    fn sub(self, r: std::ops::Range<usize>) -> Self {
        (self.0.sub(r.clone()), self.1.sub(r))
    }
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self> {
        self.0.serial_rows(n).zip(self.1.serial_rows(n))
    }
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self> {
        self.0.par_rows(n).zip(self.1.par_rows(n))
    }
}

impl<A: Lanes, B: Lanes, C: Lanes> Lanes for (A, B, C) {
    fn len(&self) -> usize {
        assert!(
            self.0.len() == self.1.len() && self.0.len() == self.2.len(),
            "lanes of unequal length"
        );
        self.0.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (a, b, c) = (
            self.0.split_at(mid),
            self.1.split_at(mid),
            self.2.split_at(mid),
        );
        ((a.0, b.0, c.0), (a.1, b.1, c.1))
    }
    fn sub(self, r: std::ops::Range<usize>) -> Self {
        (self.0.sub(r.clone()), self.1.sub(r.clone()), self.2.sub(r))
    }
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self> {
        self.0
            .serial_rows(n)
            .zip(self.1.serial_rows(n))
            .zip(self.2.serial_rows(n))
            .map(|((a, b), c)| (a, b, c))
    }
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self> {
        self.0
            .par_rows(n)
            .zip(self.1.par_rows(n))
            .zip(self.2.par_rows(n))
            .map(|((a, b), c)| (a, b, c))
    }
}

/// One item of `items` per row of `row_len` elements of slices `len` long: a lane that gives
/// each row its own scratch or partial result (`items.len()` must be the number of rows). A
/// row's kernel takes its item with [`PerRow::item`].
pub fn per_row<T: Send>(items: &mut [T], row_len: usize, len: usize) -> PerRow<'_, T> {
    assert_eq!(
        items.len(),
        len.div_ceil(row_len.max(1)),
        "one item per row"
    );
    PerRow {
        items,
        row_len,
        len,
    }
}

/// The lane of [`per_row`].
pub struct PerRow<'a, T> {
    items: &'a mut [T],
    row_len: usize,
    len: usize,
}

impl<'a, T: Send> PerRow<'a, T> {
    /// The item of a one-row lane (the kernel's).
    pub fn item(self) -> &'a mut T {
        assert_eq!(self.items.len(), 1, "a row has one item");
        &mut self.items[0]
    }
}

impl<T: Send> Lanes for PerRow<'_, T> {
    fn len(&self) -> usize {
        self.len
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        assert_eq!(mid % self.row_len, 0, "split between rows");
        let (a, b) = self.items.split_at_mut(mid / self.row_len);
        let (n, len) = (self.row_len, self.len);
        (
            PerRow {
                items: a,
                row_len: n,
                len: mid,
            },
            PerRow {
                items: b,
                row_len: n,
                len: len - mid,
            },
        )
    }
    fn sub(self, _: std::ops::Range<usize>) -> Self {
        self
    }
    fn serial_rows(self, n: usize) -> impl Iterator<Item = Self> {
        assert_eq!(n, self.row_len, "rows of the item's length");
        let len = self.len;
        self.items
            .chunks_mut(1)
            .enumerate()
            .map(move |(j, t)| PerRow {
                items: t,
                row_len: n,
                len: n.min(len - j * n),
            })
    }
    fn par_rows(self, n: usize) -> impl IndexedParallelIterator<Item = Self> {
        assert_eq!(n, self.row_len, "rows of the item's length");
        let len = self.len;
        self.items
            .par_chunks_mut(1)
            .enumerate()
            .map(move |(j, t)| PerRow {
                items: t,
                row_len: n,
                len: n.min(len - j * n),
            })
    }
}

/// The rows of `lanes`, `row_len` elements each: [`Rows::for_each`] and [`Rows::fold`].
pub fn rows<L: Lanes>(lanes: L, row_len: usize) -> Rows<L> {
    Rows {
        lanes,
        row_len,
        work: row_len,
    }
}

/// The fixed chunks of [`REDUCE_CHUNK`] elements of `lanes` (the rows of [`rows`]); a kernel
/// receives the chunk's first element's offset, `j · REDUCE_CHUNK`, instead of its number.
pub fn chunks<L: Lanes>(lanes: L) -> Chunks<L> {
    Chunks(rows(lanes, REDUCE_CHUNK))
}

/// The indices `0..n`, each standing for `work` element operations (default 1):
/// [`Indices::for_each`] and [`Indices::fold`].
pub fn range(n: usize) -> Indices {
    Indices { n, work: 1 }
}

/// Rows of slices, split across threads when there is enough work (see [`rows`]).
pub struct Rows<L> {
    lanes: L,
    row_len: usize,
    work: usize,
}

impl<L: Lanes> Rows<L> {
    /// Rows that each cost `work` element operations (default: their length), which decides
    /// whether and how finely the loop is split: a coarse row that sums several fine rows is
    /// worth more than its length.
    pub fn work(self, work: usize) -> Self {
        Rows { work, ..self }
    }

    /// The rows in order, on this thread (for an outer loop around parallel inner ones).
    pub fn serial(self) -> impl Iterator<Item = L> {
        self.lanes.serial_rows(self.row_len.max(1))
    }

    /// Number of rows, and the fewest rows a thread takes (`None`: run serially).
    fn split(&self) -> (usize, Option<usize>) {
        let rows = self.lanes.len().div_ceil(self.row_len);
        let par = rows * self.work >= PAR_MIN;
        (
            rows,
            par.then(|| (PAR_MIN / 2).div_ceil(self.work.max(1)).max(1)),
        )
    }

    /// Run `f(j, row_j)` over the rows; rows write disjoint elements, so the result is the
    /// serial loop's on any number of threads.
    pub fn for_each(self, f: impl Fn(usize, L) + Sync + Send) {
        if self.row_len == 0 {
            return;
        }
        match self.split() {
            (_, None) => self
                .lanes
                .serial_rows(self.row_len)
                .enumerate()
                .for_each(|(j, r)| f(j, r)),
            (_, Some(min)) => self
                .lanes
                .par_rows(self.row_len)
                .enumerate()
                .with_min_len(min)
                .for_each(|(j, r)| f(j, r)),
        }
    }

    /// `combine(…combine(combine(init, f(0, row₀)), f(1, row₁))…)`: each row's partial,
    /// computed in parallel when there is enough work, folded in row order — the same bits on
    /// any number of threads. The kernel may also write its rows (an update fused with a
    /// reduction over what it writes, in one pass over memory).
    pub fn fold<A, P: Copy + Default + Send>(
        self,
        init: A,
        f: impl Fn(usize, L) -> P + Sync + Send,
        combine: impl Fn(A, P) -> A,
    ) -> A {
        let mut acc = init;
        if self.row_len == 0 {
            return acc;
        }
        let (_, min) = self.split();
        let Some(min) = min else {
            for (j, r) in self.lanes.serial_rows(self.row_len).enumerate() {
                acc = combine(acc, f(j, r));
            }
            return acc;
        };
        // Blocks of at most MAX_PARTS rows: their partials on the stack, folded in order.
        let block = self.row_len * MAX_PARTS;
        let mut rest = self.lanes;
        let mut j0 = 0;
        while !rest.is_empty() {
            let mid = block.min(rest.len());
            let (a, b) = rest.split_at(mid);
            rest = b;
            let n = a.len().div_ceil(self.row_len);
            let mut parts = [P::default(); MAX_PARTS];
            parts[..n]
                .par_iter_mut()
                .zip(a.par_rows(self.row_len))
                .enumerate()
                .with_min_len(min)
                .for_each(|(j, (p, r))| *p = f(j0 + j, r));
            for p in &parts[..n] {
                acc = combine(acc, *p);
            }
            j0 += n;
        }
        acc
    }
}

/// The chunks of [`chunks`].
pub struct Chunks<L>(Rows<L>);

impl<L: Lanes> Chunks<L> {
    /// Run `f(offset, chunk)` over the chunks (element-wise loops whose body the compiler sees
    /// whole, so it vectorises).
    pub fn for_each(self, f: impl Fn(usize, L) + Sync + Send) {
        self.0.for_each(|c, l| f(c * REDUCE_CHUNK, l));
    }

    /// [`Rows::fold`] over the chunks: `f(offset, chunk)` partials folded in chunk order.
    pub fn fold<A, P: Copy + Default + Send>(
        self,
        init: A,
        f: impl Fn(usize, L) -> P + Sync + Send,
        combine: impl Fn(A, P) -> A,
    ) -> A {
        self.0.fold(init, |c, l| f(c * REDUCE_CHUNK, l), combine)
    }
}

/// The indices of [`range`].
pub struct Indices {
    n: usize,
    work: usize,
}

impl Indices {
    /// Indices that each cost `work` element operations (see [`Rows::work`]).
    pub fn work(self, work: usize) -> Self {
        Indices { work, ..self }
    }

    fn min_len(&self) -> Option<usize> {
        (self.n * self.work >= PAR_MIN).then(|| (PAR_MIN / 2).div_ceil(self.work.max(1)).max(1))
    }

    /// Run `f(j)` for `j in 0..n`, in parallel when there is enough work. `f` must only touch
    /// data disjoint between indices (a safe `f` can only write through its own captures'
    /// interior mutability, so this is the loop for kernels that write by other means).
    pub fn for_each(self, f: impl Fn(usize) + Sync + Send) {
        match self.min_len() {
            None => (0..self.n).for_each(f),
            Some(min) => (0..self.n).into_par_iter().with_min_len(min).for_each(f),
        }
    }

    /// `combine(…combine(init, f(0))…, f(n − 1))`, the partials computed in parallel when
    /// there is enough work and folded in index order (the same bits on any number of threads).
    pub fn fold<A, P: Copy + Default + Send>(
        self,
        init: A,
        f: impl Fn(usize) -> P + Sync + Send,
        combine: impl Fn(A, P) -> A,
    ) -> A {
        let mut acc = init;
        let Some(min) = self.min_len() else {
            for j in 0..self.n {
                acc = combine(acc, f(j));
            }
            return acc;
        };
        let mut parts = [P::default(); MAX_PARTS];
        for b in (0..self.n).step_by(MAX_PARTS) {
            let n = MAX_PARTS.min(self.n - b);
            parts[..n]
                .par_iter_mut()
                .enumerate()
                .with_min_len(min)
                .for_each(|(j, p)| *p = f(b + j));
            for p in &parts[..n] {
                acc = combine(acc, *p);
            }
        }
        acc
    }
}

/// Component-wise `a + b`, the combiner of several sums folded at once.
#[inline]
pub fn add<const N: usize>(mut a: [f64; N], b: [f64; N]) -> [f64; N] {
    for (a, b) in a.iter_mut().zip(b) {
        *a += b;
    }
    a
}

/// A view of a mutable slice that several threads may write at **disjoint** indices while
/// others read indices nobody writes in the same parallel loop: the red–black Gauss–Seidel
/// sweep, where one colour is written and only the other is read, so no safe split of the
/// slice into owned pieces exists (a row's update reads its neighbour rows' cells of the other
/// colour while those rows' cells of its own colour are written by other threads).
///
/// Bounds are checked in release builds too, once per span: a kernel passes the range a row of
/// its loop touches to [`SharedSlice::check`] (which panics if it leaves the slice) and then
/// reads and writes inside it with `get`/`set`, which check each index in debug builds. What
/// the compiler cannot check is the absence of a data race, which is the caller's proof at each
/// `unsafe` block (the sweep's phases, whose two colours and row chunks never let one thread
/// write an element another touches). The view borrows the slice mutably for its lifetime, so
/// no other access can alias it.
#[derive(Clone, Copy)]
pub(crate) struct SharedSlice<'a> {
    ptr: *mut f64,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: access is through `get`/`set`, whose callers guarantee no element is written by one
// thread while another reads or writes it; the pointer is valid for `len` elements for 'a.
unsafe impl Send for SharedSlice<'_> {}
unsafe impl Sync for SharedSlice<'_> {}

impl<'a> SharedSlice<'a> {
    /// A view of `s`, which stays mutably borrowed while the view lives.
    pub(crate) fn new(s: &'a mut [f64]) -> Self {
        SharedSlice {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _borrow: std::marker::PhantomData,
        }
    }
    /// Panics unless `r` lies within the slice: the span a kernel's `get`/`set` will touch.
    #[inline(always)]
    pub(crate) fn check(self, r: std::ops::Range<usize>) {
        assert!(
            r.start <= r.end && r.end <= self.len,
            "SharedSlice: span {r:?} past {}",
            self.len
        );
    }
    /// Read element `k`.
    ///
    /// # Safety
    /// `k` lies in a span passed to [`check`](Self::check), and no other thread writes
    /// element `k` during this parallel loop.
    #[inline(always)]
    pub(crate) unsafe fn get(self, k: usize) -> f64 {
        debug_assert!(k < self.len);
        // SAFETY: in bounds (a checked span, caller), valid for 'a, not concurrently written.
        unsafe { *self.ptr.add(k) }
    }
    /// Write element `k`.
    ///
    /// # Safety
    /// `k` lies in a span passed to [`check`](Self::check), and no other thread reads or
    /// writes element `k` during this parallel loop.
    #[inline(always)]
    pub(crate) unsafe fn set(self, k: usize, v: f64) {
        debug_assert!(k < self.len);
        // SAFETY: in bounds (a checked span, caller), valid for 'a, exclusively owned here.
        unsafe { *self.ptr.add(k) = v }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dot_is_the_same_on_one_and_two_threads() {
        let n = 100_003;
        let a: Vec<f64> = (0..n)
            .map(|k| ((k * 7919) % 1013) as f64 / 17.0 - 20.0)
            .collect();
        let b: Vec<f64> = (0..n).map(|k| ((k * 10_007) % 997) as f64 / 3.0).collect();
        let run = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| dot(&a, &b))
        };
        let (d1, d2) = (run(1), run(2));
        assert_eq!(d1.to_bits(), d2.to_bits());
        let exact: f64 = a.iter().zip(&b).map(|(a, b)| a * b).sum();
        assert!((d1 - exact).abs() <= 1e-12 * exact.abs());
    }

    fn pool(t: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    }

    #[test]
    fn index_folds_are_the_same_on_one_and_two_threads_and_in_index_order() {
        let (rows, len) = (700, 300);
        let f = |j: usize| {
            let r = (0..len).fold(0.0, |a, i| a + ((i * 31 + j * 17) % 101) as f64 / 7.0);
            [r, -0.5 * r, 1.0]
        };
        let run = |t| pool(t).install(|| range(rows).work(len).fold([0.0; 3], f, add));
        let (a, b) = (run(1), run(2));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        let serial = (0..rows).fold([0.0; 3], |s, j| add(s, f(j)));
        assert_eq!(a, serial, "partials added in index order");
        assert_eq!(a[2], rows as f64);
    }

    #[test]
    fn fused_row_updates_and_reductions_do_not_depend_on_the_threads() {
        // Three lanes, two written and one read; rows of an odd length with a short last row,
        // long enough for several blocks of partials.
        let n = 3 * 4096 * 512 / 7 + 5;
        let c: Vec<f64> = (0..n)
            .map(|k| ((k * 7919) % 1013) as f64 / 17.0 - 20.0)
            .collect();
        let run = |t: usize, row: usize| {
            let (mut a, mut b) = (vec![1.0; n], vec![0.0; n]);
            let s = pool(t).install(|| {
                rows((&mut a[..], &mut b[..], &c[..]), row).fold(
                    (0.0, 0.0),
                    |j, (a, b, c)| {
                        let mut p = (0.0, 0.0);
                        for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                            *a = c * 0.5 + j as f64;
                            *b = c - *a;
                            p = (p.0 + *a, p.1 + *a * *b);
                        }
                        p
                    },
                    |s, p| (s.0 + p.0, s.1 + p.1),
                )
            });
            (s.0.to_bits(), s.1.to_bits(), a, b)
        };
        for row in [1, 97, REDUCE_CHUNK] {
            assert_eq!(run(1, row), run(2, row), "rows of {row}");
        }
        // The chunks' offsets, and the rows' numbers, are those of the serial loop.
        let mut y = vec![0.0; 3 * REDUCE_CHUNK + 5];
        pool(2).install(|| {
            chunks(&mut y[..]).for_each(|o, y| {
                y.iter_mut()
                    .enumerate()
                    .for_each(|(k, v)| *v = (o + k) as f64)
            })
        });
        assert!(y.iter().enumerate().all(|(k, v)| *v == k as f64));
        let mut y = vec![0.0; 10_001];
        pool(2).install(|| {
            rows(&mut y[..], 10)
                .work(1000)
                .for_each(|j, r| r.fill(j as f64))
        });
        assert!(y.iter().enumerate().all(|(k, v)| *v == (k / 10) as f64));
    }

    #[test]
    fn dot2_is_two_dots() {
        let n: usize = 4096 * 512 + 4099;
        let a: Vec<f64> = (0..n).map(|k| ((k * 7919) % 1013) as f64 / 17.0).collect();
        let b: Vec<f64> = (0..n).map(|k| ((k * 31) % 97) as f64 - 40.0).collect();
        let c: Vec<f64> = (0..n).map(|k| ((k * 13) % 89) as f64 / 3.0).collect();
        let (x, y) = pool(2).install(|| dot2(&a, &b, &c));
        assert_eq!(
            (x.to_bits(), y.to_bits()),
            (dot(&a, &b).to_bits(), dot(&a, &c).to_bits())
        );
    }
}
