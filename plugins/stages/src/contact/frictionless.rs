//! The contact's frictionless projection: each pair's force along the contact normal, acting at
//! the contact point (see the module docs of [`super`], "Frictionless").
//!
//! The face forces of a pair are summed per body into a [`PairLoad`] (net force, moment about
//! the body's centroid, and the `|f|`-weighted position of the pushed faces). The pair's
//! contact normal comes from the two bodies' own interface normals over the contact patch,
//! [`patch_normal`]; the difference between the pair's loads and their normal, contact-point
//! form is then put back on each body as a rigid load ([`Rigid::load`]): a uniform acceleration
//! plus an angular one about the centroid, of the body's material, sized on the faces so that
//! the applied net force and moment are exact.

use efsi_core::Grid;
use efsi_core::body_fractions::BodyFraction;

/// `a × b`.
pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The centre of grid cell `c` (`z = 0` on a planar or axisymmetric grid).
pub(super) fn centre(grid: &Grid, c: [isize; 3]) -> [f64; 3] {
    [
        grid.xc(c[0]),
        grid.yc(c[1]),
        if grid.is_3d() { grid.zc(c[2]) } else { 0.0 },
    ]
}

/// The centre of the face normal to axis `a` on the low side of cell `c`.
pub(super) fn face_centre(grid: &Grid, a: usize, c: [isize; 3]) -> [f64; 3] {
    let mut x = centre(grid, c);
    x[a] -= 0.5 * grid.h()[a];
    x
}

/// The centre of the face normal to axis `a` on the low side of cell `c`, from the point `x`
/// (a body's centroid): the arm of the face's force.
pub(super) fn arm(grid: &Grid, a: usize, c: [isize; 3], x: [f64; 3]) -> [f64; 3] {
    sub(face_centre(grid, a, c), x)
}

/// What the faces of one body received from one other body's halo.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PairLoad {
    /// The body pushed.
    pub k: usize,
    /// The body whose halo pushes.
    pub l: usize,
    /// `Σ f V` over the faces.
    pub force: [f64; 3],
    /// `Σ (x − x_k) × f V`, about the body's centroid `x_k`.
    pub moment: [f64; 3],
    /// `Σ |f| V`.
    pub weight: f64,
    /// `Σ |f| V (x − x_k)`.
    pub at: [f64; 3],
}

impl PairLoad {
    /// The force `f` along axis `a` on the face at `r` from the centroid, of volume `v`.
    pub fn add(&mut self, r: [f64; 3], a: usize, f: f64, v: f64) {
        let mut fv = [0.0; 3];
        fv[a] = f * v;
        self.force[a] += fv[a];
        self.moment = add(self.moment, cross(r, fv));
        self.weight += fv[a].abs();
        self.at = add(self.at, scale(r, fv[a].abs()));
    }
}

/// The unit interface normal of `φ` at cell `c`, pointing into the body: the VOF stage's Youngs
/// normal ([`crate::vof::plic::youngs_normal`], [`crate::vof::plic3d::youngs_normal`]) of the
/// 3×3(×3) block around `c`, `phi` giving the fraction at a grid cell and `h` the cells' sides.
/// `None` for a block without gradient (which has no normal).
fn interface_normal(
    phi: &impl Fn([isize; 3]) -> f64,
    c: [isize; 3],
    h: [f64; 3],
    dims: usize,
) -> Option<[f64; 3]> {
    let at = |a: isize, b: isize, z: isize| phi([c[0] + a - 1, c[1] + b - 1, c[2] + z - 1]);
    let out = if dims == 3 {
        let block: crate::vof::plic3d::Block = std::array::from_fn(|z| {
            std::array::from_fn(|b| std::array::from_fn(|a| at(a as isize, b as isize, z as isize)))
        });
        let flat = block.iter().flatten().flatten();
        if flat.clone().all(|&v| v == block[0][0][0]) {
            return None;
        }
        crate::vof::plic3d::youngs_normal(&block, h)
    } else {
        let block: [[f64; 3]; 3] =
            std::array::from_fn(|b| std::array::from_fn(|a| at(a as isize, b as isize, 1)));
        if block.iter().flatten().all(|&v| v == block[0][0]) {
            return None;
        }
        let (nx, ny) = crate::vof::plic::youngs_normal(&block, h[0], h[1]);
        [nx, ny, 0.0]
    };
    let norm = dot(out, out).sqrt();
    (norm > 0.0).then(|| scale(out, -1.0 / norm))
}

