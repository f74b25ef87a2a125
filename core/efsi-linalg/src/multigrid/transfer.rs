//! The transfer operators between levels: restriction of the residual (`R = Pᵀ`, summing the
//! children of each aggregate) and piecewise-constant prolongation `P` of the correction.

use super::level::Level;
use crate::par;

/// Cells per block of a row in [`restrict`] (even).
pub(super) const RUN: usize = 64;

/// `c.b = R (f.b − A f.x)`: the residual of the fine level summed over each aggregate, fine row
/// by fine row in the order (i, j) of the children — runs of residuals computed over slices,
/// then added pairwise (the same sums, in the same order, as one child at a time).
pub(super) fn restrict(f: &Level, c: &mut Level) {
    if f.is_3d() {
        restrict_3d(f, c);
        return;
    }
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let (fnx, fny, cnx, cs) = (f.nx, f.ny, c.nx, c.s);
    // A coarse row sums `fy` fine rows: split the loop by the fine work.
    par::rows(&mut c.b[cs..(c.ny + 1) * cs], cs)
        .work(fy * f.s)
        .for_each(|jc, row| {
            let out = &mut row[1..=cnx];
            out.fill(0.0);
            let mut r = [0.0f64; RUN];
            for j in fy * jc..(fy * jc + fy).min(fny) {
                let base = f.p(0, j);
                let mut i0 = 0;
                while i0 < fnx {
                    let len = (fnx - i0).min(RUN);
                    let r = &mut r[..len];
                    f.residual_run(base + i0, r);
                    add_run(out, i0, r, fx);
                    i0 += len;
                }
            }
        });
}

/// `f.x += P c.x`: piecewise-constant prolongation of the coarse correction.
pub(super) fn prolong(f: &mut Level, c: &Level) {
    if f.is_3d() {
        prolong_3d(f, c);
        return;
    }
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let (fnx, fs) = (f.nx, f.s);
    par::rows(&mut f.x[fs..(f.ny + 1) * fs], fs).for_each(|j, row| {
        let crow = &c.x[c.p(0, j / fy)..];
        let row = &mut row[1..=fnx];
        add_coarse(row, crow, fx);
    });
}

/// [`restrict`] of a three-dimensional level: coarse rows in parallel, each the sum over its
/// children, fine row by fine row in the order (i, j, c).
fn restrict_3d(f: &Level, c: &mut Level) {
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let fz = if c.nz < f.nz { 2 } else { 1 };
    let (fnx, fny, fnz, cnx) = (f.nx, f.ny, f.nz, c.nx);
    let span = c.rows_span();
    let (cny, cs) = (c.ny, c.s);
    par::rows(&mut c.b[span], cs)
        .work(fy * fz * f.s)
        .for_each(|r, row| {
            let (jc, kc) = (r % (cny + 2), r / (cny + 2));
            if jc >= cny {
                return;
            }
            let out = &mut row[1..=cnx];
            out.fill(0.0);
            let mut res = [0.0f64; RUN];
            for k in fz * kc..(fz * kc + fz).min(fnz) {
                for j in fy * jc..(fy * jc + fy).min(fny) {
                    let base = f.p3(0, j, k);
                    let mut i0 = 0;
                    while i0 < fnx {
                        let len = (fnx - i0).min(RUN);
                        let res = &mut res[..len];
                        f.residual_run_3d(base + i0, res);
                        add_run(out, i0, res, fx);
                        i0 += len;
                    }
                }
            }
        });
}

/// [`prolong`] on a three-dimensional level: fine rows in parallel.
fn prolong_3d(f: &mut Level, c: &Level) {
    let fx = if c.nx < f.nx { 2 } else { 1 };
    let fy = if c.ny < f.ny { 2 } else { 1 };
    let fz = if c.nz < f.nz { 2 } else { 1 };
    let (fnx, fny, fs) = (f.nx, f.ny, f.s);
    let span = f.rows_span();
    par::rows(&mut f.x[span], fs).for_each(|r, row| {
        let (j, k) = (r % (fny + 2), r / (fny + 2));
        if j >= fny {
            return;
        }
        let crow = &c.x[c.p3(0, j / fy, k / fz)..];
        let row = &mut row[1..=fnx];
        add_coarse(row, crow, fx);
    });
}

/// Add the fine residuals `r` of a run starting at fine column `i0` into the coarse row `out`:
/// pairs of fine columns into one coarse column when x is coarsened (`fx == 2`, a lone last
/// column into its own), column by column otherwise.
#[inline(always)]
fn add_run(out: &mut [f64], i0: usize, r: &[f64], fx: usize) {
    let len = r.len();
    if fx == 2 {
        let o = &mut out[i0 / 2..];
        let pairs = len / 2;
        for (m, o) in o[..pairs].iter_mut().enumerate() {
            *o = *o + r[2 * m] + r[2 * m + 1];
        }
        if len % 2 == 1 {
            o[pairs] += r[len - 1];
        }
    } else {
        for (o, r) in out[i0..i0 + len].iter_mut().zip(r.iter()) {
            *o += r;
        }
    }
}

/// Add the coarse row `crow` into the fine row `row` (piecewise-constant prolongation): each
/// coarse value into its pair of fine columns when x is coarsened (`fx == 2`), column by
/// column otherwise.
#[inline(always)]
fn add_coarse(row: &mut [f64], crow: &[f64], fx: usize) {
    if fx == 2 {
        for (pair, cx) in row.chunks_mut(2).zip(crow) {
            for x in pair {
                *x += cx;
            }
        }
    } else {
        for (x, cx) in row.iter_mut().zip(crow) {
            *x += cx;
        }
    }
}
