//! The implicit-momentum stage's options (`numerics.elastic`): the elastic solve, its coupling
//! with the projection and the caps on Δt. What each default rests on is asserted by a test or
//! measured by a benchmark, cited where it is set: `tests/tests/elastic.rs` and the stability
//! map (`cargo xtask bench-paper --case stability`, `tests/src/paper/stability.rs`: the sphere
//! of 8 cells per radius falling onto a wall at G = 1e7–1e11 Pa).

use efsi_core::Scene;
use efsi_core::scene::options::{Options, StageOptions, check_iterations, check_tolerance};
use serde::{Deserialize, Serialize};

/// Parameters of the elastic step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticOptions {
    /// Treat the elastic stress implicitly (default true). `false` makes the elastic force
    /// explicit — stable only for `Δt ≲ h √(ρ/G)`; it exists to show what the implicit term
    /// buys (`tests/tests/elastic.rs`,
    /// `stiff_solid_runs_at_the_flow_time_step_only_with_the_implicit_term`).
    #[serde(default = "yes")]
    pub implicit: bool,
    /// Relative residual at which BiCGSTAB stops: `‖r‖ ≤ tolerance · max(‖b‖, ‖M V‖)`, the
    /// step's elastic–viscous increment or the momentum, whichever is larger (default 1e-6;
    /// the `Strict` preset 1e-10). The default moves the paper's quick cases by a small
    /// fraction of their error against their references (`tests/tests/paper_quick.rs`).
    #[serde(default = "default_elastic_tol")]
    pub tolerance: f64,
    /// Iteration cap (default 5000).
    #[serde(default = "default_elastic_iter")]
    pub max_iterations: usize,
    /// Preconditioner of BiCGSTAB (default `Auto`).
    #[serde(default)]
    pub preconditioner: ElasticPreconditioner,
    /// The largest elastic-wave Courant number `Δt·c/h` a split step may take (default and
    /// largest allowed: [`MAX_WAVE_COURANT`]), `c = √(G₀/ρ_s)` the solid's shear-wave speed at
    /// rest (`G₀` the law's stiffness at `B̃ = I`) and `h` the smaller cell side. The elastic
    /// step is implicit, but the projection after a split step is not coupled to it: the strain
    /// its correction leaves in the solid is stored at stiffness G and given back the next
    /// step, which pumps energy into stiff solids at larger Courant numbers. A `time.fixed_dt`
    /// above the cap is refused.
    #[serde(default = "default_wave_courant")]
    pub wave_courant: f64,
    /// The strategy of the implicit-momentum stage: how the elastic step and the pressure
    /// projection share a time step (default `Auto`).
    #[serde(default)]
    pub coupling: ElasticCoupling,
    /// `Coupled`/`Auto` only: the coupled solve stops once `max |∇·V|·Δt` is at most this
    /// fraction of the step's divergence scale (that of the velocity before the step or of the
    /// explicit elastic increment, whichever is larger; default 1e-3) or the projection's
    /// tolerance, whichever is larger; the projection sub-step removes the rest.
    #[serde(default = "default_coupling_tolerance")]
    pub coupling_tolerance: f64,
    /// The implicit weight θ of B's stretching over a step, `B^{n+1} = Bⁿ + Δt[(1 − θ) H(Vⁿ) +
    /// θ H(V^{n+1})] + …`, in [½, 1] (default: ½, Crank–Nicolson, in a split step; ¾ in a
    /// coupled one). At an elastic-wave Courant number `s = kΔt√(G/ρ)` far above 1 the
    /// velocity's amplification per step tends to `−(1 − θ)/θ` (the elastic module's table):
    /// −1, an undamped two-step oscillation, at ½; −⅓ at ¾. Above ½ the step is first order in
    /// time for the solid. A coupled step's long steps need the damping: at ½ its stiff modes
    /// are undamped and the stability map's soft sphere gains energy; at ¾ every run of the
    /// map is stable.
    #[serde(default)]
    pub theta: Option<f64>,
    /// The weight α of the step-end stress in a split step's momentum,
    /// `ρ δ/Δt = ∇·[α τ(B^{n+1}) + (1 − α) τ(Bⁿ)]`, in [½, 1]. Unset (the default), α is the
    /// stretching's θ — the θ-method, second order in time at θ = ½ — while the step's
    /// elastic-wave Courant number `Δt·c/h` is at most [`CN_WAVE_COURANT`], rising linearly to
    /// 1 (the stress at the step's end, which damps the stiff modes) at
    /// [`DAMPED_WAVE_COURANT`] and beyond: the split projection pumps energy into an undamped
    /// stiff solid (the elastic module's "θ of the stress"). The coupled step always takes its
    /// stretching's θ.
    #[serde(default)]
    pub stress_theta: Option<f64>,
    /// `Coupled`/`Auto` only: the most FGMRES iterations per step (default 500, an order of
    /// magnitude above what the stability map's stiffest spheres take).
    #[serde(default = "default_coupling_iter")]
    pub coupling_iterations: usize,
    /// `Coupled`/`Auto` only: the largest elastic-wave Courant number `Δt·c/h` a coupled step
    /// may take (at most [`MAX_COUPLED_WAVE_COURANT`]; default [`DEFAULT_COUPLED_WAVE_COURANT`]
    /// with `Coupled`, [`DEFAULT_AUTO_COUPLED_WAVE_COURANT`] with `Auto`). The coupled step is
    /// stable far beyond the split step's [`MAX_WAVE_COURANT`]; the cap limits what long steps
    /// cost in accuracy: an impact taken in few coupled steps loses its rebound (the `coupled`
    /// module's "Limits"). `Auto` takes impacts with split steps (within [`AUTO_WALL_CELLS`] of
    /// a wall), so its cap only sets the step of a stiff solid's flight, where a long coupled
    /// step costs the time error any step of that length has: a stiff solid is no less
    /// accurate than a soft one at the step its own wave cap allows (`tests/tests/elastic.rs`,
    /// `auto_flies_a_stiff_solid_at_its_cap_no_less_accurately_than_a_soft_one_at_its_own_step`).
    #[serde(default)]
    pub coupled_wave_courant: Option<f64>,
}

