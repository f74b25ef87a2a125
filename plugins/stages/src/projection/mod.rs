//! Pressure projection: `V^{n+1} = V^{n+2/3} − Δt ∇p/ρ` with `∇·V^{n+1} = 0`
//! (seed Eqs. 21–23).
//!
//! **Equation.** `∇·(∇p/ρ) = ∇·V^{n+2/3}/Δt`, variable coefficient, with the face density the
//! average of the two cells (so the density stays inside the divergence, smooth across the
//! interface, as the seed asks). Finite-volume form per cell, axisymmetric through the face radii:
//! `Σ_f (A_f/(ρ_f h)) (p_C − p_F) = −(Σ_f A_f V_f·n)/Δt`, a symmetric positive (semi-)definite
//! five-point system ([`efsi_linalg::Stencil5`]). Walls contribute no flux (homogeneous
//! Neumann), periodic sides wrap, outflow sides fix p = 0 on the boundary face (planar and
//! axisymmetric only: the seven-point matrix of a 3-D box has no Dirichlet face, and the stage
//! refuses a 3-D scene with an Outflow side when it is built). Without an
//! outflow side the system is singular (p up to a constant): the right-hand side is projected on
//! the range (zero sum), the conjugate gradient keeps its iteration off the constants (else
//! round-off along the null space stalls it at large density ratios and tight tolerances:
//! [`efsi_linalg::pcg`], "Singular systems") and the mean pressure is set to zero.
//!
//! **Incremental pressure correction** (`numerics.projection.incremental`; by default on,
//! except in scenes with an elastic solid). The predictor stage `pressure_predictor` (phase
//! `PressurePredictor`, after the body force and before the viscous step) subtracts the last
//! step's pressure gradient, `V* ← V* − Δt ∇pⁿ/ρ`, and the projection solves for the
//! increment `φ = pⁿ⁺¹ − pⁿ` (from zero: the same initial residual as a solve for `pⁿ⁺¹`
//! warm-started from `pⁿ`), then `V^{n+1} = V^{n+2/3} − Δt ∇φ/ρ`, `pⁿ⁺¹ = pⁿ + φ` (van Kan
//! 1986; Guermond, Minev & Shen 2006). The viscous step thereby sees the whole force balance:
//! a viscous fluid at rest under gravity stays at rest, where the seed's scheme shears the
//! increment `gΔt` at no-slip side walls into a flow the projection cannot remove. The starting
//! pressure is the one that balances gravity in the grid's frame (`Projector::initialize`:
//! `g − a` projected with Δt = 1, the hydrostatic pressure where the density is layered). With
//! the classical Heun predictor of the advection a steady state depends on Δt through the
//! split advection; the default `WholeStep` predictor of a scene of one fluid removes that
//! (`tests/tests/cavity.rs`). With an elastic solid the seed's scheme stays the default: the
//! predictor's old pressure gradient, applied before the semi-implicit elastic step, feeds
//! energy into the solid (the stability map's stiff sphere fails with it). With an elastic
//! solid the projection is a sub-step of the implicit-momentum stage
//! (`efsi_stages::elastic::Momentum`), which tells it per step whether it completes the
//! pressure of a coupled elastic step (an increment on it) or finds the whole pressure; a
//! strategy that may couple never runs the incremental scheme.
//!
//! **Gravity in the seed's scheme** (the `hydrostatic` module). Without the predictor the
//! carrier fluid's hydrostatic pressure `p_h = ρ_f (g − a)·(x − x_ref)` is carried by the
//! pressure rather than by the body force: the body force adds only the excess weight
//! `Δt (1 − ρ_f/ρ_face)(g − a)` and takes `p_h` from the pressure for the step; the projection
//! solves for the excess pressure (the same matrix; warm-started from the last step's excess
//! pressure, or the coupled elastic step's increment on it) and adds `p_h` back, so between steps
//! `p` is the whole pressure. `p_h` is zero on every Outflow face (the axes that take part are
//! chosen so, `hydrostatic`), so the solve's Dirichlet condition keeps its meaning, and in a
//! closed box its mean over the cells is zero to round-off, as the whole pressure's was. The run
//! starts from `p = p_h`. The viscous and elastic steps then never see the carrier's hydrostatic
//! part: a fluid at rest in a closed box under gravity stays at rest to the last bit.
//!
//! **Solver.** Conjugate gradient warm-started from the previous pressure (from zero for an
//! increment), preconditioned by
//! the geometric multigrid W-cycle of [`efsi_linalg::Multigrid`] (default: iterations
//! independent of the grid and of density ratios up to 1e4) or, as the seed, by incomplete
//! Cholesky IC(0) (scene `numerics.projection.solver: Multigrid | IncompleteCholesky`). The
//! matrix and its preconditioner depend only on the density (the grid and the boundaries are
//! fixed for a run): they are set up again only in a step whose density differs, bit for bit,
//! from the one they were set up for, so a one-fluid scene assembles them once. With multigrid
//! the matrix is assembled into the pipeline's work pool and the multigrid's finest level keeps
//! the only copy, whose product conjugate gradient uses ([`Multigrid::fine_matrix`]: the same
//! bits as the assembled matrix's); incomplete Cholesky keeps the matrix for its products. It
//! stops when the divergence the correction would leave satisfies `max_cells |∇·V^{n+1}|·Δt ≤
//! tol` (dimensionless: the relative volume change of a cell per step; scene
//! `numerics.projection.tolerance`, default 1e-4 in a scene of one fluid and 1e-6 with a second
//! material), after at least one iteration: the warm start
//! alone often meets the tolerance, and stopping there would leave its divergence in place step
//! after step (a steady state kept `|∇·u|` up to `tol/Δt` and, stopping at 0 and 1 iterations by
//! turns, never settled); one iteration a step drives it to zero across steps. Since
//! `dV·∇·V^{n+1} = −Δt·r` for the residual `r`, the criterion is `max Δt²|r|/dV ≤ tol`, checked
//! on the true residual.
//!
//! **Three dimensions.** On a three-dimensional grid the matrix is seven-point (the z-faces'
//! couplings `h_x h_y/(ρ_f h_z)`), the right-hand side takes the z-face velocity `w` and the
//! correction subtracts the gradient from `u`, `v` and `w`; multigrid only (incomplete
//! Cholesky is two-dimensional and refused). The module `three_d` holds these kernels.
//!
//! **Postcondition** (checked in debug builds): `max |∇·V^{n+1}|·Δt ≤ tol` after the update.
//!
//! **Parallelism.** Assembly, right-hand side, the solver's vector work and the velocity update
//! run over rows in parallel (rayon); each writes its own entries and every reduction has a
//! fixed order, so the result is bit-identical on any number of threads. Nothing is allocated
//! after the first step.

