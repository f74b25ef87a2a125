//! Contact: a short-range repulsion that keeps separate bodies (and, on request, bodies and the
//! walls) a film apart where the grid no longer resolves the fluid between them.
//!
//! # Why
//!
//! Each body's fraction `φ_k` is transported on its own ([`crate::vof`]): two bodies never
//! merge, but the transport does not keep `Σ_k φ_k ≤ 1` in a cell two bodies enter together.
//! While the film between them spans cells, the resolved flow keeps them apart (its pressure
//! rises as it drains); below a cell it is no longer resolved. As the reference-map codes
//! (Rycroft et al. 2020; Wang, Kamrin & Rycroft 2022) and the Eulerian red-blood-cell codes
//! (Ii, Sugiyama et al. 2012) do, a short-range repulsion takes over there.
//!
//! # Rule
//!
//! Each body carries a halo, its fraction smoothed by a tent kernel `K` of half-width
//! `range + 1` cells (per axis, normalised, a product over the axes),
//!
//! ```text
//!     ψ_k = K * φ_k,     K(d) ∝ max(0, range + 1 − |d|)   (d in cells along each axis),
//! ```
//!
//! which is 1 deep inside the body, falls to 0 within `range` cells outside its interface, and
//! the repulsion is the force of the potential
//!
//! ```text
//!     E_c = κ Σ_{k<l} ∫ φ_k ψ_l dV  (+ κ Σ_k ∫ φ_k ψ_w dV  with `walls`),
//! ```
//!
//! the overlap of one body's volume with the other's halo (`∫ φ_k ψ_l = ∫ ψ_k φ_l`: `K` is
//! symmetric), which is zero while the bodies are more than `range` cells apart and grows as
//! they close. Moving body `k` changes it at the rate set by the force density on its material
//!
//! ```text
//!     f_k = −κ φ_k Σ_{l≠k} ∇ψ_l   (− κ φ_k ∇ψ_w),
//! ```
//!
//! which points away from the other bodies (and walls) and sums to zero over a pair
//! (`∫ φ_k ∇ψ_l = −∫ φ_l ∇ψ_k`): the pair's momentum is kept. A wall's halo `ψ_w` is that of
//! a body filling the space beyond the wall (no-slip, moving and free-slip sides; not a
//! symmetry plane, whose mirror image of a body is the body itself, nor a periodic or outflow
//! side). Being a potential force, the repulsion stores the energy `E_c` the bodies' approach
//! gives it and returns it as they part: it never supplies energy of its own. The stage keeps
//! `E_c` in the state ([`ContactEnergy`]), which the energy guard counts as stored energy. The
//! discrete exchange (the force of the step's start applied explicitly) is first order in Δt:
//! it may return a little more than `E_c` as the bodies part, a share that the step limit
//! below keeps small.
//!
//! # Scheme
//!
//! The stage runs after the body force, on the predicted velocity `V*`, before the viscous,
//! elastic and pressure steps (which see it as they see gravity): on every unknown face normal
//! to axis `a`, between cells `c − e_a` and `c`,
//!
//! ```text
//!     V*_a ← V*_a + Δt f_a / ρ_face,   f_a = −κ φ̄_k (ψ_l(c) − ψ_l(c − e_a)) / h_a,
//! ```
//!
//! `φ̄_k` the two cells' mean and `ρ_face` the face density of the momentum equation
//! ([`efsi_core::operators::face_density`]). The stored energy is summed on the same faces,
//!
//! ```text
//!     E_c = κ / d Σ_a Σ_faces φ̄_k ψ̄_l V_face   (d axes; each pair from both bodies, halved),
//! ```
//!
//! `ψ̄_l` the two cells' mean: a face that pushes has `φ̄_k ≠ 0` and a halo on one side, so it
//! stores energy. The cells' sum `Σ_c φ_k ψ_l V_c` would not: it is zero while the face between
//! a body's last cell and the first cell of the other's halo already pushes, a push that no
//! stored energy pays for, that the step limit below misses and that the energy guard flags.
//!
//! On a uniform grid the sum of face forces over a pair is zero to round-off (summation by parts
//! with the symmetric kernel), planar and three-dimensional; in axisymmetric geometry the cell
//! volumes weight the axial sums and the pair's axial momentum is kept to the discretisation error.
//! Each halo is evaluated on its body's window grown by the kernel's half-width, wrapped along
//! periodic axes: the work and storage scale with the bodies' extent. The halos, and each body's
//! face forces, are made for the bodies in parallel and gathered in the bodies' order (the
//! serial loop's sums). The fractions are those the VOF stage published at the end of the last
//! step ([`efsi_core::body_fractions`]).
//!
//! **Frictionless.** Summed over a body, the face forces of a pair are not quite normal to the
//! contact: where a body rests on another's halo, its last cells meet the halo's tail, whose
//! few nonzero values on the grid tilt the net force off the contact normal (by up to 20° on
//! nine cells per radius) and give it a moment about the body's centroid. Contact without
//! friction has neither, and the tilt is a tangential push that does work on a body sliding or
//! turning in contact: a disk resting on two others would turn steadily. So each pair's loads
//! are projected (planar and three-dimensional):
//!
//! ```text
//!     F_k ← (F_k · n) n,     M_k ← (x_c − x_k) × F_k        (and the same for l),
//! ```
//!
//! `F_k` the net of the pair's face forces on body `k` and `M_k` their moment about its
//! centroid `x_k`; `n` the contact normal, the mean of the two bodies' unit interface normals
//! (Youngs' `∇φ`, pointing from `k` to `l`) over the patch where each body lies in the other's
//! halo, weighted by `φ_k ψ_l` (and `φ_l ψ_k`); `x_c` the contact point, the centre of both
//! bodies' pushed faces weighted by `|f|`. The change is put back on each body as a rigid load,
//! the force density `ρ_k φ̄_k (a + α × (x − x_k))` on its faces with `(a, α)` solved (2 + 1 or
//! 3 + 3 unknowns) so that the faces carry the change of net force and moment exactly. The pair
//! then pushes along one line through one point: its net force and its net moment about any
//! point stay zero (momentum and angular momentum kept), and a body's moment is that of a
//! frictionless contact, zero for a disk or sphere. Only the net loads change: the distribution
//! within a body (what deforms it) is the face forces'. A wall's forces are normal already, and
//! in axisymmetric geometry a body's rigid motion is along the axis only: neither is projected.
//! The projection is not a potential force: the stored energy `E_c` stays that of the faces.
//!
//! **Friction.** With `friction` `μ > 0` a pair in contact also feels Coulomb's friction at the
//! contact point: a force on `k` (and its opposite on `l`) along the bodies' relative sliding
//! `s_t`, the tangential part of `(v_l + ω_l × (x_c − x_l)) − (v_k + ω_k × (x_c − x_k))`,
//! `(v, ω)` each body's rigid motion (the least-squares fit to its faces' velocities, on the
//! same weights as the rigid loads), of size
//!
//! ```text
//!     min(μ |F_n|, |s_t| / (Δt C)),     C = t · (a_k(t) − a_l(−t)),
//! ```
//!
//! `F_n` the pair's normal force and `C` how fast a unit force along `t = s_t / |s_t|` at the
//! contact point changes the sliding (the bodies' rigid loads' accelerations there): below
//! Coulomb's bound the force stops the sliding within the step and the bodies stick; it never
//! reverses it, so friction only takes energy. It acts between bodies (not between a body and
//! a wall), in planar and three-dimensional scenes (an axisymmetric scene that sets it is
//! refused), and it is put on each body as a rigid load, like the projection's change.
//!
//! **Step limit.** The force is explicit: while it acts (it stored energy in the last step), a
//! step may not let it move the lightest body's material by more than a fraction of a cell,
//! `Δt ≤ CFL · 2 / (C + √(C² + 4 a/h))` with the largest acceleration `a = κ K(0) / (h ρ_min)`
//! (`ρ_min` the lightest body: a face's mixture density is at least `φ̄_k ρ_k`) and `C` the
//! convective rate, as for the body force. The first step's is that of the initial fractions
//! (bodies may start within each other's halo). Otherwise it sets no limit: in the step that
//! brings a body into another's halo it moves less than a cell into it, where the force is the
//! kernel's tail, and the limit holds from the next step on.
//!
//! # Parameters (`numerics.contact`)
//!
//! - `stiffness` `κ` (Pa, an energy per volume): by default `10 ρ_max U²`, `ρ_max` the densest
//!   body and `U` the largest of the bodies' initial speeds, the moving walls' speeds and the
//!   free-fall speed `√(2|g|L)` over the domain's longest side `L` — the halo then stores ten
//!   times the kinetic energy per volume of a body arriving at that speed before the bodies
//!   share a cell. A scene in which nothing sets a body moving (no gravity, no initial speed, no
//!   moving wall) has no default: no repulsion unless it sets one.
//! - `range` (cells, in `(0, 2]`, default 1): how far a halo reaches beyond its body's interface
//!   (the gap below which the repulsion acts). At most 2: a body's window keeps two empty
//!   cells beyond its support ([`crate::vof`]).
//! - `walls` (default `false`): repel bodies from the walls too. Off, a body meets a wall through
//!   the resolved film only (as a single body always does).
//! - `friction` `μ` (default 0): Coulomb's friction between bodies in contact (see below).
//!
//! The stage runs in scenes of several bodies, and in a scene of one body with `walls: true`.
//!
//! # Limits
//!
//! The repulsion acts between the bodies' volumes, not their surfaces: it has no friction and
//! no adhesion, and its stiffness is the contact's, not the bodies' (a stiff `κ` and a soft body
//! deform the body; a soft `κ` lets bodies share a cell's worth of their halos). `SolidOverlap`
//! (`max Σ_k φ_k`) shows whether it kept the bodies apart.
//!
//! The contact normal is as good as the bodies' Youngs normals over the patch: within 1° of
//! the line of centres for two disks of nine cells per radius on square cells (the unit tests),
//! so a disk held in contact still feels a moment of about 2 % of `|F| R`. On cells of unequal
//! sides the halo reaches farther along the longer side, the patch moves along the surface
//! towards it, and so does the normal: 2.4° off for disks 1.2 apart at 57° on cells twice as
//! wide as high. Frictionless bodies slide freely
//! over each other: a pile of them keeps rearranging under gravity until every body rests on
//! contacts that balance it, slowly where the films between them drain through a viscous fluid. The single velocity field gives the film its
//! shear: bodies that meet across a film of a cell or less share its velocity, so a glancing
//! collision sets them turning through the film (the repulsion adds no moment).

