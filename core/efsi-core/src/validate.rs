//! The scene's checks, one function per section the core owns ([`Scene::validate`]): ranges
//! and consistency, each failure naming the setting's path and what was expected. The helpers
//! are public for the checks of sections the core does not own: efsi-run's `output`, the
//! stages' `solid` ([`Scene::check_diffusion`]) and `numerics` sections ([`check_tolerance`],
//! [`check_iterations`], re-exported by [`crate::scene::options`]).

use crate::grid::Geometry;
use crate::scene::*;

/// A failed check: the setting's path and what is wrong with it.
pub type Failure = (String, String);

/// A check: nothing, or a [`Failure`].
pub type Checked = Result<(), Failure>;

/// The longest scene name (bytes): it names a folder and the files in it (`<name>_<step>.vtr`),
/// which file systems limit to 255 bytes.
pub const MAX_NAME_BYTES: usize = 200;

/// The fewest cells a grid may have between two sides that are not periodic: the stages'
/// differences need a neighbour (a single cell has no inside face across that direction, and
/// the VOF stage needs 2 × 2). One cell is allowed across a periodic direction (a flow that
/// does not vary along it).
pub const MIN_CELLS_ACROSS: usize = 2;

/// The most cells a grid may have (1e8), in two dimensions as in three: beyond it the fields
/// alone outgrow this machine's memory. (The run crate's memory estimate refuses, before
/// allocation, a smaller scene whose stages need more than the machine has.)
pub const MAX_CELLS: usize = 100_000_000;

/// The last segment of a setting's path.
fn leaf(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

/// The smallest cell size (1e-150): its square and the inverse square the viscous and
/// pressure systems hold stay finite and normal.
pub const MIN_CELL_SIZE: f64 = 1e-150;

/// The largest cell size (1e150), for the same reason.
pub const MAX_CELL_SIZE: f64 = 1e150;

/// The failure of the setting at `field` (its path), saying `msg`.
pub fn err<T>(field: &str, msg: impl Into<String>) -> Result<T, Failure> {
    Err((field.to_string(), msg.into()))
}

/// `v`, the setting at `field`, must be a finite number above zero.
pub fn positive(field: &str, v: f64) -> Checked {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        err(
            field,
            format!("must be a finite number > 0, got {}", num(v)),
        )
    }
}

/// `v`, the vector at `field`, must have finite components.
pub fn finite(field: &str, (a, b): (f64, f64)) -> Checked {
    if a.is_finite() && b.is_finite() {
        Ok(())
    } else {
        err(field, "must be finite")
    }
}

/// A relative tolerance's check: within `[ε, 1)` (a residual below the unit round-off can
/// never be met).
pub fn check_tolerance(field: &'static str, tol: f64) -> Result<(), (&'static str, String)> {
    if (f64::EPSILON..1.0).contains(&tol) {
        Ok(())
    } else {
        Err((
            field,
            format!(
                "must be in [{:e}, 1) (a relative residual below the unit round-off cannot be \
                 reached), got {}",
                f64::EPSILON,
                num(tol)
            ),
        ))
    }
}

/// An iteration cap's check: at least 1.
pub fn check_iterations(field: &'static str, n: usize) -> Result<(), (&'static str, String)> {
    if n == 0 {
        Err((field, "must be ≥ 1".into()))
    } else {
        Ok(())
    }
}

/// One axis's cells: `n` (the setting at `f`) is at least one, at least [`MIN_CELLS_ACROSS`]
/// between sides that are not periodic, and cuts the extent `(lo, hi)` (the setting at `d`)
/// into cells of a size in [[`MIN_CELL_SIZE`], [`MAX_CELL_SIZE`]] and at least 1e3 ε of the
/// coordinates.
fn check_axis_cells(f: &str, n: usize, periodic: bool, (lo, hi): (f64, f64), d: &str) -> Checked {
    if n == 0 {
        return err(f, "must be at least 1 cell, got 0");
    }
    if n < MIN_CELLS_ACROSS && !periodic {
        return err(
            f,
            format!(
                "must be at least {MIN_CELLS_ACROSS} cells between sides that are not \
                 periodic (the stages' differences need a neighbour; one cell has no \
                 face inside), got {n}"
            ),
        );
    }
    // Cell sizes whose square (the viscous and pressure systems' 1/h²) over- or
    // underflows, or too small against the coordinates to tell cells apart.
    let h = (hi - lo) / n as f64;
    let scale = lo.abs().max(hi.abs());
    if !(MIN_CELL_SIZE..=MAX_CELL_SIZE).contains(&h) || h < 1e3 * f64::EPSILON * scale {
        return err(
            d,
            format!(
                "({}, {}) with {f} = {n} gives cells of size {}: a cell size must be \
                 in [{:e}, {:e}] (its square and inverse square finite) and at least \
                 {:e} of the coordinates (else neighbouring cells round to one position)",
                num(lo),
                num(hi),
                num(h),
                MIN_CELL_SIZE,
                MAX_CELL_SIZE,
                1e3 * f64::EPSILON
            ),
        );
    }
    Ok(())
}

