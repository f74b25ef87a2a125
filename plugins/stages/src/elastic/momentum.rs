//! The implicit-momentum stage `momentum`: the viscous step's successor in a scene with an
//! elastic solid, one algorithm in three sub-steps the scheduler runs, refreshes after and
//! times in turn (`efsi_core::SubStep`):
//!
//! 1. **elastic** — `V^{n+1/3} → V^{n+2/3}`: the implicit viscous–elastic system (seed Eqs.
//!    15–20; the parent module), as a split step (`A δ = b`, then the projection alone) or a
//!    coupled one (`A δ + ΔtĜ p = b` with `∇·(V + δ) = 0`, the `coupled` module), chosen by
//!    the strategy `numerics.elastic.coupling` ([`ElasticCoupling`]: `Split`, `Coupled`,
//!    `Auto`). `Auto` chooses by Δt and takes the step split when its coupled solve fails: an
//!    outcome of the step, which the next two sub-steps follow.
//! 2. **projection** — `V^{n+2/3} → V^{n+1}`, `∇·V^{n+1} = 0` (seed Eqs. 21–23,
//!    `crate::projection`): after a split step the whole pressure (or, in the incremental
//!    scheme, its increment); after a coupled step the increment on the pressure the coupled
//!    solve applied, which removes the divergence it left.
//! 3. **deformation** — `B̃^{n+1} = B̃(V^{n+1})` (seed Eqs. 24–25) with the step's θ, the
//!    Picard pass unless the step was coupled beyond the split step's wave limit, then the
//!    next step's rates, the end-of-step stress and the strain energy (the `deformation`
//!    module).
//!
//! What the first sub-step decides (coupled or split) is the stage's own field, read by the
//! other two in the same step; nothing else carries it. The stage's Δt limit is the
//! elastic-wave Courant limit of its strategy (`Auto` lifts it to the coupled step's where it
//! pays, [`Stage::lift_dt`]). Before the first step the projection sub-step alone projects the
//! initial velocity ([`SubStep::projects`]), an increment with `Coupled` (the pressure the
//! coupled step will complete), and the run starts from the hydrostatic pressure in the
//! incremental scheme and with `Coupled`.

use super::bodies::{ElasticBody, Fractions, elastic_bodies, viscosities_of};
use super::choice::{StepScheme, may_couple};
use super::coupling;
use super::deformation::DeformationStage;
use super::law::shared_laws;
use super::limits::shared_wave_limits;
use super::solve::{ElasticOperator, ElasticStage, Scratch};
use super::{B, ElasticCoupling, ElasticOptions, ElasticPreconditioner, Kernels};
use crate::block_multigrid::ViscousBlocks;
use crate::faces::UnknownFaces;
use crate::projection::{self, Projector};
use crate::viscous_operator::Coefficients;
use efsi_core::scene::{Boundary, Options, OptionsDecl, Side};
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats,
    State, StepContext, SubStep,
};
use efsi_linalg::BiCgStab;

/// The implicit-momentum stage plugin (phase Elastic): the elastic solve, the projection and
/// the deformation update as sub-steps (module docs).
pub struct Momentum;

/// The sub-steps, in order ([`MomentumStage::run_sub`]).
const SUB_STEPS: [SubStep; 3] = [
    SubStep {
        name: "elastic",
        // The pressure only in a coupled step, which leaves its pressure for the projection
        // to complete.
        writes: &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            B,
            FieldId::Pressure,
        ],
        projects: false,
    },
    SubStep {
        name: "projection",
        writes: &projection::WRITES,
        projects: true,
    },
    SubStep {
        name: "deformation",
        writes: &[B],
        projects: false,
    },
];

