//! Per-body deformation: every elastic body of a scene of several keeps its own B, its own law
//! and its own interface weights.
//!
//! # Rule
//!
//! A scene of several bodies (`solids: [ … ]`) transports each body's fraction `φ_k` on its own
//! (the VOF stage's `bodies` module). Each body `k` with a law keeps its own left Cauchy–Green
//! tensor `B_k` and its rates (a [`Deformation`]), transported by the upper-convected law of the
//! module docs of [`super`] with the weights `w_k = φ_k^{1/2}` of its own fraction — B̃ of the
//! body is `B̃_k = φ_k^{1/2} B_k` — and reset to the identity outside it ("Pure fluid"). The
//! law of body `k` (its own library and parameters) is evaluated on `B_k` only, so two bodies
//! that meet never mix their deformation histories. The stress in a cell is the mixture
//!
//! ```text
//!   τ = Σ_k w_k (τ_k(B_k) − τ_k(I)),     (shear on the edges: Σ_k (1/κ_k) τ_k,ab(B_k))
//! ```
//!
//! each term as the single body's ("The interface"), the other bodies counting as fluid in the
//! series closure of its interface edges (`μ_s` of the body, `μ_f` of the fluid). The
//! implicit system sees the sum of the bodies' tangents, `K_J δ = Σ_k vol ∇·[J_k : H(δ; B_kⁿ)]`,
//! each body's increment stretched by its own `B_kⁿ`; the block multigrid's effective viscosity
//! and the Jacobi diagonal take the sum of the bodies' stiffnesses; the coupled step uses the
//! same operator. The strain energy is `Σ_k ∫ w_k W_k(B_k) dV`, each body's kept for its probe.
//!
//! # Storage
//!
//! A scene of one body keeps the single [`Deformation`] resource on the whole grid (checkpoint
//! names `B.<part>.<c>`). A scene of several keeps [`BodyDeformations`]: each elastic body's
//! deformation, its kernels (weights, law batches, gradients) and its work arrays live on its
//! own window ([`Place`]), the box of its fraction's window (the VOF stage's `BodyWindow`)
//! grown by [`PAD`] cells on every side inside the domain; memory and work scale with the
//! bodies' extent, not with the grid times their number. Outside its window a body's B is
//! the identity and its rates, stress and weights zero (pure fluid). The kernels run on the
//! window as a grid of its own ([`efsi_core::Grid::window`]: the parent's cell sizes and
//! radii, its sides the domain's where it touches them, elsewhere even reflections); the
//! velocities are copied in, and the body's force on the unknown faces, its stiffness for the
//! preconditioners and its output tensors are added into the parent's at the same cells. The
//! window moves with the fraction's: when the VOF window is placed anew, the deformation is
//! copied onto the new box (identity and zero rates where the old one did not reach).
//!
//! **Why the window step is the full-grid step, bit for bit.** When the elastic step runs,
//! the body's support (its cells with `φ_k ≠ 0`) lies at least `vof::NEAR − 1` = 2 cells
//! inside every inner side of its fraction's window (the VOF window's rule: `NEAR` before the
//! VOF step, which grows the support by at most one cell), so at least `d = 2 + PAD` cells
//! inside the elastic window's. The deformation is written at the centres within
//! [`super::NEAR`] = 4 cells of the support and on the edges touching them: all in the
//! window's interior once `d ≥ 4`, so the window clips none of them where the whole grid would
//! not. B is read at most two cells (or edges) beyond those (the van Leer fluxes of the
//! advection; the stretching's four cells and edges are nearer): with `d ≥ 6` within the
//! interior and the window's boundary edges, never in its ghosts. The velocity, copied in
//! from the whole grid with the ghosts, is read at most [`READS`] cells beyond the centres it
//! serves: within the ghosts once `d + G ≥ 4 + 3`. Wherever B is read but not written it is
//! the identity and its rates zero, in the window as on the whole grid (reset wherever the body
//! has no solid); the fraction and its weights vanish within `d` cells of every inner side, so
//! their ghosts (even reflections) hold the zeros the grid holds there. `PAD` = 4 is the fewest
//! cells that give `d ≥ 6` (with `d = 5` the lowest written edge would be read through the
//! ghost edge that reflects it); a compile-time assertion ties it to the constants. Each body's
//! kernels run on their own window and deformation, the bodies in parallel
//! ([`efsi_linalg::par::try_each`]); the force and the stiffness are then added face by face
//! and cell by cell in the bodies' order, as on the whole grid; sums over cells (the strain
//! energy) run over the same cells in the same order.
//! A checkpoint records each window (`B.<body>.window`: its first cell and its cells along each
//! axis) with the arrays on it, and a restore takes the recorded windows.
//!
//! # Limits
//!
//! The bodies' fractions come from the state's [`BodyFractions`], which the VOF stage sets at
//! its initialisation, after every step and when a snapshot or checkpoint is restored
//! ([`efsi_core::Stage::restored`]); the elastic step refuses a state that holds none. Two
//! bodies sharing a cell add their stresses as two materials in parallel; a body's
//! interface edge counts the other body's part of it as fluid. Keeping the bodies a film apart
//! is the contact's job, not this module's.

