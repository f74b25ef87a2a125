//! `cargo xtask bench`: the cavity, drop and sphere benchmarks, ns per cell-step on one and
//! N threads.

use crate::csv::{column, read_csv};
use crate::{cargo, roofline, root, run};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A benchmark case: `cavity<N>` (Re = 1000 lid-driven cavity, N², t ∈ [0, 2]) or `drop<N>`
/// (axisymmetric drop, ρ 1 in 1e-3, μ 1e-2 in 2e-4, g = 1, box 4 × 4, N², t ∈ [0, 1],
/// Δt = 0.5/N), optionally suffixed `-ic` for the IC(0) pressure preconditioner and/or `-vmg`
/// for the block-multigrid viscous preconditioner; or `sphere`, the sphere impact of
/// `cases/sphere_impact.ron` (35 cells per radius, 82 × 164, the whole run; `--quick` until
/// t = 0.03), suffix `-ej` for the Jacobi-preconditioned elastic step; or, in three dimensions,
/// `cube<N>` (the Re = 1000 lid-driven cube on N³, a fixed number of steps from rest) and
/// `drop3d` (`cases/falling_drop_3d.ron`, the whole run; `--quick` until t = 0.25).
struct Case {
    name: String,
    scene: String,
    /// `--set` overrides of the scene (`PATH=VALUE`).
    sets: Vec<String>,
    drop: bool,
    cells: usize,
    /// The stages this case runs with the block-multigrid preconditioner (their roofline
    /// model differs).
    block_multigrid: &'static [&'static str],
    /// Whether the scene is three-dimensional (the stages' roofline models differ).
    three_d: bool,
}

fn case(name: &str, quick: bool) -> Result<Case, String> {
    let bad = || {
        format!(
            "unknown case `{name}`: expected cavity<N> or drop<N>, optionally -ic, -vmg; sphere, \
             optionally -ej; cube<N>, drop3d, sphere3d, softcube, disks20 or disk1"
        )
    };
    if name == "sphere3d" {
        return sphere3d_case(quick);
    }
    if let Some(rest) = name.strip_prefix("sphere") {
        return sphere_case(name, rest, quick).ok_or_else(bad)?;
    }
    if name == "drop3d" {
        return drop3d_case(quick);
    }
    if name == "softcube" {
        return softcube_case(quick);
    }
    if name == "disks20" || name == "disk1" {
        return disks_case(name, quick);
    }
    if let Some(n) = name.strip_prefix("cube") {
        return match n.parse::<usize>() {
            Ok(n) if n >= 8 => Ok(cube_case(name, n, quick)),
            _ => Err(bad()),
        };
    }
    // Suffixes: -ic (IC(0) pressure preconditioner), -vmg (block multigrid for the viscous
    // step instead of the default Jacobi).
    let (rest, viscous) = match name.strip_suffix("-vmg") {
        Some(b) => (b, "Multigrid"),
        None => (name, "Jacobi"),
    };
    let (base, solver) = match rest.strip_suffix("-ic") {
        Some(b) => (b, "IncompleteCholesky"),
        None => (rest, "Multigrid"),
    };
    let (drop, n) = if let Some(n) = base.strip_prefix("cavity") {
        (false, n.parse::<usize>().map_err(|_| bad())?)
    } else if let Some(n) = base.strip_prefix("drop") {
        (true, n.parse::<usize>().map_err(|_| bad())?)
    } else {
        return Err(bad());
    };
    if n < 8 {
        return Err(bad());
    }
    let numerics = format!(
        "numerics: (projection: (solver: {solver}), viscous: (preconditioner: {viscous})),"
    );
    let scene = if drop {
        drop_scene(name, n, quick, &numerics)
    } else {
        cavity_scene(name, n, quick, &numerics)
    };
    Ok(Case {
        name: name.to_string(),
        scene,
        sets: Vec::new(),
        drop,
        cells: n * n,
        block_multigrid: if viscous == "Multigrid" {
            &["viscous"]
        } else {
            &[]
        },
        three_d: false,
    })
}