use crate::scratch::{self, FieldScratch, Scratch};
use efsi_core::operators;
use efsi_core::scene::{Boundary, Options, OptionsDecl, Side};
use efsi_core::{
    BoundarySet, FieldId, Grid, Phase, Region, Scene, Stage, StageError, StagePlugin, StageStats,
    Stagger, State, StepContext,
};
use efsi_linalg::par;
use efsi_linalg::{
    IncompleteCholesky, Multigrid, Norm, SolveStats, Stencil5, Stencil5View,
    pcg::{NullSpace, solve_norm_in},
};

pub(crate) mod hydrostatic;
mod options;
pub(crate) mod three_d;
pub use options::{INTERFACE_TOLERANCE, ONE_FLUID_TOLERANCE, PressureSolver, ProjectionOptions};

/// The projection stage plugin.
pub struct Projection;

/// What the projection and its predictor read: the velocity, the density of the face weights
/// and the pressure (the predictor's gradient, the projection's warm start or base).
const READS: [FieldId; 5] = [
    FieldId::VelocityX,
    FieldId::VelocityY,
    FieldId::VelocityZ,
    FieldId::Density,
    FieldId::Pressure,
];

impl StagePlugin for Projection {
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "projection"
    }
    fn phase(&self) -> Phase {
        Phase::Projection
    }
    fn reads(&self) -> &'static [FieldId] {
        &READS
    }
    fn writes(&self) -> &'static [FieldId] {
        &WRITES
    }
    /// In every scene without an elastic solid; with one, the implicit-momentum stage
    /// (`efsi_stages::elastic::Momentum`) projects as a sub-step of its own.
    fn needed(&self, _scene: &Scene, options: &Options) -> bool {
        !crate::elastic_solid(options)
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ProjectionOptions>())
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let incremental = crate::incremental_pressure(options);
        let o: &ProjectionOptions = options.section()?;
        if grid.is_3d() && o.solver == PressureSolver::IncompleteCholesky {
            return Err(
                "numerics.projection.solver: IncompleteCholesky is two-dimensional; \
                 a three-dimensional grid takes Multigrid"
                    .into(),
            );
        }
        if let Some(side) = outflow_side_3d(grid, bc) {
            return Err(format!(
                "boundaries.{side}: Outflow is two-dimensional (planar and axisymmetric scenes); \
                 a three-dimensional box takes NoSlip, MovingWall, FreeSlip, Symmetry or Periodic \
                 sides"
            ));
        }
        Ok(Box::new(ProjectionStage {
            projector: Projector::new(scene, o, grid, bc, shared, incremental),
            incremental,
        }))
    }
}

/// The first Outflow side of a three-dimensional grid: the seven-point matrix has no
/// Dirichlet pressure face, so such a scene is refused when the stage is built.
pub(crate) fn outflow_side_3d(grid: &Grid, bc: &BoundarySet) -> Option<Side> {
    let sides = Side::of(grid.dims());
    grid.is_3d()
        .then(|| {
            sides
                .iter()
                .copied()
                .find(|&s| *bc.get(s) == Boundary::Outflow)
        })
        .flatten()
}

/// What the projection writes: the velocity and the pressure.
pub(crate) const WRITES: [FieldId; 4] = [
    FieldId::VelocityX,
    FieldId::VelocityY,
    FieldId::VelocityZ,
    FieldId::Pressure,
];

