//! Preconditioned conjugate gradient (Hestenes & Stiefel 1952) for symmetric positive
//! (semi-)definite systems, with a caller-supplied stopping rule.
//!
//! The workspace vectors are allocated once ([`Pcg::new`]) and reused, so a solve allocates
//! nothing. The caller's stopping rule sees the current residual `r = b − A x`; the recurrence
//! residual drifts from the true one over many iterations, so when the rule is met the solver
//! recomputes the true residual with one extra product and continues if it is not met after all.
//!
//! Vector updates run in parallel and dot products sum fixed chunks in order
//! ([`super::par`]), so the iterates do not depend on the number of threads. The kernels are
//! memory-bound, so passes are fused: the iterate and the residual are updated in one pass
//! that also measures the residual (with a [`Norm`], [`Pcg::solve_norm`]), and operators and
//! preconditioners may return their dot product from their own pass
//! ([`LinearOperator::apply_dot`], [`Preconditioner::apply_dot`]; Jacobi does).
//!
//! **Singular systems.** A pressure Poisson problem without a Dirichlet side is singular, its
//! null space the constants. In exact arithmetic the iteration never leaves the range; in
//! floating point the preconditioner (a multigrid's pinned coarsest solve, say) adds a constant
//! to the preconditioned residual wherever round-off leaves the residual's sum nonzero, the
//! iterate accumulates it, and once `A x` is computed with an error above the tolerance the
//! solve stalls or breaks down (`pᵀAp ≤ 0`). Told that the null space is the constants
//! ([`NullSpace::Constants`]), the solver takes each preconditioned residual off it (zero
//! mean: `P M⁻¹` with `P` the projection off the constants, the same as `P M⁻¹ P` on the range,
//! where the residual lies) — what PETSc does for a matrix with a null space attached. On a
//! breakdown it restarts from the true residual (at most three times; a singular system's
//! iterate taken off the constants first).

/// A symmetric linear operator `y = A x` on vectors of a fixed length.
pub trait LinearOperator {
    /// `y ← A x`.
    fn apply(&mut self, x: &[f64], y: &mut [f64]);

    /// `y ← A x`, returning `x·y` summed in an order that does not depend on the number of
    /// threads. Default: [`apply`](Self::apply), then [`par::dot`]; an operator may fuse the
    /// product into its own pass.
    fn apply_dot(&mut self, x: &[f64], y: &mut [f64]) -> f64 {
        self.apply(x, y);
        dot(x, y)
    }
}

/// A symmetric positive definite preconditioner `z = M⁻¹ r`.
pub trait Preconditioner {
    /// `z ← M⁻¹ r`.
    fn apply(&self, r: &[f64], z: &mut [f64]);

    /// `z ← M⁻¹ r`, returning `r·z` summed in an order that does not depend on the number of
    /// threads. Default: [`apply`](Self::apply), then [`par::dot`].
    fn apply_dot(&self, r: &[f64], z: &mut [f64]) -> f64 {
        self.apply(r, z);
        dot(r, z)
    }

    /// `Some(d)` when the preconditioner is diagonal, `z = r / d` (Jacobi): the solver then
    /// forms `z` and `r·z` in the pass that updates the residual — one pass over memory and
    /// one parallel loop fewer per iteration, the same bits as [`apply_dot`](Self::apply_dot).
    /// Default: `None`.
    fn jacobi_diagonal(&self) -> Option<&[f64]> {
        None
    }
}

/// `z ← r / d` over one chunk, returning `r·z` (the chunk partial of the Jacobi
/// [`Preconditioner::apply_dot`], shared with the solver's fused pass so both give the same
/// bits).
#[inline(always)]
fn jacobi_chunk(r: &[f64], d: &[f64], z: &mut [f64]) -> f64 {
    let n = z.len();
    let (r, d) = (&r[..n], &d[..n]);
    for ((z, r), d) in z.iter_mut().zip(r).zip(d) {
        *z = r / d;
    }
    let z = &*z;
    par::sum4(n, |k| r[k] * z[k])
}

