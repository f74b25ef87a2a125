//! The stage contract and the scheduler.
//!
//! One time step is a sequence of **phases** named by the core ([`Phase`], seed Fig. 1).
//! Physics attaches to them as **stage plugins** ([`StagePlugin`]): each declares its phase,
//! the fields it reads and writes, optional ordering constraints within its phase, and whether
//! a scene needs it. [`Pipeline::build`] assembles the pipeline from a scene with only the
//! stages it needs, checks the declarations once (every field read is provided; stages of one
//! phase that touch the same field are explicitly ordered), allocates only the declared fields,
//! and afterwards runs and times the stages. Nobody edits the time-step function to add
//! physics (STYLE.md §2–3).
//!
//! A stage may run as several **sub-steps** ([`StagePlugin::sub_steps`], [`Stage::run_sub`]):
//! one algorithm whose parts decide together within a step (the implicit-momentum stage: its
//! elastic solve, projection and deformation update, where the elastic solve's outcome — a
//! coupled or a split step — decides what the other two do). The scheduler runs and times
//! each sub-step as it runs a stage (the ghosts of what it writes refreshed after it, what it
//! wrote checked to be finite, errors named after it), prints them under their stage and
//! lists them in the timings; the stage keeps one name, one set of options and one entry in
//! snapshots.

use crate::bc::BoundarySet;
use crate::field::Field;
use crate::grid::{Geometry, Grid};
use crate::scene::{Options, Scene};
use crate::state::State;
use efsi_linalg::SolveStats;
use std::collections::BTreeSet;
use std::fmt;
use std::time::{Duration, Instant};

mod declare;
mod error;
mod outputs;
mod resources;
pub use declare::{FieldId, Phase, VELOCITY};
pub use error::ScheduleError;
pub use outputs::{OutputDecl, OutputKind};
pub use resources::Resources;

/// What a stage sees of the run besides the state.
#[derive(Clone, Copy)]
pub struct StepContext<'a> {
    /// The grid.
    pub grid: &'a Grid,
    /// The boundary conditions.
    pub bc: &'a BoundarySet,
    /// Time at the start of the step.
    pub t: f64,
    /// The step Δt.
    pub dt: f64,
    /// Index of this step (0 for the first).
    pub step: u64,
    /// The velocity at the start of the step (one field per component, `None` for `w` on a
    /// two-dimensional grid), where the caller keeps a copy unchanged for the whole step (a run
    /// that puts a failed step back keeps one anyway): [`Pipeline::run_step`] gives it to the
    /// stages that run before any stage of the step writes the velocity — for them it is the
    /// state's velocity bit for bit, ghosts included, so a stage that overwrites the velocity
    /// needs no copy of its own — and `None` to the others.
    pub start_velocity: Option<[Option<&'a Field>; 3]>,
}

/// Statistics a stage reports for one run (solver iterations and residual, if any).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageStats {
    /// The stage's linear solve, if it has one.
    pub solve: Option<SolveStats>,
}

/// A stage failed: it names itself and says why.
#[derive(Debug, Clone, thiserror::Error)]
#[error("stage `{stage}`: {message}")]
pub struct StageError {
    /// The stage.
    pub stage: String,
    /// What went wrong.
    pub message: String,
}

/// A built stage, run once per time step.
pub trait Stage: Send {
    /// Advance the state by this stage's part of the step.
    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError>;

    /// Run sub-step `k` of the stage's [`StagePlugin::sub_steps`], in order, each once per
    /// step: the scheduler calls this instead of [`run`](Self::run) for a stage that declares
    /// sub-steps, and refreshes the ghosts of what sub-step `k` writes before the next one
    /// runs. What one sub-step decides for the next (e.g. the kind of step the elastic solve
    /// took) stays in the stage. Default: [`run`](Self::run) (a stage of one step).
    fn run_sub(
        &mut self,
        _k: usize,
        ctx: &StepContext,
        state: &mut State,
    ) -> Result<StageStats, StageError> {
        self.run(ctx, state)
    }

    /// Initialise the fields this stage writes, before the first step (default: nothing). It
    /// may run more than once (see [`Pipeline::initialize`]) and must set the stage's state
    /// from the current fields each time.
    fn initialize(
        &mut self,
        _grid: &Grid,
        _bc: &BoundarySet,
        _state: &mut State,
    ) -> Result<(), StageError> {
        Ok(())
    }

    /// Add the stage's own data to a new state ([`StateResources::insert`](crate::state::StateResources::insert)), before any
    /// [`initialize`](Self::initialize); stages that share a resource add it if it is absent
    /// (default: nothing).
    fn init_state(&self, _grid: &Grid, _state: &mut State) {}

    /// The largest stable Δt for the current state, if this stage limits it (default: none).
    fn max_dt(&self, _grid: &Grid, _state: &State, _cfl: f64) -> Option<f64> {
        None
    }

    /// A longer limit on Δt this stage can take instead of `own` (its [`max_dt`](Self::max_dt))
    /// at a price, asked of the stage whose limit is the smallest once the next smallest,
    /// `others`, is known: the elastic stage's `Auto` coupling switches to its dearer coupled
    /// step only where the other stages allow steps long enough to pay for it. The step is then
    /// at most `others` (default: none, `own` stands).
    fn lift_dt(
        &self,
        _grid: &Grid,
        _state: &State,
        _own: f64,
        _others: Option<f64>,
    ) -> Option<f64> {
        None
    }