impl Scene {
    /// Check ranges and consistency, section by section; on failure, the field path and what
    /// was expected.
    pub fn validate(&self) -> Checked {
        self.validate_name()?;
        self.validate_domain_and_grid()?;
        self.validate_time()?;
        self.validate_materials()?;
        self.validate_boundaries()
    }

    /// The scene's name: a folder (`out/<name>/`) and a file stem.
    fn validate_name(&self) -> Checked {
        // The name is a folder (`out/<name>/`) and a file stem: nothing that leaves the folder,
        // names it again or breaks a line.
        if self.name.trim().is_empty()
            || self.name.len() > MAX_NAME_BYTES
            || self.name.contains(['/', '\\'])
            || self.name.chars().any(char::is_control)
            || self.name.trim_matches('.').is_empty()
        {
            return err(
                "name",
                format!(
                    "must be a non-empty name without path separators or control characters, \
                     and not `.` or `..`, of at most {MAX_NAME_BYTES} bytes (it names the output \
                     folder out/<name>/ and its files), got {:?}",
                    efsi_ron_edit::elide_text(&self.name)
                ),
            );
        }
        Ok(())
    }

    /// The keys that tell two dimensions from three: a two-dimensional scene has no third
    /// axis, a Cartesian3D one has all of it and none of the axisymmetric spellings (see
    /// [`crate::scene`]'s "Three dimensions").
    fn validate_dimensions(&self) -> Checked {
        if self.geometry != Geometry::Cartesian3D {
            return self.validate_two_axes();
        }
        self.refuse_axisymmetric_spellings()?;
        self.require_third_axis()?;
        if self.gravity.2.is_none() && self.gravity != (0.0, 0.0) {
            return err(
                "gravity",
                "a Cartesian3D scene's gravity has three components (gx, gy, gz), got two: \
                 which axis is vertical is the scene's to say",
            );
        }
        Ok(())
    }

    /// A planar or axisymmetric scene writes nothing of a third axis: no `z` extent, cell
    /// count or sides beside the `y` ones, and gravity of two components.
    fn validate_two_axes(&self) -> Checked {
        let g = self.geometry;
        let (d, n, b) = (&self.domain, &self.grid, &self.boundaries);
        let third = [
            ("domain.z", d.z.is_some(), "domain.y"),
            ("grid.nz", n.nz.is_some(), "grid.ny"),
            ("boundaries.z_min", b.z_min.is_some(), "boundaries.y_min"),
            ("boundaries.z_max", b.z_max.is_some(), "boundaries.y_max"),
        ];
        for (f, given, y) in third {
            if given {
                return err(
                    f,
                    format!(
                        "a {g:?} scene has two axes: `{}` beside `{}` would be a third \
                         (`{}` is `{}`'s axisymmetric spelling only where `{}` is not \
                         written); a three-dimensional scene is `geometry: Cartesian3D`",
                        leaf(f),
                        leaf(y),
                        leaf(f),
                        leaf(y),
                        leaf(y)
                    ),
                );
            }
        }
        if self.gravity.2.is_some() {
            return err(
                "gravity",
                format!("a {g:?} scene has two axes: gravity is (gx, gy), got three components"),
            );
        }
        Ok(())
    }

