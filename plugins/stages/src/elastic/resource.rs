//! The implicit-momentum stage's data in the [`State`](efsi_core::State): the solid's tensor B and the history its
//! transport carries from step to step ([`Deformation`], a [`StateResource`] the deformation
//! stage adds to the state), saved in checkpoints and snapshots under the names `B.<part>.<c>`
//! and `elastic_energy`.

use efsi_core::{Field, Grid, StateResource};

/// The left Cauchy–Green tensor B of the solid, from which the elastic sub-steps form the seed's
/// modified tensor `B̃ = φ_s^{1/2} B` (Eq. 8) with the current solid fraction. Since φ_s is
/// materially conserved, B and B̃ obey the same transport law; storing B (the identity in pure
/// fluid, where it is reset every step) keeps B̃ and the VOF interface consistent — rigid motion
/// leaves `B̃ = φ_s^{1/2} I` to round-off — whereas advecting B̃ and φ_s with two different
/// schemes would not.
///
/// Staggered like the stresses it produces: `b[0] = B₁₁`, `b[1] = B₂₂`, `b[2] = B₃₃` (zz in
/// plane strain, θθ axisymmetric) at cell centres, the shear `b[3] = B₁₂` at cell corners — so
/// the shear force is a compact stencil with no undamped checkerboard mode.
///
/// Seed Eqs. 13, 17 and 24 differ only in the velocity of their implicit part: each is
/// `B = Bⁿ + explicit + (Δt/2) H(V; Bⁿ)` with `H(V; B) = L(V)·B + B·L(V)ᵀ` and
/// `explicit = −Δt (AB2 of ∇·(V B)) + (Δt/2) H(Vⁿ; Bⁿ)`. The rates at the end of a step are
/// kept here (`advection`, `advection_prev`, `stretching`) because the next step's elastic
/// stage runs after the velocity has left Vⁿ.
#[derive(Clone, Debug)]
pub struct Deformation {
    /// B (components 11, 22, 33 at centres; 12 at corners).
    pub b: [Field; 4],
    /// Bⁿ, at the start of the step.
    pub start: [Field; 4],
    /// `∇·(Vⁿ Bⁿ)`.
    pub advection: [Field; 4],
    /// `∇·(Vⁿ⁻¹ Bⁿ⁻¹)`.
    pub advection_prev: [Field; 4],
    /// `H(Vⁿ; Bⁿ)`.
    pub stretching: [Field; 4],
    /// This step's explicit part.
    pub explicit: [Field; 4],
    /// This step's implicit-relaxation divisor of the corner shear `B₁₂` at interface corners
    /// (1 elsewhere): set by the elastic sub-step, used again by the end-of-step update. Scratch
    /// of one step: it is recomputed before use, so it carries no history.
    pub relax: Field,
    /// The elastic stress `τ(B̃) − τ(φ^{1/2} I)` at the end of the step (the law's stress less
    /// its stress-free isotropic part, which is pressure), staggered like `b`.
    pub stress: [Field; 4],
    /// The elastic (strain) energy in the solid at the end of the step, `∫ W dV` (per radian in
    /// axisymmetric geometry), from the law's stress by integration along the isochoric path
    /// `exp(s log B)` (see the elastic sub-step).
    pub elastic_energy: f64,
}

impl Deformation {
    /// Zero tensors shaped for `grid`.
    pub fn zeros(grid: &Grid) -> Self {
        let z = || std::array::from_fn(|_| Field::zeros(grid));
        Deformation {
            b: z(),
            start: z(),
            advection: z(),
            advection_prev: z(),
            stretching: z(),
            explicit: z(),
            relax: Field::zeros(grid),
            stress: z(),
            elastic_energy: 0.0,
        }
    }

    /// Names of the four components, in storage order.
    pub const COMPONENTS: [&'static str; 4] = ["11", "22", "33", "12"];

    /// The six tensors by name: `b`, `start`, `advection`, `advection_prev`, `stretching`,
    /// `explicit`.
    pub fn parts(&self) -> [(&'static str, &[Field; 4]); 7] {
        [
            ("b", &self.b),
            ("start", &self.start),
            ("advection", &self.advection),
            ("advection_prev", &self.advection_prev),
            ("stretching", &self.stretching),
            ("explicit", &self.explicit),
            ("stress", &self.stress),
        ]
    }

    /// [`parts`](Self::parts), mutable.
    pub fn parts_mut(&mut self) -> [(&'static str, &mut [Field; 4]); 7] {
        [
            ("b", &mut self.b),
            ("start", &mut self.start),
            ("advection", &mut self.advection),
            ("advection_prev", &mut self.advection_prev),
            ("stretching", &mut self.stretching),
            ("explicit", &mut self.explicit),
            ("stress", &mut self.stress),
        ]
    }

    /// The first non-finite component of `b` in the interior: `(component name, (i, j))`.
    pub fn first_non_finite(&self, nx: usize, ny: usize) -> Option<(&'static str, (usize, usize))> {
        const NAMES: [&str; 4] = ["11", "22", "33", "12"];
        for (c, f) in self.b.iter().enumerate() {
            let st = if c == 3 {
                efsi_core::Stagger::Corner
            } else {
                efsi_core::Stagger::Cell
            };
            if let Some(at) = f.first_non_finite(st, nx, ny) {
                return Some((NAMES[c], at));
            }
        }
        None
    }
}

impl StateResource for Deformation {
    fn arrays(&self) -> Vec<(String, &Field)> {
        let mut out = Vec::with_capacity(28);
        for (part, t) in self.parts() {
            for (c, f) in Deformation::COMPONENTS.iter().zip(t) {
                out.push((format!("B.{part}.{c}"), f));
            }
        }
        out
    }

    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        let mut out = Vec::with_capacity(28);
        for (part, t) in self.parts_mut() {
            for (c, f) in Deformation::COMPONENTS.iter().zip(t) {
                out.push((format!("B.{part}.{c}"), f));
            }
        }
        out
    }

    fn scalars(&self) -> Vec<(&'static str, f64)> {
        vec![("elastic_energy", self.elastic_energy)]
    }

    fn scalars_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
        vec![("elastic_energy", &mut self.elastic_energy)]
    }

    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(self.clone())
    }

    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        let Some(other) = (other as &dyn std::any::Any).downcast_ref::<Deformation>() else {
            return false;
        };
        // `relax` is one step's scratch: not copied, like it is not saved.
        let fits = self
            .parts()
            .iter()
            .zip(other.parts())
            .all(|((_, a), (_, b))| {
                a.iter()
                    .zip(b)
                    .all(|(f, g)| f.data().len() == g.data().len())
            });
        if !fits {
            return false;
        }
        for ((_, a), (_, b)) in self.parts_mut().into_iter().zip(other.parts()) {
            for (f, g) in a.iter_mut().zip(b) {
                f.copy_from(g);
            }
        }
        self.elastic_energy = other.elastic_energy;
        true
    }

    fn first_non_finite(&self, nx: usize, ny: usize) -> Option<(String, (usize, usize))> {
        Deformation::first_non_finite(self, nx, ny).map(|(c, at)| (format!("B{c}"), at))
    }

    fn stored_energy(&self) -> f64 {
        self.elastic_energy
    }
}