    /// Whether this stage makes the velocity divergence-free (the projection). The pipeline
    /// also runs such a stage once on the initial velocity (default: no). A stage with
    /// sub-steps says it of a sub-step instead ([`SubStep::projects`]): that sub-step alone
    /// runs on the initial velocity.
    fn projects(&self) -> bool {
        false
    }

    /// The stage's own data that carries from one step to the next and is not in the
    /// [`State`] (e.g. the viscous stage's last increments, its solver's initial guess),
    /// flattened to numbers, for checkpoints and in-memory snapshots ([`crate::snapshot`]).
    /// Scratch space that every step overwrites before reading does not belong here, nor a
    /// copy of what the state holds between steps (the VOF stage's previous velocity is the
    /// state's: it takes it back in [`restored`](Self::restored)). Default: nothing.
    ///
    /// A stage that returns data here must accept it back in [`restore`](Self::restore): a run
    /// restored from a snapshot must continue bit for bit as if it had never stopped.
    fn save(&self) -> Vec<f64> {
        Vec::new()
    }

    /// [`save`](Self::save) into `out` (its previous contents replaced), reusing its
    /// allocation: the run loop snapshots the state before every step, so a stage that keeps
    /// data should override this too (default: `*out = self.save()`).
    fn save_into(&self, out: &mut Vec<f64>) {
        *out = self.save();
    }

    /// The number of values [`save`](Self::save) would return, without making them (what a
    /// run sizes its checkpoint by): a stage that keeps full-grid data should override this
    /// too (default: `self.save().len()`).
    fn saved_len(&self) -> usize {
        self.save().len()
    }

    /// After a snapshot's data and state are back ([`restore`](Self::restore), then the
    /// state): a stage takes here what it keeps between steps as a copy of the state, instead of
    /// saving it, and puts back into the state the copies it publishes there from its own
    /// record (default: nothing).
    fn restored(&mut self, _state: &mut State) {}

    /// Take back what [`save`](Self::save) returned (of a stage built from the same scene).
    /// The default accepts only nothing; the error says what does not fit.
    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        if data.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "the stage keeps no state between steps, but the snapshot holds {} values for it",
                data.len()
            ))
        }
    }

    /// What undoing a step needs of the stage's carried-over data ([`save`](Self::save)) as
    /// the step finds it, into `out` (its previous contents replaced, its allocation reused):
    /// kept before every step of a run that puts a failed step back ([`crate::StepStart`])
    /// and given back to [`undo`](Self::undo). A stage whose step overwrites only part of its
    /// data keeps that part (the viscous stage: the older of its two increments). Default:
    /// [`save_into`](Self::save_into).
    fn keep_into(&self, out: &mut Vec<f64>) {
        self.save_into(out);
    }

    /// Put the data back as it was at the start of the step `kept` was taken before
    /// ([`keep_into`](Self::keep_into)), whether the stage ran in that step or not, completed
    /// or failed. Default: [`restore`](Self::restore).
    fn undo(&mut self, kept: &[f64]) -> Result<(), String> {
        self.restore(kept)
    }
}

/// A kind of stage: its declarations and a factory.
pub trait StagePlugin: Sync {
    /// Unique name (shown by `--print-schedule`, used in timings and errors).
    fn name(&self) -> &'static str;
    /// Where the plugin is implemented: its type's path (`crate::module::Type`), shown by
    /// `--print-schedule` so a reader finds the code of each stage.
    fn source(&self) -> &'static str {
        std::any::type_name::<Self>()
    }
    /// The phase it attaches to.
    fn phase(&self) -> Phase;
    /// Fields it reads.
    fn reads(&self) -> &'static [FieldId];
    /// Fields it writes.
    fn writes(&self) -> &'static [FieldId];
    /// The sub-steps it runs in order ([`Stage::run_sub`]), each with its name and the fields
    /// it writes (among the stage's [`writes`](Self::writes)); default: none (the stage runs as
    /// one step, [`Stage::run`]).
    fn sub_steps(&self) -> &'static [SubStep] {
        &[]
    }
    /// Names of stages of the same phase that must run before it (default: none).
    fn after(&self) -> &'static [&'static str] {
        &[]
    }
    /// What its step limit ([`Stage::max_dt`]) depends on besides `time.cfl`, for the message
    /// when Δt collapses (default: `and the velocity it sees`).
    fn limit_depends_on(&self) -> &'static str {
        "and the velocity it sees"
    }
    /// Whether the stage runs on grids of `geometry` (default: [`Geometry::Planar`] and
    /// [`Geometry::Axisymmetric`]). A stage whose kernels run over `Region` lines and axis
    /// shifts for every axis of the grid (its 3-D kernels tested) answers true for
    /// [`Geometry::Cartesian3D`]; the scheduler refuses a scene that needs a stage without
    /// support for its geometry ([`ScheduleError::Unsupported`]), naming the stage.
    fn supports(&self, geometry: Geometry) -> bool {
        matches!(geometry, Geometry::Planar | Geometry::Axisymmetric)
    }
    /// Whether `scene` needs this stage; `options` are its checked sections
    /// ([`crate::scene::options::check_sections`]).
    fn needed(&self, scene: &Scene, options: &Options) -> bool;
    /// The `numerics` section the stage reads its options from, if it has options
    /// ([`crate::scene::options`]; default: none). Several plugins may declare one section.
    fn options(&self) -> Option<crate::scene::OptionsDecl> {
        None
    }
    /// Check the scene's sections outside `numerics` that the stage owns (the VOF stage: the
    /// `solid` section, [`crate::scene::Section`]), put back their settings in force and keep
    /// what it read in `options` ([`Options::insert`]), for the stages' builds to share; on
    /// failure the setting's path and what was expected. Run with the `numerics` checks
    /// ([`crate::scene::options::check_sections`]), whether or not the scene needs the stage
    /// (default: nothing).
    fn check_scene(&self, _scene: &mut Scene, _options: &mut Options) -> crate::validate::Checked {
        Ok(())
    }
    /// The outputs the stage contributes (VTK arrays, probe quantities) computed from the
    /// state, its own resources included ([`OutputDecl`]; default: none).
    fn outputs(&self) -> &'static [OutputDecl] {
        &[]
    }
    /// Build the stage for a scene; the error says which scene value is unusable. `options`
    /// are the scene's checked sections in their owners' types (its own `numerics` options
    /// among them: [`Options::section`]), read once by the check; `shared` holds what the
    /// stages of this pipeline share while it is built (in the pipeline's order): a stage that
    /// needs what another loads or derives from the scene (the solid's law, for one) takes it
    /// from there instead of making it again.
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut Resources,
    ) -> Result<Box<dyn Stage>, String>;
}