use super::Deformation;
use efsi_core::body_fractions::{BodyFraction, BodyFractions};
use efsi_core::scene::{Boundaries, Boundary, Options, Side};
use efsi_core::{BoundarySet, Field, Geometry, Grid, Index, Scene, State, StateResource};

/// Cells an elastic body's window keeps beyond its fraction's window on every side inside the
/// domain: the fewest that keep the window step the full-grid step ("Storage" in the module
/// docs).
pub(super) const PAD: usize = 4;

// The support lies `vof::NEAR − 1 + PAD` cells inside an inner side of the window when the
// elastic step runs: at least the deformation's reach (`NEAR`) and the advection's two cells
// beyond it, and within the ghosts of the velocity's reach (`NEAR + READS`).
const _: () = {
    let inside = (crate::vof::bodies::NEAR - 1 + PAD) as isize;
    assert!(inside >= super::NEAR + 2);
    assert!(inside + efsi_core::G >= super::NEAR + READS);
};

/// The whole grid, its sides, and the scene's sides (what a body's window takes its own from).
pub(super) struct Frame {
    pub(super) grid: Grid,
    pub(super) bc: BoundarySet,
    pub(super) sides: Boundaries,
}

/// An elastic body's window: the grid cell of its first cell and its cells along each axis
/// (1 along z in two dimensions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    /// The grid cell of the window's cell `[0, 0, 0]`.
    pub lo: [usize; 3],
    /// Its cells along each axis.
    pub n: [usize; 3],
}

impl Place {
    /// The window of a body whose fraction's window is `bf` (set): that box grown by [`PAD`]
    /// cells, clipped to `parent`.
    pub(super) fn around(parent: &Grid, bf: &BodyFraction) -> Place {
        let pn = parent.n();
        let mut p = Place {
            lo: [0; 3],
            n: [1; 3],
        };
        for a in 0..parent.dims() {
            p.lo[a] = bf.lo[a].saturating_sub(PAD);
            p.n[a] = (bf.lo[a] + bf.n[a] + PAD).min(pn[a]) - p.lo[a];
        }
        p
    }

    /// A small window at the grid's first cell (a body's before its fraction is known).
    pub(super) fn first(parent: &Grid) -> Place {
        let pn = parent.n();
        Place {
            lo: [0; 3],
            n: std::array::from_fn(|a| if a < parent.dims() { pn[a].min(2) } else { 1 }),
        }
    }

    /// The grid index of the window's cell `[0, 0, 0]`.
    pub(super) fn origin(&self) -> Index {
        self.lo.map(|v| v as isize)
    }

    /// The window as a grid of its own ([`Grid::window`]).
    pub(super) fn grid(&self, parent: &Grid) -> Grid {
        parent.window(self.lo, self.n)
    }