/// Diagonal (Jacobi) preconditioning.
impl Preconditioner for [f64] {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        par::chunks(z).for_each(|o, z| {
            let (r, d) = (&r[o..o + z.len()], &self[o..o + z.len()]);
            for ((z, r), d) in z.iter_mut().zip(r).zip(d) {
                *z = r / d;
            }
        });
    }

    /// One pass: the quotient and the product together.
    fn apply_dot(&self, r: &[f64], z: &mut [f64]) -> f64 {
        par::chunks(z).fold(
            0.0,
            |o, z| jacobi_chunk(&r[o..], &self[o..], z),
            |a, b| a + b,
        )
    }

    fn jacobi_diagonal(&self) -> Option<&[f64]> {
        Some(self)
    }
}

/// A residual measure the solver computes in the same pass as its vector update
/// ([`Pcg::solve_norm`]); the same on any number of threads.
#[derive(Clone, Copy, Debug)]
pub enum Norm<'a> {
    /// The Euclidean norm `‖r‖₂` (squares summed in fixed chunks, in order).
    L2,
    /// The weighted maximum `max_k |w_k r_k|`.
    MaxWeighted(&'a [f64]),
}

impl Norm<'_> {
    /// The partial of the chunk `r` starting at element `o`.
    #[inline(always)]
    fn chunk(&self, o: usize, r: &[f64]) -> f64 {
        match self {
            Norm::L2 => par::sum4(r.len(), |k| r[k] * r[k]),
            Norm::MaxWeighted(w) => r
                .iter()
                .zip(&w[o..o + r.len()])
                .fold(0.0f64, |m, (r, w)| m.max((r * w).abs())),
        }
    }
    fn combine(&self, a: f64, b: f64) -> f64 {
        match self {
            Norm::L2 => a + b,
            Norm::MaxWeighted(_) => a.max(b),
        }
    }
    fn finish(&self, v: f64) -> f64 {
        match self {
            Norm::L2 => v.sqrt(),
            Norm::MaxWeighted(_) => v,
        }
    }

    /// The measure of `r`.
    pub fn of(&self, r: &[f64]) -> f64 {
        let v = r
            .chunks(par::REDUCE_CHUNK)
            .enumerate()
            .fold(0.0, |acc, (c, r)| {
                self.combine(acc, self.chunk(c * par::REDUCE_CHUNK, r))
            });
        self.finish(v)
    }
}

/// Statistics of one solve, reported by the stages and logged by the run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// Iterations performed.
    pub iterations: usize,
    /// The final value of the caller's residual measure.
    pub residual: f64,
    /// Whether the stopping rule was met.
    pub converged: bool,
}

impl SolveStats {
    /// The statistics of a solve that stopped after `iterations` at `residual`.
    pub(crate) fn new(iterations: usize, residual: f64, converged: bool) -> Self {
        SolveStats {
            iterations,
            residual,
            converged,
        }
    }
}

/// Reusable conjugate-gradient workspace for systems of one size: three vectors, the residual
/// `r`, the search direction `p` and `q`, which holds `A p` until the residual is updated and
/// the preconditioned residual `z = M⁻¹ r` after (the two are never needed at once).
#[derive(Clone, Debug)]
pub struct Pcg {
    r: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

use super::par::{self, dot};

impl Pcg {
    /// Workspace for systems of `n` unknowns.
    pub fn new(n: usize) -> Self {
        Pcg {
            r: vec![0.0; n],
            p: vec![0.0; n],
            q: vec![0.0; n],
        }
    }

    /// The system size.
    pub fn len(&self) -> usize {
        self.r.len()
    }

    /// Whether the system is empty.
    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }

    /// Solve `A x = b` from the initial guess in `x`.
    ///
    /// `measure(r)` maps a residual to the number compared with `tol`; iteration stops when
    /// `measure(r) ≤ tol` for the true residual, or after `max_iter` iterations. At least one
    /// iteration is made unless the initial residual is exactly zero, so a warm start that
    /// already meets the tolerance is still improved (in a time loop the residual then goes to
    /// zero across steps at a steady state instead of staying at the tolerance).
    pub fn solve<A: LinearOperator + ?Sized, M: Preconditioner + ?Sized>(
        &mut self,
        a: &mut A,
        m: &M,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
        measure: impl Fn(&[f64]) -> f64,
    ) -> SolveStats {
        let Pcg { r, p, q } = self;
        run(
            [r, p, q],
            a,
            m,
            b,
            x,
            tol,
            max_iter,
            Measure::Closure(&measure),
            false,
        )
    }