impl StagePlugin for Momentum {
    fn name(&self) -> &'static str {
        "momentum"
    }
    fn phase(&self) -> Phase {
        Phase::Elastic
    }
    fn reads(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            FieldId::Pressure,
            FieldId::Density,
            FieldId::Viscosity,
            FieldId::SolidFraction,
            B,
        ]
    }
    fn writes(&self) -> &'static [FieldId] {
        &[
            FieldId::VelocityX,
            FieldId::VelocityY,
            FieldId::VelocityZ,
            B,
            FieldId::Pressure,
        ]
    }
    /// Planar, axisymmetric and three-dimensional grids: the elastic kernels, the split and
    /// the coupled step run over the grid's axes and shear pairs.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn sub_steps(&self) -> &'static [SubStep] {
        &SUB_STEPS
    }
    fn limit_depends_on(&self) -> &'static str {
        "numerics.elastic.wave_courant (coupled_wave_courant with the coupled step) and the solid's stiffness: the elastic wave speed"
    }
    fn needed(&self, _scene: &Scene, options: &Options) -> bool {
        crate::elastic_solid(options)
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ElasticOptions>())
    }
    fn outputs(&self) -> &'static [efsi_core::OutputDecl] {
        super::outputs::OUTPUTS
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let mode = coupling(options);
        let incremental = crate::incremental_pressure(options);
        let elastic = elastic_stage(scene, options, grid, bc, shared)?;
        // `numerics.projection` as checked (its defaults in a pipeline built without the
        // projection stage's plugin, which declares it).
        let proj: projection::ProjectionOptions = options.section_or_default(scene.numerics.preset);
        let increments = incremental || may_couple(options);
        let projector = Projector::new(scene, &proj, grid, bc, shared, increments);
        let deformation = deformation_stage(scene, options, grid, bc, shared)?;
        Ok(Box::new(MomentumStage {
            elastic,
            projector,
            deformation,
            incremental,
            hydrostatic: incremental || mode == ElasticCoupling::Coupled,
            // Until the first step says otherwise (the projection of the initial velocity).
            coupled: mode == ElasticCoupling::Coupled,
        }))
    }
}

/// The elastic solve's sub-step, built for the scene.
fn elastic_stage(
    scene: &Scene,
    options: &Options,
    grid: &Grid,
    bc: &BoundarySet,
    shared: &mut efsi_core::Resources,
) -> Result<ElasticStage, String> {
    let bodies = elastic_bodies(options)?;
    let laws = shared_laws(scene, options, &bodies, shared)?;
    let ks = kernels(scene, grid, bc, &bodies);
    let n = ks[0].faces.len();
    let o: &ElasticOptions = options.section()?;
    let limits = shared_wave_limits(scene, options, grid, &bodies, &laws, shared)?;
    let periodic = Side::of(grid.dims())
        .iter()
        .any(|&s| matches!(scene.boundaries.get(s), Boundary::Periodic));
    let schemes = [false, true].map(|coupled| step_scheme(o, coupled, periodic));
    let theta = viscous_theta(scene, options);
    let coupled_work = if may_couple(options) {
        let proj: projection::ProjectionOptions = options.section_or_default(scene.numerics.preset);
        Some(super::coupled::Coupling::new(
            grid,
            bc,
            n,
            o,
            proj.tolerance_in(scene),
        ))
    } else {
        None
    };
    let fields = |n: usize| (0..n).map(|_| Field::zeros(grid)).collect::<Vec<_>>();
    let tensor = || fields(super::Deformation::components(grid));
    let edges = || fields(super::Deformation::components(grid) - 3);
    // A body's on its window, shaped when the window is placed (`ElasticStage::fit`).
    let per_body = || {
        bodies
            .iter()
            .map(|b| {
                if b.index.is_none() {
                    tensor()
                } else {
                    Vec::new()
                }
            })
            .collect::<Vec<_>>()
    };
    Ok(ElasticStage {
        mode: coupling(options),
        split_dt: limits.split,
        wave_step: limits.wave_step,
        options: o.clone(),
        phis: Fractions::new(&bodies),
        laws,
        tau: per_body(),
        tau_n: per_body(),
        op: ElasticOperator {
            ks,
            frame: frame(scene, grid, bc),
            db: per_body(),
            mass: vec![0.0; n],
            c: 0.0,
            theta_dt: 0.0,
            mu: Field::zeros(grid),
            mu_edges: edges(),
            viscous: Coefficients::new(grid, UnknownFaces::new(grid, bc)),
            dm: vec![0.0; n],
        },
        scheme: schemes[0],
        theta,
        rhs: vec![0.0; n],
        delta: vec![0.0; n],
        diag: vec![0.0; n],
        solver: BiCgStab::new(n),
        tol: o.tolerance,
        max_iter: o.max_iterations,
        implicit: o.implicit,
        schemes,
        blocks: ViscousBlocks::new(grid, bc),
        eta: Field::zeros(grid),
        eta_k: edges(),
        stiffness: Field::zeros(grid),
        eta_coefficients: Coefficients::new(grid, UnknownFaces::new(grid, bc)),
        eta_dm: vec![0.0; n],
        eta_diag: vec![0.0; n],
        scratch: Scratch {
            xu: Field::zeros(grid),
            xv: Field::zeros(grid),
            xw: grid.is_3d().then(|| Field::zeros(grid)),
            dtau: per_body(),
        },
        coupling: coupled_work,
        bodies,
    })
}