    /// The sides of the window: the domain's where it touches them, elsewhere no-slip (whose
    /// scalar and shear ghosts are even reflections).
    pub(super) fn sides(&self, parent: &Grid, sides: &Boundaries) -> Boundaries {
        let mut out = sides.clone();
        let pn = parent.n();
        for &side in Side::of(parent.dims()) {
            let a = side.axis();
            let high = side == Side::normal_to(a, true);
            let touches = if high {
                self.lo[a] + self.n[a] == pn[a]
            } else {
                self.lo[a] == 0
            };
            if touches {
                continue;
            }
            let slot = match side {
                Side::XMin => &mut out.x_min,
                Side::XMax => &mut out.x_max,
                Side::YMin => &mut out.y_min,
                Side::YMax => &mut out.y_max,
                Side::ZMin => out.z_min.get_or_insert(Boundary::NoSlip),
                Side::ZMax => out.z_max.get_or_insert(Boundary::NoSlip),
            };
            *slot = Boundary::NoSlip;
        }
        out
    }

    /// The window's record in a checkpoint (`B.<body>.window`): its first cell and its cells
    /// along each axis in the first six entries of a small field.
    fn record(&self) -> Field {
        let mut f = Field::zeros(&record_grid());
        for (d, v) in f.data_mut().iter_mut().zip(self.lo.iter().chain(&self.n)) {
            *d = *v as f64;
        }
        f
    }

    /// The window a record holds ([`Place::record`]); an error if it is not one of `parent`.
    fn of_record(parent: &Grid, data: &[f64]) -> Result<Place, String> {
        let int = |v: f64| {
            (v >= 0.0 && v.fract() == 0.0 && v < 1e12)
                .then_some(v as usize)
                .ok_or_else(|| format!("{v} is not a cell index of a window"))
        };
        let head = data
            .get(..6)
            .ok_or("a body's window record is shorter than its six numbers")?;
        let mut p = Place::first(parent);
        for a in 0..3 {
            p.lo[a] = int(head[a])?;
            p.n[a] = int(head[3 + a])?;
        }
        let pn = parent.n();
        let fits = (0..parent.dims()).all(|a| p.n[a] >= 1 && p.lo[a] + p.n[a] <= pn[a]);
        if !fits {
            return Err(format!(
                "a window of {:?} cells at {:?} does not fit the grid of {pn:?} cells",
                p.n, p.lo
            ));
        }
        Ok(p)
    }
}

/// The grid of a window's record: six cells along x.
fn record_grid() -> Grid {
    Grid::new(Geometry::Planar, 6, 1, (0.0, 1.0), (0.0, 1.0))
}

/// Whether `f` is shaped for `grid`.
pub(super) fn shaped_for(f: &Field, grid: &Grid) -> bool {
    [f.stride(), f.rows(), f.planes()] == grid.padded()
}

/// `fields` reshaped for `grid` if they are not (`count` zero fields).
pub(super) fn reshape(fields: &mut Vec<Field>, grid: &Grid, count: usize) {
    if fields.len() != count || fields.iter().any(|f| !shaped_for(f, grid)) {
        *fields = (0..count).map(|_| Field::zeros(grid)).collect();
    }
}

/// Copy the padded window of the parent field `from` whose cell `[0, 0, 0]` is the parent's
/// `origin` into the window field `to` (ghosts included), row by row.
pub(super) fn copy_in(from: &Field, to: &mut Field, origin: Index) {
    let (stride, rows, planes, gz) = (to.stride(), to.rows(), to.planes(), to.gz() as isize);
    let g = efsi_core::G;
    for k in 0..planes as isize {
        for j in 0..rows as isize {
            let (kk, jj) = (k - gz, j - g);
            let src = from.idx3([-g + origin[0], jj + origin[1], kk + origin[2]]);
            let dst = to.idx3([-g, jj, kk]);
            to.data_mut()[dst..dst + stride].copy_from_slice(&from.data()[src..src + stride]);
        }
    }
}

