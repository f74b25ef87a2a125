//! Sampling fields at points and along lines, and the time-series probes of `probes.csv`.

use crate::output::spec::ProbeSpec;
use efsi_core::body_fractions::BodyFractions;
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

/// Column names of a probe in `probes.csv` of a scene of `geometry` whose bodies are named
/// `bodies` ([`body_names`]: none for a scene of the single `solid:`);
/// [`ProbeSpec::columns_for`].
pub fn columns(p: &ProbeSpec, geometry: Geometry, bodies: &[String]) -> Vec<String> {
    p.columns_for(geometry, bodies)
}

/// The names of a scene's bodies as its probes' columns carry them: the `solids: [ … ]` list's,
/// in order; none for a scene of the single `solid:` (its columns are unprefixed) or without a
/// solid, and none for a scene whose bodies do not read (its check reports that).
pub fn body_names(scene: &efsi_core::Scene) -> Vec<String> {
    use efsi_core::scene::bodies::SceneBodies;
    match scene.bodies_spec() {
        Ok(Some(b)) if b.listed => b.list.into_iter().map(|b| b.name).collect(),
        _ => Vec::new(),
    }
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
    /// The solid fraction the solid quantities read: the state's (`Σ_k φ_k`), or one body's
    /// `φ_k` when a probe is evaluated per body ([`evaluate`]).
    pub phi: Option<&'a Field>,
    /// The cells outside which `phi` is zero, as a body's window (its first cell and its cells
    /// along each axis): the solid quantities sum over them only; `None`, the whole grid.
    pub window: Option<([usize; 3], [usize; 3])>,
}

impl Probed<'_> {
    /// The cells the solid quantities visit: [`Probed::window`], or the whole grid.
    fn cells(&self) -> Region {
        window_region(self.grid, self.window)
    }
}

/// The cells of `grid` in `window` (its first cell and its cells along each axis; `None`, the
/// whole grid).
fn window_region(grid: &Grid, window: Option<([usize; 3], [usize; 3])>) -> Region {
    let cells = Region::of(grid, Stagger::Cell);
    match window {
        None => cells,
        Some((lo, n)) => (0..3).fold(cells, |r, a| {
            r.range(a, lo[a] as isize, (lo[a] + n[a]) as isize)
        }),
    }
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
    /// Its columns in a Cartesian3D scene, in order (the z components added).
    pub columns_3d: &'static [&'static str],
    /// Whether it means something in an axisymmetric scene (a spin about the out-of-plane
    /// axis does not: the r–z plane turns about no axis of the body).
    pub axisymmetric: bool,
    /// Whether it needs a solid in the scene.
    pub needs_solid: bool,
    /// Whether it is a property of one body, evaluated per body in a scene that lists its
    /// bodies ([`evaluate`]); false for the whole scene's.
    pub per_body: bool,
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
        axisymmetric: true,
        needs_solid: false,
        per_body: false,
        eval: |p, out| out.push(kinetic_energy(p.grid, p.state)),
    },
    Quantity {
        name: "potential_energy",
        columns: &["potential_energy"],
        columns_3d: &["potential_energy"],
        axisymmetric: true,
        needs_solid: false,
        per_body: false,
        eval: |p, out| out.push(potential_energy_of(p.grid, &p.state.rho, p.gravity)),
    },
    Quantity {
        name: "max_divergence",
        columns: &["max_divergence"],
        columns_3d: &["max_divergence"],
        axisymmetric: true,
        needs_solid: false,
        per_body: false,
        eval: |p, out| out.push(max_divergence(p.grid, p.state)),
    },
    Quantity {
        name: "max_speed",
        columns: &["max_speed"],
        columns_3d: &["max_speed"],
        axisymmetric: true,
        needs_solid: false,
        per_body: false,
        eval: |p, out| out.push(max_speed(p.grid, p.state)),
    },
    Quantity {
        name: "solid_volume",
        columns: &["solid_volume"],
        columns_3d: &["solid_volume"],
        axisymmetric: true,
        needs_solid: true,
        per_body: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.push(m.volume),
            None => out.push(f64::NAN),
        },
    },
    Quantity {
        name: "solid_centroid",
        columns: &["solid_x", "solid_y"],
        columns_3d: &["solid_x", "solid_y", "solid_z"],
        axisymmetric: true,
        needs_solid: true,
        per_body: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.extend(&m.centroid[..p.grid.dims()]),
            None => out.extend(std::iter::repeat_n(f64::NAN, p.grid.dims())),
        },
    },
    Quantity {
        name: "solid_velocity",
        columns: &["solid_u", "solid_v"],
        columns_3d: &["solid_u", "solid_v", "solid_w"],
        axisymmetric: true,
        needs_solid: true,
        per_body: true,
        eval: |p, out| match moments(p) {
            Some(m) => out.extend(&m.velocity[..p.grid.dims()]),
            None => out.extend(std::iter::repeat_n(f64::NAN, p.grid.dims())),
        },
    },
    Quantity {
        name: "solid_pieces",
        columns: &["solid_pieces", "solid_largest_piece"],
        columns_3d: &["solid_pieces", "solid_largest_piece"],
        axisymmetric: true,
        needs_solid: true,
        per_body: true,
        eval: |p, out| match p.phi {
            Some(phi) => {
                let s = pieces_in(p.grid, phi, p.window);
                out.extend([s.count as f64, s.largest]);
            }
            None => out.extend([f64::NAN, f64::NAN]),
        },
    },
    Quantity {
        name: "solid_spin",
        columns: &["solid_spin"],
        columns_3d: &["solid_spin_x", "solid_spin_y", "solid_spin_z"],
        axisymmetric: false,
        needs_solid: true,
        per_body: true,
        eval: |p, out| {
            let spin = p.phi.map_or([f64::NAN; 3], |phi| {
                spin_in(p.grid, p.state, phi, p.cells())
            });
            // Three components in three dimensions; ω_z, the only one, in two.
            out.extend(&spin[if p.grid.is_3d() { 0 } else { 2 }..]);
        },
    },
    Quantity {
        name: "solid_overlap",
        columns: &["max_solid_fraction_sum", "solid_overlap_volume"],
        columns_3d: &["max_solid_fraction_sum", "solid_overlap_volume"],
        axisymmetric: true,
        needs_solid: true,
        per_body: false,
        eval: |p, out| match &p.state.phi {
            Some(phi) => {
                let (most, excess) = solid_overlap(p.grid, phi);
                out.extend([most, excess]);
            }
            None => out.extend([f64::NAN, f64::NAN]),
        },
    },
];

