//! Flexible GMRES (Saad 1993) with restarts, for non-symmetric systems whose preconditioner
//! changes from one application to the next (an inner solve, a multigrid cycle on a block of
//! a saddle-point system).
//!
//! Right preconditioning: the iterate is `x = x₀ + Z y`, with `Z` the preconditioned vectors
//! kept (the "flexible" part: `z_k = M_k⁻¹ v_k` may differ for every `k`), and `y` minimising
//! `‖r₀ − A Z y‖₂` on the Arnoldi basis, orthogonalised by modified Gram–Schmidt. The
//! residual's norm is known from the Givens rotations without forming it; when it meets the
//! target, or after `restart` vectors, the iterate is formed and the **true** residual
//! `b − A x` handed to the caller's acceptance rule, which may ask for more (a
//! saddle-point system's blocks each have their own units and tolerance, which one 2-norm
//! cannot state). Workspace is allocated once ([`Fgmres::new`]); a solve allocates nothing.
//! Dot products sum fixed chunks in order ([`super::par`]), so the iterates do not depend on the
//! number of threads.

use super::par::{self, REDUCE_CHUNK, dot, dot_serial};
use rayon::prelude::*;

/// Reorthogonalise once when cancellation left less than this fraction of the new vector.
const REORTH: f64 = 0.01;
use super::pcg::{LinearOperator, SolveStats};

/// A preconditioner that may change between applications (`z ≈ M⁻¹ r`), as flexible Krylov
/// methods allow: it may run an inner iteration or keep state.
pub trait FlexiblePreconditioner {
    /// `z ← M⁻¹ r`.
    fn apply(&mut self, r: &[f64], z: &mut [f64]);
}

/// Reusable FGMRES workspace for systems of one size and restart length.
#[derive(Clone, Debug)]
pub struct Fgmres {
    restart: usize,
    /// The Arnoldi basis (`restart + 1` vectors) and the preconditioned vectors (`restart`).
    v: Vec<Vec<f64>>,
    z: Vec<Vec<f64>>,
    /// Hessenberg matrix by columns, Givens rotations, the rotated right-hand side, the
    /// least-squares coefficients.
    h: Vec<Vec<f64>>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    y: Vec<f64>,
    /// The residual `b − A x`.
    r: Vec<f64>,
    /// Per fixed chunk of the vectors, the partial dot products against the basis (and the
    /// new vector's own), folded in chunk order: thread-count independent.
    parts: Vec<f64>,
    /// This iteration's projections on the basis.
    proj: Vec<f64>,
}

/// The outcome of an acceptance check in [`Fgmres::solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Accept {
    /// The iterate is good enough: stop.
    Done,
    /// Go on until the residual's 2-norm is at most this (the caller's rule was not met with
    /// the previous target).
    Continue(f64),
}

impl Fgmres {
    /// Workspace for `n` unknowns, restarting after `restart` (≥ 1) vectors.
    pub fn new(n: usize, restart: usize) -> Self {
        let restart = restart.max(1);
        Fgmres {
            restart,
            v: vec![vec![0.0; n]; restart + 1],
            z: vec![vec![0.0; n]; restart],
            h: vec![vec![0.0; restart + 1]; restart],
            cs: vec![0.0; restart],
            sn: vec![0.0; restart],
            g: vec![0.0; restart + 1],
            y: vec![0.0; restart],
            r: vec![0.0; n],
            parts: vec![0.0; n.div_ceil(REDUCE_CHUNK).max(1) * (restart + 2)],
            proj: vec![0.0; restart + 2],
        }
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.r.len()
    }