/// The contact normal of bodies `k` (fractions `bk`) and `l` (`bl`), pointing from `k` to `l`:
/// the mean of their unit interface normals (Youngs) over the patch where each body's material
/// lies in the other's halo, weighted by `φ_k ψ_l` (and `φ_l ψ_k`). `None` where there is no
/// patch. `halo_l`/`halo_k` give a halo at a grid cell, `wrap` wraps a cell along the periodic
/// axes; `h` is the cells' sides.
pub(super) fn patch_normal(
    (bk, bl): (&BodyFraction, &BodyFraction),
    halo_k: impl Fn([isize; 3]) -> f64,
    halo_l: impl Fn([isize; 3]) -> f64,
    wrap: impl Fn([isize; 3]) -> [isize; 3],
    h: [f64; 3],
    dims: usize,
) -> Option<[f64; 3]> {
    let mut n = [0.0; 3];
    for (b, halo, sign) in [(bk, &halo_l as &dyn Fn(_) -> f64, -1.0), (bl, &halo_k, 1.0)] {
        let phi = |c: [isize; 3]| b.at(wrap(c));
        for (c, f) in b.cells() {
            if f == 0.0 {
                continue;
            }
            let psi = halo(wrap(c));
            if psi == 0.0 {
                continue;
            }
            // Into the body: out of k (−) and into l (+) both point from k to l.
            if let Some(m) = interface_normal(&phi, c, h, dims) {
                n = add(n, scale(m, sign * f * psi));
            }
        }
    }
    let norm = dot(n, n).sqrt();
    (norm > 0.0).then(|| scale(n, 1.0 / norm))
}

/// One pair's contact in its normal, contact-point form (from [`to_normal`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Contact {
    /// The contact point from body `k`'s centroid, and from `l`'s (each in its own frame).
    pub r: [[f64; 3]; 2],
    /// The normal force on `k` and on `l`.
    pub force: [[f64; 3]; 2],
    /// The changes of net force on `k` and on `l` that the projection makes.
    pub change: [[f64; 3]; 2],
    /// The changes of moment about each body's centroid.
    pub moment_change: [[f64; 3]; 2],
}

/// The normal, contact-point form of one pair's loads: `on_k` (body `k`'s load from `l`'s
/// halo) and `on_l` made to act along the normal `n` at one contact point, the centre of both
/// bodies' pushed faces weighted by `|f|`. `None` where neither body is pushed. `image` takes a
/// displacement from `k`'s frame to the nearest image (periodic axes).
pub(super) fn to_normal(
    on_k: &PairLoad,
    on_l: &PairLoad,
    centroids: (&[f64; 3], &[f64; 3]),
    n: [f64; 3],
    image: impl Fn([f64; 3]) -> [f64; 3],
) -> Option<Contact> {
    let (xk, xl) = centroids;
    // l's frame onto k's: l's nearest image beside k (periodic axes).
    let shift = sub(add(*xk, image(sub(*xl, *xk))), *xl);
    let w = on_k.weight + on_l.weight;
    if w == 0.0 {
        return None;
    }
    let c_in_k = scale(
        add(
            add(scale(*xk, on_k.weight), on_k.at),
            add(scale(add(*xl, shift), on_l.weight), on_l.at),
        ),
        1.0 / w,
    );
    let r = [sub(c_in_k, *xk), sub(sub(c_in_k, shift), *xl)];
    let force = [on_k, on_l].map(|p| scale(n, dot(p.force, n)));
    Some(Contact {
        r,
        force,
        change: [sub(force[0], on_k.force), sub(force[1], on_l.force)],
        moment_change: [
            sub(cross(r[0], force[0]), on_k.moment),
            sub(cross(r[1], force[1]), on_l.moment),
        ],
    })
}