/// The whole grid and its sides, for the bodies' windows.
fn frame(scene: &Scene, grid: &Grid, bc: &BoundarySet) -> super::bodies::Frame {
    super::bodies::Frame {
        grid: grid.clone(),
        bc: bc.clone(),
        sides: scene.boundaries.clone(),
    }
}

/// One set of kernels per elastic body, each with its own solid viscosity.
fn kernels(scene: &Scene, grid: &Grid, bc: &BoundarySet, bodies: &[ElasticBody]) -> Vec<Kernels> {
    bodies
        .iter()
        .map(|b| {
            let (mu_f, mu_s) = viscosities_of(scene, b);
            match b.index {
                None => Kernels::new(grid, bc, mu_f, mu_s),
                // Placed on the body's window when its fraction is known.
                Some(_) => {
                    let first = super::bodies::Place::first(grid);
                    Kernels::windowed(grid, bc, &scene.boundaries, first, mu_f, mu_s)
                }
            }
        })
        .collect()
}

/// The split (`coupled` false) or coupled step's scheme from the options; `periodic` if the
/// scene has a periodic side.
fn step_scheme(o: &ElasticOptions, coupled: bool, periodic: bool) -> StepScheme {
    StepScheme {
        theta: o.stretch_theta(coupled),
        // The coupled step's momentum takes the stress at its stretching's θ (see `coupled`,
        // "The stress at θ"); the split step's weight depends on the step's elastic-wave
        // Courant number, set per step (`ElasticStage::set_scheme`).
        alpha: if coupled { o.stretch_theta(true) } else { 1.0 },
        preconditioner: match o.preconditioner {
            // The coupled step keeps the multigrid: with Jacobi for its velocity block its
            // FGMRES stagnates.
            ElasticPreconditioner::Auto if !coupled && periodic => ElasticPreconditioner::Jacobi,
            ElasticPreconditioner::Auto => ElasticPreconditioner::Multigrid,
            p => p,
        },
    }
}

/// The viscous stage's implicit weight θ where the scene has one (the elastic system carries
/// the same viscous term), else 0.
fn viscous_theta(scene: &Scene, options: &Options) -> f64 {
    if crate::viscous::Viscous.needed(scene, options) {
        options
            .section_or_default::<crate::viscous::ViscousOptions>(scene.numerics.preset)
            .theta
    } else {
        0.0
    }
}

