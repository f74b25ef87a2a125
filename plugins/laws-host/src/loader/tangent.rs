//! The finite-difference tangent check: a law's tangent `J = ∂τ/∂B̃` against central
//! differences of its stress at fixed deformed states, within [`FD_TANGENT_TOLERANCE`].

use super::{COMPONENTS, FD_TANGENT_TOLERANCE};
use crate::{ConstitutiveLaw, LawError, Sym, Tangent};
use std::fmt;

/// The outcome of the finite-difference tangent check ([`check_tangent`]): the worst entry.
#[derive(Clone, Debug, PartialEq)]
pub struct TangentCheck {
    /// Number of deformed states tested.
    pub states: usize,
    /// Number of states skipped because the law could not evaluate them (outside its domain,
    /// e.g. past a locking stretch); at most half.
    pub skipped: usize,
    /// The worst `max|J − J_fd| / max(max|J|, max|J_fd|, max|J(I)|)` over the states (the
    /// error relative to the state's tangent, floored by the law's stiffness at rest: see
    /// [`FD_TANGENT_TOLERANCE`]).
    pub worst_relative_error: f64,
    /// The state where it occurred.
    pub worst_state: Sym,
    /// The worst entry there: row `a` (stress component) and column `b` (B̃ component).
    pub worst_entry: (usize, usize),
    /// The law's tangent entry there.
    pub tangent: f64,
    /// The finite-difference value there.
    pub finite_difference: f64,
}

impl TangentCheck {
    /// Whether the check passed ([`FD_TANGENT_TOLERANCE`]).
    pub fn passed(&self) -> bool {
        self.worst_relative_error <= FD_TANGENT_TOLERANCE
    }
}

impl fmt::Display for TangentCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (a, b) = self.worst_entry;
        write!(
            f,
            "worst relative error {:.3e} (tolerance {FD_TANGENT_TOLERANCE:e}) over {} states ({} skipped), at ∂τ{}/∂B̃{} = {:.6e} vs finite difference {:.6e}, B̃ = {:?}",
            self.worst_relative_error,
            self.states,
            self.skipped,
            COMPONENTS[a],
            COMPONENTS[b],
            self.tangent,
            self.finite_difference,
            self.worst_state
        )
    }
}

/// The deformed states of the tangent check: `B̃ = I`, `B̃ = 0.5 I` (φ = 0.25), and 24
/// states `B̃ = φ^{1/2} F Fᵀ` with `F` the identity plus entries uniform in ±0.25 (F11, F12,
/// F21, F22, and F33 out of plane) and `φ` cycling through 1, 0.6, 0.25, 0.05 — a fixed seed,
/// so every law sees the same states.
pub fn tangent_check_states() -> Vec<Sym> {
    let mut rng = XorShift(0x5EED_1A3F_0C0F_FEE5);
    let phis = [1.0, 0.6, 0.25, 0.05_f64];
    let amplitude = 0.25;
    let mut states = vec![[1.0, 1.0, 1.0, 0.0], [0.5, 0.5, 0.5, 0.0]];
    for k in 0..24 {
        let mut r = || amplitude * (2.0 * rng.uniform() - 1.0);
        let (f11, f12, f21, f22, f33) = (1.0 + r(), r(), r(), 1.0 + r(), 1.0 + r());
        let s = phis[k % phis.len()].sqrt();
        states.push([
            s * (f11 * f11 + f12 * f12),
            s * (f21 * f21 + f22 * f22),
            s * f33 * f33,
            s * (f11 * f21 + f12 * f22),
        ]);
    }
    states
}