    /// [`solve`](Self::solve) with a [`Norm`] as the measure, computed in the same pass as
    /// the update of the iterate and the residual (one sweep over memory fewer per
    /// iteration).
    pub fn solve_norm<A: LinearOperator + ?Sized, M: Preconditioner + ?Sized>(
        &mut self,
        a: &mut A,
        m: &M,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
        norm: Norm,
    ) -> SolveStats {
        let Pcg { r, p, q } = self;
        run(
            [r, p, q],
            a,
            m,
            b,
            x,
            tol,
            max_iter,
            Measure::Norm(norm),
            false,
        )
    }
}

/// [`Pcg::solve_norm`] on borrowed work vectors — `work` holds three slices of the system's
/// length (`r`, `p`, `q`; their contents on entry do not matter) — for callers that share one
/// pool of vectors between several solves; with [`NullSpace::None`] the same iterates, bit for
/// bit. With [`NullSpace::Constants`] the system is singular, its null space the constant
/// vectors, and `b` sums to zero (the caller projects it): every preconditioned residual is
/// taken off the null space (module docs, "Singular systems").
#[allow(clippy::too_many_arguments)]
pub fn solve_norm_in<A: LinearOperator + ?Sized, M: Preconditioner + ?Sized>(
    work: [&mut [f64]; 3],
    a: &mut A,
    m: &M,
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    max_iter: usize,
    norm: Norm,
    null: NullSpace,
) -> SolveStats {
    let singular = null == NullSpace::Constants;
    run(
        work,
        a,
        m,
        b,
        x,
        tol,
        max_iter,
        Measure::Norm(norm),
        singular,
    )
}

/// The null space of the operator, which [`solve_norm_in`] keeps the iteration off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NullSpace {
    /// None (or none the solver is told of): a positive definite system.
    None,
    /// The constant vectors: a Poisson problem with no Dirichlet side.
    Constants,
}

/// Subtract the mean of `v` (summed in fixed chunks in order: the same bits on any number of
/// threads).
fn remove_mean(v: &mut [f64]) {
    if v.is_empty() {
        return;
    }
    let sum: f64 = v
        .chunks(par::REDUCE_CHUNK)
        .map(|c| par::sum4(c.len(), |k| c[k]))
        .sum();
    let mean = sum / v.len() as f64;
    par::chunks(v).for_each(|_, v| v.iter_mut().for_each(|x| *x -= mean));
}

/// `z ← M⁻¹ r` and `r·z`; with `deflate`, `z` is taken off the constants (zero mean).
fn precondition<M: Preconditioner + ?Sized>(m: &M, r: &[f64], z: &mut [f64], deflate: bool) -> f64 {
    if !deflate {
        return m.apply_dot(r, z);
    }
    m.apply(r, z);
    remove_mean(z);
    dot(r, z)
}

/// The most restarts from the true residual after a breakdown (`pᵀAp ≤ 0`) in one solve.
const MAX_RESTARTS: usize = 3;