/// The sphere impact as shipped (35 cells per radius, t ∈ [0, 0.06]); quick: until t = 0.03,
/// just after first contact. Suffix (`rest`) -ej: the Jacobi-preconditioned elastic step; None
/// for another suffix.
fn sphere_case(name: &str, rest: &str, quick: bool) -> Option<Result<Case, String>> {
    let elastic = match rest {
        "" => "Multigrid",
        "-ej" => "Jacobi",
        _ => return None,
    };
    // The scene as shipped, changed by overrides (not by editing its text, which broke
    // whenever the scene's layout changed).
    let path = root().join("cases/sphere_impact.ron");
    let scene = match std::fs::read_to_string(&path) {
        Ok(s) => s,
        Err(e) => return Some(Err(format!("{}: {e}", path.display()))),
    };
    let mut sets = vec![format!("numerics.elastic.preconditioner={elastic}")];
    if quick {
        sets.push("time.end=0.03".into());
    }
    Some(Ok(Case {
        name: name.to_string(),
        scene,
        sets,
        drop: false,
        cells: 82 * 164,
        block_multigrid: if elastic == "Multigrid" {
            &["elastic"]
        } else {
            &[]
        },
        three_d: false,
    }))
}

/// The shipped three-dimensional drop (`cases/falling_drop_3d.ron`, 32 × 64 × 32 cells on a
/// quarter of the box, Δt = 1/128), its whole run t ∈ [0, 1] (quick: [0, 0.25]), its fields
/// written only at the end. The scene unedited, changed by overrides.
fn drop3d_case(quick: bool) -> Result<Case, String> {
    let scene = shipped("falling_drop_3d.ron")?;
    let end = if quick { 0.25 } else { 1.0 };
    Ok(Case {
        name: "drop3d".into(),
        scene,
        sets: vec![format!("time.end={end}"), format!("output.vtk_every={end}")],
        drop: true,
        cells: 32 * 64 * 32,
        block_multigrid: &[],
        three_d: true,
    })
}

/// A shipped scene's text, to be changed by overrides.
fn shipped(file: &str) -> Result<String, String> {
    let path = root().join("cases").join(file);
    std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The three-dimensional elastic sphere (`cases/sphere_impact_3d.ron`) at 10 cells per radius
/// (23 × 47 × 23 cells on the quarter box), released 4 mm above the substrate at its 1.22 m/s:
/// the fall, the first contact near 3.3 ms and the compression to t = 6 ms (quick: 3 ms, the
/// fall only). The scene unedited, changed by overrides.
fn sphere3d_case(quick: bool) -> Result<Case, String> {
    let end = if quick { 0.003 } else { 0.006 };
    Ok(Case {
        name: "sphere3d".into(),
        scene: shipped("sphere_impact_3d.ron")?,
        sets: vec![
            "grid.nx=23".into(),
            "grid.ny=47".into(),
            "grid.nz=23".into(),
            "solid.shape=Sphere(center: (0.0, 0.0232, 0.0), radius: 0.0192)".into(),
            format!("time.end={end}"),
            format!("output.vtk_every={end}"),
        ],
        drop: false,
        cells: 23 * 47 * 23,
        block_multigrid: &["elastic"],
        three_d: true,
    })
}

/// The neo-Hookean sphere in the lid-driven cube (`cases/soft_sphere_in_cube.ron`) at 24³,
/// t ∈ [0, 1] (quick: [0, 0.25]). The scene unedited, changed by overrides.
fn softcube_case(quick: bool) -> Result<Case, String> {
    let end = if quick { 0.25 } else { 1.0 };
    Ok(Case {
        name: "softcube".into(),
        scene: shipped("soft_sphere_in_cube.ron")?,
        sets: vec![
            "grid.nx=24".into(),
            "grid.ny=24".into(),
            "grid.nz=24".into(),
            format!("time.end={end}"),
            format!("output.vtk_every={end}"),
        ],
        drop: false,
        cells: 24 * 24 * 24,
        block_multigrid: &["elastic"],
        three_d: true,
    })
}

/// The twenty soft disks of `cases/twenty_disks.ron` (`disks20`) or its first disk alone
/// (`disk1`: the same scene, `solids` cut to its first entry), on the same 128² grid at the
/// same step (Δt ≤ 8e-4, the contact's own limit in the twenty's pile), t ∈ [0, 0.2] (quick:
/// [0, 0.05]), with the same probes: the cost of twenty bodies against one body, per
/// cell-step and in peak memory. The scene unedited, changed by overrides.
fn disks_case(name: &str, quick: bool) -> Result<Case, String> {
    let scene = shipped("twenty_disks.ron")?;
    let end = if quick { 0.05 } else { 0.2 };
    let mut sets = vec![
        format!("time.end={end}"),
        "time.dt_max=8e-4".into(),
        format!("output.vtk_every={end}"),
        "output.probes=[SolidCentroid, SolidVelocity, SolidVolume, KineticEnergy]".into(),
    ];
    if name == "disk1" {
        sets.push(format!("solids=[{}]", first_solid(&scene)?));
    }
    Ok(Case {
        name: name.into(),
        scene,
        sets,
        drop: false,
        cells: 128 * 128,
        block_multigrid: &["elastic"],
        three_d: false,
    })
}

/// The text of the first entry of the scene's `solids: [ … ]` list (its balanced parentheses).
fn first_solid(scene: &str) -> Result<String, String> {
    let missing = || "cases/twenty_disks.ron: no `solids: [ ( … ) ]` list".to_string();
    let list = scene.find("solids:").ok_or_else(missing)?;
    let open = list + scene[list..].find('(').ok_or_else(missing)?;
    let mut depth = 0usize;
    for (i, c) in scene[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return Ok(scene[open..=open + i].to_string());
                }
            }
            _ => {}
        }
    }
    Err(missing())
}

