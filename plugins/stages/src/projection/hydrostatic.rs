//! The carrier fluid's hydrostatic pressure, which the seed's (non-incremental) scheme carries in
//! the pressure rather than in the body force.
//!
//! **Split.** With `ρ_f` the density of the scene's fluid and `e = g − a` gravity in the grid's
//! frame, `ρ e = ∇p_h + (ρ − ρ_f) e` with `p_h = ρ_f e·(x − x_ref)`. The body force adds only the
//! excess weight, `Δt (1 − ρ_f/ρ_face) e` (zero where the face is carrier fluid alone), and during
//! the step the state's pressure holds the excess pressure `p − p_h`: the body force subtracts
//! `p_h` from `p` and the projection adds it back after its solve, so between steps `p` is the
//! whole pressure (outputs, probes, wall forces, checkpoints). `ρ_face` is the projection's face
//! density ([`efsi_core::operators::face_density`]) and `p_h` is linear, so the discrete
//! gradient of `p_h` over `ρ_face` equals the weight removed to round-off, and the solve
//! (for the excess pressure, warm-started from the last step's) is the seed's scheme
//! rewritten. The viscous and elastic steps then never see the carrier's hydrostatic part,
//! which at no-slip walls the implicit viscous step would shear into vorticity the projection
//! cannot remove: a fluid at rest under gravity in a closed box stays at rest to the last bit.
//!
//! **Axes.** An axis takes part (its component of `e` is split and `p_h` varies along it) when it
//! is not periodic (a periodic column has no hydrostatic balance) and every Outflow side of the
//! domain is normal to it, on one end: `x_ref` is that side's coordinate, so `p_h = 0` on every
//! Outflow face and `p = 0` there keeps its meaning exactly; without Outflow sides `x_ref` is the
//! domain's centre, where the closed box's mean pressure (zero) then also keeps its meaning to
//! round-off. An axis along which an Outflow side lies (an Outflow side parallel to `e`'s
//! component), or with Outflow sides at both ends, does not take part: its component of `e` is
//! applied whole as in the seed's scheme.
//!
//! **Limit.** Only the carrier's hydrostatic part leaves the body force: the excess weight of a
//! layer of a heavier fluid (a law-less solid) that spans the box from wall to wall is still
//! sheared at the side walls by the viscous step. The incremental scheme, whose predictor
//! balances the whole pressure, keeps such a layer at rest.
//!
//! **When.** With gravity and the seed's scheme (`numerics.projection.incremental` off, the
//! default with an elastic solid), for the split and the coupled elastic step alike (the coupled
//! solve starts from and finds the excess pressure). The incremental scheme balances gravity by
//! its predictor's pressure instead (the `projection` module) and does not split.

use efsi_core::scene::{Boundary, Options, Side};
use efsi_core::{BoundarySet, Field, Grid, Region, Scene, Stagger, State};

/// The split of gravity into the carrier's hydrostatic pressure and the excess weight (module
/// docs): the carrier's density and, per axis, the reference coordinate of an axis that takes
/// part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hydrostatic {
    /// The carrier fluid's density `ρ_f`.
    density: f64,
    /// Per axis, `x_ref` if the axis takes part, else `None`.
    reference: [Option<f64>; 3],
}

impl Hydrostatic {
    /// The split for a scene: `None` without gravity, with the incremental scheme, or when no
    /// axis takes part (module docs).
    pub(crate) fn of(
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
    ) -> Option<Hydrostatic> {
        if scene.gravity.xyz() == [0.0; 3] || crate::incremental_pressure(options) {
            return None;
        }
        Self::for_sides(scene.fluid.density, grid, bc)
    }

    /// The split for carrier density `density` on `grid` with the sides `bc`, whatever the
    /// scheme.
    pub(crate) fn for_sides(density: f64, grid: &Grid, bc: &BoundarySet) -> Option<Hydrostatic> {
        let sides = Side::of(grid.dims());
        let outflow: Vec<Side> = sides
            .iter()
            .copied()
            .filter(|&s| *bc.get(s) == Boundary::Outflow)
            .collect();
        let h = grid.h();
        let lo = [grid.xf(0), grid.yf(0), grid.zf(0)];
        let n = grid.n();
        let reference: [Option<f64>; 3] = std::array::from_fn(|c| {
            if c >= grid.dims() || bc.periodic(c) {
                return None;
            }
            let hi = lo[c] + n[c] as f64 * h[c];
            match outflow.as_slice() {
                [] => Some(0.5 * (lo[c] + hi)),
                [s] if *s == Side::normal_to(c, false) => Some(lo[c]),
                [s] if *s == Side::normal_to(c, true) => Some(hi),
                _ => None,
            }
        });
        reference
            .iter()
            .any(Option::is_some)
            .then_some(Hydrostatic { density, reference })
    }

    /// The carrier's density `ρ_f`.
    pub(crate) fn density(&self) -> f64 {
        self.density
    }

