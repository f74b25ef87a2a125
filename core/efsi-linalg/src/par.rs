//! Data-parallel loops (rayon) whose results do not depend on the number of threads.
//!
//! Every parallel loop here either writes disjoint elements from read-only inputs (bit-identical
//! to the serial loop by construction) or, for reductions, sums fixed-size chunks and then adds
//! the chunk sums in order — the same summation tree whatever the pool size, so a solve run on
//! one thread and on many gives bit-identical iterates.

use rayon::prelude::*;

/// Length of the fixed chunks of a reduction (a multiple of 4).
pub const REDUCE_CHUNK: usize = 4096;

/// Below this many elements a loop runs serially (a fork costs a few microseconds).
///
/// Chosen by measurement (whole processes on two threads, interleaved, each round started on a
/// quiet machine, 2026-11-28): 2048 instead of 8192 made the 35-cells-per-radius sphere's
/// two-thread run 7–8 % faster (medians of 6, 8 and 10 rounds: 0.967, 0.917, 0.927 of 8192's
/// time), with the drop 256² (0.985) and the cavity 128² (1.042 and 0.915 in two sets of
/// rounds) within the noise and one thread unchanged (0.995–1.004); 1024 and 512 were no better
/// than 2048 (sphere 0.916–0.934 and 0.897–0.914), 16384 and 32768 9 % and 16 % slower.
pub const PAR_MIN: usize = 2048;

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

/// `Σ a_k b_k`, summed in fixed chunks of [`REDUCE_CHUNK`] added in order: the result is the
/// same bit for bit whatever the number of threads.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    if a.len() < PAR_MIN {
        return a
            .chunks(REDUCE_CHUNK)
            .zip(b.chunks(REDUCE_CHUNK))
            .map(|(a, b)| dot_serial(a, b))
            .fold(0.0, |s, v| s + v);
    }
    let n = a.len().div_ceil(REDUCE_CHUNK);
    // At most a few hundred chunk sums: a small stack buffer, folded in order.
    const MAX: usize = 512;
    if n <= MAX {
        let mut parts = [0.0f64; MAX];
        parts[..n]
            .par_iter_mut()
            .zip(a.par_chunks(REDUCE_CHUNK).zip(b.par_chunks(REDUCE_CHUNK)))
            .for_each(|(p, (a, b))| *p = dot_serial(a, b));
        parts[..n].iter().fold(0.0, |s, v| s + v)
    } else {
        a.chunks(REDUCE_CHUNK * MAX)
            .zip(b.chunks(REDUCE_CHUNK * MAX))
            .map(|(a, b)| dot(a, b))
            .fold(0.0, |s, v| s + v)
    }
}