/// Steps of the cube benchmark (quick: a quarter).
const CUBE_STEPS: usize = 40;

/// The Re = 1000 lid-driven cube on `n`³ from rest (an impulsive start: a developed state of
/// the cube takes ~10⁴ steps at 64³, longer than the bench), [`CUBE_STEPS`] steps of the fixed
/// Δt = ½h (Courant number ½ at the lid's speed; quick: a quarter of the steps), the default
/// solvers (multigrid pressure, Jacobi viscous step).
fn cube_case(name: &str, n: usize, quick: bool) -> Case {
    let dt = 0.5 / n as f64;
    let steps = if quick { CUBE_STEPS / 4 } else { CUBE_STEPS };
    let scene = format!(
        r#"// Lid-driven cube, Re = 1000, from rest (cargo xtask bench).
Scene(
    name: "{name}",
    geometry: Cartesian3D,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),
    grid: (nx: {n}, ny: {n}, nz: {n}),
    time: (end: {end:e}, fixed_dt: {dt:e}),
    fluid: (density: 1.0, viscosity: 0.001),
    boundaries: (
        x_min: NoSlip, x_max: NoSlip,
        y_min: NoSlip, y_max: MovingWall(speed: 1.0),
        z_min: NoSlip, z_max: NoSlip,
    ),
)
"#,
        end = dt * steps as f64
    );
    Case {
        name: name.to_string(),
        scene,
        sets: Vec::new(),
        drop: false,
        cells: n * n * n,
        block_multigrid: &[],
        three_d: true,
    }
}

/// The axisymmetric drop on `n`², t ∈ [0, 1] (quick: [0, 0.25]), Δt = 0.5/n.
fn drop_scene(name: &str, n: usize, quick: bool, numerics: &str) -> String {
    let end = if quick { 0.25 } else { 1.0 };
    format!(
        r#"// Axisymmetric drop falling from rest (cargo xtask bench).
Scene(
    name: "{name}",
    geometry: Axisymmetric,
    domain: (r: (0.0, 4.0), z: (0.0, 4.0)),
    grid: (nr: {n}, nz: {n}),
    time: (end: {end}, fixed_dt: {dt:e}),
    fluid: (density: 1e-3, viscosity: 2e-4),
    gravity: (0.0, -1.0),
    solid: (shape: Disk(center: (0.0, 3.0), radius: 0.5), density: 1.0, viscosity: 1e-2),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    {numerics}
    output: (probe_every: {end}, probes: [SolidCentroid, SolidVelocity]),
)
"#,
        dt = 0.5 / n as f64
    )
}

/// The Re = 1000 lid-driven cavity on `n`², t ∈ [0, 2] (quick: [0, 0.5]).
fn cavity_scene(name: &str, n: usize, quick: bool, numerics: &str) -> String {
    let end = if quick { 0.5 } else { 2.0 };
    format!(
        r#"// Lid-driven cavity, Re = 1000, from rest (cargo xtask bench).
Scene(
    name: "{name}",
    geometry: Planar,
    domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
    grid: (nx: {n}, ny: {n}),
    time: (end: {end}, cfl: 0.4, dt_max: 1.0),
    fluid: (density: 1.0, viscosity: 0.001),
    boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    {numerics}
)
"#
    )
}