/// The predictor of the incremental pressure correction: `V* ← V* − Δt ∇pⁿ/ρ` with the last
/// step's pressure, before the viscous and elastic steps (module docs). Scheduled when
/// `numerics.projection.incremental` (by default on unless the scene has an elastic solid;
/// never with the coupled elastic step).
pub struct PressurePredictor;

impl StagePlugin for PressurePredictor {
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "pressure_predictor"
    }
    fn phase(&self) -> Phase {
        Phase::PressurePredictor
    }
    fn reads(&self) -> &'static [FieldId] {
        &READS
    }
    fn writes(&self) -> &'static [FieldId] {
        &[FieldId::VelocityX, FieldId::VelocityY]
    }
    fn needed(&self, _scene: &Scene, options: &Options) -> bool {
        crate::incremental_pressure(options)
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ProjectionOptions>())
    }
    fn build(
        &self,
        _scene: &Scene,
        _options: &Options,
        _grid: &Grid,
        _bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        Ok(Box::new(PredictorStage))
    }
}

struct PredictorStage;

impl Stage for PredictorStage {
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        if let Some(w) = state.w.as_mut().filter(|_| ctx.grid.is_3d()) {
            let faces = three_d::unknown_faces(ctx.bc, ctx.grid);
            let vel = [&mut state.u, &mut state.v, w];
            three_d::subtract_gradient_3d(ctx.grid, faces, &state.p, &state.rho, ctx.dt, vel);
        } else {
            subtract_gradient(
                ctx.grid,
                ctx.bc,
                &state.p,
                &state.rho,
                ctx.dt,
                &mut state.u,
                &mut state.v,
            );
        }
        Ok(StageStats::default())
    }
}

/// Work vectors the projection takes from the pipeline's pool.
const WORK: usize = 6;

/// Vectors of one value per cell that the matrix takes in the pool while it is assembled for
/// multigrid (its diagonal and couplings; one more, the top couplings, in three dimensions),
/// before the solve takes the [`WORK`] vectors in the same place.
const MATRIX: usize = 3;

/// The preconditioner the scene chose; incomplete Cholesky with the matrix, which multigrid
/// keeps itself.
enum Precond {
    Multigrid(Multigrid),
    IncompleteCholesky(IncompleteCholesky, Stencil5),
}

/// The projection of a scene without an elastic solid: the seed's scheme or the incremental
/// one, the same every step.
struct ProjectionStage {
    projector: Projector,
    /// Whether the scene runs the incremental scheme (`crate::incremental_pressure`).
    incremental: bool,
}

/// The pressure projection (module docs) with its solver and work space: the projection
/// stage's, and the implicit-momentum stage's sub-step.
pub(crate) struct Projector {
    tol: f64,
    max_iter: usize,
    precond: Precond,
    /// The pipeline's work vectors: [`WORK`] of one value per cell while the stage runs (the
    /// right-hand side, the pressure solved for, the residual weights and the solver's three);
    /// before them, with multigrid, the [`MATRIX`] vectors of the matrix being assembled in
    /// the same place.
    scratch: Scratch,
    /// The pressure increment of a projection that completes a pressure already applied (the
    /// incremental scheme's predictor's, or the coupled elastic step's): solved for from zero,
    /// applied to the velocity and added to that pressure. `None` where no projection is one;
    /// else a field of the pipeline's pool of work fields (`fields`) while such a projection
    /// runs, an empty placeholder between.
    increment: Option<efsi_core::Field>,
    /// The pipeline's work fields, of which the increment borrows one.
    fields: FieldScratch,
    /// Gravity, whose hydrostatic pressure (in the grid's frame) a run may start from
    /// ([`Projector::initialize`]).
    gravity: (f64, f64),
    /// Gravity's three components, for the carrier's hydrostatic pressure.
    gravity3: [f64; 3],
    /// The seed's scheme's split of gravity, as the body force makes it ([`hydrostatic`]): the
    /// carrier's hydrostatic pressure, which the body force takes from the pressure and each
    /// projection adds back after its solve.
    hydrostatic: Option<hydrostatic::Hydrostatic>,
    /// The density (with its ghosts) the matrix and its preconditioner were last set up for;
    /// empty before the first solve. They depend on nothing else that changes during a run, so
    /// a step whose density is bit for bit the last one's reuses them (every step of a
    /// one-fluid scene). `None` with multigrid and a second material: every step assembles
    /// and sets up only a matrix the multigrid does not hold already
    /// ([`Multigrid::is_set_up_for`]), no copy of the density kept (0.55 MB at 256²).
    set_up_for: Option<Density>,
}

/// A density as [`Projector::set_up_for`] keeps it: a copy, or — when every value (ghosts
/// included) has the same bits, as in a scene of one fluid — that value and the count, no
/// array. Either way it equals a density exactly when the density is bit for bit the one
/// kept.
#[derive(Default)]
struct Density {
    copy: Vec<f64>,
    /// The bits of the one value and the count, if the density kept is uniform.
    uniform: Option<(u64, usize)>,
}

impl Density {
    /// Whether `rd` is bit for bit the density kept (never before the first [`keep`](Self::keep)).
    fn is(&self, rd: &[f64]) -> bool {
        match self.uniform {
            Some((bits, len)) => rd.len() == len && rd.iter().all(|x| x.to_bits() == bits),
            None => {
                self.copy.len() == rd.len()
                    && self
                        .copy
                        .iter()
                        .zip(rd)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
            }
        }
    }