/// [`copy_in`] of the window's points `lo ≤ I ≤ hi` only (window indices, clipped to the
/// window field's storage, ghosts included), row by row.
pub(super) fn copy_box_in(from: &Field, to: &mut Field, origin: Index, lo: Index, hi: Index) {
    let g = efsi_core::G;
    let gz = to.gz() as isize;
    let top = [
        to.stride() as isize - g,
        to.rows() as isize - g,
        to.planes() as isize - gz,
    ];
    let bottom = [-g, -g, -gz];
    let lo: Index = std::array::from_fn(|a| lo[a].max(bottom[a]));
    let hi: Index = std::array::from_fn(|a| hi[a].min(top[a] - 1));
    if (0..3).any(|a| lo[a] > hi[a]) {
        return;
    }
    let len = (hi[0] - lo[0] + 1) as usize;
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            let src = from.idx3([lo[0] + origin[0], j + origin[1], k + origin[2]]);
            let dst = to.idx3([lo[0], j, k]);
            to.data_mut()[dst..dst + len].copy_from_slice(&from.data()[src..src + len]);
        }
    }
}

/// Copy the points `region` (of the window field `from`, a region of its grid) into the
/// parent field `to` at the same cells (`origin` the parent index of the window's first cell).
pub(super) fn copy_out(from: &Field, to: &mut Field, origin: Index, region: &efsi_core::Region) {
    for l in (0..region.lines()).map(|n| region.line(n)) {
        let at = super::plus(l.start, origin);
        let dst = to.idx3(at);
        to.data_mut()[dst..dst + l.len].copy_from_slice(from.at(&l, [0; 3]));
    }
}

/// How far beyond its centres `c` [`super::Kernels::gradient_in`] and
/// [`super::Kernels::advect`] read the velocity along each axis: the gradient window is `c`
/// and one cell more, the edges' two-point gradients read one cell below an edge, the bulk
/// stencil two below and one above; the advection reads the faces of `c`'s cells and of its
/// edges' boxes, one cell about an edge.
const READS: isize = 3;

/// An elastic body of the scene: its index among the scene's bodies (`None` for the single
/// solid of a scene of one body, whose fraction is the state's) and its settings.
#[derive(Clone, Debug)]
pub(super) struct ElasticBody {
    pub(super) index: Option<usize>,
    pub(super) name: String,
    pub(super) solid: crate::solid::Solid,
    /// The path of its settings in the scene (`solid`, `solids[1]`), for messages.
    pub(super) path: String,
}

/// The elastic bodies of a checked scene: the single solid (with its law), or every body of a
/// scene of several that has a law, in the scene's order.
pub(super) fn elastic_bodies(options: &Options) -> Result<Vec<ElasticBody>, String> {
    if let Ok(s) = crate::solid::solid(options) {
        return Ok(vec![ElasticBody {
            index: None,
            name: efsi_core::scene::bodies::SINGLE.to_string(),
            solid: s.clone(),
            path: "solid".to_string(),
        }]);
    }
    let bodies = crate::solid::bodies(options)?;
    Ok(bodies
        .list
        .iter()
        .enumerate()
        .filter(|(_, b)| b.solid.law.is_some())
        .map(|(k, b)| ElasticBody {
            index: Some(k),
            name: b.name.clone(),
            solid: b.solid.clone(),
            path: crate::solid::Body::path(true, k),
        })
        .collect())
}

/// Whether a checked scene has an elastic body: a solid with a law, or a body with a law among
/// several.
pub(crate) fn any_elastic(options: &Options) -> bool {
    match crate::solid::solid(options) {
        Ok(s) => s.law.is_some(),
        Err(_) => crate::solid::bodies(options)
            .is_ok_and(|b| b.list.iter().any(|b| b.solid.law.is_some())),
    }
}

/// The fluid's and body `b`'s viscosities, for its interface edges.
pub(super) fn viscosities_of(scene: &Scene, b: &ElasticBody) -> (f64, f64) {
    (scene.fluid.viscosity, b.solid.viscosity(&scene.fluid))
}

