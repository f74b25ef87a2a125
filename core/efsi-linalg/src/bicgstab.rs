//! Preconditioned BiCGSTAB (van der Vorst 1992) for non-symmetric systems, with right
//! preconditioning so the residual it monitors is the true one of `A x = b`.
//!
//! The elastic system `M δ − (Δt²/4) ∇·(J : H(δ))` is not symmetric for a general law (its
//! tangent `J = ∂τ/∂B̃` need not be the second derivative of an energy in the displacement
//! gradient), so conjugate gradients do not apply. Workspace is allocated once.
//!
//! Vector updates run in parallel and dot products sum fixed chunks in order
//! ([`super::par`]), so the iterates do not depend on the number of threads. Each update is
//! fused with the reductions over what it writes (`s` with `‖s‖²`; `x` and `r` with `‖r‖²` and
//! the next iteration's `(r₀, r)`; `(t, t)` with `(t, s)`): five passes over the vectors an
//! iteration besides the two products and preconditioner applications, with the same chunk
//! sums, in the same order, as separate passes.

use super::par::{self, dot, dot_serial, dot2};
use super::pcg::{LinearOperator, Preconditioner, SolveStats};

/// Reusable BiCGSTAB workspace for systems of one size.
#[derive(Clone, Debug)]
pub struct BiCgStab {
    r: Vec<f64>,
    r0: Vec<f64>,
    p: Vec<f64>,
    v: Vec<f64>,
    s: Vec<f64>,
    t: Vec<f64>,
    ph: Vec<f64>,
    sh: Vec<f64>,
}

impl BiCgStab {
    /// Workspace for `n` unknowns.
    pub fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        BiCgStab {
            r: z(),
            r0: z(),
            p: z(),
            v: z(),
            s: z(),
            t: z(),
            ph: z(),
            sh: z(),
        }
    }

    /// Solve `A x = b` from the guess in `x` until `‖b − A x‖₂ ≤ tol` or `max_iter` iterations.
    pub fn solve<A: LinearOperator + ?Sized, M: Preconditioner + ?Sized>(
        &mut self,
        a: &mut A,
        m: &M,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> SolveStats {
        let BiCgStab {
            r,
            r0,
            p,
            v,
            s,
            t,
            ph,
            sh,
        } = self;
        a.apply(x, t);
        let rr = sub_norm2(r, b, 1.0, t);
        let mut res = rr.sqrt();
        if res <= tol {
            return SolveStats::new(0, res, true);
        }
        r0.copy_from_slice(r);
        let (mut rho, mut alpha, mut omega) = (1.0f64, 1.0f64, 1.0f64);
        // (r₀, r): with r₀ = r at the start it is ‖r‖²; later the last iteration's fused
        // update of r computes it.
        let mut r0r = rr;
        p.fill(0.0);
        v.fill(0.0);
        for it in 1..=max_iter {
            let rho_new = r0r;
            if rho_new == 0.0 || !rho_new.is_finite() {
                return SolveStats::new(it, res, false);
            }
            let beta = (rho_new / rho) * (alpha / omega);
            rho = rho_new;
            new_direction(p, r, v, beta, omega);
            m.apply(p, ph);
            a.apply(ph, v);
            alpha = rho / dot(r0, v);
            let sn = sub_norm2(s, r, alpha, v).sqrt();
            if sn <= tol {
                axpy(x, alpha, ph);
                return SolveStats::new(it, sn, true);
            }
            m.apply(s, sh);
            a.apply(sh, t);
            let (tt, ts) = dot2(t, t, s);
            omega = if tt > 0.0 { ts / tt } else { 0.0 };
            let rr;
            (rr, r0r) = finish_iteration(x, r, s, [ph, sh, t, r0], alpha, omega);
            res = rr.sqrt();
            if res <= tol {
                return SolveStats::new(it, res, true);
            }
            if omega == 0.0 || !res.is_finite() {
                return SolveStats::new(it, res, false);
            }
        }
        SolveStats::new(max_iter, res, false)
    }
}

/// `y ← a − c·b` and `‖y‖²`, in one pass.
fn sub_norm2(y: &mut [f64], a: &[f64], c: f64, b: &[f64]) -> f64 {
    par::chunks(y).fold(
        0.0,
        |o, y| {
            for (k, y) in y.iter_mut().enumerate() {
                *y = a[o + k] - c * b[o + k];
            }
            dot_serial(y, y)
        },
        |a, p| a + p,
    )
}

/// The search direction `p ← r + β (p − ω v)`.
fn new_direction(p: &mut [f64], r: &[f64], v: &[f64], beta: f64, omega: f64) {
    par::chunks(p).for_each(|o, p| {
        for (k, p) in p.iter_mut().enumerate() {
            *p = r[o + k] + beta * (*p - omega * v[o + k]);
        }
    });
}

/// `x ← x + a·y`.
fn axpy(x: &mut [f64], a: f64, y: &[f64]) {
    par::chunks(x).for_each(|o, x| {
        for (k, x) in x.iter_mut().enumerate() {
            *x += a * y[o + k];
        }
    });
}