mod frictionless;

use efsi_core::body_fractions::{BodyFraction, BodyFractions};
use efsi_core::operators::face_density;
use efsi_core::scene::bodies::Bodies;
use efsi_core::scene::options::StageOptions;
use efsi_core::scene::{Boundary, Options, OptionsDecl, Side};
use efsi_core::schedule::VELOCITY;
use efsi_core::state::StateResource;
use efsi_core::{
    BoundarySet, Field, FieldId, Grid, Phase, Scene, Stage, StageError, StagePlugin, StageStats,
    State, StepContext,
};
use frictionless::{Motion, PairLoad, Rigid};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The largest `range`: a body's window keeps two empty cells beyond its support.
pub const MAX_RANGE: f64 = 2.0;

/// The factor of the default stiffness over `ρ_max U²` (see the module docs).
pub const STIFFNESS_FACTOR: f64 = 10.0;

/// The contact's options (`numerics.contact`; see the module docs).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactOptions {
    /// The repulsion's stiffness κ (Pa); by default `10 ρ_max U²` (module docs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// How far (cells) a body's halo reaches beyond its interface, in `(0, 2]` (default 1).
    #[serde(default = "one")]
    pub range: f64,
    /// Whether the walls repel the bodies too (default `false`).
    #[serde(default)]
    pub walls: bool,
    /// Coulomb's friction coefficient between bodies in contact (default 0: frictionless).
    #[serde(default)]
    pub friction: f64,
}

fn one() -> f64 {
    1.0
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions {
            stiffness: None,
            range: 1.0,
            walls: false,
            friction: 0.0,
        }
    }
}

impl StageOptions for ContactOptions {
    const SECTION: &'static str = "contact";

    fn validate(&self, scene: &Scene) -> Result<(), (&'static str, String)> {
        if let Some(k) = self.stiffness
            && !(k.is_finite() && k >= 0.0)
        {
            return Err((
                "stiffness",
                format!(
                    "must be a finite number ≥ 0 (Pa), got {}",
                    efsi_core::scene::num(k)
                ),
            ));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err((
                "friction",
                format!(
                    "must be a finite number ≥ 0 (Coulomb's coefficient), got {}",
                    efsi_core::scene::num(self.friction)
                ),
            ));
        }
        if self.friction > 0.0 && scene.geometry == efsi_core::Geometry::Axisymmetric {
            return Err((
                "friction",
                "has no effect in axisymmetric geometry (a body's rigid motion is along the axis \
                 only): leave it 0"
                    .into(),
            ));
        }
        if !(self.range > 0.0 && self.range <= MAX_RANGE) {
            return Err((
                "range",
                format!(
                    "must be in (0, {MAX_RANGE}] cells (a body's window keeps {MAX_RANGE} empty \
                     cells beyond the body), got {}",
                    efsi_core::scene::num(self.range)
                ),
            ));
        }
        Ok(())
    }

    fn resolve(&mut self, scene: &Scene, options: &Options) {
        if self.stiffness.is_none() {
            self.stiffness = Some(default_stiffness(scene, options));
        }
    }
}

/// κ: the scene's `stiffness`, or its default.
fn stiffness(o: &ContactOptions, scene: &Scene, options: &Options) -> f64 {
    o.stiffness
        .unwrap_or_else(|| default_stiffness(scene, options))
}

/// `10 ρ_max U²` (module docs); 0 where nothing sets a body moving.
fn default_stiffness(scene: &Scene, options: &Options) -> f64 {
    let Some(bodies) = options.get::<Bodies>() else {
        return 0.0;
    };
    let rho = bodies
        .list
        .iter()
        .map(|b| b.solid.density)
        .fold(0.0, f64::max);
    let body_speed = bodies
        .list
        .iter()
        .filter_map(|b| b.solid.velocity.map(|v| v.norm()))
        .fold(0.0, f64::max);
    let sides = Side::of(if scene.domain.z.is_some() { 3 } else { 2 });
    let wall_speed = sides
        .iter()
        .filter_map(|&s| match scene.boundaries.get(s) {
            Boundary::MovingWall { speed, .. } => Some(speed.abs()),
            _ => None,
        })
        .fold(0.0, f64::max);
    let d = &scene.domain;
    let longest = [Some(d.x), Some(d.y), d.z]
        .into_iter()
        .flatten()
        .map(|(a, b)| b - a)
        .fold(0.0, f64::max);
    let fall = (2.0 * scene.gravity.norm() * longest).sqrt();
    let u = body_speed.max(wall_speed).max(fall);
    STIFFNESS_FACTOR * rho * u * u
}

/// The contact stage's plugin (module docs).
pub struct Contact;