/// The deformations of the elastic bodies of a scene of several (the bodies with a law, in the
/// scene's order): each body's [`Deformation`] on its window ([`Place`]), with its name, saved
/// in checkpoints and snapshots under the names `B.<body>.window` (the window) and
/// `B.<body>.<part>.<c>`.
#[derive(Clone, Debug)]
pub struct BodyDeformations {
    /// The bodies' names.
    pub names: Vec<String>,
    /// Their deformations, each on its window.
    pub bodies: Vec<Deformation>,
    /// Their windows.
    pub places: Vec<Place>,
    /// Each window's record ([`Place::record`]).
    records: Vec<Field>,
    /// The grid the windows are boxes of.
    parent: Grid,
}

impl BodyDeformations {
    /// Body `k`'s deformation moved onto the window `to`: its values where the two windows
    /// share cells (ghosts included), the identity and zero rates elsewhere.
    pub(super) fn place(&mut self, k: usize, to: Place) {
        let from = self.places[k];
        if from == to {
            return;
        }
        let grid = to.grid(&self.parent);
        let mut moved = Deformation::zeros(&grid);
        moved.set_identity();
        for f in moved.start.iter_mut().take(3) {
            f.fill(1.0);
        }
        let old = &self.bodies[k];
        let shift: Index = std::array::from_fn(|a| from.lo[a] as isize - to.lo[a] as isize);
        for ((_, dst), (_, src)) in moved.parts_mut().into_iter().zip(old.parts()) {
            for (d, s) in dst.iter_mut().zip(src) {
                copy_shared(s, d, shift);
            }
        }
        moved.elastic_energy = old.elastic_energy;
        self.bodies[k] = moved;
        self.places[k] = to;
        self.records[k] = to.record();
    }

    /// The window grid of body `k`.
    pub(super) fn grid(&self, k: usize) -> Grid {
        self.places[k].grid(&self.parent)
    }
}

/// Copy the entries of the window field `from` into the window field `to` where they share a
/// point; `shift` is `from`'s first cell less `to`'s (point `I` of `from` is `I + shift` of
/// `to`).
fn copy_shared(from: &Field, to: &mut Field, shift: Index) {
    let g = efsi_core::G;
    let (fs, fr, fp, fz) = (
        from.stride(),
        from.rows(),
        from.planes(),
        from.gz() as isize,
    );
    let (ts, tr, tp, tz) = (to.stride(), to.rows(), to.planes(), to.gz() as isize);
    let span = |n: usize, lo: isize, s: isize, m: usize, mlo: isize| {
        let a = lo.max(mlo - s);
        let b = (lo + n as isize).min(mlo + m as isize - s);
        (a, b)
    };
    let (i0, i1) = span(fs, -g, shift[0], ts, -g);
    let (j0, j1) = span(fr, -g, shift[1], tr, -g);
    let (k0, k1) = span(fp, -fz, shift[2], tp, -tz);
    if i0 >= i1 {
        return;
    }
    let len = (i1 - i0) as usize;
    for k in k0..k1 {
        for j in j0..j1 {
            let src = from.idx3([i0, j, k]);
            let dst = to.idx3([i0 + shift[0], j + shift[1], k + shift[2]]);
            to.data_mut()[dst..dst + len].copy_from_slice(&from.data()[src..src + len]);
        }
    }
}

