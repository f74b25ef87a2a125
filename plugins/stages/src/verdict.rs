//! What a Krylov solve that stopped short of its tolerance says: whether it **diverged** — its
//! residual ended at or above where it started (or is not finite), so more iterations cannot
//! help and the system itself is at fault — or merely **did not converge** in the iterations
//! allowed, which more iterations (or a shorter step) may cure.

/// The message of a solve by `solver` that stopped after `iterations` with relative residual
/// `relative` (against the right-hand side, where the solve started) above `tolerance`
/// (`tolerance_setting`); `limit_setting` is the iteration cap's setting, `advice` what to
/// change when the solve was merely short of iterations, `cause` what to check when it
/// diverged.
pub(crate) fn unconverged(
    solver: &str,
    iterations: usize,
    relative: f64,
    tolerance: f64,
    tolerance_setting: &str,
    limit_setting: &str,
    advice: &str,
    cause: &str,
) -> String {
    if relative >= 1.0 || relative.is_nan() {
        format!(
            "{solver} diverged: after {iterations} iterations the relative residual is {relative:.3e}, \
             no smaller than where it started (1), so more iterations will not help \
             ({tolerance_setting} is {tolerance:.1e}); {cause}"
        )
    } else {
        format!(
            "{solver} did not converge in {iterations} iterations, the limit {limit_setting} \
             (relative residual {relative:.3e} > {tolerance_setting} {tolerance:.1e}); {advice}"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::unconverged;

    /// A residual that grew (the adversary's `solid.viscosity = 1e-20`: 3.2e58) is a
    /// divergence, not a lack of iterations; one that fell short is the other.
    #[test]
    fn a_grown_residual_is_a_divergence() {
        let m = |r| {
            unconverged(
                "BiCGSTAB",
                5000,
                r,
                1e-8,
                "tol",
                "cap",
                "raise cap",
                "check",
            )
        };
        let grown = m(3.2e58);
        assert!(
            grown.starts_with("BiCGSTAB diverged: after 5000 iterations the relative residual is 3.200e58, no smaller than where it started (1), so more iterations will not help"),
            "{grown}"
        );
        assert!(
            grown.ends_with("; check") && !grown.contains("raise cap"),
            "{grown}"
        );
        assert!(m(f64::NAN).contains("diverged"));
        assert!(m(1.0).contains("diverged"));
        let short = m(3e-3);
        assert_eq!(
            short,
            "BiCGSTAB did not converge in 5000 iterations, the limit cap (relative residual 3.000e-3 > tol 1.0e-8); raise cap"
        );
    }
}