/// One run's figures.
#[derive(Clone)]
struct Figures {
    total: f64,
    stages: Vec<(String, f64, f64)>,
    steps: f64,
    fall: Option<f64>,
    wall: f64,
    /// The run's peak resident memory (bytes; `run.json`'s `peak_rss_bytes`, NaN where the
    /// system does not report it).
    peak_rss: f64,
}

fn run_case(c: &Case, threads: usize, out: &Path, binary: &Path) -> Result<Figures, String> {
    let dir = out.join(format!("{}_t{threads}", c.name));
    let scene = out.join(format!("{}.ron", c.name));
    std::fs::write(&scene, &c.scene).map_err(|e| e.to_string())?;
    let mut cmd = Command::new(binary);
    cmd.arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&dir)
        .arg("-q")
        .arg("--threads")
        .arg(threads.to_string())
        // Repeats and reruns replace the case's earlier outputs.
        .arg("--overwrite")
        .args(c.sets.iter().flat_map(|s| ["--set", s.as_str()]))
        .stdout(std::process::Stdio::null());
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start efsi: {e}"))?;
    if !status.success() {
        return Err(format!("{}: efsi failed ({status})", c.name));
    }
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let j: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let stages = j["stages"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|s| {
                    (
                        s["name"].as_str().unwrap_or("?").to_string(),
                        num(&s["ns_per_cell_step"]),
                        num(&s["solver_iterations_per_step"]),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let fall = if c.drop {
        let p = dir.join("probes.csv");
        let (h, cols) = read_csv(&p)?;
        let z = column(&h, &cols, "solid_y", &p)?;
        Some(z[0] - z[z.len() - 1])
    } else {
        None
    };
    Ok(Figures {
        total: num(&j["ns_per_cell_step"]),
        stages,
        steps: num(&j["steps"]),
        fall,
        wall: num(&j["wall_seconds"]),
        peak_rss: num(&j["peak_rss_bytes"]),
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Element-wise medians of several runs of one case.
fn median_figures(runs: &[Figures]) -> Figures {
    let mut f = runs[0].clone();
    f.total = median(runs.iter().map(|r| r.total).collect());
    f.wall = median(runs.iter().map(|r| r.wall).collect());
    f.peak_rss = median(runs.iter().map(|r| r.peak_rss).collect());
    for (k, s) in f.stages.iter_mut().enumerate() {
        s.1 = median(runs.iter().map(|r| r.stages[k].1).collect());
        s.2 = median(runs.iter().map(|r| r.stages[k].2).collect());
    }
    f
}

/// What `cargo xtask bench` is asked for.
struct Request {
    quick: bool,
    roofline: bool,
    /// Copy `bench.json` to the page's snapshot and render `docs/benchmarks.md` again.
    write_docs: bool,
    out: PathBuf,
    /// The thread counts each case runs on: 1, and N unless N is 1.
    pools: Vec<usize>,
    repeat: usize,
    cases: Vec<Case>,
    /// `--binary PATH`: time that build of efsi instead of building this one.
    binary: Option<PathBuf>,
    /// The command as given, for the JSON.
    command: String,
}

fn parse(args: &[String]) -> Result<Request, String> {
    let value = |flag: &str| args.windows(2).find(|w| w[0] == flag).map(|w| w[1].clone());
    let count = |flag: &str, default: usize| match value(flag) {
        Some(t) => t.parse().map_err(|_| format!("{flag} {t}: not a number")),
        None => Ok(default),
    };
    let has = |flag: &str| args.iter().any(|a| a == flag);
    let quick = has("--quick");
    let threads = count(
        "--threads",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
    )?;
    let names = value("--cases").unwrap_or_else(|| {
        if quick {
            "cavity128,drop128,cube64,drop3d".into()
        } else {
            "cavity128,cavity256,drop128,drop256,sphere,cube64,drop3d,sphere3d,softcube,disk1,disks20"
                .into()
        }
    });
    let cases = names
        .split(',')
        .map(|n| case(n.trim(), quick))
        .collect::<Result<Vec<_>, _>>()?;
    let given: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| *a != "--write-docs")
        .collect();
    Ok(Request {
        quick,
        roofline: has("--roofline"),
        write_docs: has("--write-docs"),
        out: value("--out")
            .map(PathBuf::from)
            .unwrap_or_else(|| root().join("target/bench")),
        pools: if threads == 1 {
            vec![1]
        } else {
            vec![1, threads]
        },
        repeat: count("--repeat", 1)?.max(1),
        cases,
        binary: value("--binary").map(PathBuf::from),
        command: ["cargo xtask bench"]
            .into_iter()
            .chain(given)
            .collect::<Vec<_>>()
            .join(" "),
    })
}

/// The efsi binary to time: `--binary`, else this workspace's, built in release.
fn efsi_binary(req: &Request) -> Result<PathBuf, String> {
    if let Some(b) = &req.binary {
        return Ok(b.clone());
    }
    let mut c = cargo();
    c.args(["build", "--quiet", "--release", "-p", "efsi"]);
    run(c, "build efsi (release)")?;
    Ok(root().join("target/release/efsi"))
}

/// The runs of one case, per pool size. The runs alternate between the pool sizes, so that a
/// load change on the machine affects both alike and the ratio is measured within one run of
/// the bench.
fn measure(c: &Case, req: &Request, binary: &Path) -> Result<Vec<Vec<Figures>>, String> {
    let mut runs: Vec<Vec<Figures>> = vec![Vec::new(); req.pools.len()];
    for _ in 0..req.repeat {
        for (k, &t) in req.pools.iter().enumerate() {
            runs[k].push(run_case(c, t, &req.out, binary)?);
        }
    }
    Ok(runs)
}

/// The range `(lo, hi)` of `v`, positive figures.
fn range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)))
}

