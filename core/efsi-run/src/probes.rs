//! Sampling fields at points and along lines, and the time-series probes of `probes.csv`.

use crate::output::spec::ProbeSpec;
use efsi_core::field::Field;
use efsi_core::grid::{Geometry, Grid};
use efsi_core::operators;
use efsi_core::scene::{Side, Vector};
use efsi_core::state::State;
use efsi_core::{Line, OutputDecl, OutputKind, Region, Stagger, unit};

/// Bilinear interpolation of a staggered field at `(x, y)`; `(ox, oy)` is the position of
/// index (0, 0) in cell units (`(0.5, 0.5)` for cell centres, `(0, 0.5)` for x-faces, …).
/// Ghost values are used near the boundary, so a point on a wall gets the wall value.
pub fn interpolate(grid: &Grid, f: &Field, (ox, oy): (f64, f64), (x, y): (f64, f64)) -> f64 {
    let fi = (x - grid.x0) / grid.dx - ox;
    let fj = (y - grid.y0) / grid.dy - oy;
    let i0 = (fi.floor() as isize).clamp(-1, grid.nx as isize);
    let j0 = (fj.floor() as isize).clamp(-1, grid.ny as isize);
    let wx = (fi - i0 as f64).clamp(0.0, 1.0);
    let wy = (fj - j0 as f64).clamp(0.0, 1.0);
    (1.0 - wy) * ((1.0 - wx) * f[(i0, j0)] + wx * f[(i0 + 1, j0)])
        + wy * ((1.0 - wx) * f[(i0, j0 + 1)] + wx * f[(i0 + 1, j0 + 1)])
}

/// Trilinear interpolation of a staggered field of a three-dimensional grid at `at`; `o` is the
/// position of index `[0, 0, 0]` in cell units (`[0.5; 3]` for cell centres, `[0, 0.5, 0.5]`
/// for x-faces, …). Ghost values are used near the boundary, as by [`interpolate`].
pub fn interpolate3(grid: &Grid, f: &Field, o: [f64; 3], at: [f64; 3]) -> f64 {
    let (lo, h, n) = ([grid.x0, grid.y0, grid.z0], grid.h(), grid.n());
    let mut i0 = [0isize; 3];
    let mut w = [0.0; 3];
    for a in 0..3 {
        let fi = (at[a] - lo[a]) / h[a] - o[a];
        i0[a] = (fi.floor() as isize).clamp(-1, n[a] as isize);
        w[a] = (fi - i0[a] as f64).clamp(0.0, 1.0);
    }
    let mut v = 0.0;
    for c in 0..8usize {
        let mut weight = 1.0;
        let mut at = i0;
        for a in 0..3 {
            let up = (c >> a) & 1 == 1;
            weight *= if up { w[a] } else { 1.0 - w[a] };
            at[a] += up as isize;
        }
        v += weight * f[at];
    }
    v
}

/// A named field sampled at a point of a three-dimensional grid ([`interpolate3`]; names from
/// [`crate::output::spec::FIELD_NAMES`], `w` among them); NaN for an unknown name.
pub fn sample3(grid: &Grid, state: &State, field: &str, at: [f64; 3]) -> f64 {
    let u = || interpolate3(grid, &state.u, [0.0, 0.5, 0.5], at);
    let v = || interpolate3(grid, &state.v, [0.5, 0.0, 0.5], at);
    let w = || {
        state
            .w
            .as_ref()
            .map_or(f64::NAN, |w| interpolate3(grid, w, [0.5, 0.5, 0.0], at))
    };
    let cell = |f: &Field| interpolate3(grid, f, [0.5; 3], at);
    match field {
        "u" => u(),
        "v" => v(),
        "w" => w(),
        "speed" => u().hypot(v()).hypot(w()),
        "p" => cell(&state.p),
        "density" => cell(&state.rho),
        "viscosity" => cell(&state.mu),
        "solid_fraction" => state.phi.as_ref().map_or(f64::NAN, cell),
        _ => f64::NAN,
    }
}

/// A named field at a point of the grid's dimension: [`sample_in`] at `(x, y)` in two
/// dimensions, [`sample3`] (or a stage's field, [`interpolate3`]) at `(x, y, z)` in three.
pub fn sample_at(
    grid: &Grid,
    state: &State,
    outputs: &[OutputDecl],
    field: &str,
    at: Vector,
) -> f64 {
    if !grid.is_3d() {
        return sample_in(grid, state, outputs, field, at.planar());
    }
    let stage = outputs.iter().find_map(|o| match o.kind {
        OutputKind::Field(f) if o.name == field => Some(f),
        _ => None,
    });
    match stage {
        Some(f) => f(state).map_or(f64::NAN, |f| interpolate3(grid, f, [0.5; 3], at.xyz())),
        None => sample3(grid, state, field, at.xyz()),
    }
}