/// The iteration, on the work vectors `[r, p, q]`; `q` holds `A p`, then `z = M⁻¹ r` once `r`
/// is updated. `singular`: the null space is the constants (module docs, "Singular systems").
#[allow(clippy::too_many_arguments)]
fn run<A: LinearOperator + ?Sized, M: Preconditioner + ?Sized>(
    [r, p, q]: [&mut [f64]; 3],
    a: &mut A,
    m: &M,
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    max_iter: usize,
    measure: Measure,
    singular: bool,
) -> SolveStats {
    let n = b.len();
    assert!(
        r.len() == n && p.len() == n && q.len() == n,
        "PCG: work vector length ≠ system size"
    );
    assert_eq!(n, x.len());
    let mut res = true_residual(a, b, x, r, q, measure);
    let mut it = 0;
    let converged = |iterations: usize, residual: f64| SolveStats {
        iterations,
        residual,
        converged: true,
    };
    // At least one iteration unless the residual is exactly zero: a warm start already
    // within the tolerance would otherwise leave its residual in place step after step, so
    // a steady state would keep an error up to the tolerance (and a solver that stops at 0
    // or 1 iterations by turns never lets it settle); one iteration per step drives it to
    // zero across steps at the cost of that iteration.
    if res == 0.0 {
        return converged(0, res);
    }
    let mut rz = precondition(m, r, q, singular);
    p.copy_from_slice(q);
    let mut restarts = 0;
    while it < max_iter {
        let pq = a.apply_dot(p, q);
        if pq <= 0.0 || !pq.is_finite() {
            // Breakdown: p is in the null space (singular system) or the operator is not SPD.
            // In a singular system the recursively updated residual drifts off the range by
            // round-off until the preconditioned direction is nearly a null vector; restarting
            // from the true residual removes the drift.
            if !pq.is_finite() || restarts == MAX_RESTARTS {
                break;
            }
            restarts += 1;
            if singular {
                remove_mean(x);
            }
            res = true_residual(a, b, x, r, q, measure);
            if res <= tol {
                return converged(it, res);
            }
            rz = precondition(m, r, q, singular);
            p.copy_from_slice(q);
            continue;
        }
        let mut rz_fused;
        let jacobi = m.jacobi_diagonal().filter(|_| !singular);
        (res, rz_fused) = update(x, r, q, p, rz / pq, measure, jacobi);
        it += 1;
        if res <= tol {
            // Confirm with the true residual (which replaces r, so a fused r·z is stale).
            rz_fused = None;
            res = true_residual(a, b, x, r, q, measure);
            if res <= tol {
                return converged(it, res);
            }
        }
        let rz_new = rz_fused.unwrap_or_else(|| precondition(m, r, q, singular));
        new_direction(p, q, rz_new / rz);
        rz = rz_new;
    }
    SolveStats {
        iterations: it,
        residual: res,
        converged: res <= tol,
    }
}

/// `r = b − A x` (with `q` as the product's scratch) and its measure, in one pass when the
/// measure is a [`Norm`] (the chunks and their fold are `Norm::of`'s).
fn true_residual<A: LinearOperator + ?Sized>(
    a: &mut A,
    b: &[f64],
    x: &[f64],
    r: &mut [f64],
    q: &mut [f64],
    measure: Measure,
) -> f64 {
    a.apply(x, q);
    let q = &*q;
    let diff = |o: usize, r: &mut [f64]| {
        let (b, q) = (&b[o..o + r.len()], &q[o..o + r.len()]);
        for ((r, b), q) in r.iter_mut().zip(b).zip(q) {
            *r = b - q;
        }
    };
    match measure {
        Measure::Norm(n) => {
            let v = par::chunks(&mut *r).fold(
                0.0,
                |o, r| {
                    diff(o, r);
                    n.chunk(o, r)
                },
                |a, b| n.combine(a, b),
            );
            n.finish(v)
        }
        Measure::Closure(f) => {
            par::chunks(&mut *r).for_each(diff);
            f(r)
        }
    }
}