    /// Whether the workspace is for no unknowns.
    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }

    /// Solve `A x = b` from the guess in `x`: iterate until the residual's 2-norm is at most
    /// `tol`, then ask `accept` with the true residual `b − A x`; it stops the solve or sets a
    /// new target. Stops unconverged after `max_iter` preconditioned products, or when the
    /// iteration breaks down (a non-finite residual). `iterations` counts preconditioner
    /// applications (one product with `A` each, plus one per acceptance check).
    pub fn solve<A, M, F>(
        &mut self,
        a: &mut A,
        m: &mut M,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
        mut accept: F,
    ) -> SolveStats
    where
        A: LinearOperator + ?Sized,
        M: FlexiblePreconditioner + ?Sized,
        F: FnMut(&[f64]) -> Accept,
    {
        let mut target = tol;
        let mut iterations = 0;
        let mut beta = residual(a, x, b, &mut self.r);
        loop {
            if !beta.is_finite() {
                return SolveStats::new(iterations, beta, false);
            }
            if beta <= target {
                match accept(&self.r) {
                    Accept::Done => return SolveStats::new(iterations, beta, true),
                    Accept::Continue(t) => target = t.min(0.5 * beta),
                }
                if beta == 0.0 {
                    // Nothing left to reduce: the rule cannot be met by iterating.
                    return SolveStats::new(iterations, beta, false);
                }
            }
            if iterations >= max_iter {
                return SolveStats::new(iterations, beta, false);
            }
            let (k, est) = self.cycle(a, m, beta, target, max_iter, &mut iterations);
            self.update_iterate(k, x);
            beta = residual(a, x, b, &mut self.r);
            if k > 0 && !est.is_finite() {
                beta = est;
            }
        }
    }

    /// One restart cycle from the residual `r` of norm `beta`: Arnoldi vectors until the
    /// residual estimate meets `target`, `restart` vectors are kept or `max_iter` products
    /// are spent. Returns the number of vectors and the estimate.
    fn cycle<A, M>(
        &mut self,
        a: &mut A,
        m: &mut M,
        beta: f64,
        target: f64,
        max_iter: usize,
        iterations: &mut usize,
    ) -> (usize, f64)
    where
        A: LinearOperator + ?Sized,
        M: FlexiblePreconditioner + ?Sized,
    {
        par::chunks((&mut self.v[0][..], &self.r[..]))
            .for_each(|_, (v, r)| v.iter_mut().zip(r).for_each(|(v, r)| *v = r / beta));
        self.g.fill(0.0);
        self.g[0] = beta;
        let mut k = 0;
        let mut est = beta;
        while k < self.restart && *iterations < max_iter {
            *iterations += 1;
            m.apply(&self.v[k], &mut self.z[k]);
            let hn = self.arnoldi(a, k);
            est = self.rotate(k);
            k += 1;
            if est <= target || hn == 0.0 || !est.is_finite() {
                break;
            }
        }
        (k, est)
    }

    /// The Arnoldi vector `v_{k+1} ∝ A z_k`, orthogonalised against `v_0..=v_k` by modified
    /// Gram–Schmidt (twice when cancellation left less than [`REORTH`] of it), normalised;
    /// fills column `k` of the Hessenberg matrix and returns the new vector's norm.
    fn arnoldi<A: LinearOperator + ?Sized>(&mut self, a: &mut A, k: usize) -> f64 {
        let (head, tail) = self.v.split_at_mut(k + 1);
        let w = &mut tail[0];
        a.apply(&self.z[k], w);
        let col = &mut self.h[k];
        col[..=k].fill(0.0);
        let (parts, proj) = (&mut self.parts, &mut self.proj);
        let w2 = project(head, w, parts, proj);
        subtract(head, &proj[..=k], w);
        let mut hn = dot(w, w).sqrt();
        for (c, p) in col.iter_mut().zip(&proj[..=k]) {
            *c += p;
        }
        if hn < REORTH * w2.sqrt() {
            project(head, w, parts, proj);
            subtract(head, &proj[..=k], w);
            hn = dot(w, w).sqrt();
            for (c, p) in col.iter_mut().zip(&proj[..=k]) {
                *c += p;
            }
        }
        col[k + 1] = hn;
        if hn > 0.0 {
            par::chunks(&mut w[..]).for_each(|_, w| w.iter_mut().for_each(|w| *w /= hn));
        }
        hn
    }

    /// Applies the previous Givens rotations to column `k` of the Hessenberg matrix, forms
    /// the one that zeroes its subdiagonal, rotates the right-hand side `g`; returns the
    /// residual estimate `|g_{k+1}|`.
    fn rotate(&mut self, k: usize) -> f64 {
        let (col, cs, sn, g) = (&mut self.h[k], &mut self.cs, &mut self.sn, &mut self.g);
        for i in 0..k {
            let (p, q) = (col[i], col[i + 1]);
            col[i] = cs[i] * p + sn[i] * q;
            col[i + 1] = -sn[i] * p + cs[i] * q;
        }
        let (p, q) = (col[k], col[k + 1]);
        let rr = p.hypot(q);
        let (c, s) = if rr > 0.0 {
            (p / rr, q / rr)
        } else {
            (1.0, 0.0)
        };
        cs[k] = c;
        sn[k] = s;
        col[k] = rr;
        col[k + 1] = 0.0;
        g[k + 1] = -s * g[k];
        g[k] *= c;
        g[k + 1].abs()
    }

    /// `x += Z y` with `H y = g` (upper triangular, the first `k` columns).
    fn update_iterate(&mut self, k: usize, x: &mut [f64]) {
        let (h, g, y) = (&self.h, &self.g, &mut self.y);
        for i in (0..k).rev() {
            let mut s = g[i];
            for j in i + 1..k {
                s -= h[j][i] * y[j];
            }
            y[i] = if h[i][i] != 0.0 { s / h[i][i] } else { 0.0 };
        }
        for c in y[..k].iter_mut() {
            *c = -*c;
        }
        subtract(&self.z[..k], &y[..k], x);
    }
}

/// `r = b − A x`; returns `‖r‖₂`.
fn residual<A: LinearOperator + ?Sized>(a: &mut A, x: &[f64], b: &[f64], r: &mut [f64]) -> f64 {
    a.apply(x, r);
    par::chunks((&mut r[..], b))
        .for_each(|_, (r, b)| r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r));
    dot(r, r).sqrt()
}