/// Kinetic energy `½∫ρ|u|² dV` of the state ([`operators::kinetic_energy`]).
pub fn kinetic_energy(grid: &Grid, state: &State) -> f64 {
    operators::kinetic_energy(grid, &state.velocity(), &state.rho)
}

/// Gravitational potential energy `−∫ρ g·x dV` of the densities `rho`
/// ([`operators::potential_energy`]).
pub fn potential_energy_of(grid: &Grid, rho: &Field, gravity: Vector) -> f64 {
    operators::potential_energy(grid, rho, gravity.xyz())
}

/// `max |∇·u|` over the cells ([`operators::max_abs_div`]).
pub fn max_divergence(grid: &Grid, state: &State) -> f64 {
    operators::max_abs_div(grid, &state.velocity())
}

/// A named field sampled at a point (names from [`crate::output::spec::FIELD_NAMES`]).
pub fn sample(grid: &Grid, state: &State, field: &str, at: (f64, f64)) -> f64 {
    let u = || interpolate(grid, &state.u, (0.0, 0.5), at);
    let v = || interpolate(grid, &state.v, (0.5, 0.0), at);
    match field {
        "u" => u(),
        "v" => v(),
        "speed" => u().hypot(v()),
        "p" => interpolate(grid, &state.p, (0.5, 0.5), at),
        "density" => interpolate(grid, &state.rho, (0.5, 0.5), at),
        "viscosity" => interpolate(grid, &state.mu, (0.5, 0.5), at),
        "solid_fraction" => state
            .phi
            .as_ref()
            .map_or(f64::NAN, |f| interpolate(grid, f, (0.5, 0.5), at)),
        _ => f64::NAN,
    }
}

/// A named field sampled at a point: a shared field ([`sample`]) or one of the stages'
/// `outputs` ([`OutputKind::Field`]); NaN for a name neither has.
pub fn sample_in(
    grid: &Grid,
    state: &State,
    outputs: &[OutputDecl],
    field: &str,
    at: (f64, f64),
) -> f64 {
    let stage = outputs.iter().find_map(|o| match o.kind {
        OutputKind::Field(f) if o.name == field => Some(f),
        _ => None,
    });
    match stage {
        Some(f) => f(state).map_or(f64::NAN, |f| interpolate(grid, f, (0.5, 0.5), at)),
        None => sample(grid, state, field, at),
    }
}

/// Column names of a probe in `probes.csv` of a scene of `geometry`.
pub fn columns(p: &ProbeSpec, geometry: Geometry) -> Vec<String> {
    p.columns(geometry)
}

/// The quantity `name` of the stages' `outputs` ([`OutputKind::Quantity`]), NaN if none.
pub fn quantity(grid: &Grid, state: &State, outputs: &[OutputDecl], name: &str) -> f64 {
    outputs
        .iter()
        .find_map(|o| match o.kind {
            OutputKind::Quantity(f) if o.name == name => Some(f(grid, state)),
            _ => None,
        })
        .unwrap_or(f64::NAN)
}

/// What a probe is evaluated on: the simulation's grid and state, the scene's gravity and the
/// scheduled stages' outputs ([`efsi_core::Pipeline::outputs`]).
#[derive(Clone, Copy)]
pub struct Probed<'a> {
    /// The grid.
    pub grid: &'a Grid,
    /// The state.
    pub state: &'a State,
    /// The scene's gravity.
    pub gravity: Vector,
    /// The scheduled stages' outputs.
    pub outputs: &'a [OutputDecl],
}

/// A quantity of the framework: one or more columns of `probes.csv`, declared as the stages
/// declare theirs ([`OutputKind::Quantity`]) and found, as theirs are, by its name
/// ([`evaluate_quantity`]).
#[derive(Clone, Copy, Debug)]
pub struct Quantity {
    /// Its name (`Quantity("name")` in a scene).
    pub name: &'static str,
    /// Its columns in a planar or axisymmetric scene, in order.
    pub columns: &'static [&'static str],
    /// Its columns in a Cartesian3D scene, in order (the z components added); none for a
    /// quantity that is two-dimensional only.
    pub columns_3d: &'static [&'static str],
    /// Whether it needs a solid in the scene.
    pub needs_solid: bool,
    /// Its values, appended (one per column).
    pub eval: fn(&Probed, &mut Vec<f64>),
}