/// `x += α p`, `r −= α q` (`q = A p`) and the measure of `r`, in one pass. With a Jacobi
/// preconditioner (diagonal `d`) and a norm, the same pass also forms `z = r / d` over `q`
/// chunk by chunk, once the chunk has used it, and returns `r·z`.
#[allow(clippy::too_many_arguments)]
fn update(
    x: &mut [f64],
    r: &mut [f64],
    q: &mut [f64],
    p: &[f64],
    alpha: f64,
    measure: Measure,
    jacobi: Option<&[f64]>,
) -> (f64, Option<f64>) {
    let step = |o: usize, x: &mut [f64], r: &mut [f64], q: &[f64]| {
        let n = x.len();
        let (p, q) = (&p[o..o + n], &q[..n]);
        for (x, p) in x.iter_mut().zip(p) {
            *x += alpha * p;
        }
        for (r, q) in r.iter_mut().zip(q) {
            *r -= alpha * q;
        }
    };
    match (measure, jacobi) {
        (Measure::Norm(nm), Some(d)) => {
            let (v, rz) = par::chunks((x, r, q)).fold(
                (0.0, 0.0),
                |o, (x, r, q)| {
                    step(o, x, r, q);
                    (nm.chunk(o, r), jacobi_chunk(r, &d[o..], q))
                },
                |a, b| (nm.combine(a.0, b.0), a.1 + b.1),
            );
            (nm.finish(v), Some(rz))
        }
        (Measure::Norm(nm), None) => {
            let q = &*q;
            let v = par::chunks((x, r)).fold(
                0.0,
                |o, (x, r)| {
                    step(o, x, r, &q[o..]);
                    nm.chunk(o, r)
                },
                |a, b| nm.combine(a, b),
            );
            (nm.finish(v), None)
        }
        (Measure::Closure(f), _) => {
            let q = &*q;
            par::chunks((x, &mut *r)).for_each(|o, (x, r)| step(o, x, r, &q[o..]));
            (f(r), None)
        }
    }
}

/// The next search direction `p ← z + β p`.
fn new_direction(p: &mut [f64], z: &[f64], beta: f64) {
    par::chunks(p).for_each(|o, p| {
        let z = &z[o..o + p.len()];
        for (p, z) in p.iter_mut().zip(z) {
            *p = z + beta * *p;
        }
    });
}