impl Quantity {
    /// Its columns in a scene of `geometry` (none: it does not run there).
    pub fn columns_in(&self, geometry: Geometry) -> &'static [&'static str] {
        match geometry {
            Geometry::Cartesian3D => self.columns_3d,
            Geometry::Axisymmetric if !self.axisymmetric => &[],
            _ => self.columns,
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
    p.phi.map(|phi| moments_in(p.grid, p.state, phi, p.cells()))
}

/// Append the probe's values to `out`; `gravity` is the scene's, `outputs` the scheduled
/// stages' ([`efsi_core::Pipeline::outputs`]). A probe of a quantity is evaluated by name
/// ([`evaluate_quantity`]), whichever way the scene names it.
///
/// **Per body.** In a scene of several bodies (the state holds their fractions,
/// [`BodyFractions`]) a probe of one body ([`ProbeSpec::per_body`]) is evaluated once per
/// body, in the scene's order, by the same kernel on that body's `φ_k` (written into a field of
/// the grid) in place of the state's `Σ_k φ_k` — one column group per body, named as
/// [`columns`] names them (NaN before the VOF stage has set the fractions). Otherwise, and for
/// a scene of one body, once on the state's solid fraction. [`ProbeSpec::BodyContact`] reads
/// the bodies' fractions pair by pair ([`body_contact`]); [`ProbeSpec::ElasticEnergy`] per
/// body each body's strain energy as the elastic stage records it beside its fraction
/// ([`efsi_core::body_fractions::BodyFraction::elastic_energy`]).
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
        phi: state.phi.as_ref(),
        window: None,
    };
    let bodies = state.resources.get::<BodyFractions>();
    if *p == ProbeSpec::BodyContact {
        if let Some(all) = bodies {
            body_contact(grid, all, out);
        }
        return;
    }
    match bodies.filter(|_| p.per_body()) {
        None => evaluate_on(p, &probed, out),
        // Each body's own strain energy, as the elastic stage left it.
        Some(all) if *p == ProbeSpec::ElasticEnergy => {
            let each = |b: &efsi_core::body_fractions::BodyFraction| match b.is_set() {
                true => b.elastic_energy,
                false => f64::NAN,
            };
            out.extend(all.bodies.iter().map(each));
        }
        Some(all) => {
            // Each body's φ_k on the grid, zero elsewhere: the last body's window cleared and
            // this one's written (the field as `BodyFraction::fill` leaves it).
            let mut phi = Field::zeros(grid);
            let mut last: Option<&efsi_core::body_fractions::BodyFraction> = None;
            for b in &all.bodies {
                if b.is_set() {
                    if let Some(l) = last {
                        write_window(&mut phi, l, false);
                    }
                    write_window(&mut phi, b, true);
                    last = Some(b);
                    // φ_k is zero outside its window: the sums over the window's cells, in
                    // the grid's order, are those over the grid bit for bit.
                    let on = Probed {
                        phi: Some(&phi),
                        window: Some((b.lo, b.n)),
                        ..probed
                    };
                    evaluate_on(p, &on, out);
                } else {
                    let n = p.columns(grid.geometry).len();
                    out.extend(std::iter::repeat_n(f64::NAN, n));
                }
            }
        }
    }
}

/// Write the values of body `b`'s fraction into its window's cells of `phi` (a field of the
/// grid), or zero there (`values` false), row by row.
fn write_window(phi: &mut Field, b: &efsi_core::body_fractions::BodyFraction, values: bool) {
    let [nx, ny, nz] = b.n;
    let lo = b.lo.map(|v| v as isize);
    for k in 0..nz {
        for j in 0..ny {
            let at = phi.idx3([lo[0], lo[1] + j as isize, lo[2] + k as isize]);
            let row = &mut phi.data_mut()[at..at + nx];
            match values {
                true => row.copy_from_slice(&b.phi[(k * ny + j) * nx..][..nx]),
                false => row.fill(0.0),
            }
        }
    }
}

/// [`evaluate`] on the solid fraction `p.phi`.
fn evaluate_on(probe: &ProbeSpec, p: &Probed, out: &mut Vec<f64>) {
    let (grid, state, outputs) = (p.grid, p.state, p.outputs);
    match (probe, p.phi) {
        (ProbeSpec::Point { field, at, .. }, _) => {
            out.push(sample_at(grid, state, outputs, field, *at))
        }
        (ProbeSpec::ContactForce { wall }, Some(phi)) => {
            out.push(contact_force_of(grid, state, phi, outputs, *wall))
        }
        (ProbeSpec::ContactRadius { wall }, Some(phi)) => {
            out.push(contact_radius_of(grid, state, phi, outputs, *wall))
        }
        (ProbeSpec::SolidExtent { at, z }, Some(phi)) => {
            let (b, t) = solid_extent_of(grid, phi, *at, z.unwrap_or(0.0));
            out.extend([b, t]);
        }
        (quantity, _) => match quantity.quantity() {
            Some(name) => evaluate_quantity(name, p, out),
            None => out.extend(std::iter::repeat_n(
                f64::NAN,
                quantity.columns(grid.geometry).len(),
            )),
        },
    }
}