/// The framework's quantities (see [`ProbeSpec`] for each one's definition); a probe names one
/// as `Quantity("name")` or by its own variant (`KineticEnergy`).
pub const QUANTITIES: &[Quantity] = &[
    Quantity {
        name: "kinetic_energy",
        columns: &["kinetic_energy"],
        columns_3d: &["kinetic_energy"],
        needs_solid: false,
        eval: |p, out| out.push(kinetic_energy(p.grid, p.state)),
    },
    Quantity {
        name: "potential_energy",
        columns: &["potential_energy"],
        columns_3d: &["potential_energy"],
        needs_solid: false,
        eval: |p, out| out.push(potential_energy_of(p.grid, &p.state.rho, p.gravity)),
    },
    Quantity {
        name: "max_divergence",
        columns: &["max_divergence"],
        columns_3d: &["max_divergence"],
        needs_solid: false,
        eval: |p, out| out.push(max_divergence(p.grid, p.state)),
    },
    Quantity {
        name: "max_speed",
        columns: &["max_speed"],
        columns_3d: &["max_speed"],
        needs_solid: false,
        eval: |p, out| out.push(max_speed(p.grid, p.state)),
    },
    Quantity {
        name: "solid_volume",
        columns: &["solid_volume"],
        columns_3d: &["solid_volume"],
        needs_solid: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.push(m.volume),
            None => out.push(f64::NAN),
        },
    },
    Quantity {
        name: "solid_centroid",
        columns: &["solid_x", "solid_y"],
        columns_3d: &["solid_x", "solid_y", "solid_z"],
        needs_solid: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.extend(&m.centroid[..p.grid.dims()]),
            None => out.extend(std::iter::repeat_n(f64::NAN, p.grid.dims())),
        },
    },
    Quantity {
        name: "solid_velocity",
        columns: &["solid_u", "solid_v"],
        columns_3d: &["solid_u", "solid_v", "solid_w"],
        needs_solid: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.extend(&m.velocity[..p.grid.dims()]),
            None => out.extend(std::iter::repeat_n(f64::NAN, p.grid.dims())),
        },
    },
    Quantity {
        name: "solid_pieces",
        columns: &["solid_pieces", "solid_largest_piece"],
        columns_3d: &[],
        needs_solid: true,
        eval: |p, out| match &p.state.phi {
            Some(phi) => {
                let s = solid_pieces(p.grid, phi);
                out.extend([s.count as f64, s.largest]);
            }
            None => out.extend([f64::NAN, f64::NAN]),
        },
    },
];

impl Quantity {
    /// Its columns in a scene of `geometry` (none: it does not run there).
    pub fn columns_in(&self, geometry: Geometry) -> &'static [&'static str] {
        if geometry == Geometry::Cartesian3D {
            self.columns_3d
        } else {
            self.columns
        }
    }
}

/// The framework's quantity `name`, if it has one.
pub fn framework_quantity(name: &str) -> Option<&'static Quantity> {
    QUANTITIES.iter().find(|q| q.name == name)
}

/// Append the values of the quantity `name`: the framework's ([`QUANTITIES`]), else a
/// scheduled stage's ([`OutputKind::Quantity`], one column; NaN if no stage reports it).
pub fn evaluate_quantity(name: &str, probed: &Probed, out: &mut Vec<f64>) {
    match framework_quantity(name) {
        Some(q) => (q.eval)(probed, out),
        None => out.push(quantity(probed.grid, probed.state, probed.outputs, name)),
    }
}

/// The largest speed at the cell centres (each component the mean of its two faces).
fn max_speed(grid: &Grid, state: &State) -> f64 {
    let vel = state.velocity();
    Region::of(grid, Stagger::Cell).max(0.0, |l| {
        let faces: [_; 3] =
            std::array::from_fn(|a| vel.get(a).map(|f| (f.at(&l, [0; 3]), f.at(&l, unit(a)))));
        let mut m = 0.0f64;
        for n in 0..l.len {
            let s = faces
                .iter()
                .flatten()
                .map(|(lo, hi)| 0.5 * (lo[n] + hi[n]))
                .fold(0.0f64, f64::hypot);
            m = m.max(s);
        }
        m
    })
}