    /// Keep `rd`.
    fn keep(&mut self, rd: &[f64]) {
        let first = rd.first().map(|x| x.to_bits());
        self.uniform = first
            .filter(|&b| rd.iter().all(|x| x.to_bits() == b))
            .map(|b| (b, rd.len()));
        self.copy.clear();
        if self.uniform.is_none() {
            self.copy.extend_from_slice(rd);
        }
    }
}

impl Projector {
    /// The projector of the options `o` (`numerics.projection`); `increments` if any of its
    /// projections may complete a pressure already applied ([`Projector::project`]'s
    /// `increment`).
    pub(crate) fn new(
        scene: &Scene,
        o: &ProjectionOptions,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
        increments: bool,
    ) -> Projector {
        let n = grid.cells();
        // Multigrid's matrix is assembled in the pool, beside the work vectors.
        let (precond, matrix) = match o.solver {
            PressureSolver::Multigrid => (
                Precond::Multigrid(Multigrid::new(2)),
                MATRIX + usize::from(grid.is_3d()),
            ),
            PressureSolver::IncompleteCholesky => (
                Precond::IncompleteCholesky(
                    IncompleteCholesky::new(),
                    Stencil5::new(grid.nx, grid.ny, bc.periodic(0), bc.periodic(1)),
                ),
                0,
            ),
        };
        let keep_density =
            matches!(precond, Precond::IncompleteCholesky(..)) || !crate::second_material(scene);
        Projector {
            tol: o.tolerance_in(scene),
            max_iter: o.max_iterations,
            precond,
            scratch: Scratch::reserve(shared, WORK.max(matrix) * n),
            increment: increments.then(efsi_core::Field::default),
            fields: FieldScratch::reserve(shared, grid, usize::from(increments)),
            gravity: scene.gravity.planar(),
            gravity3: scene.gravity.xyz(),
            // The body force, built before, decides.
            hydrostatic: shared
                .get::<Option<hydrostatic::Hydrostatic>>()
                .copied()
                .flatten(),
            // A copy of the density (one value where it is uniform) where it decides alone
            // whether to assemble (assembling and setting up every step is dearer than the
            // comparison); where a second
            // material changes the density nearly every step, the multigrid's own matrix is
            // compared with the assembled one instead.
            set_up_for: keep_density.then(Density::default),
        }
    }

    /// The scene's divergence tolerance (`numerics.projection.tolerance` in force).
    pub(crate) fn tolerance(&self) -> f64 {
        self.tol
    }
}

/// Assemble the projection's five-point matrix `Σ_f (A_f/(ρ_f h)) (p_C − p_F)` from the density
/// (rows in parallel).
pub(crate) fn assemble(a: &mut Stencil5, grid: &Grid, bc: &BoundarySet, rho: &efsi_core::Field) {
    assemble_into([&mut a.diag, &mut a.east, &mut a.north], grid, bc, rho);
}

/// [`assemble`] into the diagonal and the east and north couplings of a matrix (`nx·ny` values
/// each, rows of `nx`).
fn assemble_into(
    [diag, east, north]: [&mut [f64]; 3],
    grid: &Grid,
    bc: &BoundarySet,
    rho: &efsi_core::Field,
) {
    let cells = Assembly {
        grid,
        rho,
        periodic: [bc.periodic(0), bc.periodic(1)],
    };
    cells.couplings(east, north);
    let outflow = |s: Side| *bc.get(s) == Boundary::Outflow;
    let outflow = [Side::XMin, Side::XMax, Side::YMin, Side::YMax].map(outflow);
    cells.diagonal(diag, east, north, outflow);
}

/// A two-dimensional grid's cells as the projection's matrix couples them: the grid, the
/// density, and which of the axes x, y are periodic.
struct Assembly<'a> {
    grid: &'a Grid,
    rho: &'a efsi_core::Field,
    periodic: [bool; 2],
}

