//! The MAC grid's discrete operators, named after the mathematics and written once for any
//! number of axes: a kernel calls them on a [`Line`] of a [`Region`] and gets the values on the
//! line's indices, exactly the line's length; the integrals and norms over the grid are folds of
//! the same stencils over its cells.
//!
//! With `e_a` the unit shift along axis `a`, `h_a` the cell size along it, and the
//! axisymmetric radius factors `r_f` (at x-faces) and `r_c` (at cell centres) of
//! [`crate::grid`] (all ones in planar and three-dimensional Cartesian geometry):
//!
//! | operator        | location of the result | value at `I`                                                        |
//! |-----------------|------------------------|---------------------------------------------------------------------|
//! | [`div`]         | cell centre            | `(r_f u₀[I+e₀] − r_f u₀[I])/(r_c h₀) + Σ_{a≥1} (u_a[I+e_a] − u_a[I])/h_a` |
//! | [`net_outflux`] | cell centre            | `∮ u·n dA = (r_f u₀[I+e₀] − r_f u₀[I]) A₀ + Σ_{a≥1} r_c (u_a[I+e_a] − u_a[I]) A_a`, `A_a = Π_{b≠a} h_b` |
//! | [`grad`]        | `a`-face               | `(p[I] − p[I−e_a])/h_a`                                             |
//! | [`lap`]         | cell centre            | `(r_f(i+1)(p[I+e₀]−p[I]) − r_f(i)(p[I]−p[I−e₀]))/(r_c h₀²) + Σ_{a≥1} (p[I+e_a] − 2p[I] + p[I−e_a])/h_a²` |
//! | [`face_avg`]    | `a`-face (from centres)| `½(p[I−e_a] + p[I])`                                                |
//! | [`centre_avg`]  | cell centre (from `a`-faces) | `½(u[I] + u[I+e_a])`                                          |
//! | [`face_density`]| face (from two cells)  | `½(ρ_lo + ρ_hi)`                                                    |
//!
//! and over the grid's cells: [`max_abs_div`] `max |∇·u|`, [`kinetic_energy`] `½∫ρ|u|² dV` and
//! [`potential_energy`] `−∫ρ g·x dV`. `net_outflux` is `vol·∇·u` in flux form (per radian when
//! axisymmetric, per unit depth when planar: `h₂ = dz = 1` on a two-dimensional grid), for
//! kernels that balance volumes cell by cell; it takes one index.
//!
//! `lap = div ∘ grad` on the interior: the finite-volume Laplacian, second-order accurate and
//! exact for polynomials of degree two in Cartesian geometry (the tests check it to round-off
//! in three dimensions). The axes summed are the grid's ([`Grid::dims`]): two on a
//! two-dimensional grid, three on a three-dimensional one, so a kernel written with them needs
//! no change when the grid gets its third axis. A velocity is passed as one face-normal
//! component per axis, `&[u, v]` or `&[u, v, w]` ([`crate::State::velocity`]).
//!
//! The integrals sum each line's cells in order and the lines in line order
//! ([`Region::sum`]), the maxima are maxima: the same bits on any number of threads. On a
//! two-dimensional grid each operator is the planar/axisymmetric expression term for term (the
//! third axis adds a term, it does not regroup the others), so planar and axisymmetric results
//! do not depend on the third axis existing.

use crate::field::{Field, Stagger};
use crate::grid::Grid;
use crate::loops::{Index, Line, Region, unit};

/// The density on the face between two cells of densities `a` and `b`: their arithmetic mean.
/// The one face-density rule of every stage: the mass of a momentum control volume (advection,
/// viscous and elastic steps) and `1/ρ_f` in the pressure equation and its correction — the
/// density stays inside the divergence, smooth across an interface (seed Eqs. 21–23).
#[inline(always)]
pub fn face_density(a: f64, b: f64) -> f64 {
    0.5 * (a + b)
}

/// `∇·u` at the cell centres of `line` into `out`: `vel` holds one face-normal velocity per
/// axis of the grid (u on x-faces, v on y-faces, and w on z-faces in three dimensions).
pub fn div(grid: &Grid, vel: &[&Field], line: &Line, out: &mut [f64]) {
    let out = &mut out[..line.len];
    each_div(grid, vel, line, |n, d| out[n] = d);
}