/// The friction force on body `k` of a pair in contact (`−` it on `l`): Coulomb's, at most
/// `μ |F_n|`, against the bodies' relative sliding at the contact point, and never more than
/// the force that stops the sliding within the step `dt` (the bodies then stick). `bodies`
/// gives each body's rigid modes and rigid motion; `n` is the contact normal.
pub(super) fn friction(
    contact: &Contact,
    n: [f64; 3],
    mu: f64,
    dt: f64,
    bodies: [(&Rigid, &Motion); 2],
) -> Option<[f64; 3]> {
    let [(rk, mk), (rl, ml)] = bodies;
    let [ck, cl] = contact.r;
    let slide = sub(ml.vector(cl), mk.vector(ck));
    let slide = sub(slide, scale(n, dot(slide, n)));
    let speed = dot(slide, slide).sqrt();
    let normal = dot(contact.force[0], contact.force[0]).sqrt();
    if speed == 0.0 || normal == 0.0 || mu == 0.0 {
        return None;
    }
    let t = scale(slide, 1.0 / speed);
    // How fast a unit force along t on k (and −t on l) at the contact point changes the sliding.
    let on_k = rk.load(t, cross(ck, t))?.vector(ck);
    let on_l = rl
        .load(scale(t, -1.0), cross(cl, scale(t, -1.0)))?
        .vector(cl);
    let compliance = dot(sub(on_k, on_l), t);
    if compliance <= 0.0 {
        return None;
    }
    Some(scale(t, (mu * normal).min(speed / (dt * compliance))))
}

/// One body's rigid modes on its faces: the `dims` translations, then the rotations about the
/// centroid (about z only in two dimensions), and their Gram matrix over the faces weighted by
/// `ρ_k φ̄_k V` (each face carrying its own axis' component). The same matrix maps a rigid
/// load's `(a, α)` to its net force and moment, and a rigid motion's `(v, ω)` to its momentum
/// and angular momentum.
pub(super) struct Rigid {
    /// The Gram matrix (the first `modes` rows and columns).
    g: [[f64; 6]; 6],
    dims: usize,
}

/// A rigid field `a + α × r` (an acceleration, a velocity) in the modes of [`Rigid`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Motion {
    s: [f64; 6],
    dims: usize,
}

/// The number of rigid modes: the `dims` translations, then the rotations.
fn modes(dims: usize) -> usize {
    if dims == 3 { 6 } else { 3 }
}

/// Mode `m`'s field at `r` from the centroid.
fn mode(m: usize, r: [f64; 3], dims: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    if m < dims {
        e[m] = 1.0;
        e
    } else {
        e[if dims == 3 { m - 3 } else { 2 }] = 1.0;
        cross(e, r)
    }
}

/// A force and moment as the modes' right-hand side: the forces along the `dims` axes, then
/// the moments (about z only in two dimensions).
fn load(dims: usize, force: [f64; 3], moment: [f64; 3]) -> [f64; 6] {
    let mut e = [0.0; 6];
    e[..dims].copy_from_slice(&force[..dims]);
    if dims == 3 {
        e[3..6].copy_from_slice(&moment);
    } else {
        e[2] = moment[2];
    }
    e
}

impl Rigid {
    /// The modes on the faces `faces` (`(axis, r from the centroid, ρ_k φ̄_k V)` each).
    pub fn new(faces: impl Iterator<Item = (usize, [f64; 3], f64)>, dims: usize) -> Self {
        let n = modes(dims);
        let mut g = [[0.0; 6]; 6];
        for (axis, r, w) in faces {
            let m: [f64; 6] =
                std::array::from_fn(|i| if i < n { mode(i, r, dims)[axis] } else { 0.0 });
            for i in 0..n {
                if m[i] != 0.0 {
                    for j in 0..n {
                        g[i][j] += w * m[i] * m[j];
                    }
                }
            }
        }
        Rigid { g, dims }
    }

