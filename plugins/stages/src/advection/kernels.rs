//! The momentum advection's kernels, written once for any number of axes over [`Region`] lines
//! and axis shifts ([`unit`]): the face masses, the face fluxes, their balance, and the SSP-RK2
//! step that combines them (the scheme is the parent module's).
//!
//! Component `c` of the velocity lives on the `c`-faces; its control volume `I` (centred on
//! the `c`-face `I`) has, along each axis `a`, a lower face shared with control volume
//! `I − e_a` and an upper one shared with `I + e_a`. Through the lower `a`-face flow
//!
//! - the mass flux `F_m = â · m̃` and the momentum flux `F_q = F_m · ũ_c`, with the advecting
//!   velocity `â = ½(u_a[I − e_c] + u_a[I])` (for `a = c` the cell centre between the faces
//!   `I − e_c` and `I`; for `a ≠ c` the edge between the two cells beside the face), and `m̃`,
//!   `ũ_c` the van Leer reconstructions of the face mass and of `u_c` from
//!   `[I − 2e_a, I − e_a, I, I + e_a]`, upwind by the sign of `â`;
//! - and the balance of control volume `I` is
//!   `L = −[(R⁺F[I + e₀] − R⁻F[I])/(h₀ r) + Σ_{a≥1} (F_a[I + e_a] − F_a[I])/h_a]`,
//!   with the axisymmetric radius factors at the two x-faces of the control volume `R⁻, R⁺`
//!   and at its centre `r` (`r_c(i−1), r_c(i), r_f(i)` for `c = 0`; `r_f(i), r_f(i+1), r_c(i)`
//!   otherwise; all ones in planar and three-dimensional geometry).
//!
//! Each face flux is computed once: along x (the lines' axis) into a buffer of the line, along
//! axis 1 into a buffer that the next line of the same band of lines reads as its lower flux
//! (the band's first line computes its lower flux itself, so the flux through a band's lower
//! edge is computed twice), along every further axis into a full-grid flux array ([`work`]
//! counts them), which the balance differences. The tendencies are compact: one value per
//! control volume, line after line. Every band writes only its own lines, and every flux is
//! the same function of the same values wherever it is computed, so the results are the same,
//! bit for bit, on any number of threads.

use efsi_core::operators::{face_density, minus};
use efsi_core::{Field, Grid, Index, Line, Region, Stagger, unit};
use efsi_linalg::par;
use std::ops::Range;

/// The location of velocity component `c` (the `c`-faces).
pub(crate) const FACES: [Stagger; 3] = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];

/// Full-grid work arrays of a step on a grid of `dims` axes: per component the momentum
/// tendency and the current stage's face masses (2); one mass tendency, which each component
/// uses in turn (its masses and momenta advance as soon as its own tendencies are known: no
/// other component reads its masses); and the mass and momentum fluxes along each axis beyond
/// the second, shared by the components (2 per axis): `4·dims − 3` (5 in two dimensions, 9 in
/// three). The start-of-step velocity is read from the caller's copy where it keeps one, else
/// copied into `dims` more arrays.
pub const fn work(dims: usize) -> usize {
    4 * dims - 3
}

/// A shift by `k` along axis `a`.
#[inline(always)]
fn along(a: usize, k: isize) -> Index {
    let mut s = [0; 3];
    s[a] = k;
    s
}

/// van Leer limited face value for advecting velocity `a` between `c0` (left/below) and `c1`,
/// with `cm` left of `c0` and `c2` right of `c1`.
#[inline(always)]
pub(crate) fn face_value(a: f64, cm: f64, c0: f64, c1: f64, c2: f64) -> f64 {
    let (up, c, d) = if a >= 0.0 { (cm, c0, c1) } else { (c2, c1, c0) };
    let denom = d - c;
    if denom.abs() < 1e-300 {
        return c;
    }
    let r = (c - up) / denom;
    let psi = (r + r.abs()) / (1.0 + r.abs());
    c + 0.5 * psi * denom
}