impl Assembly<'_> {
    /// The couplings `A_f/(ρ_f h)` across each cell's east and north faces (zero across a
    /// side that is not periodic), with `ρ_f` the faces' density.
    fn couplings(&self, east: &mut [f64], north: &mut [f64]) {
        let (grid, rho) = (self.grid, self.rho);
        let (nx, ny, m) = (grid.nx, grid.ny, &grid.metric);
        let (dx, dy) = (grid.dx, grid.dy);
        let [px, py] = self.periodic;
        par::rows(east, nx).for_each(|j, row| {
            let jj = j as isize;
            for (i, e) in row.iter_mut().enumerate() {
                let ii = i as isize;
                *e = if i + 1 < nx || px {
                    let ie = if i + 1 < nx { ii + 1 } else { 0 };
                    m.rx(ii + 1) * dy / (operators::face_density(rho[(ii, jj)], rho[(ie, jj)]) * dx)
                } else {
                    0.0
                };
            }
        });
        par::rows(north, nx).for_each(|j, row| {
            let jj = j as isize;
            for (i, n) in row.iter_mut().enumerate() {
                let ii = i as isize;
                *n = if j + 1 < ny || py {
                    let jn = if j + 1 < ny { jj + 1 } else { 0 };
                    m.rc(ii) * dx / (operators::face_density(rho[(ii, jj)], rho[(ii, jn)]) * dy)
                } else {
                    0.0
                };
            }
        });
    }

    /// The diagonal: the sum of a cell's four couplings (`east`, `north` and its neighbours'),
    /// plus on each `outflow` side (x_min, x_max, y_min, y_max) the coupling to `p = 0` on the
    /// boundary face, half a cell away.
    fn diagonal(&self, diag: &mut [f64], east: &[f64], north: &[f64], outflow: [bool; 4]) {
        let (grid, rho) = (self.grid, self.rho);
        let (nx, ny, m) = (grid.nx, grid.ny, &grid.metric);
        let (dx, dy) = (grid.dx, grid.dy);
        let [px, py] = self.periodic;
        let [o_xmin, o_xmax, o_ymin, o_ymax] = outflow;
        par::rows(diag, nx).for_each(|j, row| {
            let jj = j as isize;
            for (i, dk) in row.iter_mut().enumerate() {
                let k = j * nx + i;
                let ii = i as isize;
                let w = if i > 0 {
                    east[k - 1]
                } else if px {
                    east[k + nx - 1]
                } else {
                    0.0
                };
                let s = if j > 0 {
                    north[k - nx]
                } else if py {
                    north[k + (ny - 1) * nx]
                } else {
                    0.0
                };
                let mut d = east[k] + north[k] + w + s;
                // Outflow sides: p = 0 on the boundary face, half a cell away.
                let r = rho[(ii, jj)];
                if i == 0 && o_xmin {
                    d += 2.0 * m.rx(0) * dy / (r * dx);
                }
                if i + 1 == nx && o_xmax {
                    d += 2.0 * m.rx(ii + 1) * dy / (r * dx);
                }
                if j == 0 && o_ymin {
                    d += 2.0 * m.rc(ii) * dx / (r * dy);
                }
                if j + 1 == ny && o_ymax {
                    d += 2.0 * m.rc(ii) * dx / (r * dy);
                }
                *dk = d;
            }
        });
    }
}

impl Stage for ProjectionStage {
    fn projects(&self) -> bool {
        true
    }

    /// The incremental scheme starts from the hydrostatic pressure, the seed's from zero
    /// ([`Projector::initialize`]).
    fn initialize(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        self.projector.initialize(grid, bc, state, self.incremental)
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let tol = self.projector.tol;
        self.projector.project(ctx, state, tol, self.incremental)
    }
}

impl Projector {
    /// The starting pressure: with `hydrostatic` (the incremental scheme, and the coupled
    /// elastic step's `Coupled`) the one that balances gravity, `p⁰` with `g − ∇p⁰/ρ`
    /// divergence-free (the hydrostatic pressure where the density is layered), so that the
    /// first step's predictor already cancels what gravity cannot move; else the carrier's
    /// hydrostatic pressure where the seed's scheme splits gravity ([`hydrostatic`]: the
    /// excess pressure starts from zero), or zero. The solve is an increment's where this
    /// projector's are ([`Projector::new`]), as the first step's will be.
    pub(crate) fn initialize(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
        hydrostatic: bool,
    ) -> Result<(), StageError> {
        state.p.fill(0.0);
        // Gravity in the grid's frame (a frame acceleration set before the first step counts).
        let a = state.frame_acceleration;
        let (gx, gy) = (self.gravity.0 - a.0, self.gravity.1 - a.1);
        if let Some(h) = self.hydrostatic.filter(|_| !hydrostatic) {
            // The seed's scheme with the split: the carrier's hydrostatic pressure, the excess
            // pressure zero.
            let e = hydrostatic::Hydrostatic::effective(self.gravity3, state);
            h.add(grid, bc, e, &mut state.p, 1.0);
            return Ok(());
        }
        if !hydrostatic || (gx, gy) == (0.0, 0.0) {
            return Ok(());
        }
        // Project the field g (on the faces the flow may cross) with Δt = 1: what the
        // projection removes is ∇p⁰/ρ. The divergence to 1e-12 of its initial size.
        let (u0, v0) = (state.u.clone(), state.v.clone());
        let w0 = state.w.clone();
        let (nx, ny) = (grid.nx, grid.ny);
        let (ux, vy) = (bc.normal_faces(0, nx), bc.normal_faces(1, ny));
        state.u.fill(0.0);
        state.v.fill(0.0);
        if let Some(w) = state.w.as_mut().filter(|_| grid.is_3d()) {
            // Gravity has no z component: w = 0; u and v on the unknown faces of every plane.
            w.fill(0.0);
            let x = Region::of(grid, Stagger::XFace).range(0, ux.lo, ux.hi);
            x.for_each(&mut state.u, |_, u| u.fill(gx));
            let y = Region::of(grid, Stagger::YFace).range(1, vy.lo, vy.hi);
            y.for_each(&mut state.v, |_, v| v.fill(gy));
        } else {
            for j in 0..ny as isize {
                for i in ux.lo..ux.hi {
                    state.u[(i, j)] = gx;
                }
            }
            for j in vy.lo..vy.hi {
                for i in 0..nx as isize {
                    state.v[(i, j)] = gy;
                }
            }
        }
        bc.fill_velocity3(
            grid,
            &mut state.u,
            &mut state.v,
            state.w.as_mut(),
            0.0,
            true,
        );
        let ctx = StepContext {
            grid,
            bc,
            t: 0.0,
            dt: 1.0,
            step: 0,
            start_velocity: None,
        };
        let tol = 1e-12 * gx.hypot(gy) / grid.dx.min(grid.dy);
        let solved = self.solve(&ctx, state, tol, self.increment.is_some());
        state.u.copy_from(&u0);
        state.v.copy_from(&v0);
        if let (Some(w), Some(w0)) = (state.w.as_mut(), w0.as_ref()) {
            w.copy_from(w0);
        }
        if solved.is_err() || !state.p.data().iter().all(|p| p.is_finite()) {
            // A gravity too large for floating point (1e300): start from p = 0 as the seed's
            // scheme does; the first step then reports what overflows, stage and cell named.
            state.p.fill(0.0);
        }
        Ok(())
    }
}