/// One line of the roofline table.
struct RoofRow {
    case: String,
    threads: usize,
    stage: String,
    ns: f64,
    bytes: f64,
    bandwidth: f64,
    of_memory: f64,
    of_cache: f64,
}

/// The roofline figures of a case's median run `f` on `t` threads, against the triad
/// bandwidths `mem` and `llc`; appends its lines to `rows`.
fn roofline_json(
    c: &Case,
    t: usize,
    f: &Figures,
    (mem, llc): (f64, f64),
    rows: &mut Vec<RoofRow>,
) -> serde_json::Value {
    let bytes = |n: &String, it: f64| {
        roofline::model(n, c.block_multigrid.contains(&n.as_str()), c.three_d)
            .map(|m| roofline::bytes(m, it))
    };
    let mut row = |stage: &str, ns: f64, b: f64| {
        let bw = b / (ns * 1e-9);
        rows.push(RoofRow {
            case: c.name.clone(),
            threads: t,
            stage: stage.to_string(),
            ns,
            bytes: b,
            bandwidth: bw,
            of_memory: bw / mem,
            of_cache: bw / llc,
        });
        bw
    };
    let per_stage: Vec<serde_json::Value> = f
        .stages
        .iter()
        .filter_map(|(n, ns, it)| {
            let b = bytes(n, *it)?;
            let bw = row(n, *ns, b);
            Some(serde_json::json!({
                "name": n, "bytes_per_cell_step": b, "achieved_bytes_per_s": bw,
                "fraction_of_memory_triad": bw / mem,
                "fraction_of_cache_triad": bw / llc,
            }))
        })
        .collect();
    let total_bytes: f64 = f.stages.iter().filter_map(|(n, _, it)| bytes(n, *it)).sum();
    let bw = row("total", f.total, total_bytes);
    serde_json::json!({
        "memory_triad_bytes_per_s": mem, "cache_triad_bytes_per_s": llc,
        "bytes_per_cell_step": total_bytes, "achieved_bytes_per_s": bw,
        "fraction_of_memory_triad": bw / mem, "fraction_of_cache_triad": bw / llc,
        "stages": per_stage,
    })
}