/// `∇·u` at each cell centre of `line`, handed to `f(n, value)` in order along the line: the
/// one loop of [`div`] and [`max_abs_div`].
#[inline(always)]
fn each_div(grid: &Grid, vel: &[&Field], line: &Line, mut f: impl FnMut(usize, f64)) {
    assert_eq!(vel.len(), grid.dims(), "one velocity component per axis");
    let m = &grid.metric;
    let (rw, re, rc) = (m.rx_on(line, 0), m.rx_on(line, 1), m.rc_on(line, 0));
    let (uw, ue) = (vel[0].at(line, [0; 3]), vel[0].at(line, unit(0)));
    let (vs, vn) = (vel[1].at(line, [0; 3]), vel[1].at(line, unit(1)));
    let w = vel
        .get(2)
        .map(|w| (w.at(line, [0; 3]), w.at(line, unit(2))));
    let [dx, dy, dz] = grid.h();
    for n in 0..line.len {
        let d = (re[n] * ue[n] - rw[n] * uw[n]) / (rc[n] * dx) + (vn[n] - vs[n]) / dy;
        f(n, w.map_or(d, |(wb, wt)| d + (wt[n] - wb[n]) / dz));
    }
}

/// `max |∇·u|` over the cells ([`div`]; `vel` one component per axis).
pub fn max_abs_div(grid: &Grid, vel: &[&Field]) -> f64 {
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        let mut m = 0.0f64;
        each_div(grid, vel, &l, |_, d| m = m.max(d.abs()));
        m
    })
}

/// The net volume flux `∮ u·n dA` out of the cell `c` (the module's table; `vel` one component
/// per axis): `vol·∇·u` in flux form, per radian when axisymmetric.
#[inline]
pub fn net_outflux(grid: &Grid, vel: &[&Field], c: Index) -> f64 {
    let m = &grid.metric;
    let [dx, dy, dz] = grid.h();
    let up = |a: usize| {
        let e = unit(a);
        [c[0] + e[0], c[1] + e[1], c[2] + e[2]]
    };
    let (u, v, i) = (vel[0], vel[1], c[0]);
    let out = (m.rx(i + 1) * u[up(0)] - m.rx(i) * u[c]) * (dy * dz)
        + m.rc(i) * (v[up(1)] - v[c]) * (dx * dz);
    vel.get(2)
        .map_or(out, |w| out + m.rc(i) * (w[up(2)] - w[c]) * (dx * dy))
}