/// See [`ProbeSpec::BodyContact`]: for each pair `(a, b)` of bodies, in the order of
/// [`columns`], `∫ min(φ_a, φ_b) dV` over the cells both windows cover and the number of
/// cells where both fractions exceed [`PIECE_PHI_MIN`]. A body whose fraction is not set yet
/// gives NaN.
pub fn body_contact(grid: &Grid, all: &BodyFractions, out: &mut Vec<f64>) {
    let bodies = &all.bodies;
    for (k, a) in bodies.iter().enumerate() {
        for b in &bodies[k + 1..] {
            if !(a.is_set() && b.is_set()) {
                out.extend([f64::NAN, f64::NAN]);
                continue;
            }
            // Only the cells of both windows can hold both (elsewhere `min(φ_a, φ_b)` is
            // at most 0): those of a's window that lie in b's, in a's order.
            let (lo, hi): ([usize; 3], [usize; 3]) = (
                std::array::from_fn(|x| a.lo[x].max(b.lo[x])),
                std::array::from_fn(|x| (a.lo[x] + a.n[x]).min(b.lo[x] + b.n[x])),
            );
            let (mut shared, mut cells) = (0.0, 0usize);
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
                    for i in lo[0]..hi[0] {
                        let at = [i, j, k].map(|v| v as isize);
                        let m = a.at(at).min(b.at(at));
                        if m > 0.0 {
                            shared += m * cell_volume(grid, at[0]);
                        }
                        cells += usize::from(m > PIECE_PHI_MIN);
                    }
                }
            }
            out.extend([shared, cells as f64]);
        }
    }
}

/// See [`ProbeSpec::SolidOverlap`]: the largest solid fraction of a cell, `max Σ_k φ_k` (at
/// most 1 where no bodies overlap), and the volume in excess of full cells,
/// `∫ max(0, Σ_k φ_k − 1) dV`, over the interior cells of `phi` (the state's `Σ_k φ_k`).
pub fn solid_overlap(grid: &Grid, phi: &Field) -> (f64, f64) {
    let cells = Region::of(grid, Stagger::Cell);
    let most = cells.max(0.0, |line| {
        phi.at(&line, [0; 3]).iter().fold(0.0f64, |m, f| m.max(*f))
    });
    let [excess] = cells.sum(|line| {
        let mut e = 0.0;
        for (f, [i, _, _]) in phi.at(&line, [0; 3]).iter().zip(line.indices()) {
            if *f > 1.0 {
                e += (f - 1.0) * cell_volume(grid, i);
            }
        }
        [e]
    });
    (most, excess)
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
    moments_in(grid, state, phi, Region::of(grid, Stagger::Cell))
}

/// [`solid_moments`] over the cells `cells` (those outside are taken as holding no solid).
fn moments_in(grid: &Grid, state: &State, phi: &Field, cells: Region) -> SolidMoments {
    /// The faces normal to `a` on either side of the line's cells.
    fn faces<'f>(c: &'f Field, line: &Line, a: usize) -> (&'f [f64], &'f [f64]) {
        (c.at(line, [0; 3]), c.at(line, unit(a)))
    }
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

/// A cell of the first layer along a wall ([`wall_cells`]).
#[derive(Clone, Copy, Debug)]
struct WallCell {
    /// Its index.
    at: [isize; 3],
    /// Its wall-face area (per radian when axisymmetric, per unit depth when planar).
    area: f64,
    /// How far the cell reaches from the wall's corner (the lower end of each axis along the
    /// wall): the largest projection of the cell's points on the direction from the corner to
    /// its centre, `|s| + ½ Σ_t (s_t/|s|) h_t` with `s` the centre's offset along the wall's
    /// axes `t` — in two dimensions, `s + ½h`, the far edge of the cell.
    reach: f64,
}

/// The cells of the first layer along `wall` (the cells with index 0, or `n − 1`, along the
/// wall's axis), in storage order; the same code for a row of a two-dimensional grid and a
/// layer of a three-dimensional one.
fn wall_cells(grid: &Grid, wall: Side) -> Vec<WallCell> {
    let wall = planar_wall(wall);
    let (a, n, h, m) = (wall.axis(), grid.n(), grid.h(), &grid.metric);
    let tangential: Vec<usize> = (0..grid.dims()).filter(|&t| t != a).collect();
    let layer = if wall.is_upper() {
        n[a] as isize - 1
    } else {
        0
    };
    let mut range = n.map(|n| 0..n as isize);
    range[a] = layer..layer + 1;
    let mut cells = Vec::new();
    for k in range[2].clone() {
        for j in range[1].clone() {
            for i in range[0].clone() {
                let at = [i, j, k];
                // The radius factor of the wall face: the x-face's for an x wall, the cell's.
                let r = match (a, wall.is_upper()) {
                    (0, false) => m.rx(0),
                    (0, true) => m.rx(n[0] as isize),
                    _ => m.rc(i),
                };
                let area = tangential.iter().fold(r, |s, &t| s * h[t]);
                let s: Vec<f64> = tangential
                    .iter()
                    .map(|&t| (at[t] as f64 + 0.5) * h[t])
                    .collect();
                let norm = s.iter().map(|s| s * s).sum::<f64>().sqrt();
                let edge =
                    (tangential.iter().zip(&s)).fold(0.0, |e, (&t, s)| e + s / norm * (0.5 * h[t]));
                cells.push(WallCell {
                    at,
                    area,
                    reach: norm + edge,
                });
            }
        }
    }
    cells
}

/// A wall of the scene's grid: `ZMin` and `ZMax` are the axisymmetric spellings of `YMin` and
/// `YMax` (the z sides of a three-dimensional box are its own).
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

/// The elastic stress the stages output (the VTK array `stress`, six components per cell):
/// `Some(None)` when no scheduled stage declares one (a solid without a law: no elastic
/// stress), `None` when one is declared but has no values.
fn stress(grid: &Grid, state: &State, outputs: &[OutputDecl]) -> Option<Option<Vec<f64>>> {
    let declared = outputs.iter().find_map(|o| match o.kind {
        OutputKind::Array { values, .. } if o.name == "stress" => Some(values),
        _ => None,
    });
    match declared {
        Some(values) => values(grid, state).map(Some),
        None => Some(None),
    }
}

