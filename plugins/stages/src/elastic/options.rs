//! The elastic stages' options (`numerics.elastic`), read by the elastic and deformation stages.

use efsi_core::Scene;
use efsi_core::scene::options::{Options, StageOptions, check_iterations, check_tolerance};
use serde::{Deserialize, Serialize};

/// Parameters of the elastic step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticOptions {
    /// Treat the elastic stress implicitly (default true). `false` makes the elastic force
    /// explicit — stable only for `Δt ≲ h √(ρ/G)`; it exists to show what the implicit term buys.
    #[serde(default = "yes")]
    pub implicit: bool,
    /// Relative residual at which BiCGSTAB stops: `‖r‖ ≤ tolerance · max(‖b‖, ‖M V‖)`, the
    /// step's elastic–viscous increment or the momentum, whichever is larger (default 1e-6;
    /// the `Strict` preset 1e-10). Chosen by the measured trade: the sphere impact at 35
    /// cells per radius takes 6.0 iterations a step instead of 12.2 at 1e-10 with its
    /// restitution 5e-6 apart (0.948607 against 0.948602) and its contact time, compression and
    /// volume drift unchanged; the paper's quick cases move by at most 2 % of their error (the
    /// oscillating Couette flows, whose elastic layer this solve drives; at 1e-5 they moved by
    /// up to 14 %).
    #[serde(default = "default_elastic_tol")]
    pub tolerance: f64,
    /// Iteration cap (default 5000).
    #[serde(default = "default_elastic_iter")]
    pub max_iterations: usize,
    /// Preconditioner of BiCGSTAB (default `Auto`).
    #[serde(default)]
    pub preconditioner: ElasticPreconditioner,
    /// The largest elastic-wave Courant number `Δt·c/h` a step may take (default and largest
    /// allowed: [`MAX_WAVE_COURANT`]), `c = √(G₀/ρ_s)` the solid's shear-wave speed at rest
    /// (`G₀` the law's stiffness at `B̃ = I`) and `h` the smaller cell side. The elastic step
    /// is implicit, but the pressure projection after it is not coupled to it: the strain its
    /// correction leaves in the solid is stored at stiffness G and given back at the next
    /// step, which pumps energy into stiff solids once `Δt·c/h` passes ≈ 5 (measured by the
    /// stability map, `cargo xtask bench-paper --case stability`). The time step is capped so;
    /// a `time.fixed_dt` above the cap is refused.
    #[serde(default = "default_wave_courant")]
    pub wave_courant: f64,
    /// How the elastic step and the pressure projection are coupled (default `Auto`: per step,
    /// the split step or the coupled one).
    #[serde(default)]
    pub coupling: ElasticCoupling,
    /// `Coupled`/`Auto` only: the coupled solve stops once `max |∇·V|·Δt` is at most this fraction
    /// of the step's divergence scale (that of the velocity before the step or of the
    /// explicit elastic increment, whichever is larger; default 1e-3) or the projection's
    /// tolerance, whichever is larger; the projection stage removes the rest.
    #[serde(default = "default_coupling_tolerance")]
    pub coupling_tolerance: f64,
    /// The implicit weight θ of B's stretching over a step, `B^{n+1} = Bⁿ + Δt[(1 − θ) H(Vⁿ) +
    /// θ H(V^{n+1})] + …` (default: 0.5, Crank–Nicolson, in a split step; 0.75 in a coupled one).
    /// At an elastic-wave Courant number `s = kΔt√(G/ρ)` far above 1 the velocity's
    /// amplification per step tends to `−(1 − θ)/θ`: −1 (an undamped two-step oscillation) at
    /// 0.5, −1/3 at 0.75; above 0.5 the step is first order in time for the solid. With
    /// `Coupled`, 0.5 keeps more of an impact's rebound (the map's G = 1e9 sphere at a cap of
    /// 12: 0.97 against 0.90 m/s), but its stiff modes are undamped: the map's sphere at
    /// G = 1e7 Pa and CFL 0.9 gained 18 % of its energy budget at 6 cells per radius, and
    /// 1.3 % at 12; at 0.75 every run of the map is stable. In between (the map's sphere at
    /// G = 1e9 Pa, CFL 0.5, `Coupled`, at 16 ms; `Split` 1.030 m/s): 0.6 keeps the rebound at
    /// caps of 4, 8 and 12 (1.060, 1.048, 1.042 against 1.019, 0.958, 0.911 at 0.75) and
    /// gains no energy, but at caps of 100 and 200 it rests on the wall as 0.75 does; 0.55 at a
    /// cap of 25 gains 0.4 % of the budget (1.087 m/s) and 0.5 at 200 leaves the wall faster
    /// than it came (1.30 against 1.23 m/s, +51 % of the budget at the end). The stiff spinning
    /// disk's extra loss of kinetic energy at large caps (see `coupled_wave_courant`) is not
    /// θ's damping: at a cap of 200, 0.6 and 0.55 lose 1.48e-3 and 1.82e-3 against 1.17e-3.
    #[serde(default)]
    pub theta: Option<f64>,
    /// The weight α of the step-end stress in a split step's momentum,
    /// `ρ δ/Δt = ∇·[α τ(B^{n+1}) + (1 − α) τ(Bⁿ)]`, in [½, 1]. Unset (the default), α is the
    /// stretching's θ — the θ-method, second order in time at θ = ½ — while the step's
    /// elastic-wave Courant number `Δt·c/h` is at most [`CN_WAVE_COURANT`], rising linearly to
    /// 1 (the stress at the step's end, which damps the stiff modes) at
    /// [`DAMPED_WAVE_COURANT`] and beyond: the split projection pumps energy into an undamped
    /// stiff solid (see the elastic module's "θ of the stress"). The coupled step always takes
    /// its stretching's θ.
    #[serde(default)]
    pub stress_theta: Option<f64>,
    /// `Coupled`/`Auto` only: the most FGMRES iterations per step (default 500, an order of
    /// magnitude above what the stability map's stiffest spheres take).
    #[serde(default = "default_coupling_iter")]
    pub coupling_iterations: usize,
    /// `Coupled`/`Auto` only: the largest elastic-wave Courant number `Δt·c/h` a step may take
    /// (at most [`MAX_COUPLED_WAVE_COURANT`]; default [`DEFAULT_COUPLED_WAVE_COURANT`] with
    /// `Coupled`, [`DEFAULT_AUTO_COUPLED_WAVE_COURANT`] with `Auto`). The coupled step is stable
    /// far beyond the split step's [`MAX_WAVE_COURANT`]; what the cap limits is accuracy: an
    /// impact taken in few coupled steps is damped (see the `coupled` module's "Limits"). The
    /// stability map's sphere (8 cells per radius, CFL 0.5) at G = 1e9 Pa under `Coupled` moves
    /// up at 16 ms at 0.65 m/s with a cap of 25, 0.10 at 50, and rests on the wall at 200
    /// (split: 1.03), hence 25 there. `Auto` takes impacts with split steps (within
    /// [`AUTO_WALL_CELLS`] of a wall), so its cap only sets the step of a stiff solid's flight:
    /// 454, 339, 284 and 232 steps at caps of 25, 50, 100 and 200 (1.030, 1.029, 1.025,
    /// 1.025 m/s; no energy gained beyond 2.9e-5 of the budget).
    ///
    /// A long coupled step away from walls costs the time error any step of that length has
    /// (first order in time), no more: so `Auto` takes its flights at the largest cap, and a
    /// stiff solid is no less accurate than a soft one at the step its own wave cap allows
    /// (`tests/tests/elastic.rs`, the spinning disk).
    #[serde(default)]
    pub coupled_wave_courant: Option<f64>,
}