/// [`face_value`] in van Leer's harmonic form, one division instead of two and no branch on
/// the data: with `p = q_C − q_U` and `q = q_D − q_C`, `½ψ(p/q)·q = pq/(p + q)` where
/// `pq > 0`, else 0 — the same limiter, rounded differently.
#[inline(always)]
fn limited(a: f64, cm: f64, c0: f64, c1: f64, c2: f64) -> f64 {
    let pos = a >= 0.0;
    let up = if pos { cm } else { c2 };
    let c = if pos { c0 } else { c1 };
    let d = if pos { c1 } else { c0 };
    let (p, q) = (c - up, d - c);
    // The quotient is formed before the test (a select, not a branch, so the loops over faces
    // vectorise); where `pq ≤ 0` it is discarded.
    let pq = p * q;
    let ratio = pq / (p + q);
    c + if pq > 0.0 { ratio } else { 0.0 }
}

/// Flux `(a m̃, a m̃ q̃)` through a control-volume face with advecting velocity `a`, from the
/// masses `m` and values `q` of the four control volumes along the flux direction.
#[inline(always)]
fn flux(a: f64, m: [f64; 4], q: [f64; 4]) -> (f64, f64) {
    let fm = a * limited(a, m[0], m[1], m[2], m[3]);
    (fm, fm * limited(a, q[0], q[1], q[2], q[3]))
}

/// The face masses of component `c` (the densities of its control volumes) everywhere in the
/// padded storage: `ρ_f[I] = ½(ρ[I − e_c] + ρ[I])`, the lowest ghost layer along `c`
/// repeating the next one (its cell below is outside the storage). The ghost masses are not
/// advanced by the Euler stages (the boundary set fills velocities, not face masses), so
/// across a periodic side the mass and momentum fluxes match their images only where the
/// density is uniform and the mass does not change; inside the box every flux enters the two
/// control volumes it separates and the sums are conserved to round-off.
pub(crate) fn face_masses(grid: &Grid, rho: &Field, c: usize, m: &mut [f64]) {
    let whole = Region::whole(grid);
    let lowest = whole.lo()[c];
    whole.for_each(whole.storage(m), |l, m| {
        let m = &mut m[..l.len];
        if c == 0 {
            let r = &rho.at(&l, [0; 3])[..l.len];
            m[0] = face_density(r[0], r[1]);
            for n in 1..l.len {
                m[n] = face_density(r[n - 1], r[n]);
            }
        } else {
            let (below, here) = if l.start[c] == lowest {
                ([0; 3], unit(c))
            } else {
                (minus(c), [0; 3])
            };
            let (b, h) = (&rho.at(&l, below)[..l.len], &rho.at(&l, here)[..l.len]);
            for n in 0..l.len {
                m[n] = face_density(b[n], h[n]);
            }
        }
    });
}