impl Projector {
    /// The projection with the divergence tolerance `tol` (the scene's): the whole pressure
    /// from the last step's, or with `increment` (the incremental scheme, a coupled elastic
    /// step) the increment on the pressure already applied. With the seed's scheme's split of
    /// gravity ([`hydrostatic`]) the pressure solved for is the excess over the carrier's
    /// hydrostatic pressure, which is then added back.
    pub(crate) fn project(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        tol: f64,
        increment: bool,
    ) -> Result<StageStats, StageError> {
        let stats = self.solve(ctx, state, tol, increment)?;
        if let Some(h) = &self.hydrostatic {
            let e = hydrostatic::Hydrostatic::effective(self.gravity3, state);
            h.add(ctx.grid, ctx.bc, e, &mut state.p, 1.0);
        }
        Ok(stats)
    }

    /// [`Projector::project`] without adding the carrier's hydrostatic pressure back (also
    /// the starting pressure's solve of [`Projector::initialize`], with a stricter `tol`).
    fn solve(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        tol: f64,
        increment: bool,
    ) -> Result<StageStats, StageError> {
        let grid = ctx.grid;
        self.set_up(grid, ctx.bc, &state.rho);
        let mut pool = self.scratch.lock();
        let (vectors, _) = pool.split_at_mut(WORK * grid.cells());
        let [b, x, weight, r, pw, q] = scratch::take::<WORK>(vectors, grid.cells());
        rhs_and_weights(grid, state, ctx.dt, b, weight);
        // An increment on the pressure already applied (the incremental scheme's predictor,
        // or the coupled elastic step's) from zero, else the whole pressure from the last
        // step's.
        let incremental = increment && self.increment.is_some();
        if incremental {
            x.fill(0.0);
        } else {
            copy_pressure(grid, &state.p, x);
        }
        let singular = !ctx.bc.has_pressure_reference();
        if singular {
            let mean = b.iter().sum::<f64>() / b.len() as f64;
            b.iter_mut().for_each(|b| *b -= mean);
        }
        let norm = Norm::MaxWeighted(weight);
        let null = if singular {
            NullSpace::Constants
        } else {
            NullSpace::None
        };
        let st = self
            .precond
            .solve([r, pw, q], b, x, tol, self.max_iter, norm, null);
        if !st.converged {
            return Err(StageError {
                stage: "projection".into(),
                message: format!(
                    "pressure solve did not converge in {} iterations: max|∇·u|·Δt = {:.3e} > tolerance {:.1e}; \
                     raise numerics.projection.max_iterations or loosen numerics.projection.tolerance",
                    st.iterations, st.residual, tol
                ),
            });
        }
        if singular {
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            par::chunks(&mut *x).for_each(|_, x| x.iter_mut().for_each(|p| *p -= mean));
        }
        // The increment's field from the pool, zeroed, for the correction.
        let lent = self.increment.as_mut().filter(|_| incremental);
        if let Some(f) = lent {
            self.fields.swap(std::slice::from_mut(f), true);
        }
        correct(&mut self.increment, ctx, state, x, incremental);
        if let Some(f) = self.increment.as_mut().filter(|_| incremental) {
            self.fields.swap(std::slice::from_mut(f), false);
        }
        drop(pool);
        if cfg!(debug_assertions) {
            check_divergence(ctx, state, tol);
        }
        Ok(StageStats { solve: Some(st) })
    }

