//! The solid's limits, checked before the run: the elastic-wave Courant limit on Δt and the
//! fewest cells across a solid.

use efsi_core::scene::Options;
use efsi_core::{Grid, Scene};
use efsi_laws_host::ConstitutiveLaw;

/// The fewest cells across an elastic solid (its section's hydraulic diameter `4A/P` over the
/// cell size in two dimensions, its `6V/S` in three: a disk's or a ball's diameter) that a
/// scene may have. The interface treatment (the series corners and the PLIC corner
/// fractions of the module docs) spans a cell on each side of the interface; in a solid fewer
/// cells across it is most of the solid, the solid's bulk stress is no longer resolved, and an
/// impact can return more energy as motion than it took in. The check is a floor on the
/// resolution, not an accuracy target.
pub const MIN_CELLS_ACROSS: f64 = 5.0;

/// The largest Δt the elastic-wave Courant limits allow, `s·h/c` with `h` the smallest cell
/// size over the grid's axes, `c = √(G₀/ρ_s)` and `G₀` the largest diagonal entry of the law's
/// tangent at `B̃ = I` (in-plane or full, as the grid's tensor; the shear modulus for the
/// shipped laws): `split` at `s` = [`super::ElasticOptions::wave_courant`], `coupled` at
/// [`super::ElasticOptions::coupled_wave_courant`] where the scene may take the coupled step
/// (else equal to `split`). The stiffness is the rest state's: a law that stiffens under strain
/// (Gent near its locking stretch, Mooney–Rivlin with `C3 > 0`) carries faster waves where the
/// solid is deformed than this limit allows for — it is under-limited there, and a run that
/// goes unstable at large strain needs a smaller `time.cfl` or `wave_courant`.
#[derive(Clone, Copy, Debug)]
pub(super) struct WaveLimits {
    pub(super) split: f64,
    pub(super) coupled: f64,
    /// `h/c`: the Δt of one elastic-wave Courant number.
    pub(super) wave_step: f64,
}

/// The [`WaveLimits`] of the scene's elastic bodies (`laws` theirs, in order), worked out once
/// per pipeline and shared by the elastic and deformation sub-steps: each body's limits
/// ([`wave_limit_of`]), the smallest of each over the bodies (the fastest wave caps the step).
pub(super) fn shared_wave_limits(
    scene: &Scene,
    options: &Options,
    grid: &Grid,
    bodies: &[super::bodies::ElasticBody],
    laws: &[std::sync::Arc<dyn ConstitutiveLaw>],
    shared: &mut efsi_core::Resources,
) -> Result<WaveLimits, String> {
    shared
        .get_or_try_insert_with(|| {
            let mut all = bodies.iter().zip(laws).map(|(b, law)| {
                wave_limit_of(scene, options, grid, law.as_ref(), &b.solid, &b.path)
            });
            let first = all.next().ok_or("the scene has no elastic body")??;
            all.try_fold(first, |m, l| {
                let l = l?;
                Ok::<_, String>(WaveLimits {
                    split: m.split.min(l.split),
                    coupled: m.coupled.min(l.coupled),
                    wave_step: m.wave_step.min(l.wave_step),
                })
            })
        })
        .copied()
}

/// The [`WaveLimits`]. A `time.fixed_dt` above the larger one is refused here, before the run
/// starts, naming the limit and what to change; so is a solid narrower than
/// [`MIN_CELLS_ACROSS`].
#[cfg(test)]
pub(super) fn wave_limit(
    scene: &Scene,
    options: &Options,
    grid: &Grid,
    law: &dyn ConstitutiveLaw,
) -> Result<WaveLimits, String> {
    let solid = crate::solid::solid(options)?;
    wave_limit_of(scene, options, grid, law, solid, "solid")
}