/// `proj[i] = basis[i]·w` for every basis vector, in one pass over `w`; returns `w·w`. The
/// partials of each fixed chunk are folded in chunk order.
fn project(basis: &[Vec<f64>], w: &[f64], parts: &mut [f64], proj: &mut [f64]) -> f64 {
    let k = basis.len();
    let stride = k + 1;
    let chunks = w.len().div_ceil(REDUCE_CHUNK);
    let parts = &mut parts[..chunks * stride];
    parts
        .par_chunks_mut(stride)
        .enumerate()
        .with_min_len(2)
        .for_each(|(c, p)| {
            let lo = c * REDUCE_CHUNK;
            let hi = (lo + REDUCE_CHUNK).min(w.len());
            let wc = &w[lo..hi];
            for (p, v) in p.iter_mut().zip(basis) {
                *p = dot_serial(&v[lo..hi], wc);
            }
            p[k] = dot_serial(wc, wc);
        });
    proj[..stride].fill(0.0);
    for p in parts.chunks(stride) {
        for (a, b) in proj.iter_mut().zip(p) {
            *a += b;
        }
    }
    proj[k]
}

/// `w −= Σ_i c_i basis[i]`, chunk by chunk (each chunk of `w` stays in cache).
fn subtract(basis: &[Vec<f64>], c: &[f64], w: &mut [f64]) {
    par::chunks(&mut w[..]).for_each(|lo, wc| {
        for (v, &ci) in basis.iter().zip(c) {
            let vc = &v[lo..lo + wc.len()];
            for (w, v) in wc.iter_mut().zip(vc) {
                *w -= ci * v;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_systems::AdvDiff;

    /// Jacobi on odd calls, nothing on even ones: a preconditioner that changes every time.
    struct Alternating(usize);
    impl FlexiblePreconditioner for Alternating {
        fn apply(&mut self, r: &[f64], z: &mut [f64]) {
            self.0 += 1;
            let d = if self.0 % 2 == 1 { 3.0 } else { 1.0 };
            for (z, r) in z.iter_mut().zip(r) {
                *z = r / d;
            }
        }
    }

    fn problem(n: usize) -> (Vec<f64>, Vec<f64>) {
        let xe: Vec<f64> = (0..n).map(|k| (k as f64 * 0.3).sin()).collect();
        let mut b = vec![0.0; n];
        AdvDiff(n).apply(&xe, &mut b);
        (xe, b)
    }

    #[test]
    fn solves_a_non_symmetric_system_with_a_changing_preconditioner_across_restarts() {
        let n = 80;
        let (xe, b) = problem(n);
        let mut x = vec![0.0; n];
        let mut checks = 0;
        let s = Fgmres::new(n, 7).solve(
            &mut AdvDiff(n),
            &mut Alternating(0),
            &b,
            &mut x,
            1e-11,
            500,
            |r| {
                checks += 1;
                assert!(dot(r, r).sqrt() <= 1e-11);
                Accept::Done
            },
        );
        assert!(s.converged, "{s:?}");
        assert_eq!(checks, 1);
        // Restarted (7 vectors a cycle) and still converged.
        assert!(s.iterations > 7, "{s:?}");
        for k in 0..n {
            assert!((x[k] - xe[k]).abs() < 1e-10, "{k}: {} vs {}", x[k], xe[k]);
        }
    }

    #[test]
    fn the_acceptance_rule_can_ask_for_more() {
        let n = 50;
        let (xe, b) = problem(n);
        let mut x = vec![0.0; n];
        // A rule on one component only: the maximum error in the first ten rows.
        let mut asked = 0;
        let s = Fgmres::new(n, 30).solve(
            &mut AdvDiff(n),
            &mut Alternating(0),
            &b,
            &mut x,
            1e-2,
            500,
            |r| {
                if r[..10].iter().all(|v| v.abs() <= 1e-12) {
                    Accept::Done
                } else {
                    asked += 1;
                    Accept::Continue(1e-13)
                }
            },
        );
        assert!(s.converged, "{s:?}");
        assert!(asked >= 1);
        assert!((x[3] - xe[3]).abs() < 1e-11);
    }

    #[test]
    fn gives_up_after_max_iterations_and_on_nan() {
        let n = 40;
        let (_, b) = problem(n);
        let mut x = vec![0.0; n];
        let s = Fgmres::new(n, 5).solve(
            &mut AdvDiff(n),
            &mut Alternating(0),
            &b,
            &mut x,
            1e-14,
            3,
            |_| Accept::Done,
        );
        assert!(!s.converged && s.iterations == 3, "{s:?}");
        let mut bad = b.clone();
        bad[7] = f64::NAN;
        x.fill(0.0);
        let s = Fgmres::new(n, 5).solve(
            &mut AdvDiff(n),
            &mut Alternating(0),
            &bad,
            &mut x,
            1e-10,
            100,
            |_| Accept::Done,
        );
        assert!(!s.converged, "{s:?}");
    }
}