/// What the fluxes through a run of `a`-faces read: the two values of the advecting velocity
/// around each face and the masses and values of the advected component at the four control
/// volumes along `a` ([`flux`]).
struct Stencil<'a> {
    adv: [&'a [f64]; 2],
    m: [&'a [f64]; 4],
    q: [&'a [f64]; 4],
}

/// Where a [`Stencil`] reads: each array with the storage offset of its shift from a line's
/// first index, the same for every line of a region (computed once per loop, so that a line's
/// stencil costs one bounds-checked slice per array, not the shifts' arithmetic).
struct Shape<'a> {
    adv: [(&'a [f64], isize); 2],
    m: [(&'a [f64], isize); 4],
    q: [(&'a [f64], isize); 4],
}

impl<'a> Shape<'a> {
    /// The stencil of component `c` (velocity `vel`, face masses `m`) through the lower
    /// `a`-faces of the control volumes `I + s·e_a`; `l` is a line of the region it serves
    /// (whose grid the arrays are checked against).
    #[inline(always)]
    fn new(l: &Line, [a, c, s]: [usize; 3], vel: &[&'a Field], m: &'a [f64]) -> Self {
        let (ua, uc) = (vel[a], vel[c]);
        // The layout checks of `Field::at` and `Line::on`, once for the loop.
        let _ = (ua.at(l, [0; 3]), uc.at(l, [0; 3]), l.on(m, [0; 3]));
        let up = along(a, s as isize);
        let mc = minus(c);
        let lo = [mc[0] + up[0], mc[1] + up[1], mc[2] + up[2]];
        let shift = |k: isize| uc.offset(along(a, k + s as isize));
        Shape {
            adv: [(ua.data(), ua.offset(lo)), (ua.data(), ua.offset(up))],
            m: [-2, -1, 0, 1].map(|k| (m, shift(k))),
            q: [-2, -1, 0, 1].map(|k| (uc.data(), shift(k))),
        }
    }

    /// The stencil on the columns `x` of line `l`.
    #[inline(always)]
    fn on(&self, l: &Line, x: Range<usize>) -> Stencil<'a> {
        let o = l.linear(0) as isize;
        let (m, q) = (&self.m, &self.q);
        Stencil {
            adv: [cols(self.adv[0], o, &x), cols(self.adv[1], o, &x)],
            m: [
                cols(m[0], o, &x),
                cols(m[1], o, &x),
                cols(m[2], o, &x),
                cols(m[3], o, &x),
            ],
            q: [
                cols(q[0], o, &x),
                cols(q[1], o, &x),
                cols(q[2], o, &x),
                cols(q[3], o, &x),
            ],
        }
    }
}

/// The columns `x` of the run at storage offset `o + off` of `data` (bounds-checked).
#[inline(always)]
fn cols<'a>((data, off): (&'a [f64], isize), o: isize, x: &Range<usize>) -> &'a [f64] {
    let k = usize::try_from(o + off).expect("a shift below the storage");
    &data[k + x.start..k + x.end]
}

impl<'a> Stencil<'a> {
    /// The mass and momentum fluxes `(fm, fq)` through the faces, one per entry of `fm`.
    #[inline(always)]
    fn fluxes(&self, fm: &mut [f64], fq: &mut [f64]) {
        let n = fm.len();
        let (fq, [a0, a1]) = (&mut fq[..n], [&self.adv[0][..n], &self.adv[1][..n]]);
        let ([m0, m1, m2, m3], [q0, q1, q2, q3]) = (self.m, self.q);
        let ms = [&m0[..n], &m1[..n], &m2[..n], &m3[..n]];
        let qs = [&q0[..n], &q1[..n], &q2[..n], &q3[..n]];
        for i in 0..n {
            (fm[i], fq[i]) = flux(
                0.5 * (a0[i] + a1[i]),
                [ms[0][i], ms[1][i], ms[2][i], ms[3][i]],
                [qs[0][i], qs[1][i], qs[2][i], qs[3][i]],
            );
        }
    }
}

/// The mass and momentum fluxes `(fm, fq)` of component `c` through the lower `a`-faces
/// (`a ≥ 2`) of the control volumes `cv` and the upper faces of its last layer along `a`.
fn face_fluxes(
    cv: Region,
    a: usize,
    c: usize,
    vel: &[&Field],
    m: &[f64],
    fm: &mut [f64],
    fq: &mut [f64],
) {
    let faces = cv.range(a, cv.lo()[a], cv.hi()[a] + 1);
    if faces.is_empty() {
        return;
    }
    let shape = Shape::new(&faces.line(0), [a, c, 0], vel, m);
    faces.for_each((faces.storage(fm), faces.storage(fq)), |l, (fm, fq)| {
        shape.on(&l, 0..l.len).fluxes(fm, fq);
    });
}

/// Control volumes per chunk of a line whose x- and axis-1 fluxes are kept on the stack.
const CHUNK: usize = 128;

/// Bands of lines per component: a band's lines run in order on one thread, so the flux
/// through the upper axis-1 face of one line is the lower one of the next.
const BANDS: usize = 8;

/// The balance of component `c` on its control volumes `cv` (module docs): what every band
/// reads.
struct Balance<'a> {
    cv: Region,
    c: usize,
    h: [f64; 3],
    vel: &'a [&'a Field],
    m: &'a [f64],
    /// The x-faces of the control volumes: one more column than `cv`.
    xs: Region,
    /// The radius factors at the lower and upper x-face and at the centre of each column's
    /// control volume (the same on every line).
    radii: [&'a [f64]; 3],
    /// The mass and momentum fluxes along the axes `2..` (full-grid arrays).
    further: &'a [(&'a [f64], &'a [f64])],
}

/// The momentum and mass tendencies `(qt, mt)` of component `c` on its control volumes `cv`
/// (module docs; compact, line after line), from the fluxes along the axes `2..` in `further`
/// (`(fm, fq)` per axis).
#[allow(clippy::too_many_arguments)]
fn balance<'a>(
    grid: &'a Grid,
    cv: Region,
    c: usize,
    vel: &'a [&'a Field],
    m: &'a [f64],
    further: &'a [(&'a [f64], &'a [f64])],
    qt: &mut [f64],
    mt: &mut [f64],
) {
    if cv.is_empty() {
        return;
    }
    let (metric, l) = (&grid.metric, cv.line(0));
    let radii = if c == 0 {
        [
            metric.rc_on(&l, -1),
            metric.rc_on(&l, 0),
            metric.rx_on(&l, 0),
        ]
    } else {
        [
            metric.rx_on(&l, 0),
            metric.rx_on(&l, 1),
            metric.rc_on(&l, 0),
        ]
    };
    let k = Balance {
        cv,
        c,
        h: grid.h(),
        vel,
        m,
        xs: cv.range(0, cv.lo()[0], cv.hi()[0] + 1),
        radii,
        further,
    };
    let len = cv.len(0);
    let band = cv.lines().div_ceil(BANDS) * len;
    let size = cv.size();
    par::rows((&mut qt[..size], &mut mt[..size]), band).for_each(|b, (qt, mt)| {
        let lines = b * band / len..(b * band + qt.len()) / len;
        for n0 in (0..len).step_by(CHUNK) {
            k.tile(lines.clone(), n0..len.min(n0 + CHUNK), qt, mt);
        }
        k.further(lines, qt, mt);
    });
}

impl Balance<'_> {
    /// The x- and axis-1 terms of the balance on the columns `x` of the lines `lines` (one
    /// band, whose tendencies `qt`, `mt` are), line after line: each line's upper axis-1
    /// fluxes are the next one's lower fluxes (a band's first line and the first line of a
    /// plane compute theirs). Without further axes the sum is the tendency (negated).
    fn tile(&self, lines: Range<usize>, x: Range<usize>, qt: &mut [f64], mt: &mut [f64]) {
        let (len, w, c) = (self.cv.len(0), x.len(), self.c);
        let ([mut ylo, mut yhi], [mut qlo, mut qhi]) = ([[0.0; CHUNK]; 2], [[0.0; CHUNK]; 2]);
        let (mut below, mut above) = ((&mut ylo, &mut qlo), (&mut yhi, &mut qhi));
        let (mut bm, mut bq) = ([0.0; CHUNK + 1], [0.0; CHUNK + 1]);
        let last = self.further.is_empty();
        if lines.is_empty() {
            return;
        }
        let (vel, m, l0) = (self.vel, self.m, self.cv.line(lines.start));
        let (lower, upper) = (
            Shape::new(&l0, [1, c, 0], vel, m),
            Shape::new(&l0, [1, c, 1], vel, m),
        );
        let across = Shape::new(&self.xs.line(lines.start), [0, c, 0], vel, m);
        for n in lines.clone() {
            let (l, xl) = (self.cv.line(n), self.xs.line(n));
            if n == lines.start || l.start[1] == self.cv.lo()[1] {
                lower
                    .on(&l, x.clone())
                    .fluxes(&mut below.0[..w], &mut below.1[..w]);
            }
            upper
                .on(&l, x.clone())
                .fluxes(&mut above.0[..w], &mut above.1[..w]);
            across
                .on(&xl, x.start..x.end + 1)
                .fluxes(&mut bm[..=w], &mut bq[..=w]);
            let o = (n - lines.start) * len + x.start;
            let (qt, mt) = (&mut qt[o..o + w], &mut mt[o..o + w]);
            let [rm, rp, r] = self.radii;
            let (rm, rp, r) = (&rm[x.clone()], &rp[x.clone()], &r[x.clone()]);
            let (m0, m1, q0, q1) = (&below.0[..w], &above.0[..w], &below.1[..w], &above.1[..w]);
            let (bm, bq, h) = (&bm[..=w], &bq[..=w], self.h);
            for i in 0..w {
                let d = h[0] * r[i];
                let sq = (rp[i] * bq[i + 1] - rm[i] * bq[i]) / d + (q1[i] - q0[i]) / h[1];
                let sm = (rp[i] * bm[i + 1] - rm[i] * bm[i]) / d + (m1[i] - m0[i]) / h[1];
                (qt[i], mt[i]) = if last { (-sq, -sm) } else { (sq, sm) };
            }
            std::mem::swap(&mut below, &mut above);
        }
    }

    /// The terms of the axes `2..` added to the tendencies `qt`, `mt` of the lines `lines` (one
    /// band), the last one negating the sum.
    fn further(&self, lines: Range<usize>, qt: &mut [f64], mt: &mut [f64]) {
        let len = self.cv.len(0);
        let rows = qt.chunks_exact_mut(len).zip(mt.chunks_exact_mut(len));
        for (n, (qt, mt)) in lines.zip(rows) {
            let l = self.cv.line(n);
            for (a, &(fm, fq)) in (2..).zip(self.further) {
                let last = a == self.further.len() + 1;
                let (m0, m1) = (&l.on(fm, [0; 3])[..len], &l.on(fm, unit(a))[..len]);
                let (q0, q1) = (&l.on(fq, [0; 3])[..len], &l.on(fq, unit(a))[..len]);
                for i in 0..len {
                    let sq = qt[i] + (q1[i] - q0[i]) / self.h[a];
                    let sm = mt[i] + (m1[i] - m0[i]) / self.h[a];
                    (qt[i], mt[i]) = if last { (-sq, -sm) } else { (sq, sm) };
                }
            }
        }
    }
}