impl StagePlugin for Contact {
    /// Planar, axisymmetric and three-dimensional: one dimension-generic code path.
    fn supports(&self, _geometry: efsi_core::Geometry) -> bool {
        true
    }
    fn name(&self) -> &'static str {
        "contact"
    }
    fn phase(&self) -> Phase {
        Phase::BodyForce
    }
    fn after(&self) -> &'static [&'static str] {
        &["body_force"]
    }
    fn reads(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn writes(&self) -> &'static [FieldId] {
        &VELOCITY
    }
    fn limit_depends_on(&self) -> &'static str {
        "numerics.contact.stiffness and the densities"
    }
    fn options(&self) -> Option<OptionsDecl> {
        Some(OptionsDecl::of::<ContactOptions>())
    }
    fn needed(&self, scene: &Scene, options: &Options) -> bool {
        let Some(bodies) = options.get::<Bodies>() else {
            return false;
        };
        let o: ContactOptions = options.section_or_default(efsi_core::scene::Preset::Default);
        stiffness(&o, scene, options) > 0.0 && (bodies.list.len() > 1 || o.walls)
    }
    fn build(
        &self,
        scene: &Scene,
        options: &Options,
        grid: &Grid,
        bc: &BoundarySet,
        _shared: &mut efsi_core::Resources,
    ) -> Result<Box<dyn Stage>, String> {
        let o = options.section::<ContactOptions>()?;
        let bodies = options
            .get::<Bodies>()
            .ok_or_else(|| "the scene has no bodies".to_string())?;
        let kappa = stiffness(o, scene, options);
        let densities: Vec<f64> = bodies.list.iter().map(|b| b.solid.density).collect();
        let mut walls = [[false; 2]; 3];
        let mut periodic = [false; 3];
        for (a, (w, p)) in walls.iter_mut().zip(&mut periodic).enumerate() {
            if a >= grid.dims() {
                break;
            }
            for (hi, wall) in w.iter_mut().enumerate() {
                let b = scene.boundaries.get(Side::normal_to(a, hi == 1));
                *wall = o.walls
                    && matches!(
                        b,
                        Boundary::NoSlip | Boundary::MovingWall { .. } | Boundary::FreeSlip
                    );
                *p = matches!(b, Boundary::Periodic);
            }
        }
        let faces = std::array::from_fn(|a| {
            if a < grid.dims() {
                let r = bc.normal_faces(a, grid.n()[a]);
                (r.lo, r.hi)
            } else {
                (0, 0)
            }
        });
        let mut stage = ContactStage::new(kappa, Kernel::new(o.range), densities, faces, grid);
        stage.walls = walls;
        stage.periodic = periodic;
        stage.frictionless = !grid.is_axisymmetric();
        stage.friction = o.friction;
        Ok(Box::new(stage))
    }
}

/// The tent kernel of one axis: weights `K(d)`, `d = −m … m`, summing to 1.
#[derive(Clone, Debug)]
struct Kernel {
    /// Half-width in cells, `⌈range⌉`.
    m: usize,
    /// `K(−m) … K(m)`.
    w: Vec<f64>,
}

impl Kernel {
    fn new(range: f64) -> Self {
        let m = range.ceil() as usize;
        let raw: Vec<f64> = (-(m as isize)..=m as isize)
            .map(|d| (range + 1.0 - d.unsigned_abs() as f64).max(0.0))
            .collect();
        let s: f64 = raw.iter().sum();
        Kernel {
            m,
            w: raw.into_iter().map(|x| x / s).collect(),
        }
    }

    /// `K(d)`.
    fn at(&self, d: isize) -> f64 {
        let i = d + self.m as isize;
        if i < 0 || i as usize >= self.w.len() {
            0.0
        } else {
            self.w[i as usize]
        }
    }

    /// A wall's halo at the cell `i` cells from it (0: the cell beside it): `Σ_{d > i} K(d)`.
    fn wall(&self, i: usize) -> f64 {
        ((i + 1)..=self.m).map(|d| self.at(d as isize)).sum()
    }
}

/// A box of cells (first cell, cells per axis) holding values x fastest.
#[derive(Clone, Debug, Default)]
struct Halo {
    lo: [isize; 3],
    n: [usize; 3],
    v: Vec<f64>,
    /// The smoothing's second buffer (reused).
    spare: Vec<f64>,
}

/// What one body's faces gather in a step (reused): the bodies near it, its loads from each of
/// them (`pairs`), its face forces `(axis, face, f_a)` and each axis' share of `E_c / κ`.
#[derive(Clone, Debug, Default)]
struct Pushed {
    near: Vec<usize>,
    pairs: Vec<PairLoad>,
    updates: Vec<(usize, [isize; 3], f64)>,
    energy: [f64; 3],
}

impl Halo {
    /// The value at grid cell `at` (already wrapped), 0 outside the box.
    fn at(&self, at: [isize; 3]) -> f64 {
        let mut index = 0;
        for a in (0..3).rev() {
            let i = at[a] - self.lo[a];
            if i < 0 || i >= self.n[a] as isize {
                return 0.0;
            }
            index = index * self.n[a] + i as usize;
        }
        self.v[index]
    }
}

/// The energy the repulsion stores, `E_c` (module docs), as of the stage's last step.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContactEnergy {
    /// `E_c` (J; per unit depth in planar geometry, per radian in axisymmetric geometry).
    pub energy: f64,
}

impl StateResource for ContactEnergy {
    /// None: the stage sets it from the bodies' fractions every step.
    fn arrays(&self) -> Vec<(String, &Field)> {
        Vec::new()
    }
    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        Vec::new()
    }
    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(*self)
    }
    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        match (other as &dyn std::any::Any).downcast_ref::<ContactEnergy>() {
            Some(o) => {
                *self = *o;
                true
            }
            None => false,
        }
    }
    fn stored_energy(&self) -> f64 {
        self.energy
    }
}

struct ContactStage {
    kappa: f64,
    kernel: Kernel,
    /// Which sides repel (`[axis][low, high]`).
    walls: [[bool; 2]; 3],
    periodic: [bool; 3],
    /// The least density of the bodies, for the step limit: the force on a face is
    /// `κ φ̄_k ∇ψ_l` and its density `ρ_face ≥ φ̄_k ρ_k` (mixture), so `f/ρ_face ≤ κ|∇ψ_l|/ρ_k`.
    rho_min: f64,
    /// Each body's density, for the rigid loads of the frictionless projection.
    densities: Vec<f64>,
    /// Whether pairs' forces are made frictionless (module docs; not in axisymmetric geometry).
    frictionless: bool,
    /// Coulomb's coefficient between bodies (`friction`).
    friction: f64,
    n: [usize; 3],
    dims: usize,
    /// The unknown faces along each axis (first, one past the last).
    faces: [(isize, isize); 3],
    /// Each body's halo `ψ_k`, reused between steps.
    halos: Vec<Halo>,
    /// Each body's support (first and last cells with `φ_k ≠ 0`), found once per step.
    supports: Vec<Option<Bounds>>,
    /// What each body's faces gathered in the last step.
    pushed: Vec<Pushed>,
    /// `E_c` as of the last step: the stage's record (snapshots and checkpoints carry it), which
    /// it publishes in the state ([`ContactEnergy`]).
    energy: f64,
    /// The last step's face forces `(axis, face, f_a)`.
    updates: Vec<(usize, [isize; 3], f64)>,
    /// Each body's centroid (reused).
    centroids: Vec<[f64; 3]>,
    /// Each body's change of net force and moment from the frictionless projection (reused).
    changes: Vec<([f64; 3], [f64; 3])>,
    /// Each body's rigid modes and, with friction, its rigid motion, where a pair needs them
    /// (reused).
    rigid: Vec<Option<(Rigid, Option<Motion>)>>,
}

/// The velocity a step's friction sees (the predicted velocity the stage acts on) and the step.
#[derive(Clone, Copy)]
struct Flow<'a> {
    velocity: [Option<&'a Field>; 3],
    dt: f64,
}

/// A box of cells: its first and last cell.
type Bounds = ([isize; 3], [isize; 3]);

