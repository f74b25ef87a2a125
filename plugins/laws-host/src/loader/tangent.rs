//! The finite-difference tangent check: a law's tangent `J = ∂τ/∂B̃` against central
//! differences of its stress at fixed deformed states, within [`FD_TANGENT_TOLERANCE`] — on
//! in-plane tensors ([`check_tangent`]) and on full 3-D ones ([`check_tangent_full`]).

use super::{COMPONENTS, FD_TANGENT_TOLERANCE};
use crate::{ConstitutiveLaw, LawError, Sym, Sym6};
use std::fmt;

/// The outcome of the finite-difference tangent check ([`check_tangent`],
/// [`check_tangent_full`]): the worst entry.
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
    /// The state where it occurred: 4 components `[b11, b22, b33, b12]` (in-plane check) or 6
    /// `[b11, b22, b33, b12, b23, b13]` (full check).
    pub worst_state: Vec<f64>,
    /// The worst entry there: row `a` (stress component) and column `b` (B̃ component), indices
    /// into the state's components.
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

    /// The worst entry's names, e.g. `("12", "23")`.
    pub fn worst_entry_names(&self) -> (&'static str, &'static str) {
        (
            COMPONENTS[self.worst_entry.0],
            COMPONENTS[self.worst_entry.1],
        )
    }
}

impl fmt::Display for TangentCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (a, b) = self.worst_entry_names();
        write!(
            f,
            "worst relative error {:.3e} (tolerance {FD_TANGENT_TOLERANCE:e}) over {} states ({} skipped), at ∂τ{a}/∂B̃{b} = {:.6e} vs finite difference {:.6e}, B̃ = {:?}",
            self.worst_relative_error,
            self.states,
            self.skipped,
            self.tangent,
            self.finite_difference,
            self.worst_state
        )
    }
}

/// The in-plane states of the tangent check: `B̃ = I`, `B̃ = 0.5 I` (φ = 0.25), and 24
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

/// The full states of the 3-D tangent check: `B̃ = I`, `B̃ = 0.5 I`, and 24 states
/// `B̃ = φ^{1/2} F Fᵀ` with `F` the identity plus all nine entries uniform in ±0.25 and `φ`
/// cycling through 1, 0.6, 0.25, 0.05 (a fixed seed) — every component of `B̃`, the
/// out-of-plane shears 23 and 13 included, is non-zero.
pub fn tangent_check_states_full() -> Vec<Sym6> {
    let mut rng = XorShift(0x3D5E_ED1A_3F0C_0FFE);
    let phis = [1.0, 0.6, 0.25, 0.05_f64];
    let amplitude = 0.25;
    let mut states = vec![
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
        [0.5, 0.5, 0.5, 0.0, 0.0, 0.0],
    ];
    for k in 0..24 {
        let f: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                f64::from(u8::from(i == j)) + amplitude * (2.0 * rng.uniform() - 1.0)
            })
        });
        let s = phis[k % phis.len()].sqrt();
        let b = |i: usize, j: usize| s * (0..3).map(|m| f[i][m] * f[j][m]).sum::<f64>();
        states.push([b(0, 0), b(1, 1), b(2, 2), b(0, 1), b(1, 2), b(0, 2)]);
    }
    states
}

/// Checks a law's in-plane tangent against central finite differences of its stress at
/// [`tangent_check_states`] (two batched calls: the states with tangents, then the ±h
/// perturbations with stresses only). Returns the worst entry; the caller compares it with
/// [`FD_TANGENT_TOLERANCE`] ([`TangentCheck::passed`]). States the law cannot evaluate (outside
/// its domain) are skipped, up to half of them; it fails if the law cannot evaluate `B̃ = I` or
/// more than half the states. Works for any [`ConstitutiveLaw`], built in or loaded.
pub fn check_tangent(law: &dyn ConstitutiveLaw) -> Result<TangentCheck, LawError> {
    check(
        &|b: &[Sym], t: &mut [Sym], j: Option<&mut [[f64; 16]]>| law.evaluate(b, t, j),
        &tangent_check_states(),
    )
}

/// The same check on full 3-D tensors, at [`tangent_check_states_full`], through
/// [`ConstitutiveLaw::evaluate_full`]: every entry of the 6×6 tangent, the out-of-plane shears'
/// rows and columns included. An error for a law that carries in-plane tensors only.
pub fn check_tangent_full(law: &dyn ConstitutiveLaw) -> Result<TangentCheck, LawError> {
    check(
        &|b: &[Sym6], t: &mut [Sym6], j: Option<&mut [[f64; 36]]>| law.evaluate_full(b, t, j),
        &tangent_check_states_full(),
    )
}

/// A batch evaluation with `N` components per tensor and `NN = N²` per tangent.
type Evaluate<'a, const N: usize, const NN: usize> =
    dyn Fn(&[[f64; N]], &mut [[f64; N]], Option<&mut [[f64; NN]]>) -> Result<(), LawError> + 'a;

