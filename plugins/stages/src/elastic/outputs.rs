//! The implicit-momentum stage's outputs ([`StagePlugin::outputs`](efsi_core::StagePlugin::outputs)):
//! the VTK arrays `B` (B̃ = φ^{1/2} B) and `stress` (the elastic extra stress), and the probe
//! quantity `elastic_energy`, all from the [`Deformation`] resource — in a scene of several
//! bodies from each elastic body's ([`super::BodyDeformations`]), summed over the bodies:
//! `B̃ = Σ_k φ_k^{1/2} B_k`, the stress `Σ_k τ_k`, the energy `Σ_k ∫ w_k W_k dV`.

use super::bodies::{BodyDeformations, deformations};
use efsi_core::body_fractions::BodyFractions;
use efsi_core::{Field, Geometry, Grid, OutputDecl, OutputKind, Region, Stagger, State};

/// What the elastic plugin contributes.
pub(super) const OUTPUTS: &[OutputDecl] = &[
    OutputDecl {
        name: "B",
        meaning: "B̃ = φ^{1/2} B, not B: the left Cauchy–Green tensor B = F Fᵀ of the solid weighted by the square root of the solid fraction (divide by √φ for B; I in a solid at rest, 0 in the fluid); the shear component is the mean of the cell's four corners; present with a solid that has a law",
        unit: "1",
        kind: OutputKind::Array {
            components: |g| match g {
                Geometry::Planar => vec!["B̃xx", "B̃yy", "B̃zz (out of plane)", "B̃xy", "0", "0"],
                Geometry::Axisymmetric => vec!["B̃rr", "B̃θθ", "B̃zz", "0", "0", "B̃rz"],
                Geometry::Cartesian3D => vec!["B̃xx", "B̃yy", "B̃zz", "B̃xy", "B̃yz", "B̃xz"],
            },
            values: |grid, state| {
                let phi = state.phi.as_ref()?;
                let Some(many) = state.resources.get::<BodyDeformations>() else {
                    let d = deformations(state).first()?;
                    return Some(tensor(grid, &d.b, Some(phi)));
                };
                // Each body's B weighted by its own fraction, on its window, summed.
                let all = state.resources.get::<BodyFractions>()?;
                let mut out = vec![0.0; 6 * grid.cells()];
                for (k, (name, d)) in many.names.iter().zip(&many.bodies).enumerate() {
                    let b = all.bodies.iter().find(|b| &b.name == name)?;
                    let (place, window) = (many.places[k], many.grid(k));
                    let mut f = efsi_core::Field::zeros(&window);
                    let o = place.origin();
                    for (at, v) in b.cells() {
                        let w = [at[0] - o[0], at[1] - o[1], at[2] - o[2]];
                        // Its support lies inside the window (module docs of `bodies`).
                        if (0..3).all(|a| (0..place.n[a] as isize).contains(&w[a])) {
                            f[w] = v;
                        }
                    }
                    add_on(&mut out, grid, &tensor(&window, &d.b, Some(&f)), place);
                }
                Some(out)
            },
        },
    },
    OutputDecl {
        name: "stress",
        meaning: "the elastic extra stress only, τ(B̃) − τ(φ^{1/2} I): the law's stress less its isotropic rest stress; without the pressure and the viscous stress (the Cauchy stress is −p I + 2μD + this); the shear component is the mean of the cell's four corners; present with a solid that has a law",
        unit: "Pa",
        kind: OutputKind::Array {
            components: |g| match g {
                Geometry::Planar => vec!["τxx", "τyy", "τzz (out of plane)", "τxy", "0", "0"],
                Geometry::Axisymmetric => vec!["τrr", "τθθ", "τzz", "0", "0", "τrz"],
                Geometry::Cartesian3D => vec!["τxx", "τyy", "τzz", "τxy", "τyz", "τxz"],
            },
            values: |grid, state| {
                state.phi.as_ref()?;
                if let Some(many) = state.resources.get::<BodyDeformations>() {
                    // Each body's on its window, summed.
                    let mut out = vec![0.0; 6 * grid.cells()];
                    for (k, d) in many.bodies.iter().enumerate() {
                        let t = tensor(&many.grid(k), &d.stress, None);
                        add_on(&mut out, grid, &t, many.places[k]);
                    }
                    return Some(out);
                }
                let ds = deformations(state);
                let mut out = tensor(grid, &ds.first()?.stress, None);
                for d in ds.iter().skip(1) {
                    add(&mut out, &tensor(grid, &d.stress, None));
                }
                Some(out)
            },
        },
    },
    OutputDecl {
        name: "elastic_energy",
        meaning: "the elastic (strain) energy stored in the solid, ∫ W(B̃) dV (per radian in axisymmetric geometry)",
        unit: "J",
        kind: OutputKind::Quantity(elastic_energy),
    },
];

