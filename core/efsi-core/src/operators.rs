//! The MAC grid's discrete operators, named after the mathematics and written once for any
//! number of axes: a kernel calls them on a [`Line`] of a [`Region`](crate::Region) and gets
//! the values on the line's indices, exactly the line's length.
//!
//! With `e_a` the unit shift along axis `a`, `h_a` the cell size along it, and the
//! axisymmetric radius factors `r_f` (at x-faces) and `r_c` (at cell centres) of
//! [`crate::grid`] (all ones in planar and three-dimensional Cartesian geometry):
//!
//! | operator        | location of the result | value at `I`                                                        |
//! |-----------------|------------------------|---------------------------------------------------------------------|
//! | [`div`]         | cell centre            | `(r_f u₀[I+e₀] − r_f u₀[I])/(r_c h₀) + Σ_{a≥1} (u_a[I+e_a] − u_a[I])/h_a` |
//! | [`grad`]        | `a`-face               | `(p[I] − p[I−e_a])/h_a`                                             |
//! | [`lap`]         | cell centre            | `(r_f(i+1)(p[I+e₀]−p[I]) − r_f(i)(p[I]−p[I−e₀]))/(r_c h₀²) + Σ_{a≥1} (p[I+e_a] − 2p[I] + p[I−e_a])/h_a²` |
//! | [`face_avg`]    | `a`-face (from centres)| `½(p[I−e_a] + p[I])`                                                |
//! | [`centre_avg`]  | cell centre (from `a`-faces) | `½(u[I] + u[I+e_a])`                                          |
//!
//! `lap = div ∘ grad` on the interior: the finite-volume Laplacian, second-order accurate and
//! exact for polynomials of degree two in Cartesian geometry (the tests check it to round-off
//! in three dimensions). The axes summed are the grid's ([`Grid::dims`]): two on a
//! two-dimensional grid, three on a three-dimensional one, so a kernel written with them needs
//! no change when the grid gets its third axis.

use crate::field::Field;
use crate::grid::Grid;
use crate::loops::{Line, unit};

/// `∇·u` at the cell centres of `line` into `out`: `vel` holds one face-normal velocity per
/// axis of the grid (u on x-faces, v on y-faces, and w on z-faces in three dimensions).
pub fn div(grid: &Grid, vel: &[&Field], line: &Line, out: &mut [f64]) {
    assert_eq!(vel.len(), grid.dims(), "one velocity component per axis");
    let m = &grid.metric;
    let (rw, re, rc) = (m.rx_on(line, 0), m.rx_on(line, 1), m.rc_on(line, 0));
    let (uw, ue) = (vel[0].at(line, [0; 3]), vel[0].at(line, unit(0)));
    let (vs, vn) = (vel[1].at(line, [0; 3]), vel[1].at(line, unit(1)));
    let (dx, dy) = (grid.dx, grid.dy);
    let out = &mut out[..line.len];
    for (n, o) in out.iter_mut().enumerate() {
        *o = (re[n] * ue[n] - rw[n] * uw[n]) / (rc[n] * dx) + (vn[n] - vs[n]) / dy;
    }
    if let Some(w) = vel.get(2) {
        let (wb, wt) = (w.at(line, [0; 3]), w.at(line, unit(2)));
        for (n, o) in out.iter_mut().enumerate() {
            *o += (wt[n] - wb[n]) / grid.dz;
        }
    }
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
pub const fn minus(a: usize) -> crate::loops::Index {
    let mut s = [0; 3];
    s[a] = -1;
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Stagger;
    use crate::grid::Geometry;
    use crate::loops::Region;

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