/// The solid's moments, if the state has a solid.
fn moments(p: &Probed) -> Option<SolidMoments> {
    p.state
        .phi
        .as_ref()
        .map(|phi| solid_moments(p.grid, p.state, phi))
}

/// Append the probe's values to `out`; `gravity` is the scene's, `outputs` the scheduled
/// stages' ([`efsi_core::Pipeline::outputs`]). A probe of a quantity is evaluated by name
/// ([`evaluate_quantity`]), whichever way the scene names it.
pub fn evaluate(
    p: &ProbeSpec,
    grid: &Grid,
    state: &State,
    gravity: Vector,
    outputs: &[OutputDecl],
    out: &mut Vec<f64>,
) {
    let probed = Probed {
        grid,
        state,
        gravity,
        outputs,
    };
    match p {
        ProbeSpec::Point { field, at, .. } => out.push(sample_at(grid, state, outputs, field, *at)),
        ProbeSpec::ContactForce { wall } => out.push(contact_force(grid, state, outputs, *wall)),
        ProbeSpec::ContactRadius { wall } => out.push(contact_radius(grid, state, outputs, *wall)),
        ProbeSpec::SolidExtent { at } => {
            let (b, t) = solid_extent(grid, state, *at);
            out.extend([b, t]);
        }
        quantity => match quantity.quantity() {
            Some(name) => evaluate_quantity(name, &probed, out),
            None => out.extend(std::iter::repeat_n(
                f64::NAN,
                columns(p, grid.geometry).len(),
            )),
        },
    }
}

/// Volume, centroid and volume-weighted velocity of the solid phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidMoments {
    /// `∫φ dV` (per radian when axisymmetric, per unit depth when planar).
    pub volume: f64,
    /// `∫φ x dV / ∫φ dV`: x, y and, in three dimensions, z (0 in two).
    pub centroid: [f64; 3],
    /// `∫φ u dV / ∫φ dV` with the cell-centre velocity (each component the mean of its two
    /// faces): u, v and, in three dimensions, w (0 in two).
    pub velocity: [f64; 3],
}

/// The moments of `phi` over the grid, in two or three dimensions (lines in parallel, summed
/// in line order: the same bits on any number of threads).
pub fn solid_moments(grid: &Grid, state: &State, phi: &Field) -> SolidMoments {
    /// The faces normal to `a` on either side of the line's cells.
    fn faces<'f>(c: &'f Field, line: &Line, a: usize) -> (&'f [f64], &'f [f64]) {
        (c.at(line, [0; 3]), c.at(line, unit(a)))
    }
    let cells = Region::of(grid, Stagger::Cell);
    let w_faces = state.w.as_ref().filter(|_| grid.is_3d());
    let [v, mx, my, mz, mu, mv, mw] = cells.sum(|line| {
        let mut s = [0.0; 7];
        let f = phi.at(&line, [0; 3]);
        let (u, v) = (faces(&state.u, &line, 0), faces(&state.v, &line, 1));
        let w = w_faces.map(|w| faces(w, &line, 2));
        for (n, [i, j, k]) in line.indices().enumerate() {
            let cell = grid.cell_volume(i);
            let dv = f[n] * if w.is_some() { cell * grid.dz } else { cell };
            if dv == 0.0 {
                continue;
            }
            s[0] += dv;
            s[1] += dv * grid.xc(i);
            s[2] += dv * grid.yc(j);
            s[4] += dv * (0.5 * (u.0[n] + u.1[n]));
            s[5] += dv * (0.5 * (v.0[n] + v.1[n]));
            if let Some(w) = w {
                s[3] += dv * grid.zc(k);
                s[6] += dv * (0.5 * (w.0[n] + w.1[n]));
            }
        }
        s
    });
    let inv = if v > 0.0 { 1.0 / v } else { f64::NAN };
    SolidMoments {
        volume: v,
        centroid: [mx * inv, my * inv, mz * inv],
        velocity: [mu * inv, mv * inv, mw * inv],
    }
}