/// The stopping measure: a caller's function of the whole residual, or a fusable [`Norm`].
#[derive(Clone, Copy)]
enum Measure<'a> {
    Closure(&'a dyn Fn(&[f64]) -> f64),
    Norm(Norm<'a>),
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Tri(usize);
    impl LinearOperator for Tri {
        fn apply(&mut self, x: &[f64], y: &mut [f64]) {
            for k in 0..self.0 {
                let l = if k > 0 { x[k - 1] } else { 0.0 };
                let r = if k + 1 < self.0 { x[k + 1] } else { 0.0 };
                y[k] = 2.0 * x[k] - l - r;
            }
        }
    }

    /// A 1-D Neumann operator `−(k u')'` with face coefficients `k` (one fewer than the
    /// unknowns): singular, its null space the constants.
    struct Neumann(Vec<f64>);
    impl LinearOperator for Neumann {
        fn apply(&mut self, x: &[f64], y: &mut [f64]) {
            y.fill(0.0);
            for (f, k) in self.0.iter().enumerate() {
                let flux = k * (x[f + 1] - x[f]);
                y[f] -= flux;
                y[f + 1] += flux;
            }
        }
    }

    /// Jacobi plus `α 1 1ᵀ`: symmetric positive definite, but it adds a large constant to every
    /// preconditioned residual whose sum round-off leaves nonzero.
    struct ConstantHeavy(Vec<f64>, f64);
    impl Preconditioner for ConstantHeavy {
        fn apply(&self, r: &[f64], z: &mut [f64]) {
            let s: f64 = r.iter().sum();
            for ((z, r), d) in z.iter_mut().zip(r).zip(&self.0) {
                *z = r / d + self.1 * s;
            }
        }
    }

    /// A singular system whose preconditioned residual picks up constants stalls (the
    /// iterate's constant grows until `A x` is computed with an error above the tolerance);
    /// told the null space, the solver keeps off it and converges.
    #[test]
    fn a_singular_system_is_kept_off_its_null_space() {
        let n = 400;
        // Coefficients over four orders of magnitude, as a density ratio of 1e4 makes them.
        let k: Vec<f64> = (0..n - 1)
            .map(|f| if (f / 50) % 2 == 0 { 1e4 } else { 1.0 })
            .collect();
        let mut d = vec![0.0; n];
        for (f, k) in k.iter().enumerate() {
            d[f] += k;
            d[f + 1] += k;
        }
        let mut b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let mean = b.iter().sum::<f64>() / n as f64;
        b.iter_mut().for_each(|b| *b -= mean);
        let m = ConstantHeavy(d, 1e12);
        let tol = 1e-10 * dot(&b, &b).sqrt();
        let solve = |null: NullSpace| {
            let (mut r, mut p, mut q) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let mut x = vec![0.0; n];
            let work = [&mut r[..], &mut p[..], &mut q[..]];
            let mut a = Neumann(k.clone());
            let s = solve_norm_in(work, &mut a, &m, &b, &mut x, tol, 4000, Norm::L2, null);
            (s, x)
        };
        let (plain, _) = solve(NullSpace::None);
        let (kept, x) = solve(NullSpace::Constants);
        eprintln!("plain {plain:?}, kept {kept:?}");
        assert!(
            !plain.converged,
            "the plain solve was expected to stall: {plain:?}"
        );
        assert!(kept.converged, "{kept:?}");
        // The residual of the answer, recomputed.
        let mut ax = vec![0.0; n];
        Neumann(k.clone()).apply(&x, &mut ax);
        let r = ax
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(r <= tol * (1.0 + 1e-6), "true residual {r:e}");
    }

    #[test]
    fn solves_1d_laplacian_in_n_iterations() {
        let n = 50;
        let b = vec![1.0; n];
        let mut x = vec![0.0; n];
        let diag = vec![2.0; n];
        let s = Pcg::new(n).solve(&mut Tri(n), diag.as_slice(), &b, &mut x, 1e-12, 1000, |r| {
            r.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        });
        assert!(s.converged && s.iterations <= n, "{s:?}");
        // Exact: x_k = (k+1)(n-k)/2.
        for k in 0..n {
            let e = ((k + 1) * (n - k)) as f64 / 2.0;
            assert!((x[k] - e).abs() < 1e-9 * e, "{k}: {} vs {e}", x[k]);
        }
    }

    /// [`Tri`] whose `pᵀAp` reads 0 (a breakdown) at the given calls of `apply_dot`.
    struct BreaksDown {
        a: Tri,
        calls: usize,
        at: fn(usize) -> bool,
    }
    impl LinearOperator for BreaksDown {
        fn apply(&mut self, x: &[f64], y: &mut [f64]) {
            self.a.apply(x, y)
        }
        fn apply_dot(&mut self, x: &[f64], y: &mut [f64]) -> f64 {
            self.calls += 1;
            self.a.apply(x, y);
            if (self.at)(self.calls) {
                0.0
            } else {
                dot(x, y)
            }
        }
    }

    /// `Tri(n) x = 1` by Jacobi-preconditioned CG to 1e-12 with breakdowns at the products
    /// `at` picks: the stats, the solution and the number of products taken.
    fn solve_breaking_down(n: usize, at: fn(usize) -> bool) -> (SolveStats, Vec<f64>, usize) {
        let (b, diag) = (vec![1.0; n], vec![2.0; n]);
        let mut x = vec![0.0; n];
        let mut a = BreaksDown {
            a: Tri(n),
            calls: 0,
            at,
        };
        let max = |r: &[f64]| r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let s = Pcg::new(n).solve(&mut a, diag.as_slice(), &b, &mut x, 1e-12, 1000, max);
        (s, x, a.calls)
    }

    /// A breakdown is restarted from the true residual: the solve still reaches the exact
    /// solution, with the iterations before the breakdown counted.
    #[test]
    fn a_breakdown_restarts_from_the_true_residual() {
        let n = 50;
        let (s, x, _) = solve_breaking_down(n, |c| c == 6);
        assert!(s.converged && s.iterations > 5, "{s:?}");
        for k in 0..n {
            let e = ((k + 1) * (n - k)) as f64 / 2.0;
            assert!((x[k] - e).abs() < 1e-9 * e, "{k}: {} vs {e}", x[k]);
        }
    }

    /// A solve that keeps breaking down stops after [`MAX_RESTARTS`] restarts, unconverged,
    /// well before its iteration limit — no endless loop.
    #[test]
    fn a_solve_that_keeps_breaking_down_stops_unconverged() {
        let (s, x, calls) = solve_breaking_down(50, |c| c >= 3);
        assert!(!s.converged && s.iterations == 2, "{s:?}");
        assert_eq!(calls, 3 + MAX_RESTARTS, "products taken");
        assert!(x.iter().all(|v| v.is_finite()));
    }
}