/// The strain energy of the last step's end, summed over the elastic bodies (NaN without the
/// resource).
fn elastic_energy(_grid: &Grid, state: &State) -> f64 {
    let ds = deformations(state);
    let first = ds.first().map_or(f64::NAN, |d| d.elastic_energy);
    ds.iter().skip(1).fold(first, |e, d| e + d.elastic_energy)
}

/// `out += t`.
fn add(out: &mut [f64], t: &[f64]) {
    for (o, t) in out.iter_mut().zip(t) {
        *o += t;
    }
}

/// `out += t` where `t` is a [`tensor`] of the window `place` of `grid` and `out` one of `grid`.
fn add_on(out: &mut [f64], grid: &Grid, t: &[f64], place: super::bodies::Place) {
    let (pn, (lo, n)) = (grid.n(), (place.lo, place.n));
    for k in 0..n[2] {
        for j in 0..n[1] {
            let row = 6 * (j + n[1] * k) * n[0];
            let at = 6 * (((k + lo[2]) * pn[1] + j + lo[1]) * pn[0] + lo[0]);
            add(&mut out[at..at + 6 * n[0]], &t[row..row + 6 * n[0]]);
        }
    }
}

/// A staggered tensor (11, 22, 33 at centres, each shear on the edges of its pair) at the cell
/// centres as a VTK symmetric tensor (XX, YY, ZZ, XY, YZ, XZ), each shear the mean of the cell's
/// four edges of its pair, weighted by `φ^{1/2}` if `phi` is given. Planar: 1 = X, 2 = Y,
/// 3 = Z. Axisymmetric (the r–z slice in the X–Z plane): r = X, z = Z, θ = Y. Three
/// dimensions: 1, 2, 3 = X, Y, Z (12, 23, 13 = XY, YZ, XZ).
fn tensor(grid: &Grid, t: &[Field], phi: Option<&Field>) -> Vec<f64> {
    let mut out = vec![0.0; 6 * grid.cells()];
    let (c11, c22, c33, c12) = if grid.is_axisymmetric() {
        (0, 2, 1, 5)
    } else {
        (0, 1, 2, 3)
    };
    let pairs = &crate::viscous_operator::SHEAR[..t.len() - 3];
    let cells = Region::of(grid, Stagger::Cell);
    for l in (0..cells.lines()).map(|n| cells.line(n)) {
        let [t11, t22, t33] = [0, 1, 2].map(|c| t[c].at(&l, [0; 3]));
        let shear: [super::Four; 3] = std::array::from_fn(|p| {
            let p = p.min(pairs.len() - 1);
            super::Four::new(&t[3 + p], &l, super::edges_of_cell(pairs[p].0))
        });
        let phi = phi.map(|p| p.at(&l, [0; 3]));
        let row = &mut out[6 * l.n * l.len..][..6 * l.len];
        for (n, out) in row.chunks_exact_mut(6).enumerate() {
            let w = phi.map_or(1.0, |p| p[n].clamp(0.0, 1.0).sqrt());
            out[c11] = w * t11[n];
            out[c22] = w * t22[n];
            out[c33] = w * t33[n];
            for (p, s) in shear.iter().enumerate().take(pairs.len()) {
                out[if p == 0 { c12 } else { 3 + p }] = w * s.avg(n);
            }
        }
    }
    out
}