    /// The matrix and its preconditioner for the density `rho`, unless they are set up for
    /// it already (see [`Projector::set_up_for`]).
    fn set_up(&mut self, grid: &Grid, bc: &BoundarySet, rho: &efsi_core::Field) {
        let rd = rho.data();
        let same = self.set_up_for.as_ref().is_some_and(|s| s.is(rd));
        if same {
            return;
        }
        match &mut self.precond {
            Precond::Multigrid(mg) if grid.is_3d() => {
                let mut pool = self.scratch.lock();
                let [diag, east, north, top] = scratch::take::<4>(&mut pool, grid.cells());
                let periodic = three_d::periodic_axes(bc, grid);
                three_d::assemble_3d_into([diag, east, north, top], grid, periodic, rho);
                let a = Stencil5View {
                    nx: grid.nx,
                    ny: grid.ny,
                    nz: grid.nz,
                    periodic_x: periodic[0],
                    periodic_y: periodic[1],
                    periodic_z: periodic[2],
                    diag,
                    east,
                    north,
                    top,
                };
                if self.set_up_for.is_some() || !mg.is_set_up_for(a) {
                    mg.setup_view(a);
                }
            }
            Precond::Multigrid(mg) => {
                let mut pool = self.scratch.lock();
                let [diag, east, north] = scratch::take::<MATRIX>(&mut pool, grid.cells());
                assemble_into([diag, east, north], grid, bc, rho);
                let a = Stencil5View {
                    nx: grid.nx,
                    ny: grid.ny,
                    nz: 1,
                    periodic_x: bc.periodic(0),
                    periodic_y: bc.periodic(1),
                    periodic_z: false,
                    diag,
                    east,
                    north,
                    top: &[],
                };
                // Without a copy of the density, the matrix is compared with the one the
                // multigrid holds.
                if self.set_up_for.is_some() || !mg.is_set_up_for(a) {
                    mg.setup_view(a);
                }
            }
            Precond::IncompleteCholesky(ic, a) => {
                assemble(a, grid, bc, rho);
                ic.factor(a);
            }
        }
        if let Some(s) = &mut self.set_up_for {
            s.keep(rd);
        }
    }
}

/// The pressure solved for, `x` (per cell), applied: `V^{n+1} = V^{n+2/3} − Δt ∇φ/ρ` on the
/// unknown faces with `φ` the increment (held in `increment`) added to the pressure already
/// there (`incremental`), or the whole pressure in the seed's scheme.
fn correct(
    increment: &mut Option<efsi_core::Field>,
    ctx: &StepContext,
    state: &mut State,
    x: &[f64],
    incremental: bool,
) {
    let grid = ctx.grid;
    let nx = grid.nx;
    let target = match increment {
        Some(f) if incremental => f,
        _ => &mut state.p,
    };
    Region::of(grid, Stagger::Cell).for_each(&mut *target, |line, row| {
        row.copy_from_slice(&x[line.n * nx..(line.n + 1) * nx]);
    });
    ctx.bc.fill_scalar(grid, target, true);
    let increment = increment.as_ref().filter(|_| incremental);
    if let Some(f) = increment {
        for (p, x) in state.p.data_mut().iter_mut().zip(f.data()) {
            *p += x;
        }
    }
    let (bc, dt) = (ctx.bc, ctx.dt);
    let phi = increment.unwrap_or(&state.p);
    if let Some(w) = state.w.as_mut().filter(|_| grid.is_3d()) {
        let faces = three_d::unknown_faces(bc, grid);
        let vel = [&mut state.u, &mut state.v, w];
        three_d::subtract_gradient_3d(grid, faces, phi, &state.rho, dt, vel);
    } else {
        subtract_gradient(grid, bc, phi, &state.rho, dt, &mut state.u, &mut state.v);
    }
}

/// The projection's right-hand side `b` (the velocity's divergence over Δt, per cell) and the
/// residual weights Δt²/dV of the norm it is solved to.
fn rhs_and_weights(grid: &Grid, state: &State, dt: f64, b: &mut [f64], weight: &mut [f64]) {
    if let Some(w) = state.w.as_ref().filter(|_| grid.is_3d()) {
        three_d::divergence_rhs_3d(grid, [&state.u, &state.v, w], dt, b);
        weight.fill(dt * dt / (grid.dx * grid.dy * grid.dz));
    } else {
        divergence_rhs(grid, &state.u, &state.v, dt, b);
        // The residual weights Δt²/dV.
        par::rows(&mut *weight, grid.nx).for_each(|_, row| {
            for (i, w) in row.iter_mut().enumerate() {
                *w = dt * dt / grid.cell_volume(i as isize);
            }
        });
    }
}

/// The pressure `p` into `x` (per cell, rows of `nx`): the solve's initial guess when it
/// solves for the whole pressure.
fn copy_pressure(grid: &Grid, p: &efsi_core::Field, x: &mut [f64]) {
    if grid.is_3d() {
        let nx = grid.nx;
        let cells = Region::of(grid, Stagger::Cell);
        par::rows(&mut *x, nx).for_each(|r, row| {
            row.copy_from_slice(p.at(&cells.line(r), [0; 3]));
        });
    } else {
        par::rows(&mut *x, grid.nx).for_each(|j, row| {
            for (i, x) in row.iter_mut().enumerate() {
                *x = p[(i as isize, j as isize)];
            }
        });
    }
}