/// The cells of the first row along `wall`: for each, its index `(i, j)`, its wall-face area
/// (per radian when axisymmetric) and its distance along the wall from the wall's start.
fn wall_cells(grid: &Grid, wall: Side) -> Vec<((isize, isize), f64, f64)> {
    let wall = planar_wall(wall);
    let m = &grid.metric;
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    match wall {
        Side::YMin | Side::YMax => {
            let j = if wall == Side::YMin { 0 } else { ny - 1 };
            (0..nx)
                .map(|i| ((i, j), m.rc(i) * grid.dx, (i as f64 + 0.5) * grid.dx))
                .collect()
        }
        // The x sides (`planar_wall` left no z side).
        _ => {
            let i = if wall == Side::XMin { 0 } else { nx - 1 };
            let r = if wall == Side::XMin {
                m.rx(0)
            } else {
                m.rx(nx)
            };
            (0..ny)
                .map(|j| ((i, j), r * grid.dy, (j as f64 + 0.5) * grid.dy))
                .collect()
        }
    }
}

/// A wall of a two-dimensional scene: `ZMin` and `ZMax` are the axisymmetric spellings of
/// `YMin` and `YMax` (the contact probes are two-dimensional: the output checks refuse them in
/// a Cartesian3D scene).
pub fn planar_wall(wall: Side) -> Side {
    match wall {
        Side::ZMin => Side::YMin,
        Side::ZMax => Side::YMax,
        w => w,
    }
}

/// The smallest solid fraction of a wall cell that can be in contact — the elastic stage's own
/// threshold: a cell holding less carries no deformation, so no elastic stress to press with.
/// Absolute, so a trace of solid left by the interface advection (φ ≈ 1e-18) never counts.
pub const CONTACT_MIN_SOLID_FRACTION: f64 = 1e-3;

/// The elastic stress the stages output (the VTK array `stress`, six components per cell),
/// if the state has one.
fn stress(grid: &Grid, state: &State, outputs: &[OutputDecl]) -> Option<Vec<f64>> {
    outputs.iter().find_map(|o| match o.kind {
        OutputKind::Array { values, .. } if o.name == "stress" => values(grid, state),
        _ => None,
    })
}

/// The contact cells along `wall` — [`ProbeSpec::ContactForce`]'s definition, shared by both
/// contact probes: each first-row cell holding at least [`CONTACT_MIN_SOLID_FRACTION`] of solid
/// and pressing on the wall (`p − p_a − τ_nn > 0`, with `p_a` the mean pressure of the row's
/// other cells, or 0 if there are none), as (traction, wall-face area, position along the wall).
/// `τ_nn` is the normal component of the stages' `stress` output.
fn contact_cells(grid: &Grid, state: &State, tau: &[f64], wall: Side) -> Vec<(f64, f64, f64)> {
    let Some(phi) = &state.phi else {
        return Vec::new();
    };
    let wall = planar_wall(wall);
    let cells = wall_cells(grid, wall);
    // The normal component's place in the VTK tensor (XX, YY, ZZ, …; r–z in the X–Z plane).
    let normal = match wall {
        Side::XMin | Side::XMax => 0,
        _ if grid.is_axisymmetric() => 2,
        _ => 1,
    };
    let tau_nn = |(i, j): (isize, isize)| tau[6 * (j as usize * grid.nx + i as usize) + normal];
    let solid = |c: (isize, isize)| phi[c] >= CONTACT_MIN_SOLID_FRACTION;
    let (mut pa, mut na) = (0.0, 0usize);
    for &(c, _, _) in &cells {
        if !solid(c) {
            pa += state.p[c];
            na += 1;
        }
    }
    let pa = if na > 0 { pa / na as f64 } else { 0.0 };
    cells
        .iter()
        .filter(|&&(c, _, _)| solid(c))
        .map(|&(c, area, s)| (state.p[c] - pa - tau_nn(c), area, s))
        .filter(|&(t, _, _)| t > 0.0)
        .collect()
}

/// See [`ProbeSpec::ContactForce`]: exactly 0 when no cell is in contact.
/// `outputs` are the scheduled stages' (NaN without a solid or a `stress` output).
pub fn contact_force(grid: &Grid, state: &State, outputs: &[OutputDecl], wall: Side) -> f64 {
    let Some(tau) = state.phi.as_ref().and(stress(grid, state, outputs)) else {
        return f64::NAN;
    };
    // Summed from +0.0 (an empty `Sum` of f64 is −0.0).
    contact_cells(grid, state, &tau, wall)
        .iter()
        .fold(0.0, |f, (t, a, _)| f + t * a)
}

/// See [`ProbeSpec::ContactRadius`]: exactly 0 when no cell is in contact.
/// `outputs` as for [`contact_force`].
pub fn contact_radius(grid: &Grid, state: &State, outputs: &[OutputDecl], wall: Side) -> f64 {
    let Some(tau) = state.phi.as_ref().and(stress(grid, state, outputs)) else {
        return f64::NAN;
    };
    let h = if matches!(planar_wall(wall), Side::YMin | Side::YMax) {
        grid.dx
    } else {
        grid.dy
    };
    contact_cells(grid, state, &tau, wall)
        .iter()
        .fold(0.0f64, |m, (_, _, s)| m.max(s + 0.5 * h))
}

