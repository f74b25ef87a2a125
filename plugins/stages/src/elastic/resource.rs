//! The implicit-momentum stage's data in the [`State`](efsi_core::State): the solid's tensor B and the history its
//! transport carries from step to step ([`Deformation`], a [`StateResource`] the deformation
//! stage adds to the state), saved in checkpoints and snapshots under the names `B.<part>.<c>`
//! and `elastic_energy`.

use efsi_core::{Field, Grid, Stagger, StateResource};

/// The left Cauchy–Green tensor B of the solid, from which the elastic sub-steps form the seed's
/// modified tensor `B̃ = φ_s^{1/2} B` (Eq. 8) with the current solid fraction. Since φ_s is
/// materially conserved, B and B̃ obey the same transport law; storing B (the identity in pure
/// fluid, where it is reset every step) keeps B̃ and the VOF interface consistent — rigid motion
/// leaves `B̃ = φ_s^{1/2} I` to round-off — whereas advecting B̃ and φ_s with two different
/// schemes would not.
///
/// Staggered like the stresses it produces, component `c` of every part being the field `[c]`:
/// `B₁₁, B₂₂, B₃₃` (`[0]`, `[1]`, `[2]`; 33 is zz in plane strain, θθ axisymmetric) at cell
/// centres, then the shear components on the edges of their pair of axes, in the order of
/// the viscous operator's shear pairs — `B₁₂` (`[3]`) on the xy-edges (the cell corners
/// of a two-dimensional grid), `B₂₃` (`[4]`) on the yz-edges (along x), `B₁₃` (`[5]`) on the
/// xz-edges (along y) — as the viscous stress: four components on a two-dimensional grid, six on
/// a three-dimensional one ([`Deformation::components`]). The shear force is then a compact
/// stencil with no undamped checkerboard mode.
///
/// Seed Eqs. 13, 17 and 24 differ only in the velocity of their implicit part: each is
/// `B = Bⁿ + explicit + (Δt/2) H(V; Bⁿ)` with `H(V; B) = L(V)·B + B·L(V)ᵀ` and
/// `explicit = −Δt (AB2 of ∇·(V B)) + (Δt/2) H(Vⁿ; Bⁿ)`. The rates at the end of a step are
/// kept here (`advection`, `advection_prev`, `stretching`) because the next step's elastic
/// stage runs after the velocity has left Vⁿ.
#[derive(Clone, Debug)]
pub struct Deformation {
    /// B (components 11, 22, 33 at centres; the shear on the edges).
    pub b: Vec<Field>,
    /// Bⁿ, at the start of the step.
    pub start: Vec<Field>,
    /// `∇·(Vⁿ Bⁿ)`.
    pub advection: Vec<Field>,
    /// `∇·(Vⁿ⁻¹ Bⁿ⁻¹)`.
    pub advection_prev: Vec<Field>,
    /// `H(Vⁿ; Bⁿ)`.
    pub stretching: Vec<Field>,
    /// This step's explicit part.
    pub explicit: Vec<Field>,
    /// This step's implicit-relaxation factor of each shear pair's component at its interface
    /// edges (1 elsewhere; one field per pair): set by the elastic sub-step, used again by
    /// the end-of-step update. Scratch of one step: it is recomputed before use, so it carries
    /// no history.
    pub relax: Vec<Field>,
    /// The elastic stress `τ(B̃) − τ(φ^{1/2} I)` at the end of the step (the law's stress less
    /// its stress-free isotropic part, which is pressure), staggered like `b`.
    pub stress: Vec<Field>,
    /// The elastic (strain) energy in the solid at the end of the step, `∫ W dV` (per radian in
    /// axisymmetric geometry), from the law's stress by integration along the isochoric path
    /// `exp(s log B)` (see the elastic sub-step).
    pub elastic_energy: f64,
}

impl Deformation {
    /// Zero tensors shaped for `grid`: [`Deformation::components`] fields each.
    pub fn zeros(grid: &Grid) -> Self {
        let z = || {
            (0..Deformation::components(grid))
                .map(|_| Field::zeros(grid))
                .collect()
        };
        Deformation {
            b: z(),
            start: z(),
            advection: z(),
            advection_prev: z(),
            stretching: z(),
            explicit: z(),
            relax: (3..Deformation::components(grid))
                .map(|_| Field::zeros(grid))
                .collect(),
            stress: z(),
            elastic_energy: 0.0,
        }
    }

    /// Names of the components, in storage order (the first four on a two-dimensional grid).
    pub const COMPONENTS: [&'static str; 6] = ["11", "22", "33", "12", "23", "13"];

    /// Number of components on `grid`: 4 on a two-dimensional grid, 6 on a three-dimensional
    /// one.
    pub fn components(grid: &Grid) -> usize {
        3 + crate::viscous_operator::shear_pairs(grid.dims()).len()
    }

    /// Where component `c` lives: centres for 11, 22, 33, the edges of its pair for the shear.
    pub fn stagger(c: usize) -> Stagger {
        match c {
            0..3 => Stagger::Cell,
            _ => crate::viscous_operator::SHEAR[c - 3].1,
        }
    }

    /// The seven tensors by name: `b`, `start`, `advection`, `advection_prev`, `stretching`,
    /// `explicit`, `stress`.
    pub fn parts(&self) -> [(&'static str, &[Field]); 7] {
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
    pub fn parts_mut(&mut self) -> [(&'static str, &mut [Field]); 7] {
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
        for (c, f) in self.b.iter().enumerate() {
            if let Some(at) = f.first_non_finite(Deformation::stagger(c), nx, ny) {
                return Some((Deformation::COMPONENTS[c], at));
            }
        }
        None
    }
}

impl StateResource for Deformation {
    fn arrays(&self) -> Vec<(String, &Field)> {
        let mut out = Vec::with_capacity(7 * self.b.len());
        for (part, t) in self.parts() {
            for (c, f) in Deformation::COMPONENTS.iter().zip(t) {
                out.push((format!("B.{part}.{c}"), f));
            }
        }
        out
    }

    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        let mut out = Vec::with_capacity(7 * self.b.len());
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
                a.len() == b.len()
                    && a.iter()
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

impl Deformation {
    /// B = I: the normal components 1, the shear 0.
    pub(super) fn set_identity(&mut self) {
        for (c, f) in self.b.iter_mut().enumerate() {
            f.fill(if c < 3 { 1.0 } else { 0.0 });
        }
    }

    /// The start of a step of `dt` (`r = Δt/Δt_prev`, θ of the stretching): `Bⁿ = B` and the
    /// explicit part `E = −Δt [(1 + r/2) Aⁿ − (r/2) Aⁿ⁻¹] + (1 − θ)Δt H(Vⁿ; Bⁿ)` of every
    /// component, at every entry (ghosts included).
    pub(super) fn begin_step(&mut self, dt: f64, r: f64, theta: f64) {
        for c in 0..self.b.len() {
            self.start[c].copy_from(&self.b[c]);
            let (e, a, ap, h) = (
                &mut self.explicit[c],
                &self.advection[c],
                &self.advection_prev[c],
                &self.stretching[c],
            );
            for (((e, a), ap), h) in e
                .data_mut()
                .iter_mut()
                .zip(a.data())
                .zip(ap.data())
                .zip(h.data())
            {
                *e = -dt * ((1.0 + 0.5 * r) * a - 0.5 * r * ap) + (1.0 - theta) * dt * h;
            }
        }
    }
}