/// The deformation update's sub-step, built for the scene.
fn deformation_stage(
    scene: &Scene,
    options: &Options,
    grid: &Grid,
    bc: &BoundarySet,
    shared: &mut efsi_core::Resources,
) -> Result<DeformationStage, String> {
    let bodies = elastic_bodies(options)?;
    let laws = shared_laws(scene, options, &bodies, shared)?;
    let o: &ElasticOptions = options.section()?;
    let limits = shared_wave_limits(scene, options, grid, &bodies, &laws, shared)?;
    Ok(DeformationStage {
        laws,
        ks: kernels(scene, grid, bc, &bodies),
        frame: frame(scene, grid, bc),
        phis: Fractions::new(&bodies),
        mode: coupling(options),
        limits,
        walls: Side::of(grid.dims())
            .iter()
            .map(|&side| {
                matches!(
                    scene.boundaries.get(side),
                    Boundary::NoSlip
                        | Boundary::MovingWall { .. }
                        | Boundary::FreeSlip
                        | Boundary::Symmetry
                )
            })
            .collect(),
        thetas: [o.stretch_theta(false), o.stretch_theta(true)],
        first: bodies
            .iter()
            .map(|b| match b.index {
                None => (0..super::Deformation::components(grid))
                    .map(|_| Field::zeros(grid))
                    .collect(),
                Some(_) => Vec::new(),
            })
            .collect(),
        bodies,
    })
}

/// The built stage: its three sub-steps' parts and what the first tells the others.
struct MomentumStage {
    elastic: ElasticStage,
    projector: Projector,
    deformation: DeformationStage,
    /// Whether the scene runs the incremental pressure correction (never with a strategy that
    /// may couple).
    incremental: bool,
    /// Whether the run starts from the hydrostatic pressure (the incremental scheme, and
    /// `Coupled`) rather than from zero.
    hydrostatic: bool,
    /// Whether this step's elastic sub-step was a coupled one (set by it; before the first
    /// step, whether the strategy is `Coupled`).
    coupled: bool,
}

impl Stage for MomentumStage {
    /// The sub-steps in order, each followed by the refresh of the velocity's and the
    /// pressure's ghosts the scheduler makes between them (it runs them by
    /// [`run_sub`](Self::run_sub) itself, and checks them).
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let mut stats = StageStats::default();
        for k in 0..SUB_STEPS.len() {
            let s = self.run_sub(k, ctx, state)?;
            stats.solve = s.solve.or(stats.solve);
            let (g, bc) = (ctx.grid, ctx.bc);
            let t = ctx.t + ctx.dt;
            bc.fill_velocity3(g, &mut state.u, &mut state.v, state.w.as_mut(), t, false);
            bc.fill_scalar(g, &mut state.p, true);
        }
        Ok(stats)
    }

    fn run_sub(
        &mut self,
        k: usize,
        ctx: &StepContext,
        state: &mut State,
    ) -> Result<StageStats, StageError> {
        match k {
            0 => {
                let (stats, coupled) = self.elastic.run(ctx, state)?;
                self.coupled = coupled;
                Ok(stats)
            }
            1 => {
                let tol = self.projector.tolerance();
                let increment = self.incremental || self.coupled;
                self.projector.project(ctx, state, tol, increment)
            }
            _ => self.deformation.run(ctx, state, self.coupled),
        }
    }

    fn init_state(&self, grid: &Grid, state: &mut State) {
        self.deformation.init_state(grid, state);
    }

    /// The elastic sub-step's B and rates from the initial velocity, then the starting
    /// pressure ([`Projector::initialize`]).
    fn initialize(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        self.elastic.initialize(state)?;
        self.projector.initialize(grid, bc, state, self.hydrostatic)
    }

    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        self.deformation.max_dt(grid, state, cfl)
    }

    fn lift_dt(&self, grid: &Grid, state: &State, own: f64, others: Option<f64>) -> Option<f64> {
        self.deformation.lift_dt(grid, state, own, others)
    }
}