/// A part of a stage's step that the scheduler runs, refreshes after and times on its own
/// ([`StagePlugin::sub_steps`]).
#[derive(Clone, Copy, Debug)]
pub struct SubStep {
    /// Its name (in `--print-schedule`, the timings and errors; unique in the pipeline).
    pub name: &'static str,
    /// The fields it writes: their ghosts are refreshed after it and their values checked.
    pub writes: &'static [FieldId],
    /// Whether it makes the velocity divergence-free: it alone runs once on the initial
    /// velocity ([`Pipeline::initialize`]).
    pub projects: bool,
}

struct Entry {
    name: &'static str,
    source: &'static str,
    phase: Phase,
    reads: &'static [FieldId],
    writes: &'static [FieldId],
    /// The `numerics` section of its options, if it has one.
    options: Option<&'static str>,
    /// [`StagePlugin::limit_depends_on`].
    limit: &'static str,
    stage: Box<dyn Stage>,
    /// Whether the stage runs by [`Stage::run_sub`] (it declares sub-steps).
    by_sub_steps: bool,
    /// What the scheduler runs of it: its sub-steps, or the stage itself as one step.
    steps: Vec<Timed>,
}

/// One step the scheduler runs and times: a stage's sub-step, or a stage of one step.
struct Timed {
    name: &'static str,
    writes: &'static [FieldId],
    /// [`SubStep::projects`] (for a stage of one step: [`Stage::projects`], asked when the
    /// initial velocity is projected).
    projects: bool,
    time: Duration,
    calls: u64,
    iterations: u64,
    last: StageStats,
}

impl Timed {
    fn new(name: &'static str, writes: &'static [FieldId], projects: bool) -> Timed {
        Timed {
            name,
            writes,
            projects,
            time: Duration::ZERO,
            calls: 0,
            iterations: 0,
            last: StageStats::default(),
        }
    }
}

/// Timing and solver statistics of one stage over a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StageTiming {
    /// Stage name.
    pub name: &'static str,
    /// Total wall time (s).
    pub seconds: f64,
    /// Number of runs.
    pub calls: u64,
    /// Total linear-solver iterations.
    pub iterations: u64,
}

impl Entry {
    /// Build plugin `p`'s stage ([`StagePlugin::build`]) and its entry: what the scheduler
    /// runs of it is its sub-steps, or the stage itself as one step.
    fn build(
        p: &dyn StagePlugin,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        shared: &mut Resources,
    ) -> Result<Entry, ScheduleError> {
        let stage = p
            .build(scene, options, grid, bc, shared)
            .map_err(|message| ScheduleError::Build {
                stage: p.name().to_string(),
                message,
            })?;
        let subs = p.sub_steps();
        let steps = if subs.is_empty() {
            vec![Timed::new(p.name(), p.writes(), stage.projects())]
        } else {
            subs.iter()
                .map(|s| Timed::new(s.name, s.writes, s.projects))
                .collect()
        };
        Ok(Entry {
            name: p.name(),
            source: p.source(),
            phase: p.phase(),
            reads: p.reads(),
            writes: p.writes(),
            options: p.options().map(|d| d.section),
            limit: p.limit_depends_on(),
            stage,
            by_sub_steps: !subs.is_empty(),
            steps,
        })
    }
}