/// The end of an iteration in one pass (`s` is only read): `x += α p̂ + ω ŝ`, `r = s − ω t`,
/// and the new `‖r‖²` and `(r₀, r)`.
fn finish_iteration(
    x: &mut [f64],
    r: &mut [f64],
    s: &mut [f64],
    [ph, sh, t, r0]: [&[f64]; 4],
    alpha: f64,
    omega: f64,
) -> (f64, f64) {
    par::chunks((x, r, s)).fold(
        (0.0, 0.0),
        |o, (x, r, s)| {
            for (k, x) in x.iter_mut().enumerate() {
                *x += alpha * ph[o + k] + omega * sh[o + k];
            }
            for (k, r) in r.iter_mut().enumerate() {
                *r = s[k] - omega * t[o + k];
            }
            (dot_serial(r, r), dot_serial(&r0[o..o + r.len()], r))
        },
        |a, p| (a.0 + p.0, a.1 + p.1),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(k, &mut y[k])` over `y`, in parallel chunks.
    fn for_each_mut(y: &mut [f64], f: impl Fn(usize, &mut f64) + Sync + Send) {
        par::chunks(y).for_each(|o, y| y.iter_mut().enumerate().for_each(|(k, v)| f(o + k, v)));
    }
    use crate::test_systems::AdvDiff;

    #[test]
    fn solves_a_non_symmetric_system() {
        let n = 60;
        let xe: Vec<f64> = (0..n).map(|k| (k as f64 * 0.3).sin()).collect();
        let mut b = vec![0.0; n];
        AdvDiff(n).apply(&xe, &mut b);
        let mut x = vec![0.0; n];
        let diag = vec![3.0; n];
        let s = BiCgStab::new(n).solve(&mut AdvDiff(n), diag.as_slice(), &b, &mut x, 1e-12, 500);
        assert!(s.converged, "{s:?}");
        for k in 0..n {
            assert!((x[k] - xe[k]).abs() < 1e-10);
        }
    }

    /// The textbook loop, one pass per vector operation: the reference of the fused solve.
    fn reference(
        a: &mut impl LinearOperator,
        m: &[f64],
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> (usize, f64, bool) {
        let n = b.len();
        let z = || vec![0.0; n];
        let (mut r, mut p, mut v, mut s, mut t, mut ph, mut sh) =
            (z(), z(), z(), z(), z(), z(), z());
        a.apply(x, &mut t);
        for_each_mut(&mut r, |k, r| *r = b[k] - t[k]);
        let mut res = dot(&r, &r).sqrt();
        if res <= tol {
            return (0, res, true);
        }
        let r0 = r.clone();
        let (mut rho, mut alpha, mut omega) = (1.0f64, 1.0f64, 1.0f64);
        for it in 1..=max_iter {
            let rho_new = dot(&r0, &r);
            let beta = (rho_new / rho) * (alpha / omega);
            rho = rho_new;
            for_each_mut(&mut p, |k, p| *p = r[k] + beta * (*p - omega * v[k]));
            m.apply(&p, &mut ph);
            a.apply(&ph, &mut v);
            alpha = rho / dot(&r0, &v);
            for_each_mut(&mut s, |k, s| *s = r[k] - alpha * v[k]);
            let sn = dot(&s, &s).sqrt();
            if sn <= tol {
                for_each_mut(x, |k, x| *x += alpha * ph[k]);
                return (it, sn, true);
            }
            m.apply(&s, &mut sh);
            a.apply(&sh, &mut t);
            let tt = dot(&t, &t);
            omega = if tt > 0.0 { dot(&t, &s) / tt } else { 0.0 };
            for_each_mut(x, |k, x| *x += alpha * ph[k] + omega * sh[k]);
            for_each_mut(&mut r, |k, r| *r = s[k] - omega * t[k]);
            res = dot(&r, &r).sqrt();
            if res <= tol {
                return (it, res, true);
            }
        }
        (max_iter, res, false)
    }

    /// The fused passes give the textbook loop's iterates bit for bit, serial and parallel
    /// lengths (below and above `PAR_MIN`, with a partial last chunk).
    #[test]
    fn fused_passes_match_the_reference_bit_for_bit() {
        for n in [60, 5000, 20_001] {
            let xe: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
            let mut b = vec![0.0; n];
            AdvDiff(n).apply(&xe, &mut b);
            let diag: Vec<f64> = (0..n).map(|k| 2.5 + 0.5 * (k as f64 * 0.1).cos()).collect();
            let tol = 1e-9 * dot(&b, &b).sqrt();
            let mut x = vec![0.1; n];
            let got =
                BiCgStab::new(n).solve(&mut AdvDiff(n), diag.as_slice(), &b, &mut x, tol, 200);
            let mut y = vec![0.1; n];
            let want = reference(&mut AdvDiff(n), &diag, &b, &mut y, tol, 200);
            assert!(got.converged && want.2, "n = {n}: {got:?} {want:?}");
            assert_eq!(
                (got.iterations, got.residual.to_bits()),
                (want.0, want.1.to_bits())
            );
            assert!(
                x.iter().zip(&y).all(|(a, b)| a.to_bits() == b.to_bits()),
                "n = {n}"
            );
        }
    }
}