/// The support of a body's fraction: its first and last cells with `φ_k ≠ 0`.
fn support(b: &BodyFraction) -> Option<Bounds> {
    let mut lo = [isize::MAX; 3];
    let mut hi = [isize::MIN; 3];
    for (at, f) in b.cells() {
        if f != 0.0 {
            for a in 0..3 {
                lo[a] = lo[a].min(at[a]);
                hi[a] = hi[a].max(at[a]);
            }
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

impl ContactStage {
    /// A stage of stiffness `kappa` and `kernel` for bodies of `densities` on `grid`, whose
    /// unknown faces along each axis are `faces`: no repelling wall, no periodic side,
    /// frictionless pairs without friction (the caller sets these), its buffers empty.
    fn new(
        kappa: f64,
        kernel: Kernel,
        densities: Vec<f64>,
        faces: [(isize, isize); 3],
        grid: &Grid,
    ) -> Self {
        ContactStage {
            kappa,
            kernel,
            walls: [[false; 2]; 3],
            periodic: [false; 3],
            rho_min: densities.iter().copied().fold(f64::INFINITY, f64::min),
            densities,
            frictionless: true,
            friction: 0.0,
            n: grid.n(),
            dims: grid.dims(),
            faces,
            halos: Vec::new(),
            supports: Vec::new(),
            pushed: Vec::new(),
            energy: 0.0,
            updates: Vec::new(),
            centroids: Vec::new(),
            changes: Vec::new(),
            rigid: Vec::new(),
        }
    }

    /// `at` wrapped along the periodic axes.
    fn wrap(&self, mut at: [isize; 3]) -> [isize; 3] {
        for (a, x) in at.iter_mut().enumerate().take(self.dims) {
            if self.periodic[a] {
                *x = x.rem_euclid(self.n[a] as isize);
            }
        }
        at
    }

    /// `ψ = K * φ` of body `b` on its window grown by the kernel's half-width (clipped to the
    /// domain, the whole axis along a periodic one the window spans), into `halo`.
    fn smooth(&self, b: &BodyFraction, halo: &mut Halo) {
        let m = self.kernel.m as isize;
        let mut lo = [0isize; 3];
        let mut n = [1usize; 3];
        for a in 0..self.dims {
            let whole = self.n[a] as isize;
            if self.periodic[a] && b.n[a] >= self.n[a] {
                (lo[a], n[a]) = (0, self.n[a]);
            } else {
                let l = (b.lo[a] as isize - m).max(if self.periodic[a] { -m } else { 0 });
                let h = (b.lo[a] as isize + b.n[a] as isize + m).min(if self.periodic[a] {
                    whole + m
                } else {
                    whole
                });
                (lo[a], n[a]) = (l, (h - l) as usize);
            }
        }
        // Separable: φ onto the box, then the kernel along each axis in turn.
        let len: usize = n.iter().product();
        let mut cur = std::mem::take(&mut halo.v);
        cur.clear();
        cur.resize(len, 0.0);
        let idx = |c: [usize; 3]| (c[2] * n[1] + c[1]) * n[0] + c[0];
        for (at, f) in b.cells() {
            let c: [isize; 3] = std::array::from_fn(|a| at[a] - lo[a]);
            if c.iter().zip(&n).all(|(&c, &n)| c >= 0 && (c as usize) < n) {
                cur[idx(c.map(|c| c as usize))] = f;
            }
        }
        let mut next = std::mem::take(&mut halo.spare);
        next.clear();
        next.resize(len, 0.0);
        for a in 0..self.dims {
            let wrap_all = self.periodic[a] && n[a] == self.n[a] && lo[a] == 0;
            for c2 in 0..n[2] {
                for c1 in 0..n[1] {
                    for c0 in 0..n[0] {
                        let c = [c0, c1, c2];
                        let mut s = 0.0;
                        for d in -m..=m {
                            let mut i = c[a] as isize + d;
                            if wrap_all {
                                i = i.rem_euclid(n[a] as isize);
                            } else if i < 0 || i >= n[a] as isize {
                                continue;
                            }
                            let mut e = c;
                            e[a] = i as usize;
                            s += self.kernel.at(d) * cur[idx(e)];
                        }
                        next[idx(c)] = s;
                    }
                }
            }
            std::mem::swap(&mut cur, &mut next);
        }
        halo.lo = lo;
        halo.n = n;
        halo.v = cur;
        halo.spare = next;
    }

    /// The halo of the walls at grid cell `at`, along axis `a`.
    fn wall_halo(&self, a: usize, at: [isize; 3]) -> f64 {
        let mut s = 0.0;
        let i = at[a];
        let n = self.n[a] as isize;
        if self.walls[a][0] && (0..n).contains(&i) {
            s += self.kernel.wall(i as usize);
        }
        if self.walls[a][1] && (0..n).contains(&i) {
            s += self.kernel.wall((n - 1 - i) as usize);
        }
        s
    }

    /// `E_c` and the face forces `(axis, face, f_a)` of the bodies' fractions `all` (module
    /// docs), their supports found ([`Self::find_supports`]); the caller gives the forces'
    /// vector back to `self.updates` for the next step.
    fn forces(
        &mut self,
        grid: &Grid,
        all: &BodyFractions,
        flow: Option<Flow>,
    ) -> (f64, Vec<(usize, [isize; 3], f64)>) {
        // Each body's halo, centroid and faces on their own: the bodies in parallel.
        let mut halos = std::mem::take(&mut self.halos);
        halos.resize_with(all.bodies.len(), Halo::default);
        (halos.par_iter_mut())
            .zip(all.bodies.par_iter())
            .for_each(|(h, b)| self.smooth(b, h));
        let h = grid.h();
        // The bodies' centroids, which only the frictionless projection uses.
        self.centroids.clear();
        if self.frictionless {
            (all.bodies.par_iter())
                .map(|b| {
                    let (mut m, mut x) = (0.0, [0.0; 3]);
                    for (c, f) in b.cells().filter(|&(_, f)| f != 0.0) {
                        let v = f * grid.cell_volume(c[0]);
                        let at = frictionless::centre(grid, c);
                        m += v;
                        x = std::array::from_fn(|a| x[a] + v * at[a]);
                    }
                    if m > 0.0 { x.map(|x| x / m) } else { x }
                })
                .collect_into_vec(&mut self.centroids);
        }
        // The face forces on body k's faces, from every other body's halo and the walls', and
        // E_c on the same faces (each pair's from both of its bodies, halved).
        let mut pushed = std::mem::take(&mut self.pushed);
        pushed.resize_with(all.bodies.len(), Pushed::default);
        let this = &*self;
        (pushed.par_iter_mut())
            .zip(all.bodies.par_iter())
            .enumerate()
            .for_each(|(k, (p, b))| {
                p.near.clear();
                p.pairs.clear();
                p.updates.clear();
                let Some(support) = this.supports[k] else {
                    return;
                };
                this.near_halos(&halos, support, k, &mut p.near);
                if this.frictionless {
                    p.pairs.extend(p.near.iter().map(|&l| PairLoad {
                        k,
                        l,
                        ..PairLoad::default()
                    }));
                }
                for a in 0..this.dims {
                    p.energy[a] = this.face_forces(
                        b,
                        &halos,
                        (&p.near, &mut p.pairs),
                        support,
                        a,
                        grid,
                        &mut p.updates,
                    );
                }
            });
        // Gathered in the bodies' order, each body's axes in order: the serial loop's sums.
        let mut energy = 0.0;
        let mut updates = std::mem::take(&mut self.updates);
        updates.clear();
        for (p, support) in pushed.iter().zip(&self.supports) {
            if support.is_some() {
                energy = p.energy[..self.dims].iter().fold(energy, |e, x| e + x);
                updates.extend_from_slice(&p.updates);
            }
        }
        if self.frictionless {
            self.project(grid, all, (&halos, &pushed), flow, &mut updates);
        }
        self.pushed = pushed;
        self.halos = halos;
        (self.kappa * energy / self.dims as f64 * h[2], updates)
    }

    /// The frictionless projection (module docs): each pair's loads (`pushed`, each body's from
    /// the bodies near it, in the bodies' order) made normal and
    /// acting at one contact point, with Coulomb's friction where `friction > 0` and the step's
    /// `flow` is given, the change put on each body as a rigid load, into `updates`.
    fn project(
        &mut self,
        grid: &Grid,
        all: &BodyFractions,
        (halos, pushed): (&[Halo], &[Pushed]),
        flow: Option<Flow>,
        updates: &mut Vec<(usize, [isize; 3], f64)>,
    ) {
        let mut changes = std::mem::take(&mut self.changes);
        let mut rigid = std::mem::take(&mut self.rigid);
        changes.clear();
        changes.resize(all.bodies.len(), ([0.0; 3], [0.0; 3]));
        rigid.clear();
        rigid.resize_with(all.bodies.len(), || None);
        let flow = flow.filter(|_| self.friction > 0.0);
        let (dims, n, h, periodic) = (self.dims, self.n, grid.h(), self.periodic);
        let image = |d: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|a| {
                let period = n[a] as f64 * h[a];
                if periodic[a] {
                    d[a] - period * (d[a] / period).round()
                } else {
                    d[a]
                }
            })
        };
        let mut add = |body: usize, f: [f64; 3], m: [f64; 3]| {
            let (cf, cm) = &mut changes[body];
            *cf = std::array::from_fn(|a| cf[a] + f[a]);
            *cm = std::array::from_fn(|a| cm[a] + m[a]);
        };
        let pairs = pushed.iter().flat_map(|p| &p.pairs);
        for on_k in pairs.filter(|p| p.k < p.l) {
            let (k, l) = (on_k.k, on_k.l);
            let of_l = &pushed[l].pairs;
            let on_l = of_l
                .binary_search_by_key(&k, |p| p.l)
                .map(|i| of_l[i])
                .unwrap_or_default();
            if on_k.weight == 0.0 && on_l.weight == 0.0 {
                continue;
            }
            let Some(normal) = frictionless::patch_normal(
                (&all.bodies[k], &all.bodies[l]),
                |c| halos[k].at(c),
                |c| halos[l].at(c),
                |c| self.wrap(c),
                h,
                dims,
            ) else {
                continue;
            };
            let centroids = (&self.centroids[k], &self.centroids[l]);
            let Some(contact) = frictionless::to_normal(on_k, &on_l, centroids, normal, image)
            else {
                continue;
            };
            for (i, body) in [k, l].into_iter().enumerate() {
                add(body, contact.change[i], contact.moment_change[i]);
            }
            let Some(flow) = flow else {
                continue;
            };
            for body in [k, l] {
                if rigid[body].is_none() {
                    rigid[body] = Some(self.rigid_of(grid, &all.bodies[body], body, Some(flow)));
                }
            }
            let (Some((rk, Some(mk))), Some((rl, Some(ml)))) = (&rigid[k], &rigid[l]) else {
                continue;
            };
            let bodies = [(rk, mk), (rl, ml)];
            if let Some(f) =
                frictionless::friction(&contact, normal, self.friction, flow.dt, bodies)
            {
                let [ck, cl] = contact.r;
                let g = f.map(|x| -x);
                add(k, f, frictionless::cross(ck, f));
                add(l, g, frictionless::cross(cl, g));
            }
        }
        for (k, (force, moment)) in changes.iter().enumerate() {
            if force.iter().chain(moment).all(|&x| x == 0.0) {
                continue;
            }
            if rigid[k].is_none() {
                rigid[k] = Some(self.rigid_of(grid, &all.bodies[k], k, None));
            }
            let Some((modes, _)) = &rigid[k] else {
                continue;
            };
            let Some(load) = modes.load(*force, *moment) else {
                continue;
            };
            let rho = self.densities[k];
            for (a, c, r, phi, _) in self.arms(grid, &all.bodies[k], k) {
                updates.push((a, c, rho * phi * load.at(a, r)));
            }
        }
        self.changes = changes;
        self.rigid = rigid;
    }

    /// Body `k`'s rigid modes on its faces and, given the step's `flow`, its rigid motion.
    fn rigid_of(
        &self,
        grid: &Grid,
        b: &BodyFraction,
        k: usize,
        flow: Option<Flow>,
    ) -> (Rigid, Option<Motion>) {
        let rho = self.densities[k];
        let all = || self.arms(grid, b, k);
        let modes = Rigid::new(
            all().map(|(a, _, r, phi, v)| (a, r, rho * phi * v)),
            self.dims,
        );
        let motion = flow.and_then(|flow| {
            modes.motion(all().map(|(a, c, r, phi, v)| {
                let u = flow.velocity[a].map_or(0.0, |field| field[c]);
                (a, r, rho * phi * v, u)
            }))
        });
        (modes, motion)
    }

    /// Body `k`'s faces with material ([`Self::faces_of`], the axes in turn), each
    /// `(axis, face, arm from the body's centroid, φ̄_k, V_face)`: none without a support.
    fn arms<'a>(
        &'a self,
        grid: &'a Grid,
        b: &'a BodyFraction,
        k: usize,
    ) -> impl Iterator<Item = (usize, [isize; 3], [f64; 3], f64, f64)> + 'a {
        let x = self.centroids[k];
        self.supports[k].into_iter().flat_map(move |support| {
            (0..self.dims).flat_map(move |a| {
                (self.faces_of(grid, b, support, a))
                    .map(move |(c, phi, v)| (a, c, frictionless::arm(grid, a, c, x), phi, v))
            })
        })
    }

    /// Body `b`'s faces normal to axis `a` where it has material: the unknown faces from its
    /// support's first cell to one past its last, x fastest, each `(face, φ̄_k, V_face)`.
    fn faces_of<'a>(
        &'a self,
        grid: &'a Grid,
        b: &'a BodyFraction,
        (lo, hi): Bounds,
        a: usize,
    ) -> impl Iterator<Item = ([isize; 3], f64, f64)> + Clone + 'a {
        let (f_lo, f_hi) = self.faces[a];
        let mut end = hi;
        end[a] += 1;
        (lo[2]..=end[2])
            .flat_map(move |z| {
                (lo[1]..=end[1]).flat_map(move |y| (lo[0]..=end[0]).map(move |x| [x, y, z]))
            })
            .filter(move |c| (f_lo..f_hi).contains(&c[a]))
            .filter_map(move |c| {
                let mut below = c;
                below[a] -= 1;
                let (c_w, b_w) = (self.wrap(c), self.wrap(below));
                let phi = 0.5 * (b.at(c_w) + b.at(b_w));
                (phi != 0.0).then(|| {
                    (
                        c,
                        phi,
                        0.5 * (grid.cell_volume(c_w[0]) + grid.cell_volume(b_w[0])),
                    )
                })
            })
    }

    /// The forces on body `b`'s faces normal to axis `a` from the halos `near` of `halos` and
    /// the walls', into `updates`, and each other body's share into its load of `pairs` (one
    /// per body of `near`, or none): the faces of [`Self::faces_of`]. Returns the faces' share
    /// of `E_c / κ` before the `1 / dims` (module docs: `φ̄_k ψ̄` times the face's volume, half
    /// of it for another body's halo, all of it for the walls').
    #[allow(clippy::too_many_arguments)]
    fn face_forces(
        &self,
        b: &BodyFraction,
        halos: &[Halo],
        (near, pairs): (&[usize], &mut [PairLoad]),
        support: Bounds,
        a: usize,
        grid: &Grid,
        updates: &mut Vec<(usize, [isize; 3], f64)>,
    ) -> f64 {
        let h_a = grid.h()[a];
        let mut energy = 0.0;
        let centroid = pairs.first().and_then(|p| self.centroids.get(p.k)).copied();
        for (c, phi, volume) in self.faces_of(grid, b, support, a) {
            let mut below = c;
            below[a] -= 1;
            let (c_w, b_w) = (self.wrap(c), self.wrap(below));
            let (mut dpsi, mut psi) = (0.0, 0.0);
            let r = centroid.map(|x| frictionless::arm(grid, a, c, x));
            for (i, &l) in near.iter().enumerate() {
                let (p1, p0) = (halos[l].at(c_w), halos[l].at(b_w));
                dpsi += p1 - p0;
                psi += 0.25 * (p1 + p0);
                if let (Some(pair), Some(r)) = (pairs.get_mut(i), r)
                    && p1 != p0
                {
                    pair.add(r, a, -self.kappa * phi * (p1 - p0) / h_a, volume);
                }
            }
            let (w1, w0) = (self.wall_halo(a, c_w), self.wall_halo(a, b_w));
            dpsi += w1 - w0;
            psi += 0.5 * (w1 + w0);
            if dpsi != 0.0 {
                updates.push((a, c, -self.kappa * phi * dpsi / h_a));
            }
            if psi != 0.0 {
                energy += phi * psi * volume;
            }
        }
        energy
    }

    /// `E_c` into the state's [`ContactEnergy`].
    fn publish(&self, state: &mut State) {
        if let Some(e) = state.resources.get_mut::<ContactEnergy>() {
            e.energy = self.energy;
        }
    }

    /// Into `near`, the bodies other than `k` whose halo boxes reach the box `support` grown by
    /// a cell (a periodic axis counts as reached).
    fn near_halos(
        &self,
        halos: &[Halo],
        (lo, hi): ([isize; 3], [isize; 3]),
        k: usize,
        near: &mut Vec<usize>,
    ) {
        near.clear();
        near.extend((0..halos.len()).filter(|&l| {
            l != k
                && (0..self.dims).all(|a| {
                    let h = &halos[l];
                    self.periodic[a]
                        || (h.lo[a] <= hi[a] + 1 && lo[a] - 1 < h.lo[a] + h.n[a] as isize)
                })
        }));
    }

    /// Each body's support of `all` into `self.supports` (its storage reused).
    fn find_supports(&mut self, all: &BodyFractions) {
        self.supports.clear();
        self.supports.extend(all.bodies.iter().map(support));
    }

    /// Whether two bodies (or a body and a repelling wall) are within `range + 2` cells, by
    /// their supports ([`Self::find_supports`]).
    fn in_reach(&self) -> bool {
        let reach = self.kernel.m as isize + 2;
        let boxes = || self.supports.iter().flatten();
        for (k, (lo, hi)) in boxes().enumerate() {
            for a in 0..self.dims {
                let n = self.n[a] as isize;
                if (self.walls[a][0] && lo[a] < reach) || (self.walls[a][1] && hi[a] >= n - reach) {
                    return true;
                }
            }
            for (lo2, hi2) in boxes().skip(k + 1) {
                let near = (0..self.dims).all(|a| {
                    let gap = (lo2[a] - hi[a]).max(lo[a] - hi2[a]);
                    gap < reach || self.periodic[a]
                });
                if near {
                    return true;
                }
            }
        }
        false
    }
}