/// Kinetic energy `½∫ρ|u|² dV` (per radian when axisymmetric, per unit depth when planar) of
/// the velocity `vel` (one component per axis) with the cell densities `rho`: face-centred
/// quadrature, half of each of a cell's faces belonging to it (`¼ρ(u_a[I]² + u_a[I+e_a]²)` per
/// axis, the x-faces weighted by `r_f`, the others by `r_c`).
pub fn kinetic_energy(grid: &Grid, vel: &[&Field], rho: &Field) -> f64 {
    let m = &grid.metric;
    let [dx, dy, dz] = grid.h();
    let [e] = Region::of(grid, Stagger::Cell).sum(|l| {
        let (rw, re, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
        let faces = |a: usize| (vel[a].at(&l, [0; 3]), vel[a].at(&l, unit(a)));
        let ((uw, ue), (vs, vn), w) = (faces(0), faces(1), vel.get(2).map(|_| faces(2)));
        let rho = rho.at(&l, [0; 3]);
        let mut e = 0.0;
        for n in 0..l.len {
            let mut k = 0.5 * (rw[n] * uw[n].powi(2) + re[n] * ue[n].powi(2)) / 2.0
                + 0.5 * rc[n] * (vs[n].powi(2) + vn[n].powi(2)) / 2.0;
            if let Some((wb, wt)) = w {
                k += 0.5 * rc[n] * (wb[n].powi(2) + wt[n].powi(2)) / 2.0;
            }
            e += rho[n] * k * dx * dy * dz;
        }
        [e]
    });
    e
}

/// Potential energy `−∫ρ g·x dV` of the cell densities `rho` in the gravity `g` (its first
/// [`Grid::dims`] components), `x` the cell centres (per radian when axisymmetric, per unit
/// depth when planar).
pub fn potential_energy(grid: &Grid, rho: &Field, g: [f64; 3]) -> f64 {
    let [e] = Region::of(grid, Stagger::Cell).sum(|l| {
        let rho = rho.at(&l, [0; 3]);
        let mut e = 0.0;
        for (n, [i, j, k]) in l.indices().enumerate() {
            let mut gdotx = g[0] * grid.xc(i) + g[1] * grid.yc(j);
            if grid.is_3d() {
                gdotx += g[2] * grid.zc(k);
            }
            e -= rho[n] * gdotx * (grid.cell_volume(i) * grid.dz);
        }
        [e]
    });
    e
}

/// `∂p/∂x_a` at the `a`-faces of `line` into `out`: `(p[I] − p[I−e_a])/h_a` for a
/// cell-centred `p`.
pub fn grad(grid: &Grid, p: &Field, a: usize, line: &Line, out: &mut [f64]) {
    let h = grid.h()[a];
    let (lo, hi) = (p.at(line, minus(a)), p.at(line, [0; 3]));
    for ((o, lo), hi) in out[..line.len].iter_mut().zip(lo).zip(hi) {
        *o = (hi - lo) / h;
    }
}

/// `∇·∇p` at the cell centres of `line` into `out` (the finite-volume Laplacian, with the
/// axisymmetric metric along x).
pub fn lap(grid: &Grid, p: &Field, line: &Line, out: &mut [f64]) {
    let m = &grid.metric;
    let (rw, re, rc) = (m.rx_on(line, 0), m.rx_on(line, 1), m.rc_on(line, 0));
    let c = p.at(line, [0; 3]);
    let (w, e) = (p.at(line, minus(0)), p.at(line, unit(0)));
    let dx2 = grid.dx * grid.dx;
    let out = &mut out[..line.len];
    for (n, o) in out.iter_mut().enumerate() {
        *o = (re[n] * (e[n] - c[n]) - rw[n] * (c[n] - w[n])) / (rc[n] * dx2);
    }
    for a in 1..grid.dims() {
        let (lo, hi, h) = (p.at(line, minus(a)), p.at(line, unit(a)), grid.h()[a]);
        for (n, o) in out.iter_mut().enumerate() {
            *o += (hi[n] - 2.0 * c[n] + lo[n]) / (h * h);
        }
    }
}

/// The average of the two cells beside each `a`-face of `line`: `½(p[I−e_a] + p[I])`.
pub fn face_avg(p: &Field, a: usize, line: &Line, out: &mut [f64]) {
    let (lo, hi) = (p.at(line, minus(a)), p.at(line, [0; 3]));
    for ((o, lo), hi) in out[..line.len].iter_mut().zip(lo).zip(hi) {
        *o = 0.5 * (lo + hi);
    }
}

/// The average of the two `a`-faces of each cell of `line`: `½(u[I] + u[I+e_a])`.
pub fn centre_avg(u: &Field, a: usize, line: &Line, out: &mut [f64]) {
    let (lo, hi) = (u.at(line, [0; 3]), u.at(line, unit(a)));
    for ((o, lo), hi) in out[..line.len].iter_mut().zip(lo).zip(hi) {
        *o = 0.5 * (lo + hi);
    }
}

/// A shift by −1 along axis `a`.
#[inline(always)]
pub const fn minus(a: usize) -> Index {
    let mut s = [0; 3];
    s[a] = -1;
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Geometry;

    /// `f` sampled at location `at` of `g` (the location's coordinates per axis), ghosts
    /// included.
    fn sample(g: &Grid, at: Stagger, f: impl Fn([f64; 3]) -> f64) -> Field {
        let mut p = Field::zeros(g);
        let o = at.nodal();
        for n in 0..p.data().len() {
            let [i, j, k] = p.index_of(n);
            let x = [
                if o[0] == 1 { g.xf(i) } else { g.xc(i) },
                if o[1] == 1 { g.yf(j) } else { g.yc(j) },
                if o[2] == 1 { g.zf(k) } else { g.zc(k) },
            ];
            p.data_mut()[n] = f(x);
        }
        p
    }

    /// Largest `|op(line) − want(x)|` over region `r` at location `at`.
    fn worst(
        g: &Grid,
        r: Region,
        at: Stagger,
        op: impl Fn(&Line, &mut [f64]) + Sync + Send,
        want: impl Fn([f64; 3]) -> f64 + Sync + Send,
    ) -> f64 {
        let want = sample(g, at, want);
        r.max(0.0, |l| {
            let mut out = vec![0.0; l.len];
            op(&l, &mut out);
            let w = want.at(&l, [0; 3]);
            out.iter()
                .zip(w)
                .fold(0.0, |m, (o, w)| m.max((o - w).abs()))
        })
    }

    #[test]
    fn three_dimensional_div_grad_lap_are_exact_for_quadratics() {
        let g = Grid::new_3d([7, 6, 5], (0.0, 1.4), (-0.5, 0.7), (0.2, 1.2));
        // p = 3x² − 2y² + z² + xy − 4yz + 5x − z + 2: ∇²p = 6 − 4 + 2 = 4.
        let p = |[x, y, z]: [f64; 3]| {
            3.0 * x * x - 2.0 * y * y + z * z + x * y - 4.0 * y * z + 5.0 * x - z + 2.0
        };
        let dp = [
            |[x, y, _]: [f64; 3]| 6.0 * x + y + 5.0,
            |[x, y, z]: [f64; 3]| -4.0 * y + x - 4.0 * z,
            |[_, y, z]: [f64; 3]| 2.0 * z - 4.0 * y - 1.0,
        ];
        let pc = sample(&g, Stagger::Cell, p);
        let faces = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
        for a in 0..3 {
            let e = worst(
                &g,
                Region::of(&g, faces[a]),
                faces[a],
                |l, o| grad(&g, &pc, a, l, o),
                dp[a],
            );
            assert!(e < 1e-12, "∂p/∂x_{a}: error {e:e}");
        }
        let cells = Region::of(&g, Stagger::Cell);
        let e = worst(&g, cells, Stagger::Cell, |l, o| lap(&g, &pc, l, o), |_| 4.0);
        assert!(e < 1e-11, "∇²p: error {e:e}");
        // u = (x², xy, yz²) on its faces: ∇·u = 2x + x + 2yz.
        let u = sample(&g, Stagger::XFace, |[x, _, _]| x * x);
        let v = sample(&g, Stagger::YFace, |[x, y, _]| x * y);
        let w = sample(&g, Stagger::ZFace, |[_, y, z]| y * z * z);
        let want = |[x, y, z]: [f64; 3]| 3.0 * x + 2.0 * y * z;
        let e = worst(
            &g,
            cells,
            Stagger::Cell,
            |l, o| div(&g, &[&u, &v, &w], l, o),
            want,
        );
        assert!(e < 1e-12, "∇·u: error {e:e}");
        // Averages of a linear function are exact: face ← centres and centre ← faces.
        let lin = |[x, y, z]: [f64; 3]| 2.0 * x - y + 3.0 * z;
        let wl = sample(&g, Stagger::ZFace, lin);
        let e = worst(
            &g,
            Region::of(&g, Stagger::ZFace),
            Stagger::ZFace,
            |l, o| face_avg(&sample(&g, Stagger::Cell, lin), 2, l, o),
            lin,
        );
        assert!(e < 1e-14, "centre → z-face: {e:e}");
        let e = worst(
            &g,
            cells,
            Stagger::Cell,
            |l, o| centre_avg(&wl, 2, l, o),
            lin,
        );
        assert!(e < 1e-14, "z-faces → centre: {e:e}");
    }

    #[test]
    fn three_dimensional_integrals_are_exact_for_uniform_and_linear_fields() {
        let g = Grid::new_3d([4, 3, 5], (0.0, 1.0), (0.0, 2.0), (0.0, 1.5));
        let rho = sample(&g, Stagger::Cell, |_| 2.0);
        let (u, v, w) = (
            sample(&g, Stagger::XFace, |_| 1.0),
            sample(&g, Stagger::YFace, |_| 2.0),
            sample(&g, Stagger::ZFace, |_| -3.0),
        );
        // ½ρ|U|²V = ½·2·14·3 and −∫ρ g·x dV = ρ·9.81·z̄·V = 2·9.81·0.75·3.
        let ke = kinetic_energy(&g, &[&u, &v, &w], &rho);
        assert!((ke - 42.0).abs() < 1e-12, "{ke}");
        let pe = potential_energy(&g, &rho, [0.0, 0.0, -9.81]);
        assert!((pe - 44.145).abs() < 1e-12, "{pe}");
        // u = (x, 0, z): ∇·u = 2 everywhere; the outfluxes sum to ∫∇·u dV = 2V.
        let u = sample(&g, Stagger::XFace, |[x, _, _]| x);
        let v = sample(&g, Stagger::YFace, |_| 0.0);
        let w = sample(&g, Stagger::ZFace, |[_, _, z]| z);
        let vel = [&u, &v, &w];
        assert!((max_abs_div(&g, &vel) - 2.0).abs() < 1e-13);
        let [net] = Region::of(&g, Stagger::Cell)
            .sum(|l| [l.indices().map(|c| net_outflux(&g, &vel, c)).sum()]);
        assert!((net - 6.0).abs() < 1e-12, "{net}");
    }

    #[test]
    fn axisymmetric_integrals_carry_the_radius() {
        // Per radian over r ∈ [0, 2], z ∈ [0, 1]: ½ρU²∫r dr dz = ½·3·4·2 for a uniform axial
        // velocity U = 2, and u_r = r (∇·u = 2) has the outflux 2∫r dr dz = 4.
        let g = Grid::new(Geometry::Axisymmetric, 8, 5, (0.0, 2.0), (0.0, 1.0));
        let rho = sample(&g, Stagger::Cell, |_| 3.0);
        let zero = sample(&g, Stagger::XFace, |_| 0.0);
        let v = sample(&g, Stagger::YFace, |_| 2.0);
        let ke = kinetic_energy(&g, &[&zero, &v], &rho);
        assert!((ke - 12.0).abs() < 1e-12, "{ke}");
        let u = sample(&g, Stagger::XFace, |[r, _, _]| r);
        let zero = sample(&g, Stagger::YFace, |_| 0.0);
        let [net] = Region::of(&g, Stagger::Cell)
            .sum(|l| [l.indices().map(|c| net_outflux(&g, &[&u, &zero], c)).sum()]);
        assert!((net - 4.0).abs() < 1e-12, "{net}");
        // −∫ρ g·x dV with g = (0, −1): ρ·z̄·∫r dr dz = 3·0.5·2.
        let pe = potential_energy(&g, &rho, [0.0, -1.0, 0.0]);
        assert!((pe - 3.0).abs() < 1e-12, "{pe}");
    }

    #[test]
    fn two_dimensional_axisymmetric_div_and_lap_are_exact_in_r_and_z() {
        // In (r, z): u_r = r gives ∇·u = (1/r)∂(r·r)/∂r = 2; p = r² + z² gives ∇²p = 4 + 2.
        let g = Grid::new(Geometry::Axisymmetric, 8, 5, (0.0, 2.0), (0.0, 1.0));
        let u = sample(&g, Stagger::XFace, |[r, _, _]| r);
        let v = sample(&g, Stagger::YFace, |_| 0.0);
        let cells = Region::of(&g, Stagger::Cell);
        let e = worst(
            &g,
            cells,
            Stagger::Cell,
            |l, o| div(&g, &[&u, &v], l, o),
            |_| 2.0,
        );
        assert!(e < 1e-13, "∇·u: {e:e}");
        let p = sample(&g, Stagger::Cell, |[r, z, _]| r * r + z * z);
        // The midpoint radius makes the finite-volume r-Laplacian of r² exact: 4.
        let e = worst(&g, cells, Stagger::Cell, |l, o| lap(&g, &p, l, o), |_| 6.0);
        assert!(e < 1e-12, "∇²p: {e:e}");
    }
}