/// `(Σ a_k b_k, Σ a_k c_k)` in one pass, each summed as [`dot`] sums it (the same bits as
/// two calls, on any number of threads).
pub fn dot2(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    assert!(a.len() == b.len() && a.len() == c.len());
    let add = |s: (f64, f64), v: (f64, f64)| (s.0 + v.0, s.1 + v.1);
    let part = |o: usize, a: &[f64]| {
        let n = a.len();
        (dot_serial(a, &b[o..o + n]), dot_serial(a, &c[o..o + n]))
    };
    if a.len() < PAR_MIN {
        return a
            .chunks(REDUCE_CHUNK)
            .enumerate()
            .map(|(k, a)| part(k * REDUCE_CHUNK, a))
            .fold((0.0, 0.0), add);
    }
    let big = REDUCE_CHUNK * MAX_PARTS;
    if a.len() <= big {
        let n = a.len().div_ceil(REDUCE_CHUNK);
        let mut parts = [(0.0f64, 0.0f64); MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(a.par_chunks(REDUCE_CHUNK))
            .enumerate()
            .for_each(|(k, (p, a))| *p = part(k * REDUCE_CHUNK, a));
        parts[..n].iter().fold((0.0, 0.0), |s, v| add(s, *v))
    } else {
        // As `dot` does: each block of chunks folded, then the blocks.
        (0..a.len().div_ceil(big))
            .map(|m| {
                let r = m * big..((m + 1) * big).min(a.len());
                dot2(&a[r.clone()], &b[r.clone()], &c[r])
            })
            .fold((0.0, 0.0), add)
    }
}

/// Largest number of chunk partials a reduction keeps on the stack at once.
const MAX_PARTS: usize = 512;

/// `f(offset, a_chunk, b_chunk)` over the fixed chunks of [`REDUCE_CHUNK`] elements of two
/// equal-length slices (in parallel when they are long), each returning a partial result;
/// the partials are folded in chunk order, `combine(…combine(combine(init, p₀), p₁)…)`. The
/// chunks and the fold do not depend on the number of threads, so neither does the result.
/// This fuses an element-wise update with a reduction over its results (one pass over
/// memory instead of two).
pub fn reduce_chunks2(
    a: &mut [f64],
    b: &mut [f64],
    init: f64,
    f: impl Fn(usize, &mut [f64], &mut [f64]) -> f64 + Sync + Send,
    combine: impl Fn(f64, f64) -> f64,
) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut acc = init;
    if a.len() < PAR_MIN {
        for (c, (x, y)) in a
            .chunks_mut(REDUCE_CHUNK)
            .zip(b.chunks_mut(REDUCE_CHUNK))
            .enumerate()
        {
            acc = combine(acc, f(c * REDUCE_CHUNK, x, y));
        }
        return acc;
    }
    let big = REDUCE_CHUNK * MAX_PARTS;
    for (s, (a, b)) in a.chunks_mut(big).zip(b.chunks_mut(big)).enumerate() {
        let n = a.len().div_ceil(REDUCE_CHUNK);
        let mut parts = [0.0f64; MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(
                a.par_chunks_mut(REDUCE_CHUNK)
                    .zip(b.par_chunks_mut(REDUCE_CHUNK)),
            )
            .enumerate()
            .for_each(|(c, (p, (x, y)))| *p = f(s * big + c * REDUCE_CHUNK, x, y));
        for p in &parts[..n] {
            acc = combine(acc, *p);
        }
    }
    acc
}

/// [`reduce_chunks2`] over three equal-length slices, with a pair of partials per chunk
/// (two reductions in one pass), folded in chunk order.
pub fn reduce_chunks3(
    a: &mut [f64],
    b: &mut [f64],
    c: &mut [f64],
    init: (f64, f64),
    f: impl Fn(usize, &mut [f64], &mut [f64], &mut [f64]) -> (f64, f64) + Sync + Send,
    combine: impl Fn((f64, f64), (f64, f64)) -> (f64, f64),
) -> (f64, f64) {
    assert!(a.len() == b.len() && a.len() == c.len());
    let mut acc = init;
    if a.len() < PAR_MIN {
        for (k, ((x, y), z)) in a
            .chunks_mut(REDUCE_CHUNK)
            .zip(b.chunks_mut(REDUCE_CHUNK))
            .zip(c.chunks_mut(REDUCE_CHUNK))
            .enumerate()
        {
            acc = combine(acc, f(k * REDUCE_CHUNK, x, y, z));
        }
        return acc;
    }
    let big = REDUCE_CHUNK * MAX_PARTS;
    for (s, ((a, b), c)) in a
        .chunks_mut(big)
        .zip(b.chunks_mut(big))
        .zip(c.chunks_mut(big))
        .enumerate()
    {
        let n = a.len().div_ceil(REDUCE_CHUNK);
        let mut parts = [(0.0f64, 0.0f64); MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(
                a.par_chunks_mut(REDUCE_CHUNK)
                    .zip(b.par_chunks_mut(REDUCE_CHUNK))
                    .zip(c.par_chunks_mut(REDUCE_CHUNK)),
            )
            .enumerate()
            .for_each(|(k, (p, ((x, y), z)))| *p = f(s * big + k * REDUCE_CHUNK, x, y, z));
        for p in &parts[..n] {
            acc = combine(acc, *p);
        }
    }
    acc
}

/// [`reduce_chunks2`] over one slice.
pub fn reduce_chunks(
    a: &mut [f64],
    init: f64,
    f: impl Fn(usize, &mut [f64]) -> f64 + Sync + Send,
    combine: impl Fn(f64, f64) -> f64,
) -> f64 {
    let mut acc = init;
    if a.len() < PAR_MIN {
        for (c, x) in a.chunks_mut(REDUCE_CHUNK).enumerate() {
            acc = combine(acc, f(c * REDUCE_CHUNK, x));
        }
        return acc;
    }
    let big = REDUCE_CHUNK * MAX_PARTS;
    for (s, a) in a.chunks_mut(big).enumerate() {
        let n = a.len().div_ceil(REDUCE_CHUNK);
        let mut parts = [0.0f64; MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(a.par_chunks_mut(REDUCE_CHUNK))
            .enumerate()
            .for_each(|(c, (p, x))| *p = f(s * big + c * REDUCE_CHUNK, x));
        for p in &parts[..n] {
            acc = combine(acc, *p);
        }
    }
    acc
}

/// Four-lane sum of `f(k)` for `k in 0..n` (vectorises when `f` does), for the partials of
/// [`reduce_chunks`] and [`reduce_chunks2`].
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

/// Run `f(offset, y_chunk)` over chunks of `y` (in parallel when it is long): an element-wise
/// loop whose body the compiler sees whole (it vectorises, unlike a closure per element).
pub fn for_each_chunk(y: &mut [f64], f: impl Fn(usize, &mut [f64]) + Sync + Send) {
    if y.len() < PAR_MIN {
        f(0, y);
    } else {
        y.par_chunks_mut(REDUCE_CHUNK)
            .enumerate()
            .for_each(|(c, x)| f(c * REDUCE_CHUNK, x));
    }
}

/// Run `f(k, &mut y[k], …)` over the elements of `y`, in parallel when it is long.
pub fn for_each_mut(y: &mut [f64], f: impl Fn(usize, &mut f64) + Sync + Send) {
    if y.len() < PAR_MIN {
        y.iter_mut().enumerate().for_each(|(k, v)| f(k, v));
    } else {
        y.par_iter_mut()
            .enumerate()
            .with_min_len(PAR_MIN / 2)
            .for_each(|(k, v)| f(k, v));
    }
}

/// Run `f(j, row)` over the rows (`row_len` long) of `y`, in parallel when `y` is long.
pub fn for_each_row(y: &mut [f64], row_len: usize, f: impl Fn(usize, &mut [f64]) + Sync + Send) {
    for_each_row_weighted(y, row_len, row_len, f);
}

/// [`for_each_row`] for rows that each cost `work` element operations, which decides whether
/// (and how finely) to split the loop: a coarse row that sums several fine rows is worth more
/// than its length.
pub fn for_each_row_weighted(
    y: &mut [f64],
    row_len: usize,
    work: usize,
    f: impl Fn(usize, &mut [f64]) + Sync + Send,
) {
    if row_len == 0 {
        return;
    }
    let rows = y.len().div_ceil(row_len);
    if rows * work < PAR_MIN {
        y.chunks_mut(row_len).enumerate().for_each(|(j, r)| f(j, r));
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(work.max(1)).max(1);
        y.par_chunks_mut(row_len)
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, r)| f(j, r));
    }
}

/// Run `f(j, row) -> partial` over the rows (`row_len` long) of `y`, in parallel when `y` is
/// long, and return the partials summed in row order (the same bits on any number of
/// threads): a row loop that also reduces over what it writes, in one pass.
pub fn for_each_row_sum(
    y: &mut [f64],
    row_len: usize,
    f: impl Fn(usize, &mut [f64]) -> f64 + Sync + Send,
) -> f64 {
    if row_len == 0 {
        return 0.0;
    }
    if y.len() < PAR_MIN {
        return y
            .chunks_mut(row_len)
            .enumerate()
            .fold(0.0, |s, (j, r)| s + f(j, r));
    }
    let min_rows = (PAR_MIN / 2).div_ceil(row_len).max(1);
    let mut acc = 0.0;
    for (b, block) in y.chunks_mut(row_len * MAX_PARTS).enumerate() {
        let n = block.len().div_ceil(row_len);
        let mut parts = [0.0f64; MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(block.par_chunks_mut(row_len))
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, (p, r))| *p = f(b * MAX_PARTS + j, r));
        for p in &parts[..n] {
            acc += p;
        }
    }
    acc
}