    /// A Cartesian3D scene names its axes x, y, z: the first axisymmetric spelling (`r`,
    /// `nr`, `z_min`, …) written in the domain, grid or boundaries is refused, named by the
    /// Cartesian key it stands for.
    fn refuse_axisymmetric_spellings(&self) -> Checked {
        for (section, aliases) in [
            ("domain", &self.domain.aliases),
            ("grid", &self.grid.aliases),
            ("boundaries", &self.boundaries.aliases),
        ] {
            if let Some(a) = aliases.first() {
                let meaning = match *a {
                    "r" => "x",
                    "nr" => "nx",
                    "r_min" => "x_min",
                    "r_max" => "x_max",
                    "z" => "y",
                    "nz" => "ny",
                    "z_min" => "y_min",
                    _ => "y_max",
                };
                return err(
                    &format!("{section}.{meaning}"),
                    format!(
                        "missing: `{a}` is {meaning}'s axisymmetric spelling, which a \
                         Cartesian3D scene does not use (there x, y, z are the axes{})",
                        if a.starts_with('z') || *a == "nz" {
                            format!(" and `{a}` belongs to the third)")
                        } else {
                            ")".into()
                        }
                    ),
                );
            }
        }
        Ok(())
    }

    /// A Cartesian3D scene writes all of its third axis: the extent, the cell count and both
    /// sides.
    fn require_third_axis(&self) -> Checked {
        let (d, n, b) = (&self.domain, &self.grid, &self.boundaries);
        let missing = [
            ("domain.z", d.z.is_none(), "(min, max) along the third axis"),
            (
                "grid.nz",
                n.nz.is_none(),
                "the cell count along the third axis",
            ),
            (
                "boundaries.z_min",
                b.z_min.is_none(),
                "the condition on z = z_min",
            ),
            (
                "boundaries.z_max",
                b.z_max.is_none(),
                "the condition on z = z_max",
            ),
        ];
        for (f, absent, what) in missing {
            if absent {
                return err(f, format!("missing: a Cartesian3D scene needs {what}"));
            }
        }
        Ok(())
    }

    /// The domain and the grid: the dimensions, each axis's extent, the cell count, and each
    /// axis's cells.
    fn validate_domain_and_grid(&self) -> Checked {
        self.validate_dimensions()?;
        self.validate_extents()?;
        let [nx, ny, nz] = self.grid.n();
        self.validate_cell_count([nx, ny, nz])?;
        let b = &self.boundaries;
        let mut axes = vec![
            (
                "grid.nx",
                nx,
                b.x_min == Boundary::Periodic,
                self.domain.x,
                "domain.x",
            ),
            (
                "grid.ny",
                ny,
                b.y_min == Boundary::Periodic,
                self.domain.y,
                "domain.y",
            ),
        ];
        if let (Some(z), Some(zb)) = (self.domain.z, &b.z_min) {
            axes.push(("grid.nz", nz, *zb == Boundary::Periodic, z, "domain.z"));
        }
        for (f, n, periodic, extent, d) in axes {
            check_axis_cells(f, n, periodic, extent, d)?;
        }
        Ok(())
    }

    /// Each axis's extent is `(min, max)` with `max > min`, both finite and their difference
    /// too; an axisymmetric domain starts at a radius ≥ 0.
    fn validate_extents(&self) -> Checked {
        let mut axes = vec![("domain.x", self.domain.x), ("domain.y", self.domain.y)];
        if let Some(z) = self.domain.z {
            axes.push(("domain.z", z));
        }
        for (f, (a, b)) in axes {
            if !(a.is_finite() && b.is_finite() && b > a) {
                return err(
                    f,
                    format!(
                        "must be (min, max) with max > min, got ({}, {})",
                        num(a),
                        num(b)
                    ),
                );
            }
            if !(b - a).is_finite() {
                return err(
                    f,
                    format!(
                        "its extent {} − {} overflows: the domain must be narrower than {:e}",
                        num(b),
                        num(a),
                        f64::MAX
                    ),
                );
            }
        }
        if self.geometry == Geometry::Axisymmetric && self.domain.x.0 < 0.0 {
            return err(
                "domain.x",
                format!(
                    "the radius must be ≥ 0 in axisymmetric geometry, got r_min = {}",
                    self.domain.x.0
                ),
            );
        }
        Ok(())
    }

    /// At most [`MAX_CELLS`] cells in all.
    fn validate_cell_count(&self, [nx, ny, nz]: [usize; 3]) -> Checked {
        let cells = nx.saturating_mul(ny).saturating_mul(nz);
        if cells > MAX_CELLS {
            return err(
                "grid",
                if self.geometry == Geometry::Cartesian3D {
                    format!(
                        "more than 1e8 cells ({nx} × {ny} × {nz}) is beyond a 3-D run on this machine"
                    )
                } else {
                    "more than 1e8 cells is beyond a 2-D run on this machine".into()
                },
            );
        }
        Ok(())
    }

