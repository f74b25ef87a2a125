//! Sugiyama's oscillating Couette flow with a neo-Hookean layer (`cases/oscillating_couette.ron`)
//! against the start-up reference (`tests/references/oscillating_couette/from_rest/`).

use super::plot::Scale;
use super::{Check, Options, Report, execute, figure, load_case, slug};
use efsi_core::scene::ProfileSpec;

const TIMES: [f64; 4] = [2.0, 2.8, 4.0, 4.8];

/// Run the case.
pub fn run(opts: &Options) -> Result<Report, String> {
    let dir = opts.out.join("oscillating_couette");
    let grids: &[usize] = if opts.quick {
        &[16, 32, 64]
    } else {
        &[32, 64, 128, 256]
    };
    let mut runs = Vec::new();
    let mut per_run = Vec::new();
    let mut schedule = Vec::new();
    for &n in grids {
        let (mut scene, path) = load_case("oscillating_couette.ron")?;
        scene.grid.ny = n;
        // Δt ∝ h (the scene's 0.001 at 64 cells): the elastic step is first order in time.
        scene.time.dt_max = Some(0.001 * 64.0 / n as f64);
        scene.output.vtk_every = None;
        let x = 0.5 * (scene.domain.x.0 + scene.domain.x.1);
        let h = 1.0 / n as f64;
        // The profile at the cell centres, where u lives: no interpolation.
        scene.output.profiles = vec![ProfileSpec::Line {
            name: "u".into(),
            from: (x, 0.5 * h),
            to: (x, 1.0 - 0.5 * h),
            points: n,
            fields: vec!["u".into()],
            at: TIMES.to_vec(),
        }];
        let label = format!("{n} cells");
        let (sim, run) = execute(scene, &path, &dir.join(slug(&label)), &label, opts)
            .map_err(|e| e.to_string())?;
        schedule = sim
            .pipeline()
            .stage_names()
            .iter()
            .map(|s| s.to_string())
            .collect();
        per_run.push(super::profile_errors(
            &run,
            "oscillating_couette/from_rest",
            &TIMES,
        )?);
        runs.push(run);
    }
    let (errs, orders, e64) = super::study(&mut runs, &per_run, &TIMES);
    let checks = vec![
        Check::at_most(
            "64 cells: max abs(u − u_ref) at t = 2, 2.8, 4, 4.8 (grid points)",
            e64,
            0.005,
            "e",
        ),
        Check::at_least(
            format!("observed order over {grids:?} cells (Δt ∝ h), the smallest"),
            orders.iter().copied().fold(f64::MAX, f64::min),
            1.0,
            "3",
        ),
    ];
    let mut plots = Vec::new();
    let (note, conv) = super::convergence("max error over the four times", grids, &errs, &orders);
    let mut notes = vec![note];
    let trade = vec![(
        "grids (Δt ∝ h)".to_string(),
        runs.iter()
            .filter_map(|r| r.error.map(|e| (r.wall_seconds, e)))
            .collect(),
    )];
    for (file, title, x, series) in [
        (
            "convergence",
            "Couette: error vs cells",
            "cells across",
            conv,
        ),
        (
            "tradeoff",
            "Couette: error vs wall time",
            "wall time (s)",
            trade,
        ),
    ] {
        figure(
            &dir,
            file,
            (title, x, "max abs(u − u_ref)"),
            &series,
            Scale::LogLog,
            &mut plots,
            &mut notes,
        );
    }
    Ok(Report {
        name: "oscillating_couette".into(),
        title: "Sugiyama's oscillating Couette flow, neo-Hookean layer, μ_s = 0".into(),
        reference: "the start-up-from-rest solution of `tests/references/oscillating_couette/from_rest/` (1D FE, 801 nodes), at the grid's u points".into(),
        error_metric: "max abs(u − u_ref), t = 2, 2.8, 4, 4.8".into(),
        runs,
        checks,
        plots,
        notes,
        schedule,
        recommendation: "64 cells (Δt = 0.001): 1.5e-3, a third of the target, in a few seconds; the error halves with each doubling (first order: the interface and the elastic step)".into(),
    })
}