/// Run `f(j, a_row, b_row, c_row) -> (p, q)` over the rows (`row_len` long) of three
/// equal-length slices, in parallel when they are long, and return the partials summed
/// component-wise in row order (the same bits on any number of threads): an element-wise
/// update of three vectors fused with two reductions over what it writes, in one pass.
pub fn for_each_row3_sum2(
    a: &mut [f64],
    b: &mut [f64],
    c: &mut [f64],
    row_len: usize,
    f: impl Fn(usize, &mut [f64], &mut [f64], &mut [f64]) -> (f64, f64) + Sync + Send,
) -> (f64, f64) {
    assert!(a.len() == b.len() && a.len() == c.len());
    let mut acc = (0.0, 0.0);
    if row_len == 0 {
        return acc;
    }
    if a.len() < PAR_MIN {
        for (j, ((x, y), z)) in a
            .chunks_mut(row_len)
            .zip(b.chunks_mut(row_len))
            .zip(c.chunks_mut(row_len))
            .enumerate()
        {
            let p = f(j, x, y, z);
            acc = (acc.0 + p.0, acc.1 + p.1);
        }
        return acc;
    }
    let min_rows = (PAR_MIN / 2).div_ceil(row_len).max(1);
    let block = row_len * MAX_PARTS;
    for (k, ((a, b), c)) in a
        .chunks_mut(block)
        .zip(b.chunks_mut(block))
        .zip(c.chunks_mut(block))
        .enumerate()
    {
        let n = a.len().div_ceil(row_len);
        let mut parts = [(0.0f64, 0.0f64); MAX_PARTS];
        parts[..n]
            .par_iter_mut()
            .zip(
                a.par_chunks_mut(row_len)
                    .zip(b.par_chunks_mut(row_len))
                    .zip(c.par_chunks_mut(row_len)),
            )
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, (p, ((x, y), z)))| *p = f(k * MAX_PARTS + j, x, y, z));
        for p in &parts[..n] {
            acc = (acc.0 + p.0, acc.1 + p.1);
        }
    }
    acc
}

