//! Preconditioned conjugate gradient (Hestenes & Stiefel 1952) for symmetric positive
//! (semi-)definite systems, with a caller-supplied stopping rule.
//!
//! The workspace vectors are allocated once ([`Pcg::new`]) and reused, so a solve allocates
//! nothing. The caller's stopping rule sees the current residual `r = b − A x`; the recurrence
//! residual drifts from the true one over many iterations, so when the rule is met the solver
//! recomputes the true residual with one extra product and continues if it is not met after all.
//!
//! Vector updates run in parallel and dot products sum fixed chunks in order
//! ([`super::par`]), so the iterates do not depend on the number of threads.

/// A symmetric linear operator `y = A x` on vectors of a fixed length.
pub trait LinearOperator {
    /// `y ← A x`.
    fn apply(&mut self, x: &[f64], y: &mut [f64]);
}

/// A symmetric positive definite preconditioner `z = M⁻¹ r`.
pub trait Preconditioner {
    /// `z ← M⁻¹ r`.
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// Diagonal (Jacobi) preconditioning.
impl Preconditioner for [f64] {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for ((z, r), d) in z.iter_mut().zip(r).zip(self) {
            *z = r / d;
        }
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

/// Reusable conjugate-gradient workspace for systems of one size.
#[derive(Clone, Debug)]
pub struct Pcg {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

use super::par::{self, dot};

impl Pcg {
    /// Workspace for systems of `n` unknowns.
    pub fn new(n: usize) -> Self {
        Pcg {
            r: vec![0.0; n],
            z: vec![0.0; n],
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
    /// `measure(r) ≤ tol` for the true residual, or after `max_iter` iterations.
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
        let n = b.len();
        assert_eq!(n, self.r.len());
        assert_eq!(n, x.len());
        let Pcg { r, z, p, q } = self;
        a.apply(x, q);
        par::for_each_mut(r, |k, r| *r = b[k] - q[k]);
        let mut res = measure(r);
        let mut it = 0;
        if res <= tol {
            return SolveStats {
                iterations: 0,
                residual: res,
                converged: true,
            };
        }
        m.apply(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z);
        while it < max_iter {
            a.apply(p, q);
            let pq = dot(p, q);
            if pq <= 0.0 || !pq.is_finite() {
                // Breakdown: p is in the null space (singular system) or the operator is not SPD.
                break;
            }
            let alpha = rz / pq;
            par::for_each_mut(x, |k, x| *x += alpha * p[k]);
            par::for_each_mut(r, |k, r| *r -= alpha * q[k]);
            it += 1;
            res = measure(r);
            if res <= tol {
                // Confirm with the true residual.
                a.apply(x, q);
                par::for_each_mut(r, |k, r| *r = b[k] - q[k]);
                res = measure(r);
                if res <= tol {
                    return SolveStats {
                        iterations: it,
                        residual: res,
                        converged: true,
                    };
                }
            }
            m.apply(r, z);
            let rz_new = dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            par::for_each_mut(p, |k, p| *p = z[k] + beta * *p);
        }
        SolveStats {
            iterations: it,
            residual: res,
            converged: res <= tol,
        }
    }
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
}