/// The velocity components of a step and the arrays it works in.
pub(crate) struct Work<'a> {
    /// Momentum tendencies per component (compact on its control volumes), then the momenta
    /// of the Euler stage ([`Euler::advance_mass`]).
    pub(crate) qt: [&'a mut [f64]; 3],
    /// The mass tendency of the component at hand (compact on its control volumes).
    pub(crate) mt: &'a mut [f64],
    /// The current stage's face masses per component.
    pub(crate) m: [&'a mut [f64]; 3],
    /// Mass and momentum fluxes along axis 2 (three dimensions only).
    pub(crate) fm: [&'a mut [f64]; 1],
    pub(crate) fq: [&'a mut [f64]; 1],
}

impl<'a> Work<'a> {
    /// [`work`]`(dims)` arrays of `len` values each, cut from the front of `pool`; the arrays of
    /// absent axes are empty.
    pub(crate) fn cut(pool: &'a mut [f64], dims: usize, len: usize) -> Self {
        let mut parts = pool[..work(dims) * len].chunks_exact_mut(len);
        let mut take = |n: usize, k: usize| {
            if k < n {
                parts.next().expect("pool sized by work(dims)")
            } else {
                Default::default()
            }
        };
        let m = std::array::from_fn(|k| take(dims, k));
        let qt = std::array::from_fn(|k| take(dims, k));
        let mt = take(1, 0);
        let fm = std::array::from_fn(|k| take(dims - 2, k));
        let fq = std::array::from_fn(|k| take(dims - 2, k));
        Work { qt, mt, m, fm, fq }
    }
}

/// The momentum and mass tendencies of component `c` on its control volumes `cv` into
/// `work.qt[c]` and `work.mt`, for the velocity `vel` and the face masses `work.m[c]` (ghosts
/// filled).
pub(crate) fn tendency(grid: &Grid, cv: Region, c: usize, vel: &[&Field], work: &mut Work) {
    let dims = vel.len();
    let Work {
        qt, mt, m, fm, fq, ..
    } = work;
    for a in 2..dims {
        face_fluxes(cv, a, c, vel, &*m[c], &mut *fm[a - 2], &mut *fq[a - 2]);
    }
    let further = [(&*fm[0], &*fq[0])];
    balance(
        grid,
        cv,
        c,
        vel,
        &*m[c],
        &further[..dims - 2],
        &mut *qt[c],
        mt,
    );
}

/// One Euler stage of SSP-RK2 on the control volumes of one component ([`Euler::update`]).
pub(crate) struct Euler<'a> {
    pub(crate) dt: f64,
    /// `Δt/Δtₙ₋₁` of the `WholeStep` predictor, 0 without history.
    pub(crate) lag: f64,
    /// Whether this is the second stage (averaged with the start of the step).
    pub(crate) second: bool,
    pub(crate) rho: &'a Field,
}

impl Euler<'_> {
    /// The face mass `m1` (in the fields' storage) and momentum of the faces of `region`
    /// (normal to axis `a`) after an Euler stage from the current values with the tendencies
    /// `q` (momentum) and `dm` (mass; both compact on `region`): the momentum goes where its
    /// tendency was, in `q`, and `dm` is spent. `x` is the current velocity, `x0` the
    /// start-of-step one and `y` the velocity this stage left at the previous step (empty
    /// without history). The velocity itself follows in [`velocity`](Self::velocity), once no
    /// component's tendencies read it any more. Lines in parallel, each writing its own faces.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn advance_mass(
        &self,
        region: Region,
        a: usize,
        x: &Field,
        m1: &mut [f64],
        [x0, y]: [&[f64]; 2],
        q: &mut [f64],
        dm: &mut [f64],
    ) {
        if region.is_empty() {
            return;
        }
        let (dt, lag, second) = (self.dt, self.lag, self.second);
        let below = minus(a);
        let (n, size) = (region.len(0), region.size());
        let mr = &*m1;
        par::rows((&mut q[..size], &mut dm[..size]), n).for_each(|j, (q, dm)| {
            let l = region.line(j);
            let (x0, xr, mr) = (
                &l.on(x0, [0; 3])[..n],
                &x.at(&l, [0; 3])[..n],
                &l.on(mr, [0; 3])[..n],
            );
            let y = if lag != 0.0 {
                &l.on(y, [0; 3])[..n]
            } else {
                &[]
            };
            let (rho_lo, rho_hi) = (&self.rho.at(&l, below)[..n], &self.rho.at(&l, [0; 3])[..n]);
            let (q, dm) = (&mut q[..n], &mut dm[..n]);
            for c in 0..n {
                // The other stages' increment added to the first stage's velocity.
                let other = if lag != 0.0 {
                    lag * (x0[c] - y[c])
                } else {
                    0.0
                };
                // (m, m u) after an Euler step from the current stage values (the second
                // stage from the first's momentum, without that increment).
                let m_e = mr[c] + dt * dm[c];
                let q_e = if second && lag != 0.0 {
                    mr[c] * (xr[c] - other) + dt * q[c]
                } else {
                    mr[c] * xr[c] + dt * q[c]
                };
                (dm[c], q[c]) = if !second {
                    (m_e, q_e)
                } else {
                    // The start-of-step face mass, as `face_masses` gave it.
                    let a = face_density(rho_lo[c], rho_hi[c]);
                    (0.5 * (a + m_e), 0.5 * (a * x0[c] + q_e))
                };
            }
        });
        // The new masses into their faces.
        let dm = &*dm;
        region.for_each(region.storage(m1), |l, mr| {
            mr[..l.len].copy_from_slice(&dm[l.n * l.len..][..l.len]);
        });
    }

    /// The velocity `x` of the faces of `region` (normal to axis `a`) from their momentum `q`
    /// (compact) and mass `m1` after [`advance_mass`](Self::advance_mass): `q/m`, plus in the
    /// first stage the other stages' increment (`x0` and `y` as there). Lines in parallel.
    pub(crate) fn velocity(
        &self,
        region: Region,
        x: &mut Field,
        m1: &[f64],
        [x0, y]: [&[f64]; 2],
        q: &[f64],
    ) {
        let (lag, second) = (self.lag, self.second);
        region.for_each(x, |l, xr| {
            let n = l.len;
            let (q, mr, x0) = (
                &q[l.n * n..][..n],
                &l.on(m1, [0; 3])[..n],
                &l.on(x0, [0; 3])[..n],
            );
            let y = if lag != 0.0 {
                &l.on(y, [0; 3])[..n]
            } else {
                &[]
            };
            let xr = &mut xr[..n];
            for c in 0..n {
                xr[c] = q[c] / mr[c];
                if !second && lag != 0.0 {
                    xr[c] += lag * (x0[c] - y[c]);
                }
            }
        });
    }
}