/// Run `f(j, a_row, b_row)` over the rows (`row_len` long) of two equal-length slices, in
/// parallel when they are long.
pub fn for_each_row2(
    a: &mut [f64],
    b: &mut [f64],
    row_len: usize,
    f: impl Fn(usize, &mut [f64], &mut [f64]) + Sync + Send,
) {
    assert_eq!(a.len(), b.len());
    if row_len == 0 {
        return;
    }
    if a.len() < PAR_MIN {
        a.chunks_mut(row_len)
            .zip(b.chunks_mut(row_len))
            .enumerate()
            .for_each(|(j, (x, y))| f(j, x, y));
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(row_len).max(1);
        a.par_chunks_mut(row_len)
            .zip(b.par_chunks_mut(row_len))
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, (x, y))| f(j, x, y));
    }
}

/// Run `f(j, row, &mut out[j])` over the rows (`row_len` long) of `y`, in parallel when `y` is
/// long: each row also writes its own partial result (`out` holds one per row), which the
/// caller folds in row order — a reduction, or several at once, whose result does not depend
/// on the number of threads.
pub fn for_each_row_with<T: Send>(
    y: &mut [f64],
    row_len: usize,
    out: &mut [T],
    f: impl Fn(usize, &mut [f64], &mut T) + Sync + Send,
) {
    if row_len == 0 {
        return;
    }
    assert_eq!(out.len(), y.len().div_ceil(row_len), "one partial per row");
    if y.len() < PAR_MIN {
        y.chunks_mut(row_len)
            .zip(out.iter_mut())
            .enumerate()
            .for_each(|(j, (r, o))| f(j, r, o));
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(row_len).max(1);
        y.par_chunks_mut(row_len)
            .zip(out.par_iter_mut())
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, (r, o))| f(j, r, o));
    }
}

/// [`for_each_row_with`] over the rows of two equal-length slices: `f(j, a_row, b_row,
/// &mut out[j])`.
pub fn for_each_row2_with<T: Send>(
    a: &mut [f64],
    b: &mut [f64],
    row_len: usize,
    out: &mut [T],
    f: impl Fn(usize, &mut [f64], &mut [f64], &mut T) + Sync + Send,
) {
    assert_eq!(a.len(), b.len());
    if row_len == 0 {
        return;
    }
    assert_eq!(out.len(), a.len().div_ceil(row_len), "one partial per row");
    if a.len() < PAR_MIN {
        a.chunks_mut(row_len)
            .zip(b.chunks_mut(row_len))
            .zip(out.iter_mut())
            .enumerate()
            .for_each(|(j, ((x, y), o))| f(j, x, y, o));
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(row_len).max(1);
        a.par_chunks_mut(row_len)
            .zip(b.par_chunks_mut(row_len))
            .zip(out.par_iter_mut())
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, ((x, y), o))| f(j, x, y, o));
    }
}

/// `Σ_j f(j)` for `j in 0..rows` (rows of `row_len` elements), component-wise for `N`
/// sums at once, in parallel when there is enough work: each row's partials are added in row
/// order, so the result is the same bit for bit on any number of threads.
pub fn sum_rows<const N: usize>(
    rows: usize,
    row_len: usize,
    f: impl Fn(usize) -> [f64; N] + Sync + Send,
) -> [f64; N] {
    let mut acc = [0.0f64; N];
    let mut add = |p: [f64; N]| {
        for (a, v) in acc.iter_mut().zip(p) {
            *a += v;
        }
    };
    if rows * row_len < PAR_MIN {
        (0..rows).for_each(|j| add(f(j)));
        return acc;
    }
    let min_rows = (PAR_MIN / 2).div_ceil(row_len.max(1)).max(1);
    const BLOCK: usize = 256;
    let mut parts = [[0.0f64; N]; BLOCK];
    for b in (0..rows).step_by(BLOCK) {
        let n = BLOCK.min(rows - b);
        parts[..n]
            .par_iter_mut()
            .enumerate()
            .with_min_len(min_rows)
            .for_each(|(j, p)| *p = f(b + j));
        parts[..n].iter().for_each(|p| add(*p));
    }
    acc
}