/// An `after` constraint names a stage of the same phase (`group`); one on a stage the scene
/// does not schedule (not in `chosen`) is vacuous.
fn check_after_in_phase(
    chosen: &[&dyn StagePlugin],
    group: &[&dyn StagePlugin],
) -> Result<(), ScheduleError> {
    for p in group {
        for a in p.after() {
            if !chosen.iter().any(|q| q.name() == *a) {
                continue; // constraint on an absent stage: vacuous
            }
            if !group.iter().any(|q| q.name() == *a) {
                return Err(ScheduleError::BadOrder {
                    stage: p.name().into(),
                    other: (*a).into(),
                    why: "it is in another phase",
                });
            }
        }
    }
    Ok(())
}

/// One phase's stages in an order that honours every `after` constraint: Kahn's algorithm,
/// ties broken by name for determinism; a cycle is refused.
fn sort_by_after<'a>(
    group: &[&'a dyn StagePlugin],
) -> Result<Vec<&'a dyn StagePlugin>, ScheduleError> {
    let mut done: Vec<&dyn StagePlugin> = Vec::new();
    let mut left = group.to_vec();
    left.sort_by_key(|p| p.name());
    while !left.is_empty() {
        let pos = left.iter().position(|p| {
            p.after()
                .iter()
                .all(|a| !left.iter().any(|q| q.name() == *a))
        });
        match pos {
            Some(k) => done.push(left.remove(k)),
            None => {
                return Err(ScheduleError::BadOrder {
                    stage: left[0].name().into(),
                    other: left[0].after().first().copied().unwrap_or("?").into(),
                    why: "the constraints form a cycle",
                });
            }
        }
    }
    Ok(done)
}

/// Whether `x` is (transitively) required before `y` by the `after` constraints among
/// `group`.
fn required_before(group: &[&dyn StagePlugin], x: &dyn StagePlugin, y: &dyn StagePlugin) -> bool {
    let mut stack = vec![y.name()];
    let mut seen = BTreeSet::new();
    while let Some(n) = stack.pop() {
        if let Some(s) = group.iter().find(|p| p.name() == n) {
            for a in s.after() {
                if *a == x.name() {
                    return true;
                }
                if seen.insert(*a) {
                    stack.push(a);
                }
            }
        }
    }
    false
}

/// Ambiguity: two stages of `phase` (in their order `done`) with conflicting access to a
/// field (one writes what the other reads or writes) and no (transitive) order between them.
fn check_unambiguous(
    group: &[&dyn StagePlugin],
    done: &[&dyn StagePlugin],
    phase: Phase,
) -> Result<(), ScheduleError> {
    for (k, a) in done.iter().enumerate() {
        for b in &done[k + 1..] {
            let conflict = a
                .writes()
                .iter()
                .find(|f| b.writes().contains(f) || b.reads().contains(f))
                .or_else(|| b.writes().iter().find(|f| a.reads().contains(f)));
            if let Some(f) = conflict
                && !required_before(group, *a, *b)
                && !required_before(group, *b, *a)
            {
                return Err(ScheduleError::Ambiguous {
                    a: a.name().into(),
                    b: b.name().into(),
                    phase,
                    field: f.name(),
                });
            }
        }
    }
    Ok(())
}

/// The ordered stages of a run.
pub struct Pipeline {
    entries: Vec<Entry>,
    fields: BTreeSet<FieldId>,
    outputs: Vec<OutputDecl>,
}

impl Pipeline {
    /// Assemble the pipeline for `scene` from the available `plugins`, keeping only those the
    /// scene needs, ordered by phase and by their `after` constraints, and check it. `options`
    /// are the scene's sections as checked with the same `plugins`
    /// ([`crate::scene::options::check_sections`]).
    pub fn build(
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        plugins: &[&dyn StagePlugin],
    ) -> Result<Pipeline, ScheduleError> {
        let mut names = BTreeSet::new();
        for p in plugins {
            if !names.insert(p.name()) {
                return Err(ScheduleError::DuplicateName(p.name().to_string()));
            }
        }
        let chosen = Self::choose(scene, options, grid, plugins)?;
        Self::check_step_names(&chosen)?;
        let order = Self::order(&chosen)?;
        let fields = Self::fields_of(&chosen)?;
        let mut entries = Vec::with_capacity(order.len());
        let mut shared = Resources::default();
        let mut outputs: Vec<(&'static str, OutputDecl)> = Vec::new();
        for p in order {
            for o in p.outputs() {
                if let Some((first, _)) = outputs.iter().find(|(_, x)| x.name == o.name) {
                    return Err(ScheduleError::DuplicateOutput {
                        output: o.name,
                        first,
                        second: p.name(),
                    });
                }
                outputs.push((p.name(), *o));
            }
            entries.push(Entry::build(p, scene, options, grid, bc, &mut shared)?);
        }
        Ok(Pipeline {
            entries,
            fields,
            outputs: outputs.into_iter().map(|(_, o)| o).collect(),
        })
    }

    /// The plugins `scene` needs, in the order given; refused if any of them does not run on
    /// the grid's geometry ([`ScheduleError::Unsupported`], naming them all).
    fn choose<'a>(
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        plugins: &[&'a dyn StagePlugin],
    ) -> Result<Vec<&'a dyn StagePlugin>, ScheduleError> {
        let chosen: Vec<&dyn StagePlugin> = plugins
            .iter()
            .copied()
            .filter(|p| p.needed(scene, options))
            .collect();
        let unsupported: Vec<&'static str> = chosen
            .iter()
            .filter(|p| !p.supports(grid.geometry))
            .map(|p| p.name())
            .collect();
        if !unsupported.is_empty() {
            return Err(ScheduleError::Unsupported {
                stages: unsupported,
                geometry: grid.geometry,
                cells: grid.n(),
            });
        }
        Ok(chosen)
    }