    /// `G s = rhs` by Gaussian elimination with partial pivoting; `None` where a pivot falls
    /// below 1e-12 of the diagonal's largest (a mode the faces cannot carry: a body too small
    /// to turn).
    fn solve(&self, rhs: [f64; 6]) -> Option<Motion> {
        let n = modes(self.dims);
        let mut a = [[0.0; 7]; 6];
        for i in 0..n {
            a[i][..n].copy_from_slice(&self.g[i][..n]);
            a[i][6] = rhs[i];
        }
        let big = (0..n).map(|i| a[i][i].abs()).fold(0.0, f64::max);
        if big == 0.0 {
            return None;
        }
        for col in 0..n {
            let p = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
            if a[p][col].abs() <= 1e-12 * big {
                return None;
            }
            a.swap(col, p);
            for row in col + 1..n {
                let q = a[row][col] / a[col][col];
                for j in col..7 {
                    a[row][j] -= q * a[col][j];
                }
            }
        }
        let mut s = [0.0; 6];
        for i in (0..n).rev() {
            let rest: f64 = (i + 1..n).map(|j| a[i][j] * s[j]).sum();
            s[i] = (a[i][6] - rest) / a[i][i];
        }
        Some(Motion { s, dims: self.dims })
    }

    /// The rigid load (an acceleration of the body's material) whose net force is `force` and
    /// moment about the centroid `moment`, summed on the faces.
    pub fn load(&self, force: [f64; 3], moment: [f64; 3]) -> Option<Motion> {
        self.solve(load(self.dims, force, moment))
    }

    /// The rigid motion of the body: the least-squares fit of `v + ω × r` to its faces'
    /// velocities, `faces` giving `(axis, r, ρ_k φ̄_k V, u_axis)` (the same faces as
    /// [`Rigid::new`]'s).
    pub fn motion(
        &self,
        faces: impl Iterator<Item = (usize, [f64; 3], f64, f64)>,
    ) -> Option<Motion> {
        let n = modes(self.dims);
        let mut b = [0.0; 6];
        for (axis, r, w, u) in faces {
            for (m, bm) in b.iter_mut().enumerate().take(n) {
                *bm += w * u * mode(m, r, self.dims)[axis];
            }
        }
        self.solve(b)
    }
}

impl Motion {
    /// The field along `axis` at `r` from the centroid.
    pub fn at(&self, axis: usize, r: [f64; 3]) -> f64 {
        (0..modes(self.dims))
            .map(|m| self.s[m] * mode(m, r, self.dims)[axis])
            .sum()
    }

    /// The field at `r` from the centroid.
    pub fn vector(&self, r: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| if a < self.dims { self.at(a, r) } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rigid load sized on a ring of faces gives back the asked force and moment.
    #[test]
    fn a_rigid_load_carries_the_asked_force_and_moment() {
        for dims in [2, 3] {
            let faces: Vec<(usize, [f64; 3], f64)> = (0..200)
                .map(|i| {
                    let t = i as f64 * 0.37;
                    let z = if dims == 3 { (t * 1.7).sin() } else { 0.0 };
                    (
                        i % dims,
                        [t.cos() * 2.0, t.sin() * 1.5, z],
                        1.0 + 0.3 * t.sin(),
                    )
                })
                .collect();
            let force = [0.3, -0.2, if dims == 3 { 0.1 } else { 0.0 }];
            let moment = if dims == 3 {
                [0.05, -0.4, 0.7]
            } else {
                [0.0, 0.0, 0.7]
            };
            let load = Rigid::new(faces.iter().copied(), dims)
                .load(force, moment)
                .unwrap();
            let (mut f, mut m) = ([0.0; 3], [0.0; 3]);
            for &(a, r, w) in &faces {
                let mut fv = [0.0; 3];
                fv[a] = load.at(a, r) * w;
                f = add(f, fv);
                m = add(m, cross(r, fv));
            }
            for i in 0..3 {
                assert!((f[i] - force[i]).abs() < 1e-12, "{dims}-D force {i}: {f:?}");
                assert!(
                    (m[i] - moment[i]).abs() < 1e-12,
                    "{dims}-D moment {i}: {m:?}"
                );
            }
        }
    }

    /// A single face cannot carry a moment: no load.
    #[test]
    fn a_body_too_small_to_turn_gets_no_load() {
        let faces = [(0usize, [0.0; 3], 1.0), (1, [0.0; 3], 1.0)];
        assert!(
            Rigid::new(faces.iter().copied(), 2)
                .load([1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
                .is_none()
        );
    }
}
