//! The multigrid cycle: smoothing, restriction, coarse corrections (two on the finest
//! [`W_LEVELS`] levels, one below), prolongation and smoothing in reverse order.

use super::W_LEVELS;
use super::coarsest::Coarsest;
use super::level::Level;
use super::transfer::{prolong, restrict};
use crate::par;

/// `levels[l].x ≈ A_l⁻¹ levels[l].b`, from zero: smoothing, `gamma` coarse corrections
/// (1: V-cycle, 2: W-cycle), smoothing in reverse order.
pub(super) fn cycle(
    levels: &mut [Level],
    coarsest: &mut Coarsest,
    l: usize,
    sweeps: usize,
    gamma: usize,
) {
    let nl = levels.len();
    if l + 1 == nl {
        coarsest.solve(&mut levels[l]);
        return;
    }
    {
        let lv = &mut levels[l];
        lv.x.fill(0.0);
        for _ in 0..sweeps {
            lv.sweep(0);
        }
        lv.fill_ghosts();
        let (f, c) = levels.split_at_mut(l + 1);
        restrict(&f[l], &mut c[0]);
    }
    let g = if l + 2 == nl || l >= W_LEVELS {
        1
    } else {
        gamma
    };
    for k in 0..g {
        if k > 0 {
            // Next correction from the residual of the current one.
            let c = &mut levels[l + 1];
            c.fill_ghosts();
            let mut t = std::mem::take(&mut c.t);
            let (cnx, cs) = (c.nx, c.s);
            if c.is_3d() {
                let span = c.rows_span();
                let o = span.start;
                par::rows(&mut t[span], cs).for_each(|r, row| {
                    if c.row_jc(r).is_some() {
                        c.residual_run_3d(o + r * cs + 1, &mut row[1..=cnx]);
                    }
                });
            } else {
                par::rows(&mut t[cs..(c.ny + 1) * cs], cs).for_each(|j, row| {
                    c.residual_run(c.p(0, j), &mut row[1..=cnx]);
                });
            }
            c.t = t;
            std::mem::swap(&mut c.b, &mut c.t);
            std::mem::swap(&mut c.x, &mut c.t);
        }
        if levels[l + 1].is_serial() && !levels[l].is_serial() {
            // The serial coarse levels: keep a second thread awake for the sweeps after them.
            par::serial_warm(|| cycle(levels, coarsest, l + 1, sweeps, gamma));
        } else {
            cycle(levels, coarsest, l + 1, sweeps, gamma);
        }
        if k > 0 {
            let c = &mut levels[l + 1];
            let t = &c.t;
            par::chunks(&mut c.x[..]).for_each(|o, x| {
                let n = x.len();
                for (x, t) in x.iter_mut().zip(&t[o..o + n]) {
                    *x += t;
                }
            });
        }
    }
    let (f, c) = levels.split_at_mut(l + 1);
    let lv = &mut f[l];
    prolong(lv, &c[0]);
    for _ in 0..sweeps {
        lv.sweep(1);
    }
}