    /// What runs is named uniquely within the pipeline: each stage, or in its place its
    /// sub-steps, which may take the name of a stage not scheduled with them (the
    /// implicit-momentum stage's `projection`).
    fn check_step_names(chosen: &[&dyn StagePlugin]) -> Result<(), ScheduleError> {
        let mut steps = BTreeSet::new();
        for p in chosen {
            let own = [p.name()];
            let subs: Vec<&'static str> = p.sub_steps().iter().map(|s| s.name).collect();
            let run = if subs.is_empty() { &own[..] } else { &subs[..] };
            for &n in run {
                if !steps.insert(n) {
                    return Err(ScheduleError::DuplicateName(n.to_string()));
                }
            }
        }
        Ok(())
    }

    /// The fields of the pipeline: the base set plus everything written; every field a stage
    /// reads must be among them.
    fn fields_of(chosen: &[&dyn StagePlugin]) -> Result<BTreeSet<FieldId>, ScheduleError> {
        let mut fields: BTreeSet<FieldId> = FieldId::BASE.into_iter().collect();
        for p in chosen {
            fields.extend(p.writes().iter().copied());
        }
        for p in chosen {
            for f in p.reads() {
                if !fields.contains(f) {
                    return Err(ScheduleError::MissingField {
                        stage: p.name().to_string(),
                        field: f.name(),
                    });
                }
            }
        }
        Ok(fields)
    }