/// The contact cells along `wall` — [`ProbeSpec::ContactForce`]'s definition, shared by both
/// contact probes: each first-layer cell holding at least [`CONTACT_MIN_SOLID_FRACTION`] of
/// solid and pressing on the wall (`p − p_a − τ_nn > 0`, with `p_a` the mean pressure of the
/// layer's other cells, or 0 if there are none), as (traction, wall-face area, reach along the
/// wall). `τ_nn` is the normal component of the stages' `stress` output (0 without one).
fn contact_cells(
    grid: &Grid,
    state: &State,
    body: &Field,
    tau: Option<&[f64]>,
    wall: Side,
) -> Vec<(f64, f64, f64)> {
    // The ambient pressure: of the layer's cells holding no solid of any body.
    let all = state.phi.as_ref().unwrap_or(body);
    let wall = if grid.is_3d() {
        wall
    } else {
        planar_wall(wall)
    };
    let cells = wall_cells(grid, wall);
    // The normal component's place in the VTK tensor (XX, YY, ZZ, …; r–z in the X–Z plane).
    let normal = match wall.axis() {
        1 if grid.is_axisymmetric() => 2,
        a => a,
    };
    let [nx, ny, _] = grid.n();
    let tau_nn = |[i, j, k]: [isize; 3]| {
        tau.map_or(0.0, |t| {
            t[6 * ((k as usize * ny + j as usize) * nx + i as usize) + normal]
        })
    };
    let holds = |f: &Field, c: [isize; 3]| f[c] >= CONTACT_MIN_SOLID_FRACTION;
    let solid = |c: [isize; 3]| holds(body, c);
    let (mut pa, mut na) = (0.0, 0usize);
    for c in &cells {
        if !holds(all, c.at) {
            pa += state.p[c.at];
            na += 1;
        }
    }
    let pa = if na > 0 { pa / na as f64 } else { 0.0 };
    cells
        .iter()
        .filter(|c| solid(c.at))
        .map(|c| (state.p[c.at] - pa - tau_nn(c.at), c.area, c.reach))
        .filter(|&(t, _, _)| t > 0.0)
        .collect()
}

/// See [`ProbeSpec::ContactForce`]: exactly 0 when no cell is in contact.
/// `outputs` are the scheduled stages' (NaN without a solid, or when their `stress` output has
/// no values).
pub fn contact_force(grid: &Grid, state: &State, outputs: &[OutputDecl], wall: Side) -> f64 {
    state.phi.as_ref().map_or(f64::NAN, |phi| {
        contact_force_of(grid, state, phi, outputs, wall)
    })
}

/// [`contact_force`] of the body whose fraction is `body` (the state's for one body, `φ_k`
/// for body `k` of several; the ambient pressure from the cells that hold no body).
pub fn contact_force_of(
    grid: &Grid,
    state: &State,
    body: &Field,
    outputs: &[OutputDecl],
    wall: Side,
) -> f64 {
    let Some(tau) = stress(grid, state, outputs) else {
        return f64::NAN;
    };
    // Summed from +0.0 (an empty `Sum` of f64 is −0.0).
    contact_cells(grid, state, body, tau.as_deref(), wall)
        .iter()
        .fold(0.0, |f, (t, a, _)| f + t * a)
}

/// See [`ProbeSpec::ContactRadius`]: exactly 0 when no cell is in contact.
/// `outputs` as for [`contact_force`].
pub fn contact_radius(grid: &Grid, state: &State, outputs: &[OutputDecl], wall: Side) -> f64 {
    state.phi.as_ref().map_or(f64::NAN, |phi| {
        contact_radius_of(grid, state, phi, outputs, wall)
    })
}

/// [`contact_radius`] of the body whose fraction is `body` (as [`contact_force_of`]).
pub fn contact_radius_of(
    grid: &Grid,
    state: &State,
    body: &Field,
    outputs: &[OutputDecl],
    wall: Side,
) -> f64 {
    let Some(tau) = stress(grid, state, outputs) else {
        return f64::NAN;
    };
    contact_cells(grid, state, body, tau.as_deref(), wall)
        .iter()
        .fold(0.0f64, |m, (_, _, reach)| m.max(*reach))
}

/// See [`ProbeSpec::SolidExtent`]: along the y-line through `(x, z)` (`z` ignored in two
/// dimensions).
pub fn solid_extent(grid: &Grid, state: &State, x: f64, z: f64) -> (f64, f64) {
    state
        .phi
        .as_ref()
        .map_or((f64::NAN, f64::NAN), |phi| solid_extent_of(grid, phi, x, z))
}