impl StateResource for BodyDeformations {
    fn arrays(&self) -> Vec<(String, &Field)> {
        let mut out = Vec::new();
        for ((name, d), r) in self.names.iter().zip(&self.bodies).zip(&self.records) {
            out.push((format!("B.{name}.window"), r));
            for (a, f) in d.arrays() {
                out.push((format!("B.{name}{}", &a[1..]), f));
            }
        }
        out
    }

    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        let mut out = Vec::new();
        let parts = self
            .names
            .iter()
            .zip(&mut self.bodies)
            .zip(&mut self.records);
        for ((name, d), r) in parts {
            out.push((format!("B.{name}.window"), r));
            for (a, f) in d.arrays_mut() {
                out.push((format!("B.{name}{}", &a[1..]), f));
            }
        }
        out
    }

    fn reshape(&mut self, recorded: &dyn Fn(&str) -> Option<Vec<f64>>) -> Result<(), String> {
        for k in 0..self.names.len() {
            let name = format!("B.{}.window", self.names[k]);
            let data = recorded(&name).ok_or_else(|| format!("the array `{name}` is missing"))?;
            let to = Place::of_record(&self.parent, &data).map_err(|e| format!("`{name}`: {e}"))?;
            self.place(k, to);
        }
        Ok(())
    }

    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(self.clone())
    }

    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        let Some(other) = (other as &dyn std::any::Any).downcast_ref::<BodyDeformations>() else {
            return false;
        };
        if self.names != other.names || self.bodies.len() != other.bodies.len() {
            return false;
        }
        // A body whose window differs takes the other's (one allocation); the others are
        // copied in place.
        for k in 0..self.bodies.len() {
            if self.places[k] == other.places[k] && self.bodies[k].copy_from(&other.bodies[k]) {
                continue;
            }
            self.bodies[k] = other.bodies[k].clone();
            self.places[k] = other.places[k];
            self.records[k] = other.records[k].clone();
        }
        true
    }

    fn first_non_finite(&self, _nx: usize, _ny: usize) -> Option<(String, (usize, usize))> {
        let all = self.names.iter().zip(&self.bodies).zip(&self.places);
        all.into_iter().find_map(|((name, d), p)| {
            d.first_non_finite(p.n[0], p.n[1])
                .map(|(c, (i, j))| (format!("{name}.B{c}"), (i + p.lo[0], j + p.lo[1])))
        })
    }

    /// The bodies' strain energies summed.
    fn stored_energy(&self) -> f64 {
        self.bodies.iter().map(|d| d.elastic_energy).sum()
    }
}

/// The elastic bodies' deformations taken out of the state for a sub-step (put them back with
/// [`Held::put`]).
pub(super) enum Held {
    One(Box<Deformation>),
    Many(Box<BodyDeformations>),
}

impl Held {
    /// The deformations of the state, `None` if it holds none.
    pub(super) fn take(state: &mut State) -> Option<Held> {
        if let Some(d) = state.resources.take::<Deformation>() {
            return Some(Held::One(d));
        }
        state.resources.take::<BodyDeformations>().map(Held::Many)
    }

    /// Back into the state.
    pub(super) fn put(self, state: &mut State) {
        match self {
            Held::One(d) => state.resources.put(d),
            Held::Many(d) => state.resources.put(d),
        }
    }

    /// One deformation per elastic body.
    pub(super) fn all(&mut self) -> &mut [Deformation] {
        match self {
            Held::One(d) => std::slice::from_mut(&mut **d),
            Held::Many(d) => &mut d.bodies,
        }
    }
}

/// The deformations of a state, one per elastic body (none if it holds none).
pub(super) fn deformations(state: &State) -> &[Deformation] {
    if let Some(d) = state.resources.get::<Deformation>() {
        return std::slice::from_ref(d);
    }
    state
        .resources
        .get::<BodyDeformations>()
        .map_or(&[], |d| &d.bodies[..])
}

/// Add the deformation resource for `bodies` to the state, if it has none: the single
/// [`Deformation`] for the single solid, [`BodyDeformations`] for the bodies of a scene of
/// several (each on a small window until [`place_all`] places it around its fraction).
pub(super) fn init_state(bodies: &[ElasticBody], grid: &Grid, state: &mut State) {
    let single = bodies.len() == 1 && bodies[0].index.is_none();
    if single {
        if state.resources.get::<Deformation>().is_none() {
            state.resources.insert(Deformation::zeros(grid));
        }
    } else if state.resources.get::<BodyDeformations>().is_none() {
        let first = Place::first(grid);
        let window = first.grid(grid);
        state.resources.insert(BodyDeformations {
            names: bodies.iter().map(|b| b.name.clone()).collect(),
            bodies: bodies.iter().map(|_| Deformation::zeros(&window)).collect(),
            places: bodies.iter().map(|_| first).collect(),
            records: bodies.iter().map(|_| first.record()).collect(),
            parent: grid.clone(),
        });
    }
}