/// The check of either representation (see [`check_tangent`]).
fn check<const N: usize, const NN: usize>(
    evaluate: &Evaluate<'_, N, NN>,
    states: &[[f64; N]],
) -> Result<TangentCheck, LawError> {
    let n = states.len();
    let (pairs, skipped) = match tangents_and_differences(evaluate, states) {
        Ok(pairs) => (pairs, 0),
        // Some state is outside the law's domain (e.g. past a locking stretch): test the states
        // one by one and skip those the law cannot evaluate. `B̃ = I` must evaluate, and at
        // least half the states.
        Err(first) => {
            let mut pairs = Vec::with_capacity(n);
            for (s, b) in states.iter().enumerate() {
                match tangents_and_differences(evaluate, std::slice::from_ref(b)) {
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
        |j: &[f64; NN], fd: &[f64; NN]| j.iter().chain(fd).fold(0.0_f64, |m, x| m.max(x.abs()));
    let rest = magnitude(&pairs[0].1, &pairs[0].2);
    let mut worst: Option<TangentCheck> = None;
    for (b, j, fd) in &pairs {
        let scale = magnitude(j, fd).max(rest);
        let (i, err) = (0..NN)
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
                worst_state: b.to_vec(),
                worst_entry: (i / N, i % N),
                tangent: j[i],
                finite_difference: fd[i],
            });
        }
    }
    Ok(worst.expect("at least one state"))
}

/// For each state: `(B̃, J, J_fd)`, in two batched calls (the states with tangents, then the ±h
/// perturbations with stresses only).
#[allow(clippy::type_complexity)]
fn tangents_and_differences<const N: usize, const NN: usize>(
    evaluate: &Evaluate<'_, N, NN>,
    states: &[[f64; N]],
) -> Result<Vec<([f64; N], [f64; NN], [f64; NN])>, LawError> {
    let n = states.len();
    let mut tau = vec![[0.0; N]; n];
    let mut jac = vec![[0.0; NN]; n];
    evaluate(states, &mut tau, Some(&mut jac))?;
    let steps: Vec<f64> = states
        .iter()
        .map(|b| 1e-6 * b.iter().fold(1.0_f64, |m, x| m.max(x.abs())))
        .collect();
    let mut perturbed = Vec::with_capacity(2 * N * n);
    for (b, h) in states.iter().zip(&steps) {
        for c in 0..N {
            for sign in [1.0, -1.0] {
                let mut p = *b;
                p[c] += sign * h;
                perturbed.push(p);
            }
        }
    }
    let mut tau_p = vec![[0.0; N]; 2 * N * n];
    evaluate(&perturbed, &mut tau_p, None)?;
    Ok((0..n)
        .map(|s| {
            let mut fd = [0.0; NN];
            for c in 0..N {
                let (tp, tm) = (tau_p[2 * N * s + 2 * c], tau_p[2 * N * s + 2 * c + 1]);
                for a in 0..N {
                    fd[N * a + c] = (tp[a] - tm[a]) / (2.0 * steps[s]);
                }
            }
            (states[s], jac[s], fd)
        })
        .collect())
}

/// Relative tolerance of the embedding check ([`check_embedding`]): the two evaluations of a
/// version-2 library may differ on an in-plane tensor by round-off only. A law written with the
/// SDK differs by nothing (its helpers give the same numbers both ways); a law whose two
/// functions compute in a different order differs by a few ulps, 1e-15 relative.
pub const EMBEDDING_TOLERANCE: f64 = 1e-10;

/// The outcome of the embedding check ([`check_embedding`]): the worst difference between a
/// law's in-plane evaluation and its full evaluation of the same tensors.
#[derive(Clone, Debug, PartialEq)]
pub struct EmbeddingCheck {
    /// Number of in-plane states compared.
    pub states: usize,
    /// The worst `|x_in-plane − x_full| / max|x_in-plane|`, `x` the stress (scaled by its
    /// largest component over the states) or the tangent (by its largest entry).
    pub worst_relative_difference: f64,
    /// The state where it occurred, `[b11, b22, b33, b12]`.
    pub worst_state: Vec<f64>,
    /// What differs there, e.g. `τ12` or `∂τ11/∂B̃12`.
    pub worst_entry: String,
    /// The in-plane evaluation's value there.
    pub in_plane: f64,
    /// The full evaluation's value there.
    pub full: f64,
}

impl EmbeddingCheck {
    /// Whether the check passed ([`EMBEDDING_TOLERANCE`]).
    pub fn passed(&self) -> bool {
        self.worst_relative_difference <= EMBEDDING_TOLERANCE
    }
}

impl fmt::Display for EmbeddingCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "worst relative difference {:.3e} (tolerance {EMBEDDING_TOLERANCE:e}) over {} states, at {} = {:.6e} in-plane vs {:.6e} full, B̃ = {:?}",
            self.worst_relative_difference,
            self.states,
            self.worst_entry,
            self.in_plane,
            self.full,
            self.worst_state
        )
    }
}