/// See [`ProbeSpec::SolidExtent`].
pub fn solid_extent(grid: &Grid, state: &State, at: f64) -> (f64, f64) {
    let Some(phi) = &state.phi else {
        return (f64::NAN, f64::NAN);
    };
    let i = (((at - grid.x0) / grid.dx).floor() as isize).clamp(0, grid.nx as isize - 1);
    let ny = grid.ny as isize;
    // The longest run of cells holding solid.
    let (mut best, mut run) = ((0, -1), None::<isize>);
    for j in 0..=ny {
        let solid = j < ny && phi[(i, j)] > 1e-6;
        match (solid, run) {
            (true, None) => run = Some(j),
            (false, Some(lo)) => {
                if j - 1 - lo > best.1 - best.0 {
                    best = (lo, j - 1);
                }
                run = None;
            }
            _ => {}
        }
    }
    if best.1 < best.0 {
        return (f64::NAN, f64::NAN);
    }
    let (lo, hi) = best;
    let face = |j: isize| grid.y0 + j as f64 * grid.dy;
    let bottom = face(lo + 1) - phi[(i, lo)].clamp(0.0, 1.0) * grid.dy;
    let top = face(hi) + phi[(i, hi)].clamp(0.0, 1.0) * grid.dy;
    (bottom, top)
}

/// A cell holds solid for [`solid_pieces`] above this fraction.
pub const PIECE_PHI_MIN: f64 = 1e-3;

/// A region counts as a piece for [`solid_pieces`] above this share of the solid volume.
pub const PIECE_VOLUME_MIN: f64 = 1e-3;

/// The connected solid regions of [`solid_pieces`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidPieces {
    /// The regions holding more than [`PIECE_VOLUME_MIN`] of the solid volume.
    pub count: usize,
    /// The largest region's volume over the solid volume `∫φ dV` (NaN without solid).
    pub largest: f64,
}