/// Each elastic body's deformation moved onto the window around its fraction's window
/// ([`Place::around`]), if it is not there; nothing for the single solid. An error if the
/// state holds no fraction of a body.
pub(super) fn place_all(
    bodies: &[ElasticBody],
    grid: &Grid,
    state: &mut State,
) -> Result<(), String> {
    let Some(mut many) = state.resources.take::<BodyDeformations>() else {
        return Ok(());
    };
    let r = (|| {
        let all = state
            .resources
            .get::<BodyFractions>()
            .ok_or("the bodies' fractions are not in the state")?;
        for (n, b) in bodies.iter().enumerate() {
            let bf = fraction_of(all, b)?;
            many.place(n, Place::around(grid, bf));
        }
        Ok(())
    })();
    state.resources.put(many);
    r
}

/// Body `b`'s fraction in `all`, set; an error naming it if there is none.
fn fraction_of<'a>(all: &'a BodyFractions, b: &ElasticBody) -> Result<&'a BodyFraction, String> {
    let k = b.index.expect("a body of several");
    all.bodies.get(k).filter(|f| f.is_set()).ok_or_else(|| {
        format!(
            "body \"{}\" has no fraction in the state (the VOF stage publishes them): its \
             deformation cannot be weighted",
            b.name
        )
    })
}

/// The windows of the state's deformations: `None` for the single solid's (the whole grid).
/// An iterator, so that a step allocates nothing.
pub(super) fn places(state: &State) -> impl Iterator<Item = Option<Place>> + '_ {
    let many = state.resources.get::<BodyDeformations>();
    let single = many.is_none().then_some(None);
    many.into_iter()
        .flat_map(|m| m.places.iter().map(|p| Some(*p)))
        .chain(single)
}

/// Each elastic body's fraction on its window with its ghosts filled: the state's solid
/// fraction for the single solid, else the body's `φ_k` from the state's [`BodyFractions`]
/// (the VOF stage's copy of its windows), written into a field of its kernels' window.
pub(super) struct Fractions {
    fields: Vec<Field>,
}

impl Fractions {
    /// Work fields for `bodies` (none for the single solid, which reads the state's), shaped
    /// when first refreshed.
    pub(super) fn new(bodies: &[ElasticBody]) -> Self {
        Fractions {
            fields: bodies
                .iter()
                .filter(|b| b.index.is_some())
                .map(|_| Field::default())
                .collect(),
        }
    }

    /// Refresh the bodies' fractions from `state`: each `φ_k` written into a field of its
    /// kernels' window (`ks`, one per body, placed) and its ghosts filled by the window's
    /// sides.
    pub(super) fn refresh(
        &mut self,
        bodies: &[ElasticBody],
        ks: &[super::Kernels],
        state: &State,
    ) -> Result<(), String> {
        if self.fields.is_empty() {
            return Ok(());
        }
        let all = state
            .resources
            .get::<BodyFractions>()
            .ok_or("the bodies' fractions are not in the state")?;
        for ((f, b), k) in self.fields.iter_mut().zip(bodies).zip(ks) {
            let bf = fraction_of(all, b)?;
            if !shaped_for(f, &k.grid) {
                *f = Field::zeros(&k.grid);
            } else {
                f.fill(0.0);
            }
            // The fraction's window, row by row (x fastest).
            let o = k.origin;
            let mut rows = bf.phi.chunks_exact(bf.n[0]);
            for kk in 0..bf.n[2] {
                for j in 0..bf.n[1] {
                    let at = [bf.lo[0], j + bf.lo[1], kk + bf.lo[2]];
                    let to = f.idx3([0, 1, 2].map(|a| at[a] as isize - o[a]));
                    let row = rows.next().expect("a window's values");
                    f.data_mut()[to..to + bf.n[0]].copy_from_slice(row);
                }
            }
            k.bc.fill_scalar(&k.grid, f, false);
        }
        Ok(())
    }