/// Compares a law's in-plane evaluation with its full evaluation of the same tensors embedded
/// in six components (13 = 23 = 0), at [`tangent_check_states`]: stress components 11, 22, 33,
/// 12 and the tangent's in-plane 4×4 block, which the ABI requires to be the same law. States
/// that neither evaluation can evaluate (outside the law's domain) are skipped, as in the
/// tangent check; a state only one of them evaluates is a disagreement (an infinite
/// difference). An error if `B̃ = I` cannot be evaluated.
pub fn check_embedding(law: &dyn ConstitutiveLaw) -> Result<EmbeddingCheck, LawError> {
    let all = tangent_check_states();
    let evaluated = match both(law, &all) {
        Ok(e) => e,
        Err(first) => {
            let mut kept = Vec::with_capacity(all.len());
            for (s, b) in all.iter().enumerate() {
                match both(law, std::slice::from_ref(b)) {
                    Ok(e) => kept.extend(e),
                    Err(e) if s == 0 => return Err(e),
                    Err(e) => {
                        let mut t4 = [[0.0; 4]];
                        let mut t6 = [[0.0; 6]];
                        let in_plane = law.evaluate(std::slice::from_ref(b), &mut t4, None);
                        let full = law.evaluate_full(&[embed(b)], &mut t6, None);
                        if in_plane.is_ok() != full.is_ok() {
                            return Ok(EmbeddingCheck {
                                states: s + 1,
                                worst_relative_difference: f64::INFINITY,
                                worst_state: b.to_vec(),
                                worst_entry: format!(
                                    "the {} evaluation only ({})",
                                    if in_plane.is_ok() { "in-plane" } else { "full" },
                                    e.message
                                ),
                                in_plane: t4[0][0],
                                full: t6[0][0],
                            });
                        }
                    }
                }
            }
            if 2 * kept.len() < all.len() {
                return Err(first);
            }
            kept
        }
    };
    let largest = |xs: &mut dyn Iterator<Item = f64>| xs.fold(0.0_f64, |m, x| m.max(x.abs()));
    let tau_scale = largest(&mut evaluated.iter().flat_map(|e| e.1));
    let j_scale = largest(&mut evaluated.iter().flat_map(|e| e.2));
    let first = &evaluated[0];
    let mut worst = EmbeddingCheck {
        states: evaluated.len(),
        worst_relative_difference: 0.0,
        worst_state: first.0.to_vec(),
        worst_entry: format!("τ{}", COMPONENTS[0]),
        in_plane: first.1[0],
        full: first.3[0],
    };
    let mut consider = |b: &Sym, entry: String, x: f64, y: f64, scale: f64| {
        let d = (x - y).abs() / if scale > 0.0 { scale } else { 1.0 };
        // A NaN difference (one side non-finite) counts as the worst.
        if d.is_nan() || d > worst.worst_relative_difference {
            let d = if d.is_nan() { f64::INFINITY } else { d };
            worst.worst_relative_difference = d;
            worst.worst_state = b.to_vec();
            worst.worst_entry = entry;
            worst.in_plane = x;
            worst.full = y;
        }
    };
    for (b, t4, j4, t6, j6) in &evaluated {
        for a in 0..4 {
            consider(b, format!("τ{}", COMPONENTS[a]), t4[a], t6[a], tau_scale);
            for c in 0..4 {
                consider(
                    b,
                    format!("∂τ{}/∂B̃{}", COMPONENTS[a], COMPONENTS[c]),
                    j4[4 * a + c],
                    j6[6 * a + c],
                    j_scale,
                );
            }
        }
    }
    Ok(worst)
}

/// `[b11, b22, b33, b12, 0, 0]`.
fn embed(b: &Sym) -> Sym6 {
    [b[0], b[1], b[2], b[3], 0.0, 0.0]
}

/// For each state: `(B̃, τ, J)` in-plane and `(τ, J)` of the embedded state, in one batched call
/// each way.
#[allow(clippy::type_complexity)]
fn both(
    law: &dyn ConstitutiveLaw,
    states: &[Sym],
) -> Result<Vec<(Sym, Sym, [f64; 16], Sym6, [f64; 36])>, LawError> {
    let n = states.len();
    let embedded: Vec<Sym6> = states.iter().map(embed).collect();
    let (mut t4, mut j4) = (vec![[0.0; 4]; n], vec![[0.0; 16]; n]);
    let (mut t6, mut j6) = (vec![[0.0; 6]; n], vec![[0.0; 36]; n]);
    law.evaluate(states, &mut t4, Some(&mut j4))?;
    law.evaluate_full(&embedded, &mut t6, Some(&mut j6))?;
    Ok((0..n)
        .map(|k| (states[k], t4[k], j4[k], t6[k], j6[k]))
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