/// `max(init, max_j f(j))` for `j in 0..rows` (rows of `row_len` elements), in parallel when
/// there is enough work; a maximum does not depend on the order, so neither on the number of
/// threads.
pub fn max_over_rows(
    rows: usize,
    row_len: usize,
    init: f64,
    f: impl Fn(usize) -> f64 + Sync + Send,
) -> f64 {
    if rows * row_len < PAR_MIN {
        (0..rows).map(f).fold(init, f64::max)
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(row_len.max(1)).max(1);
        (0..rows)
            .into_par_iter()
            .with_min_len(min_rows)
            .map(f)
            .reduce(|| init, f64::max)
    }
}

/// Run `f` — serial work between parallel loops — while another thread of the pool, if one
/// is free, spins until it is done, so that the parallel loop after it finds that thread
/// awake. A rayon worker with nothing to do falls asleep after some tens of microseconds,
/// and waking it costs about as long again: measured on the 2-core VM, a 256² red–black
/// sweep (100 µs on one thread, 52 µs on two back to back) took 94 µs on two threads after
/// a 50 µs serial pause. This is the "active wait" that OpenMP runtimes apply between
/// parallel regions, for the stretches where it pays (the multigrid's serial coarse levels).
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
    assert_eq!(dst.len(), src.len());
    for_each_chunk(dst, |o, d| {
        let n = d.len();
        d.copy_from_slice(&src[o..o + n]);
    });
}

/// Run `f(j)` for `j in 0..rows` (rows of `row_len` elements), in parallel when there is
/// enough work. `f` must only touch data disjoint between rows.
pub fn for_each_index(rows: usize, row_len: usize, f: impl Fn(usize) + Sync + Send) {
    if rows * row_len < PAR_MIN {
        (0..rows).for_each(f);
    } else {
        let min_rows = (PAR_MIN / 2).div_ceil(row_len.max(1)).max(1);
        (0..rows).into_par_iter().with_min_len(min_rows).for_each(f);
    }
}

/// A raw view of a mutable slice that several threads may write at **disjoint** indices while
/// others read indices nobody writes in the same parallel loop (the red–black Gauss–Seidel
/// sweep: one colour is written, only the other is read).
#[derive(Clone, Copy)]
pub(crate) struct SharedSlice {
    ptr: *mut f64,
    len: usize,
}

// SAFETY: access is through `get`/`set`, whose callers guarantee no element is written by one
// thread while another reads or writes it.
unsafe impl Send for SharedSlice {}
unsafe impl Sync for SharedSlice {}

impl SharedSlice {
    /// A view of `s` (which must outlive every use of the view).
    pub(crate) fn new(s: &mut [f64]) -> Self {
        SharedSlice {
            ptr: s.as_mut_ptr(),
            len: s.len(),
        }
    }
    /// Read element `k`.
    ///
    /// # Safety
    /// No other thread writes element `k` during this parallel loop.
    #[inline(always)]
    pub(crate) unsafe fn get(self, k: usize) -> f64 {
        debug_assert!(k < self.len);
        // SAFETY: in bounds (checked in debug builds) and not concurrently written (caller).
        unsafe { *self.ptr.add(k) }
    }
    /// Write element `k`.
    ///
    /// # Safety
    /// No other thread reads or writes element `k` during this parallel loop.
    #[inline(always)]
    pub(crate) unsafe fn set(self, k: usize, v: f64) {
        debug_assert!(k < self.len);
        // SAFETY: in bounds (checked in debug builds) and exclusively owned here (caller).
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

    #[test]
    fn row_sums_are_the_same_on_one_and_two_threads() {
        let (rows, len) = (700, 300);
        let f = |j: usize| {
            let r = (0..len).fold(0.0, |a, i| a + ((i * 31 + j * 17) % 101) as f64 / 7.0);
            [r, -0.5 * r, 1.0]
        };
        let run = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| sum_rows(rows, len, f))
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        let serial = (0..rows).fold([0.0; 3], |s, j| {
            let p = f(j);
            [s[0] + p[0], s[1] + p[1], s[2] + p[2]]
        });
        assert_eq!(a, serial, "row partials added in row order");
        assert_eq!(a[2], rows as f64);
    }
}