    /// Order by phase, then topologically by `after` within a phase; reject ambiguity.
    fn order<'a>(
        chosen: &[&'a dyn StagePlugin],
    ) -> Result<Vec<&'a dyn StagePlugin>, ScheduleError> {
        let mut out = Vec::new();
        for phase in Phase::ALL {
            let group: Vec<&dyn StagePlugin> = chosen
                .iter()
                .copied()
                .filter(|p| p.phase() == phase)
                .collect();
            check_after_in_phase(chosen, &group)?;
            let done = sort_by_after(&group)?;
            check_unambiguous(&group, &done, phase)?;
            out.extend(done);
        }
        Ok(out)
    }

    /// The fields the pipeline uses (the state allocates exactly these).
    pub fn fields(&self) -> &BTreeSet<FieldId> {
        &self.fields
    }

    /// The outputs the scheduled stages contribute, in pipeline order.
    pub fn outputs(&self) -> &[OutputDecl] {
        &self.outputs
    }

    /// Add each stage's own data to a new state ([`Stage::init_state`]), in pipeline order.
    pub fn init_state(&self, grid: &Grid, state: &mut State) {
        for e in &self.entries {
            e.stage.init_state(grid, state);
        }
    }

    /// The names of what runs, in execution order: each stage's, or in its place its
    /// sub-steps' ([`StagePlugin::sub_steps`]).
    pub fn stage_names(&self) -> Vec<&'static str> {
        self.entries
            .iter()
            .flat_map(|e| e.steps.iter().map(|s| s.name))
            .collect()
    }

    /// Whether a stage of `phase` runs in this pipeline.
    pub fn has_phase(&self, phase: Phase) -> bool {
        self.entries.iter().any(|e| e.phase == phase)
    }

    /// Initialise every stage's fields (before the first step; the stages writing material
    /// fields first, see `Pipeline::initialize_stages`), then make the initial velocity
    /// divergence-free: a solid's initial velocity blended into fluid at rest is not, and a
    /// stage that integrates velocity gradients (the elastic stage) would take the spurious
    /// compression at the interface for deformation. The projecting stage runs once, from zero
    /// pressure with the step of Courant number 1 (the stages' starting pressure is restored
    /// after), so the projected velocity depends neither on gravity nor on the frame; if the
    /// velocity changed, every stage is initialised again from it (the densities it needs come
    /// from the first pass).
    pub fn initialize(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        self.initialize_stages(grid, bc, state)?;
        // The stages' starting pressure (the hydrostatic one of the incremental projection or
        // of the seed's scheme's split of gravity) stays after the initial velocity is
        // projected; the projection itself starts from zero, so the projected velocity does not
        // depend on gravity or the frame (a frame acceleration set before the first step
        // initialises the stages again, not this projection).
        let p0 = state.p.clone();
        let before = (state.u.clone(), state.v.clone());
        // The projection's tolerance is on max|∇·u|·Δt: judge it with the step the flow allows
        // at Courant number 1, not Δt = 1 (which would ask for the divergence to round-off).
        let speed = state
            .u
            .data()
            .iter()
            .chain(state.v.data())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        // Below 1e-150 the projection's right-hand side ∇·u/Δt ~ speed² underflows: such a
        // velocity is rest to floating point, and nothing is projected.
        if speed < 1e-150 {
            return Ok(());
        }
        let ctx = StepContext {
            grid,
            bc,
            t: 0.0,
            dt: grid.dx.min(grid.dy) / speed,
            step: 0,
            start_velocity: None,
        };
        for e in &mut self.entries {
            for (k, s) in e.steps.iter().enumerate() {
                // A stage of one step is asked now (its answer may follow its build).
                let projects = if e.by_sub_steps {
                    s.projects
                } else {
                    e.stage.projects()
                };
                if !projects {
                    continue;
                }
                state.p.fill(0.0);
                e.stage.run_sub(k, &ctx, state)?;
                bc.fill_velocity3(
                    grid,
                    &mut state.u,
                    &mut state.v,
                    state.w.as_mut(),
                    0.0,
                    false,
                );
                state.p.copy_from(&p0);
                // An initial velocity too large for floating point (e.g. 1e308) projects to
                // infinities: refuse it here rather than start a run from them.
                for (f, stagger) in [
                    (&state.u, crate::Stagger::XFace),
                    (&state.v, crate::Stagger::YFace),
                ] {
                    if let Some((i, j)) = f.first_non_finite(stagger, grid.nx, grid.ny) {
                        return Err(StageError {
                            stage: s.name.to_string(),
                            message: format!(
                                "projecting the initial velocity produced a non-finite value at cell ({i}, {j}): is the initial velocity finite and of a sensible size?"
                            ),
                        });
                    }
                }
            }
        }
        if state.u.data() != before.0.data() || state.v.data() != before.1.data() {
            self.initialize_stages(grid, bc, state)?;
        }
        Ok(())
    }

    /// Every stage's [`Stage::initialize`]: first the stages that write the material fields
    /// (solid fraction, density, viscosity), which the others read, then the rest, each group in
    /// pipeline order. Without [`initialize`](Self::initialize)'s projection of the initial
    /// velocity: what a change of frame before the first step asks for.
    pub fn initialize_stages(
        &mut self,
        grid: &Grid,
        bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        let material = |e: &Entry| {
            e.writes.iter().any(|f| {
                matches!(
                    f,
                    FieldId::SolidFraction | FieldId::Density | FieldId::Viscosity
                )
            })
        };
        for first in [true, false] {
            for e in self.entries.iter_mut().filter(|e| material(e) == first) {
                e.stage.initialize(grid, bc, state)?;
            }
        }
        Ok(())
    }

    /// What the step limit of the stage named `stage` depends on
    /// ([`StagePlugin::limit_depends_on`]), if it is in the pipeline.
    pub fn limit_depends_on(&self, stage: &str) -> Option<&'static str> {
        self.entries
            .iter()
            .find(|e| e.name == stage)
            .map(|e| e.limit)
    }

    /// The largest Δt every stage allows, if any stage limits it.
    pub fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        self.limiting_stage(grid, state, cfl).map(|(_, dt)| dt)
    }

    /// The stage whose step limit is the smallest, with that limit (None if no stage limits Δt).
    /// That stage may then lift its limit ([`Stage::lift_dt`]) up to the next smallest one.
    pub fn limiting_stage(
        &self,
        grid: &Grid,
        state: &State,
        cfl: f64,
    ) -> Option<(&'static str, f64)> {
        // The smallest limit (with its entry) and the next smallest (with its stage's name).
        let mut first: Option<(&Entry, f64)> = None;
        let mut second: Option<(&'static str, f64)> = None;
        for e in &self.entries {
            let Some(d) = e.stage.max_dt(grid, state, cfl) else {
                continue;
            };
            match first {
                // Not smaller (a tie, or a NaN on either side): the first stays first.
                Some((_, fd)) if d.partial_cmp(&fd) != Some(std::cmp::Ordering::Less) => {
                    if second.is_none_or(|s| d < s.1) {
                        second = Some((e.name, d));
                    }
                }
                _ => {
                    second = first.map(|(f, fd)| (f.name, fd)).or(second);
                    first = Some((e, d));
                }
            }
        }
        let (e, d) = first?;
        match e.stage.lift_dt(grid, state, d, second.map(|s| s.1)) {
            Some(lifted) if lifted > d => match second {
                Some(s) if s.1 <= lifted => Some(s),
                _ => Some((e.name, lifted)),
            },
            _ => Some((e.name, d)),
        }
    }

    /// Run every stage once, in order (a stage's sub-steps in theirs). After each step the
    /// ghosts of what it wrote are refreshed (velocity for the end-of-step time `t + Δt`), and
    /// what it wrote is checked to be finite: a NaN or infinity is reported with the stage (or
    /// sub-step), the field and the cell.
    pub fn run_step(&mut self, ctx: &StepContext, state: &mut State) -> Result<(), StageError> {
        let mut ctx = *ctx;
        for e in &mut self.entries {
            for (k, s) in e.steps.iter_mut().enumerate() {
                let t0 = Instant::now();
                let stats = if e.by_sub_steps {
                    e.stage.run_sub(k, &ctx, state)?
                } else {
                    e.stage.run(&ctx, state)?
                };
                // The velocity of the step's start is the state's only until a stage writes it.
                if s.writes.iter().any(|id| VELOCITY.contains(id)) {
                    ctx.start_velocity = None;
                }
                s.time += t0.elapsed();
                s.calls += 1;
                if let Some(st) = stats.solve {
                    s.iterations += st.iterations as u64;
                }
                s.last = stats;
                after_step(&ctx, state, s.name, s.writes)?;
            }
        }
        Ok(())
    }

    /// Each stage's carried-over data ([`Stage::save`]), by name, in execution order.
    pub fn save_stages(&self) -> Vec<(String, Vec<f64>)> {
        self.entries
            .iter()
            .map(|e| (e.name.to_string(), e.stage.save()))
            .collect()
    }

    /// The number of values each stage's carried-over data holds ([`Stage::saved_len`]), by
    /// name, in execution order: [`save_stages`](Self::save_stages)' lengths, without the copy.
    pub fn saved_lens(&self) -> Vec<(&'static str, usize)> {
        self.entries
            .iter()
            .map(|e| (e.name, e.stage.saved_len()))
            .collect()
    }

    /// Each stage's [`Stage::keep_into`], by name, in execution order, into `out` (reusing its
    /// allocations when it already holds this pipeline's stages).
    pub fn keep_stages_into(&self, out: &mut Vec<(String, Vec<f64>)>) {
        let same = out.len() == self.entries.len()
            && out.iter().zip(&self.entries).all(|((n, _), e)| n == e.name);
        if !same {
            *out = (self.entries.iter())
                .map(|e| (e.name.to_string(), Vec::new()))
                .collect();
        }
        for ((_, data), e) in out.iter_mut().zip(&self.entries) {
            e.stage.keep_into(data);
        }
    }

    /// Each stage's [`Stage::undo`] with what [`keep_stages_into`](Self::keep_stages_into)
    /// kept; the error names the stage that refuses its data.
    pub fn undo_stages(&mut self, kept: &[(String, Vec<f64>)]) -> Result<(), StageError> {
        for (e, (name, data)) in self.entries.iter_mut().zip(kept) {
            let fail = |message: String| StageError {
                stage: e.name.to_string(),
                message,
            };
            if name != e.name {
                return Err(fail(format!("kept as the data of `{name}`")));
            }
            e.stage.undo(data).map_err(fail)?;
        }
        Ok(())
    }

    /// The fields the stages write in a step ([`StagePlugin::writes`]), each once, in the order
    /// they are first written: what a step can change of the state.
    pub fn written(&self) -> Vec<FieldId> {
        let mut out: Vec<FieldId> = Vec::new();
        for id in self.entries.iter().flat_map(|e| e.writes) {
            if !out.contains(id) {
                out.push(*id);
            }
        }
        out
    }

    /// [`save_stages`](Self::save_stages) into `out`, reusing its allocations when it already
    /// holds this pipeline's stages (no heap allocation from the second call on, for stages
    /// that implement [`Stage::save_into`]).
    pub fn save_stages_into(&self, out: &mut Vec<(String, Vec<f64>)>) {
        let same = out.len() == self.entries.len()
            && out.iter().zip(&self.entries).all(|((n, _), e)| n == e.name);
        if !same {
            *out = self.save_stages();
            return;
        }
        for ((_, data), e) in out.iter_mut().zip(&self.entries) {
            e.stage.save_into(data);
        }
    }

    /// Give each stage back its data ([`Stage::restore`]). `saved` must name the same stages in
    /// the same order (it does for a pipeline built from the same scene); otherwise, or if a
    /// stage refuses its data, the error names the stage.
    pub fn restore_stages(&mut self, saved: &[(String, Vec<f64>)]) -> Result<(), StageError> {
        let names: Vec<&str> = self.entries.iter().map(|e| e.name).collect();
        let theirs: Vec<&str> = saved.iter().map(|(n, _)| n.as_str()).collect();
        if names != theirs {
            if let Some(gathered) = self.gathered(saved) {
                return self.restore_stages(&gathered);
            }
            return Err(StageError {
                stage: "pipeline".into(),
                message: format!(
                    "the snapshot was taken with stages [{}], this pipeline has [{}]",
                    theirs.join(", "),
                    names.join(", ")
                ),
            });
        }
        for (e, (_, data)) in self.entries.iter_mut().zip(saved) {
            e.stage.restore(data).map_err(|message| StageError {
                stage: e.name.to_string(),
                message,
            })?;
        }
        Ok(())
    }

    /// `saved` as this pipeline names it, if it was taken when each stage with sub-steps ran
    /// them as stages of their own (a snapshot of an earlier efsi): the sub-steps' entries in
    /// order, each holding no data, stand for their stage with no data. `None` if it is not
    /// such a snapshot, or if any of those entries holds data (which the stage could misread).
    fn gathered(&self, saved: &[(String, Vec<f64>)]) -> Option<Vec<(String, Vec<f64>)>> {
        let mut out = Vec::with_capacity(self.entries.len());
        let mut rest = saved;
        for e in &self.entries {
            if !e.by_sub_steps {
                let ((n, data), tail) = rest.split_first()?;
                (n == e.name).then_some(())?;
                out.push((n.clone(), data.clone()));
                rest = tail;
                continue;
            }
            let k = e.steps.len();
            (rest.len() >= k).then_some(())?;
            let (subs, tail) = rest.split_at(k);
            let matches = subs
                .iter()
                .zip(&e.steps)
                .all(|((n, data), s)| n == s.name && data.is_empty());
            matches.then_some(())?;
            out.push((e.name.to_string(), Vec::new()));
            rest = tail;
        }
        rest.is_empty().then_some(out)
    }

    /// Each stage's [`Stage::restored`], once a snapshot's state is back.
    pub fn restored(&mut self, state: &mut State) {
        for e in &mut self.entries {
            e.stage.restored(state);
        }
    }

    /// The statistics each stage (each sub-step) reported in the last step, in order.
    pub fn last_stats(&self) -> Vec<(&'static str, StageStats)> {
        self.steps().map(|s| (s.name, s.last)).collect()
    }

    /// Accumulated timings per stage, a stage with sub-steps as its sub-steps.
    pub fn timings(&self) -> Vec<StageTiming> {
        self.steps()
            .map(|s| StageTiming {
                name: s.name,
                seconds: s.time.as_secs_f64(),
                calls: s.calls,
                iterations: s.iterations,
            })
            .collect()
    }

    /// What the scheduler runs and times, in order.
    fn steps(&self) -> impl Iterator<Item = &Timed> {
        self.entries.iter().flat_map(|e| &e.steps)
    }
}