impl Stage for ContactStage {
    fn init_state(&self, _grid: &Grid, state: &mut State) {
        if state.resources.get::<ContactEnergy>().is_none() {
            state.resources.insert(ContactEnergy::default());
        }
    }

    /// `E_c` of the initial fractions (bodies may start within each other's halo): the energy
    /// guard counts it as stored from the start, and the step limit holds from the first step.
    fn initialize(
        &mut self,
        grid: &Grid,
        _bc: &BoundarySet,
        state: &mut State,
    ) -> Result<(), StageError> {
        self.energy = 0.0;
        if let Some(all) = state.resources.get::<BodyFractions>()
            && all.bodies.iter().all(|b| b.is_set())
        {
            self.find_supports(all);
            if self.in_reach() {
                self.energy = self.forces(grid, all, None).0;
            }
        }
        self.publish(state);
        Ok(())
    }

    fn save(&self) -> Vec<f64> {
        vec![self.energy]
    }

    fn save_into(&self, out: &mut Vec<f64>) {
        out.clear();
        out.push(self.energy);
    }

    fn restore(&mut self, data: &[f64]) -> Result<(), String> {
        match data {
            [e] => {
                self.energy = *e;
                Ok(())
            }
            _ => Err(format!(
                "expected 1 value (the stored contact energy), got {}",
                data.len()
            )),
        }
    }

