//! The energy guard: a run whose motion gains energy that nothing supplied is stopped as
//! unstable ([`EfsiError::EnergyGrowth`]) long before a NaN would appear.
//!
//! **Rule.** With `E = KE + PE` (kinetic energy and the potential energy of gravity), the
//! guard records at the first step `E₀`, `PE₀` and the energy the initial motion and the
//! initial strain can supply, `S₀ = KE₀ + Σ stored energy` ([`efsi_core::StateResource`]'s
//! stored energy, a solid's strain energy). After every step, with `R` the largest release of
//! potential energy so far (`max (PE₀ − PE)`), the run is stopped when
//!
//! ```text
//!   E − E₀ > ENERGY_GUARD · (S₀ + R) + floor,     floor = 1e-9 (KE₀ + Σ stored + M g L),
//! ```
//!
//! `M` the mass in the domain, `g` gravity's magnitude and `L` the domain's longer side (the
//! floor absorbs round-off).
//!
//! **Where it applies.** Only where nothing else supplies energy: no moving wall, no frame
//! acceleration, no outflow boundary, no gravity along a periodic direction (walls at rest,
//! axes, free-slip walls and periodic boundaries across gravity supply none). Once a step runs
//! with a wall moving or the frame accelerating, the guard is off for the rest of the run.
//!
//! **Resumes.** Its baseline is a [`StepCheck`] record: snapshots and checkpoints carry it, so a
//! resumed run is judged against the same start as the run it continues. An empty record (a
//! snapshot taken before the first step) starts it afresh at the next step.

use crate::probes::{kinetic_energy, potential_energy_of};
use efsi_core::error::EfsiError;
use efsi_core::grid::Grid;
use efsi_core::scene::{Boundary, Scene, Side};
use efsi_core::{State, StepCheck, StepContext};

/// How far the kinetic + potential energy may rise above its start, as a multiple of the energy
/// the initial motion, the initial strain and gravity can have supplied, before a run is
/// stopped as unstable ([`EfsiError::EnergyGrowth`]). A stable run only loses energy to
/// dissipation, so it stays below the bound, which counts every source that can supply energy;
/// a run that pumps energy in grows geometrically and crosses it long before its fields
/// overflow to NaN.
pub const ENERGY_GUARD: f64 = 1.0;

/// The guard's name: the label of its record in a snapshot (a checkpoint stores that record).
pub const NAME: &str = "energy_guard";

/// The guard's baseline (see the module docs).
#[derive(Clone, Copy, Debug)]
struct Baseline {
    /// Kinetic + potential energy at the start.
    mech0: f64,
    /// Potential energy at the start.
    pe0: f64,
    /// Kinetic + strain energy at the start.
    supply0: f64,
    /// The largest drop of potential energy below its start so far.
    release: f64,
    /// An absolute allowance for round-off (1e-9 of the energies involved).
    floor: f64,
}

/// The energy guard as a step check ([`efsi_core::Simulation::add_check`];
/// [`crate::simulation`] adds it to every simulation it builds).
#[derive(Debug, Default)]
pub struct EnergyGuard {
    /// `None` until the first step after construction or a restore (the state is public and may
    /// be set up by hand in between), then `Some(None)` where something supplies energy and the
    /// guard is off.
    baseline: Option<Option<Baseline>>,
}