/// See [`ProbeSpec::SolidPieces`]: the cells with `φ > PIECE_PHI_MIN`, joined through their
/// faces (not through corners; periodic sides not wrapped), flood-filled into regions whose
/// volumes `∫φ dV` are compared with the whole solid's.
pub fn solid_pieces(grid: &Grid, phi: &Field) -> SolidPieces {
    let (nx, ny) = (grid.nx, grid.ny);
    let at = |i: usize, j: usize| phi[(i as isize, j as isize)];
    let mut total = 0.0;
    for j in 0..ny {
        for i in 0..nx {
            total += at(i, j).clamp(0.0, 1.0) * grid.cell_volume(i as isize);
        }
    }
    let mut seen = vec![false; nx * ny];
    let mut stack = Vec::new();
    let mut volumes = Vec::new();
    for start in 0..nx * ny {
        if seen[start] || at(start % nx, start / nx) <= PIECE_PHI_MIN {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut v = 0.0;
        while let Some(c) = stack.pop() {
            let (i, j) = (c % nx, c / nx);
            v += at(i, j).min(1.0) * grid.cell_volume(i as isize);
            let mut visit = |q: usize, i: usize, j: usize| {
                if !seen[q] && at(i, j) > PIECE_PHI_MIN {
                    seen[q] = true;
                    stack.push(q);
                }
            };
            if i > 0 {
                visit(c - 1, i - 1, j);
            }
            if i + 1 < nx {
                visit(c + 1, i + 1, j);
            }
            if j > 0 {
                visit(c - nx, i, j - 1);
            }
            if j + 1 < ny {
                visit(c + nx, i, j + 1);
            }
        }
        volumes.push(v);
    }
    if total <= 0.0 {
        return SolidPieces {
            count: 0,
            largest: f64::NAN,
        };
    }
    SolidPieces {
        count: volumes
            .iter()
            .filter(|&&v| v > PIECE_VOLUME_MIN * total)
            .count(),
        largest: volumes.iter().copied().fold(0.0, f64::max) / total,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_core::FieldId;

    #[test]
    fn a_quantity_is_one_probe_whichever_way_the_scene_names_it() {
        let grid = Grid::new(Geometry::Planar, 6, 4, (0.0, 1.5), (0.0, 1.0));
        let fields = [FieldId::SolidFraction].into_iter().collect();
        let mut state = State::new(&grid, 2.0, 0.1, &fields);
        for j in 0..4 {
            for i in 0..7 {
                state.u[(i, j)] = 0.25 * i as f64 - 0.1 * j as f64;
            }
        }
        let phi = state.phi.as_mut().unwrap();
        phi[(1, 1)] = 1.0;
        phi[(2, 1)] = 0.5;
        let values = |p: &ProbeSpec| {
            let mut out = Vec::new();
            evaluate(p, &grid, &state, (0.0, -9.81).into(), &[], &mut out);
            out
        };
        for (variant, name) in [
            (ProbeSpec::KineticEnergy, "kinetic_energy"),
            (ProbeSpec::PotentialEnergy, "potential_energy"),
            (ProbeSpec::MaxDivergence, "max_divergence"),
            (ProbeSpec::MaxSpeed, "max_speed"),
            (ProbeSpec::SolidVolume, "solid_volume"),
            (ProbeSpec::SolidCentroid, "solid_centroid"),
            (ProbeSpec::SolidVelocity, "solid_velocity"),
            (ProbeSpec::SolidPieces, "solid_pieces"),
        ] {
            let by_name = ProbeSpec::Quantity(name.into());
            assert_eq!(variant.quantity(), Some(name));
            let planar = Geometry::Planar;
            assert_eq!(variant.columns(planar), by_name.columns(planar), "{name}");
            assert_eq!(variant.needs_solid(), by_name.needs_solid(), "{name}");
            let (a, b) = (values(&variant), values(&by_name));
            assert_eq!(a.len(), variant.columns(planar).len(), "{name}");
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}: {a:?} {b:?}"
            );
        }
        // The numbers: 1.5 cells of solid of volume 0.0625 each, its centroid; ½∫ρ|u|² dV with
        // u = 0.25 i − 0.1 j on the x-faces (density 2, cells of 0.25 × 0.25, half of each
        // face's ½ρu² to each of its cells).
        let v = values(&ProbeSpec::SolidCentroid);
        assert_eq!(values(&ProbeSpec::SolidVolume), vec![1.5 * 0.0625]);
        assert!((v[0] - (0.375 + 0.5 * 0.625) / 1.5).abs() < 1e-15 && (v[1] - 0.375).abs() < 1e-15);
        let mut ke = 0.0;
        for j in 0..4 {
            for i in 0..6 {
                let u = |i: i32| 0.25 * i as f64 - 0.1 * j as f64;
                ke += 2.0 * 0.5 * (u(i).powi(2) + u(i + 1).powi(2)) / 2.0 * 0.0625;
            }
        }
        let got = values(&ProbeSpec::KineticEnergy)[0];
        assert!(ke > 0.1 && (got - ke).abs() < 1e-12 * ke, "{got} vs {ke}");
        // A stage's quantity no scheduled stage reports is NaN, one column named after it.
        let elastic = ProbeSpec::Quantity("elastic_energy".into());
        assert_eq!(elastic.columns(Geometry::Planar), ["elastic_energy"]);
        assert!(values(&elastic)[0].is_nan());
        assert_eq!(ProbeSpec::ElasticEnergy.quantity(), Some("elastic_energy"));
    }

    #[test]
    fn the_solid_moments_of_a_three_dimensional_state_have_z_components() {
        // 4 × 2 × 3 cells of 0.25 × 0.5 × 0.5; solid in cell (1, 0, 2) (full) and (2, 1, 0)
        // (half), each face velocity a linear function of its position.
        let grid = Grid::new_3d([4, 2, 3], (0.0, 1.0), (0.0, 1.0), (0.0, 1.5));
        let fields = [FieldId::SolidFraction].into_iter().collect();
        let mut state = State::new(&grid, 1.0, 0.1, &fields);
        let w = state.w.as_mut().expect("w on a three-dimensional grid");
        for k in -1..5isize {
            for j in -1..4isize {
                for i in -1..6isize {
                    let (a, b, c) = (i as f64, j as f64, k as f64);
                    state.u[[i, j, k]] = 0.5 * a - b;
                    state.v[[i, j, k]] = c + 0.25 * b;
                    w[[i, j, k]] = 2.0 * c - a;
                }
            }
        }
        let phi = state.phi.as_mut().unwrap();
        phi[[1, 0, 2]] = 1.0;
        phi[[2, 1, 0]] = 0.5;
        let values = |p: &ProbeSpec| {
            let mut out = Vec::new();
            evaluate(
                p,
                &grid,
                &state,
                Vector(0.0, -1.0, Some(0.0)),
                &[],
                &mut out,
            );
            out
        };
        let cell = 0.25 * 0.5 * 0.5;
        assert_eq!(values(&ProbeSpec::SolidVolume), vec![1.5 * cell]);
        // Centroid: the cells' centres weighted 1 and ½.
        let mean = |a: f64, b: f64| (a + 0.5 * b) / 1.5;
        let want = [mean(0.375, 0.625), mean(0.25, 0.75), mean(1.25, 0.25)];
        let got = values(&ProbeSpec::SolidCentroid);
        assert_eq!(got.len(), 3);
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-15, "{got:?} vs {want:?}");
        }
        // Velocity: each component the mean of its two faces at the cells.
        let u = |i: f64, j: f64| 0.5 * (i + 0.5) - j;
        let v = |j: f64, k: f64| k + 0.25 * (j + 0.5);
        let w = |i: f64, k: f64| 2.0 * (k + 0.5) - i;
        let want = [
            mean(u(1.0, 0.0), u(2.0, 1.0)),
            mean(v(0.0, 2.0), v(1.0, 0.0)),
            mean(w(1.0, 2.0), w(2.0, 0.0)),
        ];
        let got = values(&ProbeSpec::SolidVelocity);
        assert_eq!(got.len(), 3);
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-14, "{got:?} vs {want:?}");
        }
        // The columns name the z components in three dimensions only.
        let c = |p: ProbeSpec, g| p.columns(g);
        let three = Geometry::Cartesian3D;
        assert_eq!(
            c(ProbeSpec::SolidCentroid, three),
            ["solid_x", "solid_y", "solid_z"]
        );
        assert_eq!(
            c(ProbeSpec::SolidVelocity, three),
            ["solid_u", "solid_v", "solid_w"]
        );
        assert_eq!(
            c(ProbeSpec::SolidCentroid, Geometry::Axisymmetric),
            ["solid_x", "solid_y"]
        );
        assert!(ProbeSpec::SolidCentroid.three_dimensional());
        assert!(!ProbeSpec::SolidPieces.three_dimensional());
        assert!(c(ProbeSpec::SolidPieces, three).is_empty());
    }

    #[test]
    fn solid_pieces_counts_face_connected_regions_and_the_largest_share() {
        let grid = Grid::new(Geometry::Planar, 8, 6, (0.0, 1.0), (0.0, 0.75));
        let mut phi = Field::zeros(&grid);
        // No solid: no piece, no share.
        let p = solid_pieces(&grid, &phi);
        assert_eq!(p.count, 0);
        assert!(p.largest.is_nan());
        // A 3×2 block of full cells with a half-full cell beside it: one piece of 6.5 cells.
        for j in 1..3 {
            for i in 1..4 {
                phi[(i, j)] = 1.0;
            }
        }
        phi[(4, 1)] = 0.5;
        let p = solid_pieces(&grid, &phi);
        assert_eq!((p.count, p.largest), (1, 1.0));
        // A cell touching the block only at a corner is a second piece: 1 of 7.5 cells.
        phi[(4, 3)] = 1.0;
        let p = solid_pieces(&grid, &phi);
        assert_eq!(p.count, 2);
        assert!((p.largest - 6.5 / 7.5).abs() < 1e-15, "{}", p.largest);
        // Flotsam: a cell at the holding threshold is no solid, one just above it is a region
        // too small to count as a piece, but its volume still counts in the whole.
        phi[(7, 5)] = PIECE_PHI_MIN;
        assert_eq!(solid_pieces(&grid, &phi).count, 2);
        phi[(7, 5)] = 2.0 * PIECE_PHI_MIN;
        let p = solid_pieces(&grid, &phi);
        assert_eq!(p.count, 2);
        let total = 7.5 + 2.0 * PIECE_PHI_MIN;
        assert!((p.largest - 6.5 / total).abs() < 1e-15, "{}", p.largest);
        // Joining the corner cell to the block through a face makes it one piece again.
        phi[(4, 2)] = 0.25;
        let p = solid_pieces(&grid, &phi);
        assert_eq!(p.count, 1);
        let total = 7.75 + 2.0 * PIECE_PHI_MIN;
        assert!((p.largest - 7.75 / total).abs() < 1e-15, "{}", p.largest);
    }
}