    /// Whether the component along axis `c` is split.
    pub(crate) fn splits(&self, c: usize) -> bool {
        self.reference[c].is_some()
    }

    /// Gravity in the grid's frame of `state`, `g − a`, with `g` the scene's (three components).
    pub(crate) fn effective(g: [f64; 3], state: &State) -> [f64; 3] {
        let a = [state.frame_acceleration.0, state.frame_acceleration.1, 0.0];
        std::array::from_fn(|c| g[c] - a[c])
    }

    /// `p ← p + sign·p_h` on every cell (`e` gravity in the grid's frame), the ghosts then
    /// filled as the pressure's (`p = 0` on Outflow faces, where `p_h` is zero).
    pub(crate) fn add(&self, grid: &Grid, bc: &BoundarySet, e: [f64; 3], p: &mut Field, sign: f64) {
        // ρ_f e_c per axis that takes part (zero on the others), and x_ref.
        let k: [f64; 3] = std::array::from_fn(|c| {
            if self.splits(c) {
                sign * self.density * e[c]
            } else {
                0.0
            }
        });
        let r = self.reference.map(|r| r.unwrap_or(0.0));
        Region::of(grid, Stagger::Cell).for_each(&mut *p, |line, row| {
            let [_, j, kz] = line.start;
            let y = k[1] * (grid.yc(j) - r[1]);
            let z = if grid.is_3d() {
                k[2] * (grid.zc(kz) - r[2])
            } else {
                0.0
            };
            for (t, p) in row.iter_mut().enumerate() {
                let i = line.start[0] + t as isize;
                *p += k[0] * (grid.xc(i) - r[0]) + y + z;
            }
        });
        bc.fill_scalar(grid, p, true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::scene::{Boundaries, Boundary};

    fn sides(x: [Boundary; 2], y: [Boundary; 2]) -> Boundaries {
        let [x0, x1] = x;
        let [y0, y1] = y;
        Boundaries::planar(x0, x1, y0, y1)
    }

    #[test]
    fn axes_take_part_unless_periodic_or_along_an_outflow_side() {
        use Boundary::{NoSlip, Outflow, Periodic};
        let g = Grid::new(efsi_core::Geometry::Planar, 4, 8, (0.0, 1.0), (-1.0, 1.0));
        let of = |b: Boundaries| Hydrostatic::for_sides(2.0, &g, &BoundarySet::new(&b, &g));
        let closed = of(sides([NoSlip, NoSlip], [NoSlip, NoSlip])).unwrap();
        assert_eq!(closed.reference, [Some(0.5), Some(0.0), None]);
        let top = of(sides([NoSlip, NoSlip], [NoSlip, Outflow])).unwrap();
        assert_eq!(top.reference, [None, Some(1.0), None]);
        let bottom = of(sides([NoSlip, NoSlip], [Outflow, NoSlip])).unwrap();
        assert_eq!(bottom.reference, [None, Some(-1.0), None]);
        let channel = of(sides([Periodic, Periodic], [NoSlip, NoSlip])).unwrap();
        assert_eq!(channel.reference, [None, Some(0.0), None]);
        // Outflow sides on both ends of y, or an Outflow side along y with x periodic.
        assert_eq!(of(sides([NoSlip, NoSlip], [Outflow, Outflow])), None);
        assert_eq!(of(sides([Periodic, Periodic], [Periodic, Periodic])), None);
        let side = of(sides([NoSlip, Outflow], [NoSlip, NoSlip])).unwrap();
        assert_eq!(side.reference, [Some(1.0), None, None]);
    }

    #[test]
    fn the_pressure_is_linear_and_zero_on_the_outflow_side() {
        use Boundary::{NoSlip, Outflow};
        let g = Grid::new(efsi_core::Geometry::Planar, 4, 8, (0.0, 1.0), (-1.0, 1.0));
        let bc = BoundarySet::new(&sides([NoSlip, NoSlip], [NoSlip, Outflow]), &g);
        let h = Hydrostatic::for_sides(2.0, &g, &bc).unwrap();
        let mut p = Field::zeros(&g);
        h.add(&g, &bc, [3.0, -1.5, 0.0], &mut p, 1.0);
        for j in 0..8 {
            for i in 0..4 {
                // x does not take part; ρ_f e_y (y − 1).
                let want = 2.0 * -1.5 * (g.yc(j) - 1.0);
                assert!(
                    (p[(i, j)] - want).abs() < 1e-15,
                    "({i}, {j}): {}",
                    p[(i, j)]
                );
            }
        }
        // The ghost above the outflow side: p = 0 on the boundary face.
        assert!((p[(0, 8)] + p[(0, 7)]).abs() < 1e-15);
        h.add(&g, &bc, [3.0, -1.5, 0.0], &mut p, -1.0);
        assert!(p.data().iter().all(|&x| x == 0.0));
    }
}