/// How the implicit elastic step and the pressure projection share a time step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElasticCoupling {
    /// The elastic step, then the projection (seed Fig. 1): the projection's correction
    /// strains the solid without its stiffness answering within the step, which pumps energy
    /// into stiff solids above an elastic-wave Courant number of ≈ 5, so Δt is capped there
    /// (`wave_courant`).
    Split,
    /// The elastic step solves its implicit system together with the divergence constraint (FGMRES
    /// on the saddle-point system, block-triangular preconditioner from the elastic step's block
    /// multigrid and the projection's Poisson multigrid — Cahouet–Chabard), so the pressure's
    /// correction meets the solid's implicit stiffness: Δt is capped at `coupled_wave_courant`
    /// (default 25 here) elastic-wave Courant numbers instead of 4. The stability map's sphere at
    /// CFL 0.5 takes 32 and 257 steps at G = 1e7 and 1e9 Pa (split: 161, 1606) without gaining
    /// energy, and stays stable at G = 1e11 Pa. Its B stretching is damped (`theta` 0.75), so an
    /// impact taken in a few steps loses its rebound (at 16 ms 0.65 against the split step's 1.03
    /// m/s at G = 1e9; at 1e7 it stays on the wall); ≈ 1.5× the split step's cost per step on the
    /// seed's sphere.
    Coupled,
    /// Each step chooses: the coupled step (up to `coupled_wave_courant`) where the flow
    /// allows steps at least [`AUTO_COUPLED_GAIN`] times the split step's wave cap
    /// (`wave_courant`) and the solid is not busy deforming (its strain energy at most
    /// [`AUTO_STRAIN_SHARE`] of the kinetic energy), else the split step at its cap. A soft
    /// solid runs as with `Split`; a stiff one crosses the flow at the flow's step and takes
    /// an impact at the split step's, which resolves the rebound the coupled step's long steps
    /// damp. A coupled solve that does not converge within `coupling_iterations` is retaken as a
    /// split step (with `Coupled` it is an error). The stability map's sphere (8 cells per
    /// radius, CFL 0.5) at G = 1e9 Pa: 232 steps and 1.025 m/s at 16 ms (cap 200, the default
    /// with `Auto`), against Split's 1606 and 1.030 and Coupled's 257 and 0.647; at 1e7 Pa: 70
    /// steps and 0.943, against 161 and 0.943, and 30 and none (on the wall). Each step's θ is
    /// its scheme's (`theta`, when set, applies to both); with `implicit: false`, every step is
    /// split. The default: where the flow never
    /// allows longer steps than the split step's cap (the seed's sphere, every shipped case) it
    /// is `Split` to the last bit.
    #[default]
    Auto,
}