    /// The time settings.
    fn validate_time(&self) -> Checked {
        positive("time.end", self.time.end)?;
        if !(self.time.cfl > 0.0 && self.time.cfl <= 1.0) {
            return err(
                "time.cfl",
                format!("must be in (0, 1], got {}", num(self.time.cfl)),
            );
        }
        for (f, v) in [
            ("time.dt_max", self.time.dt_max),
            ("time.dt_min", self.time.dt_min),
            ("time.fixed_dt", self.time.fixed_dt),
            ("time.steady", self.time.steady),
        ] {
            if let Some(v) = v {
                positive(f, v)?;
            }
        }
        if let (Some(lo), Some(hi)) = (self.time.dt_min, self.time.dt_max)
            && lo > hi
        {
            return err(
                "time.dt_min",
                format!("must not exceed time.dt_max ({}), got {}", num(hi), num(lo)),
            );
        }
        let floor = self.time.dt_min_or_default();
        for (f, v) in [
            ("time.dt_max", self.time.dt_max),
            ("time.fixed_dt", self.time.fixed_dt),
        ] {
            if let Some(v) = v
                && v < floor
                && self.time.dt_min.is_none()
            {
                return err(
                    f,
                    format!(
                        "{} is below time.dt_min's default 1e-12·time.end = {}: every step would \
                         be refused; set time.dt_min too",
                        num(v),
                        num(floor)
                    ),
                );
            }
        }
        if let (Some(lo), Some(fixed)) = (self.time.dt_min, self.time.fixed_dt)
            && fixed < lo
        {
            return err(
                "time.fixed_dt",
                format!(
                    "{} is below time.dt_min = {}: every step would be refused",
                    num(fixed),
                    num(lo)
                ),
            );
        }
        positive("fluid.density", self.fluid.density)?;
        Ok(())
    }

    /// The fluid, gravity and the initial velocity.
    fn validate_materials(&self) -> Checked {
        if !(self.fluid.viscosity.is_finite() && self.fluid.viscosity >= 0.0) {
            return err(
                "fluid.viscosity",
                format!(
                    "must be a finite number ≥ 0, got {}",
                    num(self.fluid.viscosity)
                ),
            );
        }
        self.check_diffusion("fluid.viscosity", self.fluid.viscosity, self.fluid.density)?;
        finite("gravity", self.gravity.planar())?;
        if self.gravity.2.is_some_and(|z| !z.is_finite()) {
            return err("gravity", "must be finite");
        }
        if self.geometry == Geometry::Axisymmetric && self.gravity.0 != 0.0 {
            return err(
                "gravity",
                "must be along z (the axis) in axisymmetric geometry: (0, g_z)",
            );
        }
        if let InitialVelocity::Uniform(v) = self.initial_velocity {
            finite("initial_velocity", v)?;
        }
        if let InitialVelocity::SinSinStream { .. } = self.initial_velocity
            && self.geometry != Geometry::Planar
        {
            return err(
                "initial_velocity",
                format!(
                    "SinSinStream is a planar stream function; not available in {:?} geometry",
                    self.geometry
                ),
            );
        }
        Ok(())
    }

    /// A material's viscosity `mu` (the setting at `field`) against its density `rho`: the
    /// viscous system's coefficients are μΔt/(ρh²) with Δt ≤ time.end; beyond
    /// [`MAX_DIFFUSION_NUMBER`] their products overflow, and the solver starts from a NaN
    /// residual. (Also the check of the stages' `solid.viscosity`.)
    pub fn check_diffusion(&self, field: &str, mu: f64, rho: f64) -> Checked {
        let mut h = ((self.domain.x.1 - self.domain.x.0) / self.grid.nx as f64)
            .min((self.domain.y.1 - self.domain.y.0) / self.grid.ny as f64);
        if let (Some(z), Some(nz)) = (self.domain.z, self.grid.nz) {
            h = h.min((z.1 - z.0) / nz as f64);
        }
        let d = mu * self.time.end / (rho * h * h);
        if d.is_finite() && d > MAX_DIFFUSION_NUMBER {
            return err(
                field,
                format!(
                    "{} makes the diffusion number μ·time.end/(ρh²) = {} exceed {:e}: the \
                     viscous system's coefficients would overflow",
                    num(mu),
                    num(d),
                    MAX_DIFFUSION_NUMBER
                ),
            );
        }
        if !d.is_finite() && mu.is_finite() && rho > 0.0 {
            return err(
                field,
                format!(
                    "{} makes the diffusion number μ·time.end/(ρh²) overflow",
                    num(mu)
                ),
            );
        }
        Ok(())
    }