/// The implicit-momentum stage's strategy: how the implicit elastic step and the pressure
/// projection share a time step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElasticCoupling {
    /// The elastic step, then the projection (seed Fig. 1): the projection's correction
    /// strains the solid without its stiffness answering within the step, which pumps energy
    /// into stiff solids, so Δt is capped at `wave_courant` elastic-wave Courant numbers.
    Split,
    /// The elastic step solves its implicit system together with the divergence constraint
    /// (FGMRES on the saddle-point system, block-triangular preconditioner from the elastic
    /// step's block multigrid and the projection's Poisson multigrid, Cahouet–Chabard; the
    /// `coupled` module), so the pressure's correction meets the solid's implicit stiffness: Δt
    /// is capped at `coupled_wave_courant` instead. Its stretching is damped (`theta` ¾), so an
    /// impact taken in a few steps loses its rebound. A solve that does not converge is an
    /// error. `tests/tests/elastic.rs`:
    /// `coupled_step_runs_a_stiff_sphere_at_the_flow_step_without_gaining_energy`.
    Coupled,
    /// Each step chooses: the coupled step (up to `coupled_wave_courant`) where the flow
    /// allows steps at least [`AUTO_COUPLED_GAIN`] times the split step's wave cap and the
    /// solid is not busy deforming (its strain energy at most [`AUTO_STRAIN_SHARE`] of the
    /// kinetic energy) nor near a wall ([`AUTO_WALL_CELLS`]), else the split step at its cap.
    /// A soft solid runs as with `Split`; a stiff one crosses the flow at the flow's step and
    /// takes an impact at the split step's, which resolves the rebound. A coupled solve that
    /// does not converge within `coupling_iterations` is retaken as a split step, from the
    /// step's start. Each step's θ is its kind's (`theta`, when set, applies to both); with
    /// `implicit: false` every step is split. Where the flow never allows longer steps than
    /// the split step's cap (the seed's sphere, every shipped case) it is `Split` to the last
    /// bit. `tests/tests/elastic.rs`: `auto_coupling_runs_a_soft_solid_split_and_a_stiff_one_coupled`,
    /// `auto_takes_a_step_split_when_its_coupled_solve_does_not_converge`.
    #[default]
    Auto,
}

/// With `coupling: Auto`, the coupled step is taken only while the solid's strain energy is at
/// most this share of the flow's kinetic energy: above it the solid is exchanging energy with
/// its deformation (an impact, an oscillation) at a rate the split step's shorter steps
/// resolve (the stability map: a smaller share takes more split steps for no better rebound,
/// a larger one loses rebound).
pub const AUTO_STRAIN_SHARE: f64 = 1e-2;

/// With `coupling: Auto`, the coupled step is not taken while a cell mostly solid is within
/// this many cells of a wall, or would be after the coupled step at its velocity: the impact
/// is taken with split steps from its first contact to its release. The margin covers the
/// release too: a coupled step taken while the leaving solid is about a cell off the wall
/// stretches the sliver of solid the wall row's cell still holds with the rate of the fluid
/// filling the gap, which pulls the solid back (the `coupled` module's "Limits"; the
/// stability map keeps the split step's rebound at 1.5 cells).
pub const AUTO_WALL_CELLS: f64 = 1.5;