/// The convective rate `C = max over cells of Σ_a max(|u_a[I]|, |u_a[I + e_a]|)/h_a` of the
/// velocity `vel` (one component per axis): the explicit advective limit is `Δt ≤ CFL/C`. A
/// maximum, so the same on any number of threads.
pub fn convective_rate(grid: &Grid, vel: &[&Field]) -> f64 {
    let [dx, dy, dz] = grid.h();
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        let (u0, u1) = (vel[0].at(&l, [0; 3]), vel[0].at(&l, unit(0)));
        let (v0, v1) = (vel[1].at(&l, [0; 3]), vel[1].at(&l, unit(1)));
        let mut c = 0.0f64;
        if let Some(w) = vel.get(2) {
            let (w0, w1) = (w.at(&l, [0; 3]), w.at(&l, unit(2)));
            for n in 0..l.len {
                let uu = u0[n].abs().max(u1[n].abs());
                let vv = v0[n].abs().max(v1[n].abs());
                let ww = w0[n].abs().max(w1[n].abs());
                c = c.max(uu / dx + vv / dy + ww / dz);
            }
        } else {
            for n in 0..l.len {
                let uu = u0[n].abs().max(u1[n].abs());
                let vv = v0[n].abs().max(v1[n].abs());
                c = c.max(uu / dx + vv / dy);
            }
        }
        c
    })
}