    /// The boundary conditions: each side's ([`validate_side`](Self::validate_side)), then the
    /// axis of an axisymmetric scene whose r_min is 0.
    fn validate_boundaries(&self) -> Checked {
        let dims = if self.geometry == Geometry::Cartesian3D {
            3
        } else {
            2
        };
        for &side in Side::of(dims) {
            self.validate_side(side, dims)?;
        }
        if self.geometry == Geometry::Axisymmetric
            && self.domain.x.0 == 0.0
            && self.boundaries.x_min != Boundary::Axis
        {
            return err(
                "boundaries.x_min",
                format!(
                    "r_min = 0 is the axis: expected Axis, got {:?}",
                    self.boundaries.x_min
                ),
            );
        }
        Ok(())
    }

    /// The condition on `side` of a `dims`-dimensional scene: a periodic side has a periodic
    /// partner, an axis is r_min = 0 of an axisymmetric scene, a moving wall's parameters are
    /// valid ([`moving_wall`]).
    fn validate_side(&self, side: Side, dims: usize) -> Checked {
        let b = self.boundaries.get(side);
        let f = format!("boundaries.{}", side.field_name());
        let partner = self.boundaries.get(side.opposite());
        if *b == Boundary::Periodic && *partner != Boundary::Periodic {
            return err(
                &f,
                format!(
                    "is Periodic but its partner boundaries.{} is {:?}: a periodic side needs a periodic partner",
                    side.opposite().field_name(),
                    partner
                ),
            );
        }
        if *b == Boundary::Axis {
            if side != Side::XMin || self.geometry != Geometry::Axisymmetric {
                return err(
                    &f,
                    "Axis is only allowed on x_min (r_min) of an axisymmetric scene",
                );
            }
            if self.domain.x.0 != 0.0 {
                return err(
                    &f,
                    format!("Axis needs r_min = 0, got domain.x.0 = {}", self.domain.x.0),
                );
            }
        }
        moving_wall(&f, side, dims, b)
    }
}

/// A moving wall's parameters (the field `f` is its side's), if `b` is one: a finite speed, a
/// direction (if given) non-zero in the wall's plane ([`wall_direction`]), a positive ramp
/// width, a finite angular frequency or switch-off time.
fn moving_wall(f: &str, side: Side, dims: usize, b: &Boundary) -> Checked {
    let Boundary::MovingWall {
        speed,
        profile,
        motion,
        direction,
    } = b
    else {
        return Ok(());
    };
    if !speed.is_finite() {
        return err(&format!("{f}.speed"), "must be finite");
    }
    if let Some(d) = *direction {
        wall_direction(f, side, dims, d)?;
    }
    if let WallProfile::Sin2Ramp { width } = profile {
        positive(&format!("{f}.profile.width"), *width)?;
    }
    match motion {
        WallMotion::Sin { omega } if !omega.is_finite() => {
            err(&format!("{f}.motion.omega"), "must be finite")
        }
        WallMotion::Until { t_off } if !t_off.is_finite() => {
            err(&format!("{f}.motion.t_off"), "must be finite")
        }
        _ => Ok(()),
    }
}

/// A moving wall's direction `(x, y, z)` on `side`: finite, non-zero, with no component along
/// the wall's normal, and z zero in two dimensions.
fn wall_direction(f: &str, side: Side, dims: usize, (x, y, z): (f64, f64, f64)) -> Checked {
    let normal = [x, y, z][side.axis()];
    let norm = (x * x + y * y + z * z).sqrt();
    if !(norm.is_finite() && norm > 0.0) || normal != 0.0 || (dims == 2 && z != 0.0) {
        return err(
            &format!("{f}.direction"),
            format!(
                "({x}, {y}, {z}) must be a non-zero direction in the wall's plane: \
                 its component along the wall's normal (axis {}) zero{}",
                ["x", "y", "z"][side.axis()],
                if dims == 2 {
                    ", and z zero in two dimensions"
                } else {
                    ""
                }
            ),
        );
    }
    Ok(())
}