/// The [`WaveLimits`] of the body `solid` (its settings at `path`: `solid`, `solids[1]`).
fn wave_limit_of(
    scene: &Scene,
    options: &Options,
    grid: &Grid,
    law: &dyn ConstitutiveLaw,
    solid: &crate::solid::Solid,
    path: &str,
) -> Result<WaveLimits, String> {
    let m = super::Deformation::components(grid);
    let (mut b, mut tau, mut tangent) = ([0.0; 6], [0.0; 6], [0.0; 36]);
    b[..3].fill(1.0);
    super::stress::eval(law, m, &b[..m], &mut tau[..m], Some(&mut tangent[..m * m]))
        .map_err(|e| format!("{path}.law: at rest (B = I): {e}"))?;
    let shear = tangent[3 * (m + 1)];
    if shear.is_nan() || shear <= 0.0 {
        return Err(format!(
            "{path}.law: its shear stiffness at rest (∂τ₁₂/∂B̃₁₂ at B̃ = I) is {shear:e} Pa, not \
             positive: the material has no stable rest state (for Mooney–Rivlin, C1 + C2 must \
             be > 0)"
        ));
    }
    let g0 = (0..m)
        .map(|a| tangent[a * (m + 1)].abs())
        .fold(0.0, f64::max);
    if !(g0.is_finite() && g0 > 0.0) {
        return Err(format!(
            "{path}.law: its stiffness at rest (the tangent's diagonal at B = I) is {g0}, not a \
             positive number"
        ));
    }
    let (hs, dims) = (grid.h(), grid.dims());
    if let Some(width) = solid_width(grid, &solid.shape) {
        let h = hs[1..dims].iter().fold(hs[0], |s, &h| s.max(h));
        // The staircase estimate of the width is within 8 % for a disk 3 cells across or more.
        if width / h < 0.9 * MIN_CELLS_ACROSS {
            let measure = if dims == 3 {
                "its volume-to-surface measure 6V/S"
            } else {
                "its section's hydraulic diameter 4A/P"
            };
            return Err(format!(
                "{path}.shape: the solid is {:.1} cells across ({measure} = {width:.4e} m over \
                 cells of {h:.4e} m); an elastic solid needs at least \
                 {MIN_CELLS_ACROSS} (narrower ones were measured to gain up to 12 % of their \
                 impact energy, `cargo xtask bench-paper --case stability`): refine the grid \
                 (grid: nx, ny{} — nr, nz when axisymmetric) to cells of at most {:.4e} m, or widen the solid",
                width / h,
                if dims == 3 { ", nz" } else { "" },
                width / MIN_CELLS_ACROSS
            ));
        }
    }
    let mut o = options.section::<super::ElasticOptions>()?.clone();
    // The coupling in force: `Split` where the solid has no implicit law.
    o.coupling = super::coupling(options);
    let s = o.wave_cap();
    let option = match o.coupling {
        super::ElasticCoupling::Split => "numerics.elastic.wave_courant",
        super::ElasticCoupling::Coupled => "numerics.elastic.coupled_wave_courant",
        super::ElasticCoupling::Auto => {
            "numerics.elastic.coupled_wave_courant; coupling: Auto takes the coupled step above \
             the split step's numerics.elastic.wave_courant"
        }
    };
    let h = hs[1..dims].iter().fold(hs[0], |s, &h| s.min(h));
    let c = (g0 / solid.density).sqrt();
    let dt = s * h / c;
    if let Some(fixed) = scene.time.fixed_dt
        && fixed > dt
    {
        return Err(format!(
            "time.fixed_dt: {fixed:e} s breaks the elastic-wave limit Δt·c/h ≤ {s} \
                 ({option}): the solid's shear waves (c = √(G₀/ρ_s) = \
                 {c:.4e} m/s from G₀ = {g0:e} Pa, ρ_s = {}) cross {:.3} cells of h = {h:.4e} m \
                 per step; set time.fixed_dt ≤ {dt:.4e} s, or leave it out to let the step \
                 adapt",
            solid.density,
            fixed * c / h
        ));
    }
    Ok(WaveLimits {
        split: o.wave_courant * h / c,
        coupled: dt,
        wave_step: h / c,
    })
}

/// The solid's width for [`MIN_CELLS_ACROSS`]: in two dimensions its section's hydraulic
/// diameter ([`crate::vof::section_width`]); in three `6V/S` from its exact cell fractions φ,
/// `V = Σ φ dV` and `S = Σ |∇φ| dV` (central differences, φ held at the boundary). `None`
/// without a surface.
fn solid_width(grid: &Grid, shape: &crate::solid::Shape) -> Option<f64> {
    if !grid.is_3d() {
        return crate::vof::section_width(grid, shape);
    }
    let mut phi = efsi_core::Field::zeros(grid);
    crate::vof::fill_fraction(grid, shape, &mut phi);
    let (n, h) = (grid.n().map(|n| n as isize), grid.h());
    let dv = h[0] * h[1] * h[2];
    let at = |i: [isize; 3]| phi[std::array::from_fn::<_, 3, _>(|a| i[a].clamp(0, n[a] - 1))];
    let (mut volume, mut surface) = (0.0, 0.0);
    let cells = efsi_core::Region::of(grid, efsi_core::Stagger::Cell);
    for l in (0..cells.lines()).map(|m| cells.line(m)) {
        for i in l.indices() {
            volume += phi[i] * dv;
            let d = |a: usize| {
                let (mut lo, mut hi) = (i, i);
                (lo[a], hi[a]) = (i[a] - 1, i[a] + 1);
                (at(hi) - at(lo)) / (2.0 * h[a])
            };
            surface += (d(0).powi(2) + d(1).powi(2) + d(2).powi(2)).sqrt() * dv;
        }
    }
    (surface > 0.0).then(|| 6.0 * volume / surface)
}
