//! Preconditioned BiCGSTAB (van der Vorst 1992) for non-symmetric systems, with right
//! preconditioning so the residual it monitors is the true one of `A x = b`.
//!
//! The elastic system `M δ − (Δt²/4) ∇·(J : H(δ))` is not symmetric for a general law (its
//! tangent `J = ∂τ/∂B̃` need not be the second derivative of an energy in the displacement
//! gradient), so conjugate gradients do not apply. Workspace is allocated once.
//!
//! Vector updates run in parallel and dot products sum fixed chunks in order
//! ([`super::par`]), so the iterates do not depend on the number of threads.

use super::par::{dot, for_each_mut};
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
        for_each_mut(r, |k, r| *r = b[k] - t[k]);
        let mut res = dot(r, r).sqrt();
        if res <= tol {
            return SolveStats {
                iterations: 0,
                residual: res,
                converged: true,
            };
        }
        r0.copy_from_slice(r);
        let (mut rho, mut alpha, mut omega) = (1.0f64, 1.0f64, 1.0f64);
        p.fill(0.0);
        v.fill(0.0);
        for it in 1..=max_iter {
            let rho_new = dot(r0, r);
            if rho_new == 0.0 || !rho_new.is_finite() {
                return SolveStats {
                    iterations: it,
                    residual: res,
                    converged: false,
                };
            }
            let beta = (rho_new / rho) * (alpha / omega);
            rho = rho_new;
            for_each_mut(p, |k, p| *p = r[k] + beta * (*p - omega * v[k]));
            m.apply(p, ph);
            a.apply(ph, v);
            alpha = rho / dot(r0, v);
            for_each_mut(s, |k, s| *s = r[k] - alpha * v[k]);
            let sn = dot(s, s).sqrt();
            if sn <= tol {
                for_each_mut(x, |k, x| *x += alpha * ph[k]);
                return SolveStats {
                    iterations: it,
                    residual: sn,
                    converged: true,
                };
            }
            m.apply(s, sh);
            a.apply(sh, t);
            let tt = dot(t, t);
            omega = if tt > 0.0 { dot(t, s) / tt } else { 0.0 };
            for_each_mut(x, |k, x| *x += alpha * ph[k] + omega * sh[k]);
            for_each_mut(r, |k, r| *r = s[k] - omega * t[k]);
            res = dot(r, r).sqrt();
            if res <= tol {
                return SolveStats {
                    iterations: it,
                    residual: res,
                    converged: true,
                };
            }
            if omega == 0.0 || !res.is_finite() {
                return SolveStats {
                    iterations: it,
                    residual: res,
                    converged: false,
                };
            }
        }
        SolveStats {
            iterations: max_iter,
            residual: res,
            converged: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