impl Precond {
    /// Solve the projection's system for `x` (from its initial guess) by the conjugate
    /// gradient with this preconditioner, to `tol` in `norm`, in at most `max_iter`
    /// iterations; `work` holds the solver's vectors; `null` the system's null space (the
    /// constants where no side fixes the pressure), which the solver keeps its iteration off.
    fn solve(
        &mut self,
        work: [&mut [f64]; 3],
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
        norm: Norm<'_>,
        null: NullSpace,
    ) -> SolveStats {
        match self {
            Precond::Multigrid(mg) => {
                let a = &mut mg.fine_matrix();
                solve_norm_in(work, a, &*mg, b, x, tol, max_iter, norm, null)
            }
            Precond::IncompleteCholesky(ic, a) => {
                solve_norm_in(work, a, &*ic, b, x, tol, max_iter, norm, null)
            }
        }
    }
}

/// `b = −(net volume outflux)/Δt` per cell, as `operators::net_outflux` computes it, over slices
/// (it vectorises).
fn divergence_rhs(grid: &Grid, u: &efsi_core::Field, v: &efsi_core::Field, dt: f64, b: &mut [f64]) {
    let nx = grid.nx;
    let (rx, rc) = (grid.metric.rx_row(nx + 1), grid.metric.rc_row(nx));
    let (dx, dy) = (grid.dx, grid.dy);
    let cells = Region::of(grid, Stagger::Cell);
    par::rows(b, nx).for_each(|j, row| {
        let line = cells.line(j);
        let (uw, ue) = (u.at(&line, [0, 0, 0]), u.at(&line, [1, 0, 0]));
        let (vs, vn) = (v.at(&line, [0, 0, 0]), v.at(&line, [0, 1, 0]));
        let (rw, re) = (&rx[..nx], &rx[1..=nx]);
        for i in 0..nx {
            let out = (re[i] * ue[i] - rw[i] * uw[i]) * dy + rc[i] * (vn[i] - vs[i]) * dx;
            row[i] = -out / dt;
        }
    });
}

/// The postcondition `max |∇·V^{n+1}|·Δt ≤ tol` (debug builds), the velocity's ghosts
/// filled for the step's end first.
fn check_divergence(ctx: &StepContext, state: &mut State, tol: f64) {
    let grid = ctx.grid;
    ctx.bc.fill_velocity3(
        grid,
        &mut state.u,
        &mut state.v,
        state.w.as_mut(),
        ctx.t + ctx.dt,
        false,
    );
    let d = operators::max_abs_div(grid, &state.velocity()) * ctx.dt;
    // A non-finite divergence is not this check's to report: the scheduler names the first
    // non-finite velocity (and the stage) right after the stage.
    debug_assert!(
        !d.is_finite() || d <= tol * (1.0 + 1e-6) + 1e-15 || singular_inconsistent(ctx, state),
        "projection postcondition: max|∇·u|·Δt = {d:e} > {tol:e}"
    );
}

/// `V ← V − Δt ∇p/ρ` on the unknown faces (`bc.normal_faces`), with the face density of
/// [`operators::face_density`]: the projection's velocity update, and the incremental scheme's
/// predictor with the last step's pressure. `p`'s ghosts must be filled.
pub(crate) fn subtract_gradient(
    grid: &Grid,
    bc: &BoundarySet,
    p: &efsi_core::Field,
    rho: &efsi_core::Field,
    dt: f64,
    u: &mut efsi_core::Field,
    v: &mut efsi_core::Field,
) {
    let ux = bc.normal_faces(0, grid.nx);
    let vy = bc.normal_faces(1, grid.ny);
    let (cx, cy) = (dt / grid.dx, dt / grid.dy);
    // Over lines of faces (it vectorises): the cells east and west of each x-face, north
    // and south of each y-face.
    let faces = Region::of(grid, Stagger::XFace).range(0, ux.lo.max(0), ux.hi.max(0));
    faces.for_each(u, |line, u| {
        let (pe, pw) = (p.at(&line, [0, 0, 0]), p.at(&line, [-1, 0, 0]));
        let (re, rw) = (rho.at(&line, [0, 0, 0]), rho.at(&line, [-1, 0, 0]));
        for (t, u) in u.iter_mut().enumerate() {
            *u -= cx * (pe[t] - pw[t]) / operators::face_density(re[t], rw[t]);
        }
    });
    let faces = Region::of(grid, Stagger::YFace).range(1, vy.lo, vy.hi);
    faces.for_each(v, |line, v| {
        let (pn, ps) = (p.at(&line, [0, 0, 0]), p.at(&line, [0, -1, 0]));
        let (rn, rs) = (rho.at(&line, [0, 0, 0]), rho.at(&line, [0, -1, 0]));
        for (i, v) in v.iter_mut().enumerate() {
            *v -= cy * (pn[i] - ps[i]) / operators::face_density(rn[i], rs[i]);
        }
    });
}

/// A closed domain whose boundary velocities carry a net flux cannot be made divergence-free
/// everywhere; the postcondition does not apply (only reachable with inconsistent scenes).
fn singular_inconsistent(ctx: &StepContext, state: &State) -> bool {
    let (g, vel) = (ctx.grid, state.velocity());
    let [net] = Region::of(g, Stagger::Cell).sum(|l| {
        [l.indices()
            .map(|c| operators::net_outflux(g, &vel, c))
            .sum()]
    });
    !ctx.bc.has_pressure_reference() && net.abs() > 1e-12
}