/// Each stage's ns per cell-step, with its solver iterations per step in brackets.
fn stage_list(f: &Figures) -> String {
    f.stages
        .iter()
        .map(|(n, ns, it)| {
            if *it > 0.0 {
                format!("{n} {ns:.0} ({it:.1})")
            } else {
                format!("{n} {ns:.0}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The peak resident memory, in total and per cell, where the run reported it.
fn memory_note(f: &Figures, cells: usize) -> String {
    if f.peak_rss.is_finite() {
        format!(
            "; peak {:.1} MB ({:.0} B/cell)",
            f.peak_rss / 1e6,
            f.peak_rss / cells as f64
        )
    } else {
        String::new()
    }
}

/// Print the table line of case `c` on `pools[k]` threads and return its JSON; `limits` are
/// the triad bandwidths per pool size when `--roofline` measured them.
fn report_case(
    c: &Case,
    req: &Request,
    runs: &[Vec<Figures>],
    k: usize,
    limits: &[(f64, f64)],
    rows: &mut Vec<RoofRow>,
) -> serde_json::Value {
    let t = req.pools[k];
    let base = median_figures(&runs[0]).total;
    let f = median_figures(&runs[k]);
    let totals: Vec<f64> = runs[k].iter().map(|r| r.total).collect();
    let spread = {
        let (lo, hi) = range(&totals);
        (hi - lo) / f.total
    };
    let stages = stage_list(&f);
    // The speed-up of each alternating pair of runs: on a VM whose second core comes and goes,
    // their spread says how far to trust the ratio of the medians.
    let pairs: Vec<f64> = runs[0]
        .iter()
        .zip(&runs[k])
        .map(|(a, b)| a.total / b.total)
        .collect();
    let pair_note = if k > 0 && pairs.len() > 1 {
        let (lo, hi) = range(&pairs);
        format!(" (pairs {lo:.2}–{hi:.2}×)")
    } else {
        String::new()
    };
    // ½gt² at the drop's end time (g = 1): its free fall.
    let free_fall = f.fall.map(|_| 0.5 * if req.quick { 0.0625 } else { 1.0 });
    let fall = f
        .fall
        .zip(free_fall)
        .map(|(z, ff)| format!("; fall {z:.4} (½gt² = {ff:.4})"))
        .unwrap_or_default();
    let memory = memory_note(&f, c.cells);
    println!(
        "{:<14} {:>3} {:>6.0} {:>10.1} {:>7.2}×  {stages}{fall}; wall {:.1} s{memory}{pair_note}",
        c.name,
        t,
        f.steps,
        f.total,
        base / f.total,
        f.wall
    );
    let roof = limits.get(k).map(|&l| roofline_json(c, t, &f, l, rows));
    serde_json::json!({
        "roofline": roof,
        "case": c.name,
        "threads": t,
        "cells": c.cells,
        "steps": f.steps,
        "repeats": runs[k].len(),
        "ns_per_cell_step": f.total,
        "ns_per_cell_step_runs": totals,
        "spread": spread,
        "speedup_vs_1_thread": base / f.total,
        "speedup_pairs": pairs,
        "wall_seconds": f.wall,
        "peak_rss_bytes": f.peak_rss.is_finite().then_some(f.peak_rss),
        "peak_rss_bytes_per_cell": f.peak_rss.is_finite().then(|| f.peak_rss / c.cells as f64),
        "fall": f.fall,
        "free_fall": free_fall,
        "stages": f.stages.iter().map(|(n, ns, it)| serde_json::json!({
            "name": n, "ns_per_cell_step": ns, "solver_iterations_per_step": it
        })).collect::<Vec<_>>(),
    })
}

fn print_roofline(rows: &[RoofRow]) {
    println!(
        "\nroofline (compulsory traffic model: xtask/src/roofline.rs)\n{:<14} {:>3} {:<12} {:>10} {:>10} {:>8} {:>8} {:>8}",
        "case", "thr", "stage", "ns/cell·st", "B/cell·st", "GB/s", "of mem", "of LLC"
    );
    for r in rows {
        println!(
            "{:<14} {:>3} {:<12} {:>10.1} {:>10.0} {:>8.2} {:>7.0}% {:>7.0}%",
            r.case,
            r.threads,
            r.stage,
            r.ns,
            r.bytes,
            r.bandwidth / 1e9,
            100.0 * r.of_memory,
            100.0 * r.of_cache
        );
    }
}

/// Write `bench.json` into the output folder (and, with `--write-docs`, the page's snapshot
/// and the page).
fn write_json(req: &Request, cases: Vec<serde_json::Value>) -> Result<(), String> {
    let text = serde_json::to_string_pretty(&serde_json::json!({
        "command": req.command,
        "provenance": xtask::provenance::provenance(&root()),
        "quick": req.quick,
        "threads": req.pools,
        "roofline_models": roofline::MODELS.iter().map(|m| serde_json::json!({
            "stage": m.stage, "block_multigrid": m.block_multigrid, "three_d": m.three_d,
            "values_per_cell_step": m.fixed,
            "values_per_cell_and_iteration": m.per_iteration, "passes": m.passes,
        })).collect::<Vec<_>>(),
        "cases": cases,
    }))
    .map_err(|e| e.to_string())?;
    let path = req.out.join("bench.json");
    std::fs::write(&path, &text).map_err(|e| e.to_string())?;
    eprintln!("figures: {}", path.display());
    if req.write_docs {
        crate::docs::snapshot(&path, xtask::bench_page::BENCH_JSON)?;
    }
    Ok(())
}

pub(crate) fn bench(args: &[String]) -> Result<(), String> {
    let req = parse(args)?;
    let binary = efsi_binary(&req)?;
    std::fs::create_dir_all(&req.out).map_err(|e| e.to_string())?;
    // The bandwidth limits, measured in this run (main memory, last-level cache) per pool size.
    let limits: Vec<(f64, f64)> = if req.roofline {
        req.pools.iter().map(|&t| roofline::limits(t)).collect()
    } else {
        Vec::new()
    };
    for (&t, (mem, llc)) in req.pools.iter().zip(&limits) {
        println!(
            "triad, {t} thread(s): main memory {:.1} GB/s, last-level cache {:.1} GB/s",
            mem / 1e9,
            llc / 1e9
        );
    }
    println!(
        "{:<14} {:>3} {:>6} {:>10} {:>8}  per stage: ns/cell-step (solver iterations/step)",
        "case", "thr", "steps", "ns/cell·st", "speedup"
    );
    let (mut json, mut rows) = (Vec::new(), Vec::new());
    for c in &req.cases {
        let runs = measure(c, &req, &binary)?;
        for k in 0..req.pools.len() {
            json.push(report_case(c, &req, &runs, k, &limits, &mut rows));
        }
    }
    if req.roofline {
        print_roofline(&rows);
    }
    write_json(&req, json)
}

#[cfg(test)]
mod tests {
    use super::case;

    /// Every case the bench advertises parses; the sphere is the shipped scene, unedited, with
    /// its changes as overrides (editing its text broke the bench when the scene's `numerics`
    /// line changed).
    #[test]
    fn cases_parse_and_the_sphere_is_the_shipped_scene() {
        for name in [
            "cavity128",
            "cavity64-ic",
            "drop256",
            "drop128-ic-vmg",
            "sphere-ej",
            "cube64",
            "drop3d",
            "sphere3d",
            "softcube",
            "disks20",
            "disk1",
        ] {
            case(name, false).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        let shipped = std::fs::read_to_string(super::root().join("cases/sphere_impact.ron"))
            .expect("the shipped sphere scene");
        let c = case("sphere", true).unwrap();
        assert_eq!(c.scene, shipped);
        assert_eq!(
            c.sets,
            ["numerics.elastic.preconditioner=Multigrid", "time.end=0.03"]
        );
        assert_eq!(
            case("sphere-ej", false).unwrap().sets,
            ["numerics.elastic.preconditioner=Jacobi"]
        );
        assert!(case("sphere-x", false).is_err() && case("cube4", false).is_err());
        // The one disk is the twenty's first, with the same overrides otherwise.
        let (twenty, one) = (case("disks20", true).unwrap(), case("disk1", true).unwrap());
        assert_eq!(one.sets[..one.sets.len() - 1], twenty.sets[..]);
        let solids = one.sets.last().unwrap();
        assert!(
            solids.starts_with("solids=[(name: \"soft_00\"") && solids.ends_with("}))]"),
            "{solids}"
        );
        assert_eq!(solids.matches("shape:").count(), 1, "{solids}");
        // The 3-D drop is the shipped scene with overrides; the cube takes its steps at ½h.
        let d = case("drop3d", true).unwrap();
        assert!(d.three_d && d.drop && d.cells == 32 * 64 * 32);
        assert_eq!(d.sets, ["time.end=0.25", "output.vtk_every=0.25"]);
        let c = case("cube64", false).unwrap();
        assert!(c.three_d && c.cells == 64 * 64 * 64);
        assert!(c.scene.contains("fixed_dt: 7.8125e-3") && c.scene.contains("end: 3.125e-1"));
    }
}