/// With `coupling: Auto`, the coupled step is taken only while the solid's strain energy is at
/// most this share of the flow's kinetic energy: above it the solid is exchanging energy with
/// its deformation (an impact, an oscillation) at a rate the split step's shorter steps
/// resolve. Measured on the stability map's sphere (G = 1e9 Pa, CFL 0.5, without the wall
/// rule [`AUTO_WALL_CELLS`]): a share of 0.1 left the wall at 0.974 m/s in 282 steps, 0.01 at
/// 0.994 in 341, 0.001 at 0.994 in 747.
pub const AUTO_STRAIN_SHARE: f64 = 1e-2;

/// With `coupling: Auto`, the coupled step is not taken while a cell mostly solid is within this
/// many cells of a wall, or would be after the coupled step at its velocity: the impact is
/// taken with split steps from its first contact. Measured on the stability map's sphere (CFL
/// 0.5): at G = 1e9 Pa a margin of 1 cell took 369 steps and left the wall at 1.038 m/s, 2
/// cells 484 and 1.039, none (the strain-energy rule alone) 341 and 0.994 (`Split`: 1606 and
/// 1.032); at G = 1e10 Pa 1 cell took 1285 steps and left at 0.975 (`Split`: 5079, 0.973).
/// Since the end-of-step update resets the fluid's B before it takes the rates (see the
/// elastic module's "Pure fluid"), a coupled step taken while the leaving sphere's bottom
/// cells were one cell off the wall lost 13 % of its kinetic energy in that step (at 16 ms
/// 0.953 m/s against `Split`'s 1.030 at G = 1e9 Pa, 0.850 against 0.943 at 1e7); with 1.5
/// cells: 454 steps and 1.030, and 64 steps and 0.928 (2 cells: 491 and 1.029, 70 and
/// 0.942). The step loses there because the wall row's cell on the axis still holds a sliver
/// of solid (φ ≈ 2e-3): the coupled step stretches it with the whole cell's rate, the air
/// filling the gap under the leaving sphere (B₂₂ − 1 from −0.010 to +0.044 at the stiffness
/// `φ^{1/2} G`), which pulls the sphere back, and resets its strain a step later (see the
/// `coupled` module's "Limits").
pub const AUTO_WALL_CELLS: f64 = 1.5;

/// With `coupling: Auto`, the coupled step is taken only where it lengthens the step at least
/// this much over the split step's wave cap: a coupled step costs 1.4–1.5 split steps on the
/// seed's sphere (35 cells per radius), so a shorter gain would not pay for it.
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
/// [`ElasticOptions::coupled_wave_courant`]): the runs of the stability map's sphere measured
/// there kept their energy (8 cells per radius, G = 1e7 and 1e9 Pa, caps up to 200; 6 cells
/// per radius, CFL 0.5 and 0.9, G = 1e7, 1e9, 1e11 Pa at 100 and 200: at most 3e-5 of the
/// budget gained). Before the fluid's B was reset ahead of the end-of-step rates, 100 gained
/// 15–25 % and 200 failed, and the maximum was 50.
pub const MAX_COUPLED_WAVE_COURANT: f64 = 200.0;

/// The coupled step's default cap on `Δt·c/h` with `Coupled`: an impact taken with `Coupled`
/// keeps some of its rebound (0.65 m/s against the split step's 1.03 on the map's sphere at
/// G = 1e9 Pa; see [`ElasticOptions::coupled_wave_courant`]).
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
    /// viscous operator with an effective viscosity `θΔt μ + (Δt/2) G_eff`.
    Multigrid,
    /// Multigrid, except with the split step in scenes with a periodic boundary, where Jacobi
    /// (the default; the coupled step keeps the multigrid, with which its FGMRES converges): the
    /// red–black smoother keeps a flow uniform along a periodic direction uniform only to the
    /// solver's tolerance (a velocity of 1e-12 across a flat interface, solid fraction leaking
    /// into the fluid), where Jacobi keeps it exactly.
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