    /// Body `k`'s fraction: its field, or the state's `phi` for the single solid.
    pub(super) fn of<'a>(&'a self, k: usize, phi: &'a Field) -> &'a Field {
        self.fields.get(k).unwrap_or(phi)
    }
}

/// Each elastic body's strain energy into its record in the state's [`BodyFractions`] (for
/// its `<body>.elastic_energy` probe); nothing for the single solid.
pub(super) fn record_energies(bodies: &[ElasticBody], state: &mut State) {
    let Some(many) = state.resources.take::<BodyDeformations>() else {
        return;
    };
    if let Some(all) = state.resources.get_mut::<BodyFractions>() {
        for (b, d) in bodies.iter().zip(&many.bodies) {
            if let Some(f) = b.index.and_then(|k| all.bodies.get_mut(k)) {
                f.elastic_energy = d.elastic_energy;
            }
        }
    }
    state.resources.put(many);
}

impl super::Kernels {
    /// `f` of the kernels and the velocity `vel` of the whole grid (one field per axis) as
    /// they see it: itself on the whole grid, copied onto a window (ghosts included).
    pub(super) fn with_velocity<R>(
        &mut self,
        vel: &[&Field],
        f: impl FnOnce(&mut Self, &[&Field]) -> R,
    ) -> R {
        if self.place.is_none() {
            return f(self, vel);
        }
        let mut w = std::mem::take(&mut self.vel);
        for (w, v) in w.iter_mut().zip(vel) {
            copy_in(v, w, self.origin);
        }
        let r = f(self, &super::velocity(&w[0], &w[1], w.get(2)));
        self.vel = w;
        r
    }

    /// [`Self::with_velocity`] for `f` reading the velocity only within [`READS`] cells of the
    /// centres `c` (the velocity gradients [`super::Kernels::gradient_in`] of `c`, the
    /// advection at `c`): on a window only those points are copied in (the rest of the
    /// window's copy is not read).
    pub(super) fn with_velocity_near<R>(
        &mut self,
        vel: &[&Field],
        c: super::Window,
        f: impl FnOnce(&mut Self, &[&Field]) -> R,
    ) -> R {
        if self.place.is_none() {
            return f(self, vel);
        }
        let dims = self.grid.dims();
        let grow = |x: isize, s: isize, a: usize| if a < dims { x + s * READS } else { x };
        let (lo, hi): (Index, Index) = (
            std::array::from_fn(|a| grow(c.lo()[a], -1, a)),
            std::array::from_fn(|a| grow(c.hi()[a], 1, a)),
        );
        let mut w = std::mem::take(&mut self.vel);
        if c.points() > 0 {
            for (w, v) in w.iter_mut().zip(vel) {
                copy_box_in(v, w, self.origin, lo, hi);
            }
        }
        let r = f(self, &super::velocity(&w[0], &w[1], w.get(2)));
        self.vel = w;
        r
    }

    /// The solid's centres ([`super::Kernels::solid_c`]) in the whole grid's indices.
    pub(super) fn solid_on_grid(&self) -> super::Window {
        let c = self.solid_c;
        if c.points() == 0 {
            return c;
        }
        super::Window::boxed(
            super::plus(c.lo(), self.origin),
            super::plus(c.hi(), self.origin),
        )
    }
}

/// Kernels `ks` on the windows `places` of the state's deformations (one per body; `None`:
/// the whole grid): each rebuilt on its window where it is not there. `parent` is the whole
/// grid, `bc` and `sides` its sides.
pub(super) fn fit_kernels(
    ks: &mut [super::Kernels],
    places: impl IntoIterator<Item = Option<Place>>,
    parent: &Grid,
    bc: &BoundarySet,
    sides: &Boundaries,
) {
    for (k, p) in ks.iter_mut().zip(places) {
        if let Some(p) = p
            && k.place != Some(p)
        {
            *k = super::Kernels::windowed(parent, bc, sides, p, k.mu_f, k.mu_s);
        }
    }
}