/// Checks a law's tangent against central finite differences of its stress at
/// [`tangent_check_states`] (two batched calls: the states with tangents, then the ±h
/// perturbations with stresses only). Returns the worst entry; the caller compares it with
/// [`FD_TANGENT_TOLERANCE`] ([`TangentCheck::passed`]). States the law cannot evaluate (outside
/// its domain) are skipped, up to half of them; it fails if the law cannot evaluate `B̃ = I` or
/// more than half the states. Works for any [`ConstitutiveLaw`], built in or loaded.
pub fn check_tangent(law: &dyn ConstitutiveLaw) -> Result<TangentCheck, LawError> {
    let states = tangent_check_states();
    let n = states.len();
    let (pairs, skipped) = match tangents_and_differences(law, &states) {
        Ok(pairs) => (pairs, 0),
        // Some state is outside the law's domain (e.g. past a locking stretch): test the states
        // one by one and skip those the law cannot evaluate. `B̃ = I` must evaluate, and at
        // least half the states.
        Err(first) => {
            let mut pairs = Vec::with_capacity(n);
            for (s, b) in states.iter().enumerate() {
                match tangents_and_differences(law, std::slice::from_ref(b)) {
                    Ok(p) => pairs.extend(p),
                    Err(e) if s == 0 => return Err(e),
                    Err(_) => {}
                }
            }
            if 2 * pairs.len() < n {
                return Err(first);
            }
            let skipped = n - pairs.len();
            (pairs, skipped)
        }
    };
    // The law's stiffness at rest, `max|J(I)|` (B̃ = I is the first state, which must
    // evaluate): the floor of every state's scale, so that a state where the tangent is
    // (nearly) zero — Saint Venant–Kirchhoff with λ = 0 at B̃ = 0.5 I — is judged against the
    // law's own scale, not against round-off.
    let magnitude =
        |j: &Tangent, fd: &Tangent| j.iter().chain(fd).fold(0.0_f64, |m, x| m.max(x.abs()));
    let rest = magnitude(&pairs[0].1, &pairs[0].2);
    let mut worst: Option<TangentCheck> = None;
    for (b, j, fd) in &pairs {
        let scale = magnitude(j, fd).max(rest);
        let (i, err) = (0..16)
            .map(|i| (i, (j[i] - fd[i]).abs()))
            .fold((0, 0.0), |best, e| if e.1 > best.1 { e } else { best });
        let relative = if scale > 0.0 { err / scale } else { err };
        if worst
            .as_ref()
            .is_none_or(|w| relative > w.worst_relative_error)
        {
            worst = Some(TangentCheck {
                states: pairs.len(),
                skipped,
                worst_relative_error: relative,
                worst_state: *b,
                worst_entry: (i / 4, i % 4),
                tangent: j[i],
                finite_difference: fd[i],
            });
        }
    }
    Ok(worst.expect("at least one state"))
}

/// For each state: `(B̃, J, J_fd)`, in two batched calls (the states with tangents, then the ±h
/// perturbations with stresses only).
fn tangents_and_differences(
    law: &dyn ConstitutiveLaw,
    states: &[Sym],
) -> Result<Vec<(Sym, Tangent, Tangent)>, LawError> {
    let n = states.len();
    let mut tau = vec![[0.0; 4]; n];
    let mut jac = vec![[0.0; 16]; n];
    law.evaluate(states, &mut tau, Some(&mut jac))?;
    let steps: Vec<f64> = states
        .iter()
        .map(|b| 1e-6 * b.iter().fold(1.0_f64, |m, x| m.max(x.abs())))
        .collect();
    let mut perturbed = Vec::with_capacity(8 * n);
    for (b, h) in states.iter().zip(&steps) {
        for c in 0..4 {
            for sign in [1.0, -1.0] {
                let mut p = *b;
                p[c] += sign * h;
                perturbed.push(p);
            }
        }
    }
    let mut tau_p = vec![[0.0; 4]; 8 * n];
    law.evaluate(&perturbed, &mut tau_p, None)?;
    Ok((0..n)
        .map(|s| {
            let mut fd = [0.0; 16];
            for c in 0..4 {
                let (tp, tm) = (tau_p[8 * s + 2 * c], tau_p[8 * s + 2 * c + 1]);
                for a in 0..4 {
                    fd[4 * a + c] = (tp[a] - tm[a]) / (2.0 * steps[s]);
                }
            }
            (states[s], jac[s], fd)
        })
        .collect())
}

/// xorshift64* (seeded, reproducible).
struct XorShift(u64);

impl XorShift {
    fn uniform(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}