    /// The stored energy back in the state.
    fn restored(&mut self, state: &mut State) {
        self.publish(state);
    }

    fn max_dt(&self, grid: &Grid, state: &State, cfl: f64) -> Option<f64> {
        // Only while the repulsion acts (it stored energy in the last step): a body entering a
        // halo in one step moves less than a cell into it, where the force is the kernel's tail.
        if self.energy <= 0.0 {
            return None;
        }
        let (vel, dims) = crate::advection::velocity(grid, state);
        let c = crate::advection::convective_rate(grid, &vel[..dims]);
        let h = grid.h()[..dims]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let accel = self.kappa * self.kernel.at(0) / (h * self.rho_min);
        Some(cfl * 2.0 / (c + (c * c + 4.0 * accel / h).sqrt()))
    }

    fn run(&mut self, ctx: &StepContext, state: &mut State) -> Result<StageStats, StageError> {
        let Some(all) = state.resources.get::<BodyFractions>() else {
            return Ok(StageStats::default());
        };
        self.find_supports(all);
        if !self.in_reach() {
            // No halo overlaps another body or a wall: no force, nothing stored.
            self.energy = 0.0;
            self.publish(state);
            return Ok(StageStats::default());
        }
        if all.bodies.iter().any(|b| !b.is_set()) {
            return Err(StageError {
                stage: "contact".into(),
                message: "the bodies' fractions are not set: the VOF stage publishes them".into(),
            });
        }
        let flow = Flow {
            velocity: [Some(&state.u), Some(&state.v), state.w.as_ref()],
            dt: ctx.dt,
        };
        let (energy, updates) = self.forces(ctx.grid, all, Some(flow));
        let State {
            u,
            v,
            w,
            rho,
            resources,
            ..
        } = state;
        for &(a, c, force) in &updates {
            let mut below = c;
            below[a] -= 1;
            let below = self.wrap(below);
            let field: &mut Field = match a {
                0 => &mut *u,
                1 => &mut *v,
                _ => w.as_mut().expect("w on a three-dimensional grid"),
            };
            field[c] += ctx.dt * force / face_density(rho[below], rho[c]);
        }
        if let Some(e) = resources.get_mut::<ContactEnergy>() {
            e.energy = energy;
        }
        self.energy = energy;
        self.updates = updates;
        Ok(StageStats::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage on `n` cells of size 1 (no periodic side), walls as given.
    fn stage(n: [usize; 3], dims: usize, walls: bool) -> ContactStage {
        let faces = std::array::from_fn(|a| if a < dims { (1, n[a] as isize) } else { (0, 0) });
        let mut s = ContactStage::new(3.0, Kernel::new(1.5), vec![1.0; 2], faces, &grid(n, dims));
        s.walls = std::array::from_fn(|a| [walls && a < dims; 2]);
        s
    }

    /// A body of pseudo-random fractions on the box `lo`, `n`.
    fn body(name: &str, lo: [usize; 3], n: [usize; 3], seed: u64) -> BodyFraction {
        let mut b = BodyFraction::named(name);
        let mut x = seed;
        let values = (0..n.iter().product::<usize>()).map(move |_| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        });
        b.set(lo, n, values);
        b
    }

    fn grid(n: [usize; 3], dims: usize) -> Grid {
        let l = |a: usize| (0.0, n[a] as f64);
        if dims == 3 {
            Grid::new_3d(n, l(0), l(1), l(2))
        } else {
            Grid::new(efsi_core::Geometry::Planar, n[0], n[1], l(0), l(1))
        }
    }

    #[test]
    fn the_kernel_sums_to_one_and_a_walls_halo_is_a_bodys() {
        for range in [0.5, 1.0, 1.5, 2.0] {
            let k = Kernel::new(range);
            let s: f64 = (-2..=2).map(|d| k.at(d)).sum();
            assert!((s - 1.0).abs() < 1e-15, "{range}: {s}");
            assert_eq!(k.at(3), 0.0);
            // The wall is a body filling the cells beyond it: ψ at the cell i from it.
            for i in 0..3usize {
                let body: f64 = (1..=3).map(|j| k.at(i as isize + j)).sum();
                assert!((k.wall(i) - body).abs() < 1e-15);
            }
        }
    }

    /// Between two bodies of arbitrary fractions the face forces sum to zero (the pair's
    /// momentum is kept), planar and three-dimensional.
    #[test]
    fn a_pairs_forces_sum_to_zero() {
        for dims in [2, 3] {
            let n = [16, 12, if dims == 3 { 10 } else { 1 }];
            let nz = if dims == 3 { 4 } else { 1 };
            let g = grid(n, dims);
            let mut s = stage(n, dims, false);
            let all = BodyFractions {
                bodies: vec![
                    body("a", [2, 3, 1.min(n[2] - 1)], [6, 5, nz], 1),
                    body("b", [7, 4, 2.min(n[2] - 1)], [6, 5, nz], 2),
                ],
            };
            s.find_supports(&all);
            let (energy, updates) = s.forces(&g, &all, None);
            assert!(energy > 0.0);
            let mut sum = [0.0; 3];
            let mut scale = 0.0;
            for (a, _, f) in &updates {
                sum[*a] += f;
                scale += f.abs();
            }
            assert!(scale > 0.0);
            for (a, total) in sum.iter().enumerate() {
                assert!(
                    total.abs() <= 1e-14 * scale,
                    "{dims}-D axis {a}: {total:e} of {scale:e}"
                );
            }
        }
    }

    /// Wherever the repulsion pushes, it has stored energy: two bodies (and a body and a wall)
    /// swept from sharing cells to out of reach, planar and three-dimensional, never give a face
    /// force with `E_c = 0` (the step limit and the energy guard both key on `E_c`). The
    /// cells' overlap `Σ φ_k ψ_l` is zero one cell before the faces' forces vanish.
    #[test]
    fn a_force_always_comes_with_stored_energy() {
        for dims in [2, 3] {
            let n = [24, 10, if dims == 3 { 8 } else { 1 }];
            let nz = if dims == 3 { 4 } else { 1 };
            let g = grid(n, dims);
            for walls in [false, true] {
                let mut s = stage(n, dims, walls);
                let mut reached = [false; 2];
                let mut ahead = false;
                for gap in 0..8 {
                    let all = BodyFractions {
                        bodies: vec![
                            body("a", [2, 3, 2.min(n[2] - 1)], [5, 4, nz], 3),
                            body("b", [7 + gap, 3, 2.min(n[2] - 1)], [5, 4, nz], 4),
                        ],
                    };
                    s.find_supports(&all);
                    let (e, updates) = s.forces(&g, &all, None);
                    let pushing = updates.iter().any(|u| u.2 != 0.0);
                    assert!(
                        !pushing || e > 0.0,
                        "{dims}-D, walls {walls}, gap {gap}: a force with E_c = {e}"
                    );
                    reached[usize::from(pushing)] = true;
                    let cells: f64 = all.bodies[0]
                        .cells()
                        .map(|(at, f)| f * s.halos[1].at(at))
                        .sum();
                    ahead |= !walls && pushing && cells == 0.0;
                }
                assert_eq!(reached, [!walls, true], "{dims}-D, walls {walls}");
                assert_eq!(
                    ahead, !walls,
                    "{dims}-D: the gap where the cells' overlap is 0"
                );
            }
        }
    }

    /// A disk (`dims` 2) or ball (3)'s fractions on cells of size 1: centre `c`, radius `r`,
    /// sampled `s` times per cell along each axis.
    fn round(name: &str, c: [f64; 3], r: f64, dims: usize, s: usize) -> BodyFraction {
        let lo: [usize; 3] = std::array::from_fn(|a| {
            if a < dims {
                (c[a] - r - 3.0) as usize
            } else {
                0
            }
        });
        let n: [usize; 3] =
            std::array::from_fn(|a| if a < dims { (2.0 * r) as usize + 7 } else { 1 });
        let samples = s.pow(dims as u32);
        let values = (0..n[0] * n[1] * n[2]).map(move |i| {
            let at = [i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])];
            let inside = (0..samples)
                .filter(|p| {
                    let q = [p % s, (p / s) % s, p / (s * s)];
                    let d: f64 = (0..dims)
                        .map(|a| {
                            let x = (lo[a] + at[a]) as f64 + (q[a] as f64 + 0.5) / s as f64 - c[a];
                            x * x
                        })
                        .sum();
                    d < r * r
                })
                .count();
            inside as f64 / samples as f64
        });
        let mut b = BodyFraction::named(name);
        b.set(lo, n, values);
        b
    }

    /// A disk of [`round`] sampled 32 × 32 per cell.
    fn disk(name: &str, c: [f64; 2], r: f64) -> BodyFraction {
        round(name, [c[0], c[1], 0.0], r, 2, 32)
    }

    /// Two disks in oblique contact (the line of centres at 57° to the grid, off the cells'
    /// centres): the repulsion on each acts along the line of centres through the contact point
    /// (no moment about its centroid), the pair's net force and moment about any point are zero
    /// (momentum and angular momentum kept), and it still repels. Without the frictionless
    /// projection the halo's tail on the grid tilts the force by up to 20°: a steady torque
    /// that keeps a disk resting on two others turning. (On cells twice as wide as high the
    /// normal itself is 2.4° off at a gap of 1.2: module docs, "Limits".)
    #[test]
    fn an_oblique_contact_pushes_along_the_line_of_centres_without_turning() {
        let n = [48, 48, 1];
        let g = grid(n, 2);
        let r = 9.0;
        for (gap, turn) in [(0.6, 57.0_f64), (1.2, 57.0), (0.9, 33.0), (0.3, 71.0)] {
            let (s_, c_) = turn.to_radians().sin_cos();
            let a = [14.37, 12.81];
            let d = 2.0 * r + gap;
            let b = [a[0] + d * c_, a[1] + d * s_];
            let all = BodyFractions {
                bodies: vec![disk("a", a, r), disk("b", b, r)],
            };
            let mut s = stage(n, 2, false);
            s.find_supports(&all);
            let (e, updates) = s.forces(&g, &all, None);
            assert!(e > 0.0, "gap {gap}: no contact");
            // The whole: the pair's net force and moment about the origin, from the faces.
            let (mut total, mut total_moment, mut size) = ([0.0; 2], 0.0, 0.0);
            for &(axis, c, force) in &updates {
                let x = frictionless::face_centre(&g, axis, c);
                total[axis] += force;
                size += force.abs();
                total_moment += if axis == 0 {
                    -x[1] * force
                } else {
                    x[0] * force
                };
            }
            assert!(total.iter().all(|t| t.abs() <= 1e-13 * size), "{total:?}");
            assert!(
                total_moment.abs() <= 1e-13 * size * 48.0,
                "{total_moment:e}"
            );
            // Each body's: its load from the other's halo with the projection's change (the
            // rigid load carries that change exactly: `frictionless` tests).
            for p in s.pushed.iter().flat_map(|p| &p.pairs) {
                let (df, dm) = s.changes[p.k];
                let f = [p.force[0] + df[0], p.force[1] + df[1]];
                let sign = if p.k == 0 { -1.0 } else { 1.0 };
                let along = sign * (f[0] * c_ + f[1] * s_);
                let across = -f[0] * s_ + f[1] * c_;
                let was = (-p.force[0] * s_ + p.force[1] * c_)
                    .atan2(sign * (p.force[0] * c_ + p.force[1] * s_));
                assert!(along > 0.0, "gap {gap}, {turn}°: body {} pulled", p.k);
                assert!(
                    across.abs() <= 0.03 * along,
                    "gap {gap}, {turn}°: body {} pushed {:.2}° off the line of centres \
                     (before the projection {:.2}°)",
                    p.k,
                    across.atan2(along).to_degrees(),
                    was.to_degrees()
                );
                let moment = p.moment[2] + dm[2];
                assert!(
                    moment.abs() <= 0.03 * along * r,
                    "gap {gap}, {turn}°: body {} turned, moment {moment:e} of {:e}",
                    p.k,
                    along * r
                );
            }
        }
    }

    /// [`Self::an_oblique_contact_pushes_along_the_line_of_centres_without_turning`] in 3-D:
    /// two balls whose line of centres is oblique to all three axes.
    #[test]
    fn an_oblique_contact_of_balls_pushes_along_the_line_of_centres_without_turning() {
        let n = [32, 28, 28];
        let g = grid(n, 3);
        let r = 6.0;
        let dir = {
            let d = [0.62_f64, 0.55, 0.43];
            let l = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            d.map(|x| x / l)
        };
        for gap in [0.4, 0.9] {
            let a = [9.37, 8.81, 9.13];
            let b: [f64; 3] = std::array::from_fn(|i| a[i] + (2.0 * r + gap) * dir[i]);
            let all = BodyFractions {
                bodies: vec![round("a", a, r, 3, 8), round("b", b, r, 3, 8)],
            };
            let mut s = stage(n, 3, false);
            s.find_supports(&all);
            let (e, updates) = s.forces(&g, &all, None);
            assert!(e > 0.0, "gap {gap}: no contact");
            let (mut total, mut moment, mut size) = ([0.0; 3], [0.0; 3], 0.0);
            for &(axis, c, force) in &updates {
                let x = frictionless::face_centre(&g, axis, c);
                let mut f = [0.0; 3];
                f[axis] = force;
                total[axis] += force;
                size += force.abs();
                let m = frictionless::cross(x, f);
                moment = std::array::from_fn(|i| moment[i] + m[i]);
            }
            assert!(total.iter().all(|t| t.abs() <= 1e-13 * size), "{total:?}");
            assert!(
                moment.iter().all(|m| m.abs() <= 1e-13 * size * 32.0),
                "{moment:?}"
            );
            for p in s.pushed.iter().flat_map(|p| &p.pairs) {
                let (df, dm) = s.changes[p.k];
                let sign = if p.k == 0 { -1.0 } else { 1.0 };
                let f: [f64; 3] = std::array::from_fn(|i| p.force[i] + df[i]);
                let along: f64 = sign * (0..3).map(|i| f[i] * dir[i]).sum::<f64>();
                let across: f64 = (0..3)
                    .map(|i| (f[i] - sign * along * dir[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(along > 0.0, "gap {gap}: body {} pulled", p.k);
                assert!(
                    across <= 0.015 * along,
                    "gap {gap}: body {} pushed {:.2}° off the line of centres",
                    p.k,
                    across.atan2(along).to_degrees()
                );
                let m: f64 = (0..3)
                    .map(|i| (p.moment[i] + dm[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                // Before the projection: 1.3–1.9° and 0.021–0.031 |F| R.
                assert!(
                    m <= 0.015 * along * r,
                    "gap {gap}: body {} turned, {m:e}",
                    p.k
                );
            }
        }
    }

    /// Two disks in contact along x, the left one sliding along +y past the right one at rest:
    /// friction pulls the left one back and the right one along, `μ |F_n|` while that does not
    /// stop the sliding within the step and the sticking force beyond, and keeps the pair's
    /// momentum and angular momentum.
    #[test]
    fn friction_opposes_sliding_up_to_coulombs_bound_and_sticks_beyond() {
        let n = [48, 32, 1];
        let g = grid(n, 2);
        let (a, b) = ([14.37, 15.81], [14.37 + 18.6, 15.81]);
        let all = BodyFractions {
            bodies: vec![disk("a", a, 9.0), disk("b", b, 9.0)],
        };
        let mut v = Field::zeros(&g);
        for j in 0..n[1] as isize {
            for i in 0..24 {
                v[[i, j, 0]] = 1.0;
            }
        }
        let u = Field::zeros(&g);
        let dt = 1e-3;
        let flow = Flow {
            velocity: [Some(&u), Some(&v), None],
            dt,
        };
        // The friction: the change over the frictionless projection's.
        let run = |mu: f64| {
            let mut s = stage(n, 2, false);
            s.friction = mu;
            s.find_supports(&all);
            let (_, updates) = s.forces(&g, &all, Some(flow));
            let (mut total, mut moment, mut size) = ([0.0; 2], 0.0, 0.0);
            for &(axis, c, f) in &updates {
                let x = frictionless::face_centre(&g, axis, c);
                total[axis] += f;
                size += f.abs();
                moment += if axis == 0 { -x[1] * f } else { x[0] * f };
            }
            assert!(
                total.iter().all(|t| t.abs() <= 1e-13 * size),
                "μ {mu}: {total:?}"
            );
            assert!(moment.abs() <= 1e-13 * size * 48.0, "μ {mu}: {moment:e}");
            let normal = s.pushed[0].pairs[0].force[0] + s.changes[0].0[0];
            (s.changes.clone(), normal.abs())
        };
        let (none, normal) = run(0.0);
        assert!(normal > 0.0);
        let friction = |mu: f64| {
            let (c, _) = run(mu);
            [0, 1].map(|k| c[k].0[1] - none[k].0[1])
        };
        let [on_a, on_b] = friction(0.1);
        assert!(on_a < 0.0 && on_b > 0.0, "{on_a:e}, {on_b:e}");
        assert!(
            (on_a + 0.1 * normal).abs() <= 1e-9 * normal,
            "{on_a:e} vs {:e}",
            0.1 * normal
        );
        assert!((on_a + on_b).abs() <= 1e-12 * normal);
        // A large μ: the force that stops the sliding (1 between the rigid motions) in one
        // step, below μ |F_n| and the same for any larger μ.
        let [stick, _] = friction(1e6);
        assert!(stick < 0.0 && -stick < 1e6 * normal, "{stick:e}");
        // Two rigid disks of mass M = π R² (ρ = 1), turned about their centres by a force at
        // r = 9.3 from each: the sliding changes by 2 (1/M + r²/I) dt per unit force.
        let (m, r) = (std::f64::consts::PI * 81.0, 9.3);
        let stops = 1.0 / (dt * 2.0 * (1.0 / m + r * r / (0.5 * m * 81.0)));
        assert!(
            (-stick / stops - 1.0).abs() < 0.01,
            "{stick:e} vs {stops:e}"
        );
        assert_eq!(friction(1e7)[0], stick);
    }

    /// The potential repels: moving two bodies apart lowers the stored energy, to zero beyond
    /// the range; a wall's halo pushes a body beside it away from the wall.
    #[test]
    fn moving_bodies_apart_lowers_the_stored_energy_and_walls_repel() {
        let n = [20, 10, 1];
        let g = grid(n, 2);
        let mut s = stage(n, 2, false);
        let at = |x: usize| body("a", [x, 2, 0], [5, 5, 1], 7);
        let mut prev = f64::INFINITY;
        for gap in 0..4 {
            let all = BodyFractions {
                bodies: vec![at(3), body("b", [8 + gap, 2, 0], [5, 5, 1], 8)],
            };
            s.find_supports(&all);
            let (e, _) = s.forces(&g, &all, None);
            assert!(e < prev || e == 0.0, "gap {gap}: {e} after {prev}");
            prev = e;
        }
        assert_eq!(prev, 0.0, "beyond the range no energy");
        let mut w = stage(n, 2, true);
        let all = BodyFractions {
            bodies: vec![body("a", [0, 3, 0], [3, 3, 1], 3)],
        };
        w.find_supports(&all);
        let (e, updates) = w.forces(&g, &all, None);
        assert!(e > 0.0);
        let fx: f64 = updates.iter().filter(|u| u.0 == 0).map(|u| u.2).sum();
        assert!(fx > 0.0, "the x_min wall pushes the body along +x: {fx}");
    }
}