impl Baseline {
    /// The baseline of `state`, if the guard applies to `scene` (see the module docs).
    fn start(grid: &Grid, state: &State, scene: &Scene) -> Option<Baseline> {
        // Fluid leaving or entering through an outflow, or gravity along a periodic direction
        // (a flow driven round and round), changes the energy without a potential for it.
        let b = &scene.boundaries;
        let sides = Side::of(grid.dims());
        let open = sides
            .iter()
            .any(|&side| matches!(b.get(side), Boundary::Outflow));
        let periodic = |side: Side| matches!(b.get(side), Boundary::Periodic);
        let g = scene.gravity.xyz();
        let driven = (0..grid.dims()).any(|a| periodic(Side::normal_to(a, false)) && g[a] != 0.0);
        if open || driven {
            return None;
        }
        let ke = kinetic_energy(grid, state);
        let pe = potential_energy_of(grid, &state.rho, scene.gravity);
        let ee = state
            .resources
            .iter()
            .fold(0.0, |e, r| e + r.stored_energy().max(0.0));
        let mut mass = 0.0;
        for k in 0..if grid.is_3d() { grid.nz as isize } else { 1 } {
            for j in 0..grid.ny as isize {
                for i in 0..grid.nx as isize {
                    mass += state.rho[[i, j, k]] * grid.cell_volume(i) * grid.dz;
                }
            }
        }
        let lz = if grid.is_3d() {
            grid.nz as f64 * grid.dz
        } else {
            0.0
        };
        let reach = scene.gravity.norm() * (grid.x1() - grid.x0).max(grid.y1() - grid.y0).max(lz);
        let floor = (1e-9 * (ke + ee + mass * reach)).max(1e-300);
        [ke, pe, ee]
            .iter()
            .all(|x| x.is_finite())
            .then_some(Baseline {
                mech0: ke + pe,
                pe0: pe,
                supply0: ke + ee,
                release: 0.0,
                floor,
            })
    }
}

impl StepCheck for EnergyGuard {
    fn name(&self) -> &'static str {
        NAME
    }

    fn before(&mut self, scene: &Scene, ctx: &StepContext, state: &State) {
        // A moving wall or an accelerating frame does work the guard does not account for.
        let wall = ctx
            .bc
            .sides()
            .iter()
            .any(|&s| ctx.bc.moving_wall_speed(s).is_some_and(|w| w != 0.0));
        if wall || state.frame_acceleration != (0.0, 0.0) {
            self.baseline = Some(None);
        }
        if self.baseline.is_none() {
            self.baseline = Some(Baseline::start(ctx.grid, state, scene));
        }
    }

    fn after(&mut self, scene: &Scene, ctx: &StepContext, state: &State) -> Result<(), EfsiError> {
        let Some(Some(g)) = &mut self.baseline else {
            return Ok(());
        };
        let ke = kinetic_energy(ctx.grid, state);
        let pe = potential_energy_of(ctx.grid, &state.rho, scene.gravity);
        g.release = g.release.max(g.pe0 - pe);
        let supplied = g.supply0 + g.release;
        let gain = ke + pe - g.mech0;
        if gain > ENERGY_GUARD * supplied + g.floor {
            return Err(EfsiError::EnergyGrowth {
                t: state.t,
                step: state.step,
                gain,
                supplied,
                limit: ENERGY_GUARD,
            });
        }
        Ok(())
    }

    /// Empty before the guard starts (the first step), `[0]` when it is off,
    /// `[1, mech0, pe0, supply0, release, floor]` when it is on: the layout of the checkpoint's
    /// energy-guard record.
    fn save_into(&self, out: &mut Vec<f64>) {
        out.clear();
        // Room for the longest record: snapshots taken into this one later never allocate.
        out.reserve(6);
        match &self.baseline {
            None => {}
            Some(None) => out.push(0.0),
            Some(Some(g)) => out.extend([1.0, g.mech0, g.pe0, g.supply0, g.release, g.floor]),
        }
    }

    /// A record that does not fit starts the guard afresh at the next step.
    fn restore(&mut self, r: &[f64]) {
        self.baseline = match r {
            [x] if *x == 0.0 => Some(None),
            [x, mech0, pe0, supply0, release, floor] if *x == 1.0 => Some(Some(Baseline {
                mech0: *mech0,
                pe0: *pe0,
                supply0: *supply0,
                release: *release,
                floor: *floor,
            })),
            _ => None,
        };
    }
}