/// With `coupling: Auto`, the coupled step is taken only where it lengthens the step at least
/// this much over the split step's wave cap: a coupled step costs about 1.5 split steps, so a
/// shorter gain would not pay for it.
pub const AUTO_COUPLED_GAIN: f64 = 1.5;

impl ElasticOptions {
    /// The elastic-wave Courant number that caps Δt: `wave_courant` with the split step,
    /// `coupled_wave_courant` where the coupled step may be taken (`Coupled`, `Auto`).
    pub fn wave_cap(&self) -> f64 {
        match self.coupling {
            ElasticCoupling::Split => self.wave_courant,
            ElasticCoupling::Coupled | ElasticCoupling::Auto => self.coupled_cap(),
        }
    }

    /// The coupled step's cap on `Δt·c/h`: the scene's `coupled_wave_courant`, else
    /// [`DEFAULT_AUTO_COUPLED_WAVE_COURANT`] with `Auto` and [`DEFAULT_COUPLED_WAVE_COURANT`]
    /// otherwise.
    pub fn coupled_cap(&self) -> f64 {
        self.coupled_wave_courant
            .unwrap_or(if self.coupling == ElasticCoupling::Auto {
                DEFAULT_AUTO_COUPLED_WAVE_COURANT
            } else {
                DEFAULT_COUPLED_WAVE_COURANT
            })
    }

    /// θ of B's stretching in a coupled step (`coupled`) or a split one: the scene's, else 0.5
    /// in a split step and 0.75 in a coupled one.
    pub fn stretch_theta(&self, coupled: bool) -> f64 {
        self.theta.unwrap_or(if coupled { 0.75 } else { 0.5 })
    }

    /// The weight α of the step-end stress in a split step at the elastic-wave Courant number
    /// `courant` (`Δt·c/h`): `stress_theta` if set, else the split stretching's θ up to
    /// [`CN_WAVE_COURANT`], 1 from [`DAMPED_WAVE_COURANT`], linear in between.
    pub fn split_stress_weight(&self, courant: f64) -> f64 {
        if let Some(alpha) = self.stress_theta {
            return alpha;
        }
        let theta = self.stretch_theta(false);
        let ramp =
            ((courant - CN_WAVE_COURANT) / (DAMPED_WAVE_COURANT - CN_WAVE_COURANT)).clamp(0.0, 1.0);
        theta + (1.0 - theta) * ramp
    }
}

fn default_coupling_tolerance() -> f64 {
    1e-3
}
fn default_coupling_iter() -> usize {
    500
}

/// The largest elastic-wave Courant number `Δt·c/h` the coupled step may take (see
/// [`ElasticOptions::coupled_wave_courant`]): the largest at which the runs of the stability
/// map keep their energy.
pub const MAX_COUPLED_WAVE_COURANT: f64 = 200.0;

/// The coupled step's default cap on `Δt·c/h` with `Coupled`, which takes impacts with coupled
/// steps too: low enough that an impact keeps part of its rebound (see
/// [`ElasticOptions::coupled_wave_courant`]; `tests/tests/elastic.rs`,
/// `coupled_step_with_the_stress_at_its_theta_keeps_more_of_an_impact`).
pub const DEFAULT_COUPLED_WAVE_COURANT: f64 = 25.0;

/// The coupled step's default cap on `Δt·c/h` with `Auto`, which takes impacts with split
/// steps: the largest allowed, [`MAX_COUPLED_WAVE_COURANT`] (see
/// [`ElasticOptions::coupled_wave_courant`]).
pub const DEFAULT_AUTO_COUPLED_WAVE_COURANT: f64 = MAX_COUPLED_WAVE_COURANT;

/// Up to this elastic-wave Courant number `Δt·c/h` a split step takes the stress at its
/// stretching's θ (Crank–Nicolson at the default θ = ½: second order in time), see
/// [`ElasticOptions::stress_theta`].
pub const CN_WAVE_COURANT: f64 = 1.0;

/// From this elastic-wave Courant number `Δt·c/h` on a split step takes the stress at its end
/// (α = 1), whose damping the split projection needs for stiff solids at the wave cap; see
/// [`ElasticOptions::stress_theta`].
pub const DAMPED_WAVE_COURANT: f64 = 2.0;