/// What the scheduler does after a step named `name` that wrote `writes`: refresh their
/// ghosts (the velocity's for the step's end) and check them (and, if it wrote a stage's
/// field, every stage resource) for a non-finite value, reported with the step and the cell.
fn after_step(
    ctx: &StepContext,
    state: &mut State,
    name: &str,
    writes: &[FieldId],
) -> Result<(), StageError> {
    let (nx, ny) = (ctx.grid.nx, ctx.grid.ny);
    if writes.iter().any(|f| {
        matches!(
            f,
            FieldId::VelocityX | FieldId::VelocityY | FieldId::VelocityZ
        )
    }) {
        ctx.bc.fill_velocity3(
            ctx.grid,
            &mut state.u,
            &mut state.v,
            state.w.as_mut(),
            ctx.t + ctx.dt,
            false,
        );
    }
    for &f in writes {
        match f {
            FieldId::Pressure => ctx.bc.fill_scalar(ctx.grid, &mut state.p, true),
            FieldId::Density => ctx.bc.fill_scalar(ctx.grid, &mut state.rho, false),
            FieldId::Viscosity => ctx.bc.fill_scalar(ctx.grid, &mut state.mu, false),
            FieldId::SolidFraction => {
                if let Some(phi) = &mut state.phi {
                    ctx.bc.fill_scalar(ctx.grid, phi, false);
                }
            }
            FieldId::VelocityX | FieldId::VelocityY | FieldId::VelocityZ | FieldId::Stage(_) => {}
        }
    }
    if writes.iter().any(|f| matches!(f, FieldId::Stage(_)))
        && let Some((c, (i, j))) = state
            .resources
            .iter()
            .find_map(|r| r.first_non_finite(nx, ny))
    {
        return Err(StageError {
            stage: name.to_string(),
            message: format!(
                "produced a non-finite {c} at ({i}, {j}) in step {} (t = {:.6e}, Δt = {:.3e})",
                ctx.step, ctx.t, ctx.dt
            ),
        });
    }
    for &f in writes {
        if let Some(field) = state.field(f) {
            let stagger = match f {
                FieldId::VelocityX => crate::Stagger::XFace,
                FieldId::VelocityY => crate::Stagger::YFace,
                FieldId::VelocityZ => crate::Stagger::ZFace,
                _ => crate::Stagger::Cell,
            };
            if let Some((i, j)) = field.first_non_finite(stagger, nx, ny) {
                return Err(StageError {
                    stage: name.to_string(),
                    message: format!(
                        "produced a non-finite `{}` at cell ({i}, {j}) in step {} (t = {:.6e}, Δt = {:.3e})",
                        f.name(),
                        ctx.step,
                        ctx.t,
                        ctx.dt
                    ),
                });
            }
        }
    }
    Ok(())
}

impl fmt::Display for Pipeline {
    /// The schedule as `efsi run --print-schedule` prints it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, e) in self.entries.iter().enumerate() {
            let names = |fs: &[FieldId]| fs.iter().map(|x| x.name()).collect::<Vec<_>>().join(", ");
            let options = e
                .options
                .map_or(String::new(), |s| format!(" options numerics.{s}"));
            writeln!(
                f,
                "{:>2}. {:<18} phase {:<17} reads [{}] writes [{}]{options}  ({})",
                k + 1,
                e.name,
                format!("{:?}", e.phase),
                names(e.reads),
                names(e.writes),
                e.source
            )?;
            if e.by_sub_steps {
                for (s, letter) in e.steps.iter().zip('a'..) {
                    writeln!(
                        f,
                        "    {letter}. {:<16} writes [{}]",
                        s.name,
                        names(s.writes)
                    )?;
                }
            }
        }
        let fields: Vec<_> = self.fields.iter().map(|x| x.name()).collect();
        write!(f, "fields: {}", fields.join(", "))
    }
}

#[cfg(test)]
mod tests;