/// [`solid_extent`] of the solid fraction `phi` (one body's, or the state's).
pub fn solid_extent_of(grid: &Grid, phi: &Field, x: f64, z: f64) -> (f64, f64) {
    let i = (((x - grid.x0) / grid.dx).floor() as isize).clamp(0, grid.nx as isize - 1);
    let k = if grid.is_3d() {
        (((z - grid.z0) / grid.dz).floor() as isize).clamp(0, grid.nz as isize - 1)
    } else {
        0
    };
    let ny = grid.ny as isize;
    // The longest run of cells holding solid.
    let (mut best, mut run) = ((0, -1), None::<isize>);
    for j in 0..=ny {
        let solid = j < ny && phi[[i, j, k]] > 1e-6;
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
    let bottom = face(lo + 1) - phi[[i, lo, k]].clamp(0.0, 1.0) * grid.dy;
    let top = face(hi) + phi[[i, hi, k]].clamp(0.0, 1.0) * grid.dy;
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

/// The volume of a cell in column `i` of `grid` (per radian when axisymmetric, per unit depth
/// when planar).
fn cell_volume(grid: &Grid, i: isize) -> f64 {
    if grid.is_3d() {
        grid.cell_volume(i) * grid.dz
    } else {
        grid.cell_volume(i)
    }
}

/// See [`ProbeSpec::SolidPieces`]: the cells with `φ > PIECE_PHI_MIN`, joined through their
/// faces (4-connected in two dimensions, 6-connected in three; not through edges or corners;
/// periodic sides not wrapped), flood-filled into regions whose volumes `∫φ dV` are compared
/// with the whole solid's.
pub fn solid_pieces(grid: &Grid, phi: &Field) -> SolidPieces {
    pieces_in(grid, phi, None)
}

/// [`solid_pieces`] of the cells in `window` (its first cell and its cells along each axis;
/// `None`, the whole grid), those outside taken as holding no solid: the same pieces, found in
/// the same order, as on the whole grid when `phi` is zero outside.
fn pieces_in(grid: &Grid, phi: &Field, window: Option<([usize; 3], [usize; 3])>) -> SolidPieces {
    let (lo, n) = window.unwrap_or(([0; 3], grid.n()));
    let dims = grid.dims();
    let lo = lo.map(|v| v as isize);
    let stride = [1, n[0], n[0] * n[1]];
    let cells = n[0] * n[1] * n[2];
    let index =
        |c: usize| -> [isize; 3] { std::array::from_fn(|a| ((c / stride[a]) % n[a]) as isize) };
    // φ of the cells in their compact order (x fastest) and the volumes of a row's cells.
    let mut phis = Vec::with_capacity(cells);
    for k in 0..n[2] as isize {
        for j in 0..n[1] as isize {
            let at = phi.idx3([lo[0], j + lo[1], k + lo[2]]);
            phis.extend_from_slice(&phi.data()[at..at + n[0]]);
        }
    }
    let volumes_x: Vec<f64> = (0..n[0] as isize)
        .map(|i| cell_volume(grid, i + lo[0]))
        .collect();
    let at = |c: usize| phis[c];
    let volume = |c: usize| volumes_x[c % n[0]];
    // Σ φ dV over the cells in their order, row by row.
    let total = phis.chunks_exact(n[0]).fold(0.0, |t, row| {
        row.iter()
            .zip(&volumes_x)
            .fold(t, |t, (f, v)| t + f.clamp(0.0, 1.0) * v)
    });
    let mut seen = vec![false; cells];
    let mut stack = Vec::new();
    let mut volumes = Vec::new();
    for start in 0..cells {
        if seen[start] || at(start) <= PIECE_PHI_MIN {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut v = 0.0;
        while let Some(c) = stack.pop() {
            v += at(c).min(1.0) * volume(c);
            let ix = index(c);
            for a in 0..dims {
                let lower = (ix[a] > 0).then(|| c - stride[a]);
                let upper = (ix[a] + 1 < n[a] as isize).then(|| c + stride[a]);
                for q in [lower, upper].into_iter().flatten() {
                    if !seen[q] && at(q) > PIECE_PHI_MIN {
                        seen[q] = true;
                        stack.push(q);
                    }
                }
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

/// See [`ProbeSpec::SolidSpin`]: the angular velocity `ω` of the rigid rotation about the
/// solid's centroid `c` that fits its velocity best, `I ω = L` with `L = ∫φ r × u dV` and
/// `I = ∫φ (|r|² 1 − r rᵀ) dV` (`r = x − c`, `u` the cell-centre velocity, each component the
/// mean of its two faces; volume-weighted like [`solid_moments`]). In three dimensions the
/// 3 × 3 system, solved by Cramer's rule; in two, `ω_z = L_z / I_zz` (x and y components 0).
/// A rigid rotation `u = U + ω × (x − c)` gives `ω` exactly (to round-off): the mean of two
/// faces is exact for a velocity linear in x. NaN without solid.
pub fn solid_spin(grid: &Grid, state: &State, phi: &Field) -> [f64; 3] {
    spin_in(grid, state, phi, Region::of(grid, Stagger::Cell))
}

/// [`solid_spin`] over the cells `cells` (those outside are taken as holding no solid).
fn spin_in(grid: &Grid, state: &State, phi: &Field, cells: Region) -> [f64; 3] {
    let c = moments_in(grid, state, phi, cells).centroid;
    let w_faces = state.w.as_ref().filter(|_| grid.is_3d());
    // L (3), then I: xx, yy, zz, xy, yz, xz.
    let s: [f64; 9] = cells.sum(|line| {
        let mut s = [0.0; 9];
        let f = phi.at(&line, [0; 3]);
        let centre = |q: &Field, a: usize, n: usize| {
            0.5 * (q.at(&line, [0; 3])[n] + q.at(&line, unit(a))[n])
        };
        for (n, [i, j, k]) in line.indices().enumerate() {
            let dv = f[n] * cell_volume(grid, i);
            if dv == 0.0 {
                continue;
            }
            let z = if w_faces.is_some() {
                grid.zc(k) - c[2]
            } else {
                0.0
            };
            let r = [grid.xc(i) - c[0], grid.yc(j) - c[1], z];
            let u = [
                centre(&state.u, 0, n),
                centre(&state.v, 1, n),
                w_faces.map_or(0.0, |w| centre(w, 2, n)),
            ];
            let cross = [
                r[1] * u[2] - r[2] * u[1],
                r[2] * u[0] - r[0] * u[2],
                r[0] * u[1] - r[1] * u[0],
            ];
            let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            let inertia = [
                r2 - r[0] * r[0],
                r2 - r[1] * r[1],
                r2 - r[2] * r[2],
                -r[0] * r[1],
                -r[1] * r[2],
                -r[0] * r[2],
            ];
            for (q, x) in s.iter_mut().zip(cross.iter().chain(&inertia)) {
                *q += dv * x;
            }
        }
        s
    });
    let [lx, ly, lz, xx, yy, zz, xy, yz, xz] = s;
    if !grid.is_3d() {
        return [0.0, 0.0, lz / zz];
    }
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let i = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
    let d = det(i);
    std::array::from_fn(|a| {
        let mut m = i;
        for (row, l) in m.iter_mut().zip([lx, ly, lz]) {
            row[a] = l;
        }
        det(m) / d
    })
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
        assert!(ProbeSpec::SolidCentroid.refused_in(three).is_none());
        assert!(ProbeSpec::ElasticEnergy.refused_in(three).is_none());
        assert_eq!(c(ProbeSpec::ElasticEnergy, three), ["elastic_energy"]);
        assert_eq!(c(ProbeSpec::SolidPieces, three).len(), 2);
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

    /// Two bodies on their windows: each per-body probe once per body, from that body's
    /// fraction alone, its columns prefixed by the body's name; the overlap and contact
    /// measures from the pair.
    #[test]
    fn probes_of_several_bodies_are_evaluated_per_body_and_named_after_them() {
        use efsi_core::body_fractions::{BodyFraction, BodyFractions};
        let grid = Grid::new(Geometry::Planar, 8, 6, (0.0, 1.0), (0.0, 0.75));
        let mut state = state_with(&grid, Field::zeros(&grid));
        // Body a: cells (1..3, 1..3) full; body b: a window at (3, 1) of 2 × 2 cells, 0.25 in
        // its first cell (shared with nothing) and 0.5 in (3, 2), where a holds 0.75 — a
        // shared cell, Σφ = 1.25 there.
        let mut a = BodyFraction::named("a");
        a.set(
            [1, 1, 0],
            [3, 2, 1],
            [1.0, 1.0, 0.0, 1.0, 1.0, 0.75].into_iter(),
        );
        let mut b = BodyFraction::named("b");
        b.set([3, 1, 0], [2, 2, 1], [0.25, 0.0, 0.5, 0.0].into_iter());
        // Their strain energies as the elastic stage records them.
        (a.elastic_energy, b.elastic_energy) = (0.5, 0.25);
        let all = BodyFractions { bodies: vec![a, b] };
        let phi = state.phi.as_mut().unwrap();
        for body in &all.bodies {
            for (at, f) in body.cells() {
                phi[at] += f;
            }
        }
        state.resources.insert(all);
        let values = |p: &ProbeSpec| {
            let mut out = Vec::new();
            evaluate(p, &grid, &state, (0.0, -1.0).into(), &[], &mut out);
            out
        };
        let cell = 0.125 * 0.125;
        let vol = values(&ProbeSpec::SolidVolume);
        assert_eq!(vol, vec![4.75 * cell, 0.75 * cell]);
        let c = values(&ProbeSpec::SolidCentroid);
        assert_eq!(c.len(), 4);
        // b: 0.25 at the centre (0.4375, 0.1875), 0.5 at (0.4375, 0.3125).
        let yb = (0.25 * 0.1875 + 0.5 * 0.3125) / 0.75;
        assert!(
            (c[2] - 0.4375).abs() < 1e-15 && (c[3] - yb).abs() < 1e-15,
            "{c:?}"
        );
        let xa = (0.1875 + 0.3125 + 0.1875 + 0.3125 + 0.75 * 0.4375) / 4.75;
        assert!((c[0] - xa).abs() < 1e-15, "{c:?}");
        // Each body one piece (b's two cells share a face).
        assert_eq!(values(&ProbeSpec::SolidPieces), vec![1.0, 1.0, 1.0, 1.0]);
        // The overlap: Σφ = 1.25 in the shared cell, its excess 0.25 of a cell.
        let o = values(&ProbeSpec::SolidOverlap);
        assert_eq!(o, vec![1.25, 0.25 * cell]);
        // The pair: min(0.75, 0.5) of the shared cell; one cell holds both.
        assert_eq!(values(&ProbeSpec::BodyContact), vec![0.5 * cell, 1.0]);
        // The names: per body, prefixed; the scene's quantities and the points unprefixed.
        let names = ["a".to_string(), "b".to_string()];
        let planar = Geometry::Planar;
        let cols = |p: ProbeSpec| columns(&p, planar, &names);
        assert_eq!(
            cols(ProbeSpec::SolidCentroid),
            ["a.solid_x", "a.solid_y", "b.solid_x", "b.solid_y"]
        );
        assert_eq!(
            cols(ProbeSpec::ContactForce { wall: Side::YMin }),
            ["a.contact_force", "b.contact_force"]
        );
        assert_eq!(
            cols(ProbeSpec::SolidOverlap),
            ["max_solid_fraction_sum", "solid_overlap_volume"]
        );
        assert_eq!(
            cols(ProbeSpec::BodyContact),
            ["a.b.shared_volume", "a.b.shared_cells"]
        );
        assert_eq!(cols(ProbeSpec::KineticEnergy), ["kinetic_energy"]);
        // Each body's own strain energy.
        assert_eq!(
            cols(ProbeSpec::ElasticEnergy),
            ["a.elastic_energy", "b.elastic_energy"]
        );
        assert_eq!(values(&ProbeSpec::ElasticEnergy), vec![0.5, 0.25]);
        // Without names (the single `solid:`), the columns are the unprefixed ones.
        assert_eq!(
            columns(&ProbeSpec::SolidCentroid, planar, &[]),
            ["solid_x", "solid_y"]
        );
        // A per-body probe has one value per column, whichever the probe.
        for p in [
            ProbeSpec::SolidVelocity,
            ProbeSpec::SolidSpin,
            ProbeSpec::SolidExtent { at: 0.45, z: None },
            ProbeSpec::ContactRadius { wall: Side::YMin },
        ] {
            assert_eq!(values(&p).len(), cols(p.clone()).len(), "{p:?}");
        }
        // Extent along x = 0.45 (column 3), each body's own run of cells: b's cells (3, 1)
        // and (3, 2), from 0.25 − 0.25·0.125 to 0.25 + 0.5·0.125; a's cell (3, 2) alone, its
        // bottom at 0.375 − 0.75·0.125.
        let e = values(&ProbeSpec::SolidExtent { at: 0.45, z: None });
        let (bottom_b, top_b) = (0.25 - 0.25 * 0.125, 0.25 + 0.5 * 0.125);
        assert!(
            (e[2] - bottom_b).abs() < 1e-15 && (e[3] - top_b).abs() < 1e-15,
            "{e:?}"
        );
        assert!((e[0] - (0.375 - 0.75 * 0.125)).abs() < 1e-15, "{e:?}");
    }

    /// Two spheres of a three-dimensional grid, each on its window: the per-body probes are
    /// each sphere's own (the same kernel as in two dimensions), three centroid columns per
    /// body; the spheres apart, no cell is shared.
    #[test]
    fn probes_of_two_spheres_are_evaluated_per_body_in_three_dimensions() {
        use efsi_core::body_fractions::{BodyFraction, BodyFractions};
        let grid = Grid::new_3d([20, 24, 16], (0.0, 1.0), (0.0, 1.2), (0.0, 0.8));
        let (r, a, b) = (0.18, [0.28, 0.5, 0.4], [0.75, 0.78, 0.4]);
        let mut state = state_with(&grid, Field::zeros(&grid));
        let mut all = BodyFractions::default();
        for (name, c) in [("a", a), ("b", b)] {
            let own = ball(&grid, c, r);
            // The window: the sphere's bounding cells.
            let origin = [grid.x0, grid.y0, grid.z0];
            let cell = |x: f64, a: usize| ((x - origin[a]) / grid.h()[a]).floor() as usize;
            let lo: [usize; 3] = std::array::from_fn(|k| cell(c[k] - r, k));
            let hi: [usize; 3] = std::array::from_fn(|k| cell(c[k] + r, k));
            let n: [usize; 3] = std::array::from_fn(|k| hi[k] - lo[k] + 1);
            let mut body = BodyFraction::named(name);
            let values = (0..n[2]).flat_map(|k| {
                let own = &own;
                (0..n[1]).flat_map(move |j| {
                    (0..n[0]).map(move |i| {
                        own[[
                            (lo[0] + i) as isize,
                            (lo[1] + j) as isize,
                            (lo[2] + k) as isize,
                        ]]
                    })
                })
            });
            body.set(lo, n, values);
            let phi = state.phi.as_mut().unwrap();
            for (p, q) in phi.data_mut().iter_mut().zip(own.data()) {
                *p += q;
            }
            // The sphere's probes alone, on a state holding it only.
            let alone = state_with(&grid, own);
            let mut want = Vec::new();
            for p in [ProbeSpec::SolidVolume, ProbeSpec::SolidCentroid] {
                evaluate(&p, &grid, &alone, (0.0, 0.0).into(), &[], &mut want);
            }
            all.bodies.push(body);
            assert!((want[2] - c[1]).abs() < 0.01, "{want:?}");
            state.resources.insert(all.clone());
            let mut got = Vec::new();
            for p in [ProbeSpec::SolidVolume, ProbeSpec::SolidCentroid] {
                evaluate(&p, &grid, &state, (0.0, 0.0).into(), &[], &mut got);
            }
            // The last body's group: volume, then x, y, z.
            let k = all.bodies.len() - 1;
            let mine = [
                got[k],
                got[all.bodies.len() + 3 * k],
                got[all.bodies.len() + 3 * k + 1],
            ];
            assert_eq!(mine, [want[0], want[1], want[2]], "{name}");
        }
        let names = ["a".to_string(), "b".to_string()];
        assert_eq!(
            columns(&ProbeSpec::SolidCentroid, Geometry::Cartesian3D, &names),
            [
                "a.solid_x",
                "a.solid_y",
                "a.solid_z",
                "b.solid_x",
                "b.solid_y",
                "b.solid_z"
            ]
        );
        let mut out = Vec::new();
        for p in [ProbeSpec::SolidPieces, ProbeSpec::BodyContact] {
            evaluate(&p, &grid, &state, (0.0, 0.0).into(), &[], &mut out);
        }
        assert_eq!(out[0], 1.0);
        assert_eq!(out[2], 1.0);
        assert_eq!(out[4..], [0.0, 0.0]);
    }

    /// The solid fraction of a sphere of radius `r` about `c` in each cell of `grid`, by
    /// sampling 6³ points per cell (the 2-D grid's one plane: a disk).
    fn ball(grid: &Grid, c: [f64; 3], r: f64) -> Field {
        let mut phi = Field::zeros(grid);
        let m = 6;
        let [nx, ny, nz] = grid.n();
        let depth = if grid.is_3d() { m } else { 1 };
        for [i, j, k] in
            (0..nz).flat_map(|k| (0..ny).flat_map(move |j| (0..nx).map(move |i| [i, j, k])))
        {
            let mut inside = 0;
            for (a, b, d) in
                (0..m).flat_map(|a| (0..m).flat_map(move |b| (0..depth).map(move |d| (a, b, d))))
            {
                let x = grid.xf(i as isize) + (a as f64 + 0.5) / m as f64 * grid.dx;
                let y = grid.yf(j as isize) + (b as f64 + 0.5) / m as f64 * grid.dy;
                let z = if grid.is_3d() {
                    grid.zf(k as isize) + (d as f64 + 0.5) / m as f64 * grid.dz
                } else {
                    c[2]
                };
                inside += usize::from(
                    (x - c[0]).powi(2) + (y - c[1]).powi(2) + (z - c[2]).powi(2) < r * r,
                );
            }
            phi[[i as isize, j as isize, k as isize]] = inside as f64 / (m * m * depth) as f64;
        }
        phi
    }

    fn state_with(grid: &Grid, phi: Field) -> State {
        let fields = [FieldId::SolidFraction].into_iter().collect();
        let mut state = State::new(grid, 1.0, 0.1, &fields);
        state.phi = Some(phi);
        state
    }

    /// Two separated spheres are two pieces (6-connected), one sphere is one; and a sphere's
    /// extent along the vertical line through its centre is its diameter, to within a cell.
    #[test]
    fn pieces_and_extent_of_spheres_in_three_dimensions() {
        let grid = Grid::new_3d([20, 24, 16], (0.0, 1.0), (0.0, 1.2), (0.0, 0.8));
        let (r, a, b) = (0.18, [0.28, 0.5, 0.4], [0.75, 0.78, 0.4]);
        let mut phi = ball(&grid, a, r);
        let one = solid_pieces(&grid, &phi);
        assert_eq!(one.count, 1);
        assert!((one.largest - 1.0).abs() < 1e-14, "{}", one.largest);
        let (bottom, top) = solid_extent(&grid, &state_with(&grid, phi.clone()), a[0], a[2]);
        assert!(
            (bottom - (a[1] - r)).abs() < grid.dy && (top - (a[1] + r)).abs() < grid.dy,
            "{bottom} {top}"
        );
        assert!((top - bottom - 2.0 * r).abs() < grid.dy, "{bottom} {top}");
        let other = ball(&grid, b, r);
        for (p, q) in phi.data_mut().iter_mut().zip(other.data()) {
            *p += q;
        }
        let two = solid_pieces(&grid, &phi);
        assert_eq!(two.count, 2);
        assert!((two.largest - 0.5).abs() < 0.02, "{}", two.largest);
        // Cells meeting along an edge only are two pieces; a shared face joins them.
        let mut phi = Field::zeros(&grid);
        phi[[3, 3, 3]] = 1.0;
        phi[[4, 4, 3]] = 1.0;
        assert_eq!(solid_pieces(&grid, &phi).count, 2);
        phi[[3, 3, 4]] = 1.0;
        phi[[3, 4, 4]] = 1.0;
        phi[[4, 4, 4]] = 1.0;
        assert_eq!(solid_pieces(&grid, &phi).count, 1);
    }

    /// A rigid rotation `u = U + ω × (x − p)` of a sphere on the staggered faces gives its
    /// spin exactly, in three dimensions (all three components) and in two (ω_z).
    #[test]
    fn the_spin_of_a_rigid_rotation_is_exact() {
        let grid = Grid::new_3d([16, 18, 14], (0.0, 1.0), (0.0, 1.0), (0.0, 1.0));
        let (om, big_u, p) = ([0.7, -1.3, 2.1], [0.2, -0.4, 0.1], [0.1, 0.9, 0.3]);
        let vel = |x: [f64; 3]| {
            let r = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
            [
                big_u[0] + om[1] * r[2] - om[2] * r[1],
                big_u[1] + om[2] * r[0] - om[0] * r[2],
                big_u[2] + om[0] * r[1] - om[1] * r[0],
            ]
        };
        let mut state = state_with(&grid, ball(&grid, [0.45, 0.55, 0.5], 0.3));
        let w = state.w.as_mut().unwrap();
        for k in -1..15isize {
            for j in -1..19isize {
                for i in -1..17isize {
                    let (xc, yc, zc) = (grid.xc(i), grid.yc(j), grid.zc(k));
                    state.u[[i, j, k]] = vel([grid.xf(i), yc, zc])[0];
                    state.v[[i, j, k]] = vel([xc, grid.yf(j), zc])[1];
                    w[[i, j, k]] = vel([xc, yc, grid.zf(k)])[2];
                }
            }
        }
        let mut out = Vec::new();
        evaluate(
            &ProbeSpec::SolidSpin,
            &grid,
            &state,
            Vector(0.0, 0.0, Some(0.0)),
            &[],
            &mut out,
        );
        assert_eq!(out.len(), 3);
        for (g, w) in out.iter().zip(om) {
            assert!((g - w).abs() < 1e-12, "{out:?} vs {om:?}");
        }
        // Two dimensions: the same rotation about z.
        let grid = Grid::new(Geometry::Planar, 20, 16, (0.0, 1.0), (0.0, 0.8));
        let mut state = state_with(&grid, ball(&grid, [0.5, 0.4, 0.0], 0.25));
        for j in -1..17isize {
            for i in -1..21isize {
                state.u[(i, j)] = big_u[0] - om[2] * (grid.yc(j) - p[1]);
                state.v[(i, j)] = big_u[1] + om[2] * (grid.xc(i) - p[0]);
            }
        }
        let mut out = Vec::new();
        evaluate(
            &ProbeSpec::SolidSpin,
            &grid,
            &state,
            (0.0, -1.0).into(),
            &[],
            &mut out,
        );
        assert_eq!(out.len(), 1);
        assert!((out[0] - om[2]).abs() < 1e-12, "{out:?}");
    }

    /// A heavy fluid at rest on the floor (a box of it, no elastic stress) under its
    /// hydrostatic pressure presses on the floor with its weight less the buoyancy, down to the
    /// first layer's centres: `(ρ_s − ρ_f) g (h − h_y/2) A`; the footprint reaches from the
    /// wall's corner to the box's far corner. The same kernel on a planar and a 3-D grid.
    #[test]
    fn a_heavy_fluid_at_rest_presses_on_the_floor_with_its_weight() {
        let (rho_s, rho_f, g, top) = (3.0, 1.0, 9.81, 1.0);
        for grid in [
            Grid::new(Geometry::Planar, 10, 8, (0.0, 1.0), (0.0, top)),
            Grid::new_3d([10, 8, 10], (0.0, 1.0), (0.0, top), (0.0, 1.0)),
        ] {
            // The box: 4 cells along x and z from the corner, 3 layers high.
            let three = grid.is_3d();
            let (cols, layers) = (4isize, 3isize);
            let h = layers as f64 * grid.dy;
            let mut state = state_with(&grid, Field::zeros(&grid));
            let kmax = if three { cols } else { 1 };
            let [nx, ny, nz] = grid.n().map(|n| n as isize);
            for [i, j, k] in
                (0..nz).flat_map(|k| (0..ny).flat_map(move |j| (0..nx).map(move |i| [i, j, k])))
            {
                let y = grid.yc(j);
                let inside = i < cols && k < kmax && j < layers;
                state.phi.as_mut().unwrap()[[i, j, k]] = f64::from(u8::from(inside));
                state.p[[i, j, k]] = if inside {
                    rho_f * g * (top - h) + rho_s * g * (h - y)
                } else {
                    rho_f * g * (top - y)
                };
            }
            let area = cols as f64 * grid.dx * if three { kmax as f64 * grid.dz } else { 1.0 };
            let want = (rho_s - rho_f) * g * (h - 0.5 * grid.dy) * area;
            let force = contact_force(&grid, &state, &[], Side::YMin);
            assert!((force - want).abs() < 1e-12 * want, "{force} vs {want}");
            let reach = contact_radius(&grid, &state, &[], Side::YMin);
            let far = cols as f64 * grid.dx * if three { 2f64.sqrt() } else { 1.0 };
            assert!((reach - far).abs() < 1e-14, "{reach} vs {far}");
            // Nothing presses on the lid, nor (no solid there) on the far x wall.
            assert_eq!(contact_force(&grid, &state, &[], Side::YMax), 0.0);
            assert_eq!(contact_force(&grid, &state, &[], Side::XMax), 0.0);
        }
    }
}