/// The largest elastic-wave Courant number `Δt·c/h` allowed (see
/// [`ElasticOptions::wave_courant`]): the largest at which every run of the stability map kept
/// its energy bounded.
pub const MAX_WAVE_COURANT: f64 = 4.0;

impl Default for ElasticOptions {
    fn default() -> Self {
        ElasticOptions {
            implicit: true,
            tolerance: default_elastic_tol(),
            max_iterations: default_elastic_iter(),
            preconditioner: ElasticPreconditioner::default(),
            wave_courant: default_wave_courant(),
            coupling: ElasticCoupling::default(),
            coupling_tolerance: default_coupling_tolerance(),
            coupling_iterations: default_coupling_iter(),
            theta: None,
            stress_theta: None,
            coupled_wave_courant: None,
        }
    }
}

/// Preconditioner of the elastic step's BiCGSTAB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElasticPreconditioner {
    /// The diagonal: cheapest per iteration; iterations grow like the elastic wave's Courant
    /// number `Δt √(G/ρ) / h`.
    Jacobi,
    /// Multigrid V-cycles on the u–u and v–v blocks of an SPD approximation of the system, the
    /// viscous operator with an effective viscosity `θ_v Δt μ + αθΔt² G_eff`.
    Multigrid,
    /// Multigrid, except with the split step in scenes with a periodic boundary, where Jacobi
    /// (the default; the coupled step keeps the multigrid, with which its FGMRES converges): the
    /// red–black smoother keeps a flow uniform along a periodic direction uniform only to the
    /// solver's tolerance (a cross-flow across a flat interface, solid fraction leaking into
    /// the fluid), where Jacobi keeps it exactly.
    #[default]
    Auto,
}

fn default_wave_courant() -> f64 {
    MAX_WAVE_COURANT
}

fn default_elastic_tol() -> f64 {
    1e-6
}
fn default_elastic_iter() -> usize {
    5000
}

impl StageOptions for ElasticOptions {
    const SECTION: &'static str = "elastic";

    fn resolve(&mut self, _scene: &Scene, _options: &Options) {
        // The cap's default depends on `coupling`; θ's on each step's kind, so it stays unset.
        self.coupled_wave_courant = Some(self.coupled_cap());
    }

    fn validate(&self, _scene: &Scene) -> Result<(), (&'static str, String)> {
        check_tolerance("tolerance", self.tolerance)?;
        check_iterations("max_iterations", self.max_iterations)?;
        if !(self.wave_courant > 0.0 && self.wave_courant <= MAX_WAVE_COURANT) {
            return Err((
                "wave_courant",
                format!(
                    "must be in (0, {MAX_WAVE_COURANT}], got {}: above {MAX_WAVE_COURANT} the \
                     split projection pumps energy into stiff solids (stability map)",
                    efsi_core::scene::num(self.wave_courant)
                ),
            ));
        }
        if let Some(cap) = self.coupled_wave_courant
            && !(cap > 0.0 && cap <= MAX_COUPLED_WAVE_COURANT)
        {
            return Err((
                "coupled_wave_courant",
                format!(
                    "must be in (0, {MAX_COUPLED_WAVE_COURANT}], got {}: the largest cap the \
                     stability map measured stable",
                    efsi_core::scene::num(cap)
                ),
            ));
        }
        if !(self.coupling_tolerance > 0.0 && self.coupling_tolerance < 1.0) {
            return Err((
                "coupling_tolerance",
                format!(
                    "must be in (0, 1) (a fraction of the elastic step's divergence), got {}",
                    efsi_core::scene::num(self.coupling_tolerance)
                ),
            ));
        }
        if let Some(t) = self.theta
            && !(0.5..=1.0).contains(&t)
        {
            return Err((
                "theta",
                format!(
                    "must be in [0.5, 1] (0.5: Crank–Nicolson, 1: backward Euler), got {}",
                    efsi_core::scene::num(t)
                ),
            ));
        }
        if let Some(a) = self.stress_theta
            && !(0.5..=1.0).contains(&a)
        {
            return Err((
                "stress_theta",
                format!(
                    "must be in [0.5, 1] (0.5: the stress at mid-step, 1: at the step's end), got {a}"
                ),
            ));
        }
        check_iterations("coupling_iterations", self.coupling_iterations)?;
        if self.coupling == ElasticCoupling::Coupled && !self.implicit {
            return Err((
                "coupling",
                format!(
                    "{:?} needs the implicit elastic step (numerics.elastic.implicit: true)",
                    self.coupling
                ),
            ));
        }
        Ok(())
    }

    fn strict(&mut self) {
        self.tolerance = self.tolerance.min(1e-10);
    }
}

fn yes() -> bool {
    true
}
