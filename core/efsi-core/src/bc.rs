//! Boundary conditions as ghost-cell values.
//!
//! Every stage reads neighbours through ghost cells; this module fills them so that the stencils
//! need no boundary branches. The rules, per side, for the velocity (normal component `n`,
//! tangential `t`) and for cell scalars (`s`: density, viscosity, fraction; `p`: pressure):
//!
//! | condition   | normal face `n`   | ghost `n`        | ghost `t`                 | ghost `s` | ghost `p` |
//! |-------------|-------------------|------------------|---------------------------|-----------|-----------|
//! | NoSlip      | 0                 | odd reflection   | odd reflection (t = 0)    | even      | even      |
//! | MovingWall  | 0                 | odd reflection   | `2·U_w − t` (t = U_w)     | even      | even      |
//! | FreeSlip    | 0                 | odd reflection   | even (∂t/∂n = 0)          | even      | even      |
//! | Symmetry    | 0                 | odd reflection   | even (∂t/∂n = 0)          | even      | even      |
//! | Axis        | 0                 | odd reflection   | even                      | even      | even      |
//! | Periodic    | wraps             | wraps            | wraps                     | wraps     | wraps     |
//! | Outflow     | from the solvers  | constant         | constant                  | even      | odd (p=0) |
//!
//! Wall values are second-order accurate (the wall lies half a cell from the tangential
//! unknowns). The *homogeneous* variant (wall speed 0) serves implicit solves for corrections:
//! the full condition is affine in the unknowns, so a correction obeys the homogeneous one.
//! Symmetry is FreeSlip's rule under the name of what it models, a mirror plane of the flow.
//!
//! # Three dimensions
//!
//! On a three-dimensional grid ([`Grid::new_3d`]) the same rules hold on all six sides, for the
//! three velocity components ([`BoundarySet::fill_velocity3`]: `w` on the z-faces is normal on
//! the z sides and tangential on the others) and for scalars along z. A side has two
//! tangential components: a moving wall drives one of them — `+x` on the y and z sides, `+y` on
//! the x sides, as in two dimensions — and holds the other at zero, or, with a `direction` in
//! its plane, drives each by its share of the direction; its profile
//! ([`crate::scene::WallProfile`]) is the product of the factors along both in-wall axes (a
//! `Sin2Ramp` lid vanishes at all four edges). Ghosts are filled one axis after the other (x,
//! then y, then z), each pass over the whole padded extent of the other axes, so edge and
//! corner ghosts take the value the later axis's rule gives the earlier one's ghosts, as the
//! corners do in two dimensions.

use crate::field::Field;
use crate::grid::{G, Grid};
use crate::scene::{Boundaries, Boundary, Side};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Range of updatable (unknown) normal faces along one direction: `lo..hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceRange {
    /// First unknown face index.
    pub lo: isize,
    /// One past the last unknown face index.
    pub hi: isize,
}

/// Which wall speeds to impose when filling velocity ghosts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WallTime {
    /// The wall speeds at time `t`.
    At(f64),
    /// `(1−θ)·w(t0) + θ·w(t1)`: the θ-weighted boundary data of a θ-scheme's explicit part.
    Blend {
        /// Start of the step.
        t0: f64,
        /// End of the step.
        t1: f64,
        /// Weight of the end.
        theta: f64,
    },
    /// Fixed walls (corrections in implicit solves).
    Homogeneous,
}

/// The lines of a field across the sides normal to `axis`: every padded index of the other
/// two axes (the third has the single index 0 on a two-dimensional grid).
struct Lines {
    /// Cells along `axis`.
    n: isize,
    /// Storage stride along `axis`.
    step: isize,
    /// Storage index of `[0, 0, 0]`.
    origin: isize,
    /// Storage strides and padded index ranges of the two other axes.
    across: [(isize, std::ops::Range<isize>); 2],
}

impl Lines {
    fn new(grid: &Grid, f: &Field, axis: usize) -> Lines {
        let n = grid.n();
        let range = |a: usize| -> std::ops::Range<isize> {
            if a == 2 && !grid.is_3d() {
                0..1
            } else {
                let g = if a == 2 { grid.gz() as isize } else { G };
                -g..n[a] as isize + 1 + g
            }
        };
        let stride = |a: usize| f.offset(crate::loops::unit(a));
        let [o1, o2] = others(axis);
        Lines {
            n: n[axis] as isize,
            step: stride(axis),
            origin: f.idx3([0, 0, 0]) as isize,
            across: [(stride(o1), range(o1)), (stride(o2), range(o2))],
        }
    }

    /// Each line as (storage index of its index 0 along the axis, its indices along the two
    /// other axes), the second other axis outermost.
    fn each(&self) -> impl Iterator<Item = (isize, [isize; 2])> + '_ {
        let [(s1, r1), (s2, r2)] = &self.across;
        r2.clone().flat_map(move |c| {
            r1.clone()
                .map(move |b| (self.origin + b * s1 + c * s2, [b, c]))
        })
    }
}

/// What one ghost rule writes at a position along the axis of every line ([`Lines::apply`]),
/// from the value `x` at another position.
#[derive(Clone, Copy, Debug)]
enum Rule {
    /// `x`.
    Copy,
    /// `−x`.
    Negate,
    /// `2·speed − x`: a wall moving at `speed` (the same on every line).
    Wall(f64),
    /// 0 (the value read is not used).
    Zero,
}

impl Rule {
    #[inline(always)]
    fn of(self, x: f64) -> f64 {
        match self {
            Rule::Copy => x,
            Rule::Negate => -x,
            Rule::Wall(speed) => 2.0 * speed - x,
            Rule::Zero => 0.0,
        }
    }
}

/// Up to this many rules per call of [`Lines::apply`]: a side's two ghost layers and its
/// boundary face, on both sides.
const RULES: usize = 2 * (G as usize + 1);

/// A sequence of ghost rules `(written, read, rule)` (positions along the lines' axis), kept on
/// the stack.
struct Rules {
    list: [(isize, isize, Rule); RULES],
    len: usize,
}

impl Rules {
    fn new() -> Self {
        Rules {
            list: [(0, 0, Rule::Zero); RULES],
            len: 0,
        }
    }

    fn push(&mut self, write: isize, read: isize, rule: Rule) {
        self.list[self.len] = (write, read, rule);
        self.len += 1;
    }

    /// The rules of both sides of `axis` (`n` cells along it), each side's ghost layers
    /// outwards: `pick(boundary, ghost)` gives the position read and the rule, knowing the
    /// ghost's mirror inside, the side's first cell and the periodic image.
    fn of_sides(
        set: &BoundarySet,
        axis: usize,
        n: isize,
        mut pick: impl FnMut(&Boundary, Ghost) -> (isize, Rule),
    ) -> Self {
        let mut rules = Rules::new();
        for (side, first, dir) in [
            (Side::normal_to(axis, false), 0isize, -1isize),
            (Side::normal_to(axis, true), n - 1, 1),
        ] {
            let bc = set.get(side);
            for g in 1..=G {
                let ghost = first + dir * g;
                let at = Ghost {
                    mirror: first - dir * (g - 1),
                    first,
                    periodic: if dir < 0 { ghost + n } else { ghost - n },
                };
                let (read, rule) = pick(bc, at);
                rules.push(ghost, read, rule);
            }
        }
        rules
    }
}

/// Where a ghost's rule may read: its mirror image across the boundary face, the side's first
/// cell, and its periodic image.
#[derive(Clone, Copy)]
struct Ghost {
    mirror: isize,
    first: isize,
    periodic: isize,
}

impl Lines {
    /// The rules applied on every line in their order (`d[write] = rule(d[read])`). The lines
    /// share no entry, so whether a line takes all rules before the next line or each rule
    /// goes over all lines before the next rule gives the same values; where the lines' first
    /// other axis is the storage's contiguous one (lines along y or z), each rule goes over
    /// the lines' contiguous runs, one vectorisable pass per run.
    fn apply(&self, d: &mut [f64], rules: &Rules) {
        let rules = &rules.list[..rules.len];
        let step = self.step;
        let [(s1, r1), (s2, r2)] = &self.across;
        if *s1 != 1 {
            for (base, _) in self.each() {
                for &(write, read, rule) in rules {
                    d[(base + write * step) as usize] = rule.of(d[(base + read * step) as usize]);
                }
            }
            return;
        }
        let len = r1.len();
        for &(write, read, rule) in rules {
            for c in r2.clone() {
                let base = self.origin + r1.start + c * s2;
                let (w, r) = (
                    (base + write * step) as usize,
                    (base + read * step) as usize,
                );
                if let Rule::Zero = rule {
                    d[w..w + len].fill(0.0);
                    continue;
                }
                let (out, from) = if w < r {
                    let (lo, hi) = d.split_at_mut(r);
                    (&mut lo[w..w + len], &hi[..len])
                } else {
                    let (lo, hi) = d.split_at_mut(w);
                    (&mut hi[..len], &lo[r..r + len])
                };
                for (o, x) in out.iter_mut().zip(from) {
                    *o = rule.of(*x);
                }
            }
        }
    }
}

/// The two axes other than `axis`, in order.
fn others(axis: usize) -> [usize; 2] {
    match axis {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// The component a moving wall on a side normal to `axis` drives: y on the x sides, x on the
/// others.
fn driven(axis: usize) -> usize {
    if axis == 0 { 1 } else { 0 }
}

/// Where on a wall normal to `axis` a line of the tangential component `comp` lies: the
/// component lives on the faces of its own axis (position index·h from the wall's start) and at
/// cell centres of the other in-wall axis ((index + ½)·h).
struct WallPlace {
    h: [f64; 3],
    /// The first in-wall axis (the line's first index is along it).
    first: usize,
    comp: usize,
    /// Whether `comp` is the component a moving wall without a direction drives.
    driven: bool,
    /// The in-wall axis other than `comp` on a three-dimensional grid.
    other: Option<usize>,
}

impl WallPlace {
    fn new(grid: &Grid, axis: usize, comp: usize) -> Self {
        let [o1, o2] = others(axis);
        WallPlace {
            h: grid.h(),
            first: o1,
            comp,
            driven: comp == driven(axis),
            other: grid.is_3d().then_some(if o1 == comp { o2 } else { o1 }),
        }
    }

    /// The position along in-wall axis `a` of the line with in-wall indices `t`.
    #[inline]
    fn position(&self, t: [isize; 2], a: usize) -> f64 {
        let b = if a == self.first { t[0] } else { t[1] };
        if a == self.comp {
            b as f64 * self.h[a]
        } else {
            (b as f64 + 0.5) * self.h[a]
        }
    }
}

/// One side of one line: the storage index of the line's index 0 and the stride along it, the
/// cells along it, the side's first cell and its outward direction (−1 or 1).
struct GhostLine {
    base: isize,
    step: isize,
    n: isize,
    first: isize,
    dir: isize,
}

/// The ghost layers of a tangential component on one side of one line, outwards: wrapped at a
/// periodic side, odd at a no-slip wall, `2·speed − x` at a moving wall, even at free-slip,
/// symmetry and axis sides, the first cell's value at an outflow.
#[inline]
fn fill_line_ghosts(d: &mut [f64], line: &GhostLine, bc: &Boundary, speed: f64) {
    let &GhostLine {
        base,
        step,
        n,
        first,
        dir,
    } = line;
    let at = |a: isize| (base + a * step) as usize;
    for g in 1..=G {
        let ghost = first + dir * g;
        let mirror = first - dir * (g - 1);
        let val = match bc {
            Boundary::Periodic => d[at(if dir < 0 { ghost + n } else { ghost - n })],
            Boundary::NoSlip => -d[at(mirror)],
            Boundary::MovingWall { .. } => 2.0 * speed - d[at(mirror)],
            Boundary::FreeSlip | Boundary::Symmetry | Boundary::Axis => d[at(mirror)],
            Boundary::Outflow => d[at(first)],
        };
        d[at(ghost)] = val;
    }
}

/// The boundary conditions of a run, ready to fill ghosts.
///
/// A moving wall's speed is an input that may change between steps
/// ([`BoundarySet::set_wall_speed`], e.g. an FMU's lid-speed input): the speeds live in one cell
/// shared by every copy of the set, so the copies stages keep follow the change.
#[derive(Clone, Debug)]
pub struct BoundarySet {
    /// The condition of each side of [`Side::of`] the grid's dimensions (four or six).
    sides: Vec<Boundary>,
    /// Extent of the box along each axis.
    len: [f64; 3],
    /// Each side's moving-wall speed as `f64` bits (the scene's until set).
    speeds: Arc<[AtomicU64; 6]>,
}

impl BoundarySet {
    /// From the scene's boundary conditions: the four sides of a two-dimensional grid, the six
    /// of a three-dimensional one.
    ///
    /// # Panics
    ///
    /// On a three-dimensional grid if `b` has no z sides (a validated Cartesian3D scene has).
    pub fn new(b: &Boundaries, grid: &Grid) -> Self {
        let sides: Vec<Boundary> = Side::of(grid.dims())
            .iter()
            .map(|&s| b.get(s).clone())
            .collect();
        let speeds = Arc::new(std::array::from_fn(|k| {
            AtomicU64::new(match sides.get(k) {
                Some(Boundary::MovingWall { speed, .. }) => speed.to_bits(),
                _ => 0f64.to_bits(),
            })
        }));
        BoundarySet {
            sides,
            len: [
                grid.x1() - grid.x0,
                grid.y1() - grid.y0,
                grid.nz as f64 * grid.dz,
            ],
            speeds,
        }
    }

    /// The sides this set has: [`Side::ALL`] in two dimensions, [`Side::ALL3`] in three.
    pub fn sides(&self) -> &'static [Side] {
        Side::of(if self.sides.len() == 6 { 3 } else { 2 })
    }

    /// The speed of the moving wall on `side` (its profile and motion multiply it), if the side
    /// is one.
    pub fn moving_wall_speed(&self, side: Side) -> Option<f64> {
        matches!(
            self.sides.get(side as usize),
            Some(Boundary::MovingWall { .. })
        )
        .then(|| f64::from_bits(self.speeds[side as usize].load(Ordering::Relaxed)))
    }

    /// Set the speed of the moving wall on `side` from the next fill on, for this set and every
    /// copy of it. Refused for a side that is not a moving wall or a speed that is not finite.
    pub fn set_wall_speed(&self, side: Side, speed: f64) -> Result<(), String> {
        if !matches!(
            self.sides.get(side as usize),
            Some(Boundary::MovingWall { .. })
        ) {
            return Err(format!("{side:?} is not a moving wall"));
        }
        if !speed.is_finite() {
            return Err(format!(
                "the wall speed must be finite, got {}",
                crate::scene::num(speed)
            ));
        }
        self.speeds[side as usize].store(speed.to_bits(), Ordering::Relaxed);
        Ok(())
    }

    /// The condition on `side`.
    ///
    /// # Panics
    ///
    /// On a z side of a two-dimensional set (iterate [`sides`](Self::sides)).
    pub fn get(&self, side: Side) -> &Boundary {
        self.sides
            .get(side as usize)
            .unwrap_or_else(|| panic!("{side}: a two-dimensional grid has no z sides"))
    }

    /// Whether x (`axis = 0`), y (1) or z (2) is periodic.
    pub fn periodic(&self, axis: usize) -> bool {
        *self.get(Side::normal_to(axis, false)) == Boundary::Periodic
    }

    /// Whether the pressure is fixed somewhere (an outflow side); else it is defined up to a constant.
    pub fn has_pressure_reference(&self) -> bool {
        self.sides.contains(&Boundary::Outflow)
    }

    /// Unknown u faces along x (`axis = 0`), v faces along y (1) or w faces along z (2), of
    /// `n` cells along that axis.
    pub fn normal_faces(&self, axis: usize, n: usize) -> FaceRange {
        let n = n as isize;
        let lo = match self.get(Side::normal_to(axis, false)) {
            Boundary::Periodic | Boundary::Outflow => 0,
            _ => 1,
        };
        let hi = match self.get(Side::normal_to(axis, true)) {
            Boundary::Periodic => n,
            Boundary::Outflow => n + 1,
            _ => n,
        };
        FaceRange { lo, hi }
    }

    /// Speed of the moving wall on `side` at `when`, at the position `s` along the driven
    /// component's axis `c` and, in three dimensions, `e` along the other in-wall axis `o`
    /// (each from the wall's start).
    fn wall_speed(
        &self,
        side: Side,
        (c, s): (usize, f64),
        other: Option<(usize, f64)>,
        when: WallTime,
    ) -> f64 {
        let Boundary::MovingWall {
            profile, motion, ..
        } = self.get(side)
        else {
            return 0.0;
        };
        let at = |t: f64| {
            let speed = f64::from_bits(self.speeds[side as usize].load(Ordering::Relaxed));
            let v = speed * profile.factor(s, self.len[c]) * motion.factor(t);
            match other {
                Some((o, e)) => v * profile.factor(e, self.len[o]),
                None => v,
            }
        };
        match when {
            WallTime::Homogeneous => 0.0,
            WallTime::At(t) => at(t),
            WallTime::Blend { t0, t1, theta } => (1.0 - theta) * at(t0) + theta * at(t1),
        }
    }

    /// Fill the velocity ghosts (and boundary normal faces) of a two-dimensional grid for time
    /// `t` ([`fill_velocity3`](Self::fill_velocity3) with no `w`).
    ///
    /// With `homogeneous`, moving walls count as fixed (for corrections in implicit solves).
    pub fn fill_velocity(
        &self,
        grid: &Grid,
        u: &mut Field,
        v: &mut Field,
        t: f64,
        homogeneous: bool,
    ) {
        self.fill_velocity3(grid, u, v, None, t, homogeneous);
    }

    /// Fill the velocity ghosts (and boundary normal faces) for time `t`: `u`, `v` and, on a
    /// three-dimensional grid, `w` (`None` on a two-dimensional one).
    ///
    /// With `homogeneous`, moving walls count as fixed (for corrections in implicit solves).
    ///
    /// # Panics
    ///
    /// If `w` is given on a two-dimensional grid or missing on a three-dimensional one.
    pub fn fill_velocity3(
        &self,
        grid: &Grid,
        u: &mut Field,
        v: &mut Field,
        w: Option<&mut Field>,
        t: f64,
        homogeneous: bool,
    ) {
        let when = if homogeneous {
            WallTime::Homogeneous
        } else {
            WallTime::At(t)
        };
        self.fill_velocity3_at(grid, u, v, w, when);
    }

    /// Fill the velocity ghosts of a two-dimensional grid with the wall speeds of `when`.
    pub fn fill_velocity_at(&self, grid: &Grid, u: &mut Field, v: &mut Field, when: WallTime) {
        self.fill_velocity3_at(grid, u, v, None, when);
    }

    /// Fill the velocity ghosts with the wall speeds of `when`: `u`, `v` and, on a
    /// three-dimensional grid, `w`. Axis by axis (x, y, z): the normal component's boundary
    /// face and ghosts, then the tangential components' ghosts.
    ///
    /// # Panics
    ///
    /// If `w` is given on a two-dimensional grid or missing on a three-dimensional one.
    pub fn fill_velocity3_at(
        &self,
        grid: &Grid,
        u: &mut Field,
        v: &mut Field,
        w: Option<&mut Field>,
        when: WallTime,
    ) {
        assert_eq!(
            w.is_some(),
            grid.is_3d(),
            "w is filled exactly on a three-dimensional grid"
        );
        let mut c = [Some(u), Some(v), w];
        for axis in 0..grid.dims() {
            if let Some(f) = c[axis].as_deref_mut() {
                self.fill_normal(grid, f, axis);
            }
            for t in (0..grid.dims()).filter(|&t| t != axis) {
                if let Some(f) = c[t].as_deref_mut() {
                    self.fill_tangential(grid, f, axis, t, when);
                }
            }
        }
    }

    /// Normal component `f` along `axis`: boundary face and ghosts.
    fn fill_normal(&self, grid: &Grid, f: &mut Field, axis: usize) {
        let lines = Lines::new(grid, f, axis);
        let n = lines.n;
        let lo = self.get(Side::normal_to(axis, false));
        let hi = self.get(Side::normal_to(axis, true));
        let mut rules = Rules::new();
        if *lo == Boundary::Periodic {
            rules.push(n, 0, Rule::Copy);
            for g in 1..=G {
                rules.push(-g, n - g, Rule::Copy);
                rules.push(n + g, g, Rule::Copy);
            }
        } else {
            match lo {
                Boundary::Outflow => (1..=G).for_each(|g| rules.push(-g, 0, Rule::Copy)),
                _ => {
                    rules.push(0, 0, Rule::Zero);
                    (1..=G).for_each(|g| rules.push(-g, g, Rule::Negate));
                }
            }
            match hi {
                Boundary::Outflow => (1..=G).for_each(|g| rules.push(n + g, n, Rule::Copy)),
                _ => {
                    rules.push(n, n, Rule::Zero);
                    (1..=G).for_each(|g| rules.push(n + g, n - g, Rule::Negate));
                }
            }
        }
        lines.apply(f.data_mut(), &rules);
    }

    /// Tangential component `f` (the velocity along axis `comp`) at the sides normal to `axis`.
    /// Where no wall drives it with a speed that varies along the wall, every ghost is a rule of
    /// one value; else line by line ([`fill_tangential_lines`](Self::fill_tangential_lines)).
    fn fill_tangential(
        &self,
        grid: &Grid,
        f: &mut Field,
        axis: usize,
        comp: usize,
        when: WallTime,
    ) {
        let lines = Lines::new(grid, f, axis);
        if [false, true]
            .into_iter()
            .any(|hi| self.drives_varying(Side::normal_to(axis, hi), axis, comp, when))
        {
            self.fill_tangential_lines(grid, f, &lines, axis, comp, when);
            return;
        }
        let rules = Rules::of_sides(self, axis, lines.n, |bc, at| match bc {
            Boundary::Periodic => (at.periodic, Rule::Copy),
            Boundary::NoSlip => (at.mirror, Rule::Negate),
            Boundary::MovingWall { .. } => (at.mirror, Rule::Wall(0.0)),
            Boundary::FreeSlip | Boundary::Symmetry | Boundary::Axis => (at.mirror, Rule::Copy),
            Boundary::Outflow => (at.first, Rule::Copy),
        });
        lines.apply(f.data_mut(), &rules);
    }

    /// Whether the wall at `side` (normal to `axis`) drives component `comp` with a speed that
    /// varies along the wall at `when`: a moving wall, at a time other than `Homogeneous`,
    /// whose direction is given (it drives both tangential components) or whose driven
    /// component is `comp`.
    fn drives_varying(&self, side: Side, axis: usize, comp: usize, when: WallTime) -> bool {
        when != WallTime::Homogeneous
            && match self.get(side) {
                Boundary::MovingWall {
                    direction: Some(_), ..
                } => true,
                Boundary::MovingWall { .. } => comp == driven(axis),
                _ => false,
            }
    }

    /// The tangential ghosts of `f` line by line: on each line and side, the wall's speed at
    /// the line's place on the wall ([`tangential_speed`](Self::tangential_speed)), then the
    /// side's ghost layers ([`fill_line_ghosts`]).
    fn fill_tangential_lines(
        &self,
        grid: &Grid,
        f: &mut Field,
        lines: &Lines,
        axis: usize,
        comp: usize,
        when: WallTime,
    ) {
        let (n, step) = (lines.n, lines.step);
        let place = WallPlace::new(grid, axis, comp);
        let sides = [
            (Side::normal_to(axis, false), 0isize, -1isize),
            (Side::normal_to(axis, true), n - 1, 1),
        ];
        let d = f.data_mut();
        for (base, t) in lines.each() {
            for (side, first, dir) in sides {
                let bc = self.get(side);
                let speed = self.tangential_speed(side, bc, &place, t, when);
                let line = GhostLine {
                    base,
                    step,
                    n,
                    first,
                    dir,
                };
                fill_line_ghosts(d, &line, bc, speed);
            }
        }
    }

    /// The speed along the place's component of the wall `bc` at `side` at the place of the
    /// line with in-wall indices `t`: its own speed where it drives the component without a
    /// direction, its speed times the direction's share along the component where a direction
    /// is given, else 0.
    #[inline]
    fn tangential_speed(
        &self,
        side: Side,
        bc: &Boundary,
        place: &WallPlace,
        t: [isize; 2],
        when: WallTime,
    ) -> f64 {
        let comp = place.comp;
        let share = match bc {
            Boundary::MovingWall {
                direction: None, ..
            } if place.driven => None,
            Boundary::MovingWall {
                direction: Some((x, y, z)),
                ..
            } => Some([x, y, z][comp] / (x * x + y * y + z * z).sqrt()),
            _ => return 0.0,
        };
        let speed = self.wall_speed(
            side,
            (comp, place.position(t, comp)),
            place.other.map(|o| (o, place.position(t, o))),
            when,
        );
        match share {
            Some(share) => share * speed,
            None => speed,
        }
    }

    /// Fill ghosts of a cell-centred scalar with even reflection at walls (zero normal
    /// gradient), wrapping at periodic sides; `dirichlet_outflow` makes it odd (zero on the
    /// boundary) at outflow sides, as for the pressure. Along every axis of the grid (z too in
    /// three dimensions).
    pub fn fill_scalar(&self, grid: &Grid, f: &mut Field, dirichlet_outflow: bool) {
        for axis in 0..grid.dims() {
            let lines = Lines::new(grid, f, axis);
            let n = lines.n;
            let rules = Rules::of_sides(self, axis, n, |bc, at| match bc {
                Boundary::Periodic => (at.periodic, Rule::Copy),
                Boundary::Outflow if dirichlet_outflow => (at.mirror, Rule::Negate),
                _ => (at.mirror, Rule::Copy),
            });
            lines.apply(f.data_mut(), &rules);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Geometry;
    use crate::scene::{WallMotion, WallProfile};

    fn set(x0: Boundary, x1: Boundary, y0: Boundary, y1: Boundary) -> Boundaries {
        Boundaries::planar(x0, x1, y0, y1)
    }

    #[test]
    fn moving_lid_ghost_gives_wall_speed_on_the_wall() {
        let g = Grid::new(Geometry::Planar, 4, 4, (0.0, 1.0), (0.0, 1.0));
        let lid = Boundary::MovingWall {
            speed: 2.0,
            profile: WallProfile::Uniform,
            motion: WallMotion::Steady,
            direction: None,
        };
        let bs = BoundarySet::new(
            &set(Boundary::NoSlip, Boundary::NoSlip, Boundary::NoSlip, lid),
            &g,
        );
        let mut u = Field::filled(&g, 0.3);
        let mut v = Field::filled(&g, 0.1);
        bs.fill_velocity(&g, &mut u, &mut v, 0.0, false);
        for i in 1..4 {
            assert!(
                ((u[(i, 3)] + u[(i, 4)]) / 2.0 - 2.0).abs() < 1e-15,
                "lid speed"
            );
            assert!(
                ((u[(i, 0)] + u[(i, -1)]) / 2.0).abs() < 1e-15,
                "bottom no-slip"
            );
        }
        for j in 0..4 {
            assert_eq!(u[(0, j)], 0.0);
            assert_eq!(u[(4, j)], 0.0);
        }
        for i in 0..4 {
            assert_eq!(v[(i, 0)], 0.0);
            assert_eq!(v[(i, 4)], 0.0);
        }
    }

    #[test]
    fn periodic_wraps_and_ranges() {
        let g = Grid::new(Geometry::Planar, 4, 3, (0.0, 1.0), (0.0, 1.0));
        let bs = BoundarySet::new(
            &set(
                Boundary::Periodic,
                Boundary::Periodic,
                Boundary::NoSlip,
                Boundary::FreeSlip,
            ),
            &g,
        );
        let mut u = Field::zeros(&g);
        let mut v = Field::zeros(&g);
        for j in 0..3 {
            for i in 0..4 {
                u[(i, j)] = (i + 10 * j) as f64;
            }
        }
        bs.fill_velocity(&g, &mut u, &mut v, 0.0, false);
        assert_eq!(u[(4, 1)], u[(0, 1)]);
        assert_eq!(u[(-1, 1)], u[(3, 1)]);
        assert_eq!(u[(5, 2)], u[(1, 2)]);
        assert_eq!(u[(2, 3)], u[(2, 2)], "free slip: even");
        assert_eq!(u[(2, -1)], -u[(2, 0)], "no slip: odd");
        assert_eq!(bs.normal_faces(0, 4), FaceRange { lo: 0, hi: 4 });
        assert_eq!(bs.normal_faces(1, 3), FaceRange { lo: 1, hi: 3 });
    }

    /// A 3 × 4 × 5 grid over [0, 3] × [0, 4] × [0, 5] (unit cells).
    fn grid3() -> Grid {
        Grid::new_3d([3, 4, 5], (0.0, 3.0), (0.0, 4.0), (0.0, 5.0))
    }

    /// Six sides: `xyz` for x_min … z_max.
    fn set3(sides: [Boundary; 6]) -> Boundaries {
        let [x0, x1, y0, y1, z0, z1] = sides;
        Boundaries {
            z_min: Some(z0),
            z_max: Some(z1),
            ..Boundaries::planar(x0, x1, y0, y1)
        }
    }

    /// A field whose every entry, ghosts included, is distinct: `1 + i + 10j + 100k + c`.
    fn distinct(g: &Grid, c: f64) -> Field {
        let mut f = Field::zeros(g);
        for n in 0..f.data().len() {
            let [i, j, k] = f.index_of(n);
            f.data_mut()[n] = 1.0 + i as f64 + 10.0 * j as f64 + 100.0 * k as f64 + c;
        }
        f
    }

    fn lid(speed: f64, profile: WallProfile) -> Boundary {
        Boundary::MovingWall {
            speed,
            profile,
            motion: WallMotion::Steady,
            direction: None,
        }
    }

    /// Filled `u`, `v`, `w` of a 3 × 4 × 5 grid under `sides`.
    fn filled3(sides: [Boundary; 6], when: WallTime) -> (Grid, BoundarySet, [Field; 3]) {
        let g = grid3();
        let bs = BoundarySet::new(&set3(sides), &g);
        let (mut u, mut v, mut w) = (distinct(&g, 0.25), distinct(&g, 0.5), distinct(&g, 0.75));
        bs.fill_velocity3_at(&g, &mut u, &mut v, Some(&mut w), when);
        (g, bs, [u, v, w])
    }

    /// The mean of `f` across the side normal to `axis` (`hi`: the upper one) at transverse
    /// indices `t` (a cell-centred or tangential location) — the value on the wall — and the
    /// ghost–mirror pairs of the second layer.
    fn across(f: &Field, n: isize, axis: usize, hi: bool, t: [isize; 3]) -> (f64, f64, f64) {
        let at = |a: isize| {
            let mut i = t;
            i[axis] = a;
            f[i]
        };
        if hi {
            ((at(n - 1) + at(n)) / 2.0, at(n + 1), at(n - 2))
        } else {
            ((at(0) + at(-1)) / 2.0, at(-2), at(1))
        }
    }

    #[test]
    fn no_slip_on_six_sides_zeroes_normal_faces_and_reflects_tangential_ones_oddly() {
        let (g, _, c) = filled3([const { Boundary::NoSlip }; 6], WallTime::At(0.0));
        let n = g.n().map(|n| n as isize);
        for a in 0..3 {
            // The normal component: zero on the boundary faces, odd ghosts.
            let t = [1, 2, 3];
            let at = |f: isize| {
                let mut i = t;
                i[a] = f;
                i
            };
            assert_eq!(c[a][at(0)], 0.0);
            assert_eq!(c[a][at(n[a])], 0.0);
            assert_eq!(c[a][at(-1)], -c[a][at(1)]);
            assert_eq!(c[a][at(-2)], -c[a][at(2)]);
            assert_eq!(c[a][at(n[a] + 2)], -c[a][at(n[a] - 2)]);
            // The tangential components along the sides normal to `a`: zero on the wall.
            for comp in (0..3).filter(|&b| b != a) {
                for hi in [false, true] {
                    let (wall, ghost, mirror) = across(&c[comp], n[a], a, hi, t);
                    assert_eq!(
                        wall,
                        0.0,
                        "component {comp} at side {:?}",
                        Side::normal_to(a, hi)
                    );
                    assert_eq!(ghost, -mirror);
                }
            }
        }
    }

    #[test]
    fn a_moving_lid_on_z_max_drives_u_and_holds_v() {
        let mut sides = [const { Boundary::NoSlip }; 6];
        sides[5] = lid(2.0, WallProfile::Uniform);
        let (g, _, [u, v, w]) = filled3(sides.clone(), WallTime::At(0.0));
        let nz = g.nz as isize;
        for (i, j) in [(0, 0), (1, 2), (3, 3)] {
            assert_eq!(across(&u, nz, 2, true, [i, j, 0]).0, 2.0);
            assert_eq!(across(&v, nz, 2, true, [j.min(2), i, 0]).0, 0.0);
            assert_eq!(across(&u, nz, 2, false, [i, j, 0]).0, 0.0);
        }
        assert_eq!(w[[1, 1, nz]], 0.0);
        // Homogeneous: the same lid counts as fixed.
        let (_, _, [u, ..]) = filled3(sides, WallTime::Homogeneous);
        assert_eq!(across(&u, nz, 2, true, [1, 1, 0]).0, 0.0);
    }

    #[test]
    fn a_moving_wall_on_x_min_drives_v_and_holds_w_and_its_ramp_spans_both_wall_axes() {
        let mut sides = [const { Boundary::NoSlip }; 6];
        sides[0] = lid(3.0, WallProfile::Sin2Ramp { width: 2.0 });
        let (_, bs, [_, v, w]) = filled3(sides, WallTime::At(0.0));
        assert_eq!(bs.moving_wall_speed(Side::XMin), Some(3.0));
        // v at y-face j = 2 (s = 2 along y, the wall's middle: factor 1) and z-centre k = 0
        // (e = 0.5 along z: factor sin²(π·0.5/4)).
        let f = (std::f64::consts::PI * 0.5 / 4.0).sin().powi(2);
        let (wall, ..) = across(&v, 3, 0, false, [0, 2, 0]);
        assert!((wall - 3.0 * f).abs() < 1e-14, "{wall}");
        // At z-centre k = 2 (e = 2.5, 2.5 from the far end too: factor 1).
        let (wall, ..) = across(&v, 3, 0, false, [0, 2, 2]);
        assert!((wall - 3.0).abs() < 1e-14, "{wall}");
        assert_eq!(across(&w, 3, 0, false, [0, 2, 2]).0, 0.0);
    }

    #[test]
    fn symmetry_and_free_slip_reflect_tangential_components_evenly_on_every_side() {
        for b in [Boundary::Symmetry, Boundary::FreeSlip] {
            let (g, _, c) = filled3(std::array::from_fn(|_| b.clone()), WallTime::At(0.0));
            let n = g.n().map(|n| n as isize);
            for a in 0..3 {
                for comp in (0..3).filter(|&x| x != a) {
                    for hi in [false, true] {
                        let t = [1, 1, 1];
                        let at = |f: isize| {
                            let mut i = t;
                            i[a] = f;
                            i
                        };
                        let (first, ghost) = if hi { (n[a] - 1, n[a]) } else { (0, -1) };
                        assert_eq!(c[comp][at(ghost)], c[comp][at(first)], "{b:?}");
                    }
                }
                let mut i = [1, 1, 1];
                i[a] = n[a];
                assert_eq!(c[a][i], 0.0);
            }
        }
    }

    #[test]
    fn periodic_z_wraps_every_component_and_the_scalars() {
        let mut sides = [const { Boundary::NoSlip }; 6];
        sides[4] = Boundary::Periodic;
        sides[5] = Boundary::Periodic;
        let (g, bs, [u, v, w]) = filled3(sides, WallTime::At(0.0));
        let nz = g.nz as isize;
        assert_eq!(w[[1, 1, nz]], w[[1, 1, 0]]);
        assert_eq!(w[[1, 1, -1]], w[[1, 1, nz - 1]]);
        assert_eq!(w[[1, 1, nz + 2]], w[[1, 1, 2]]);
        assert_eq!(u[[1, 2, -2]], u[[1, 2, nz - 2]]);
        assert_eq!(v[[2, 1, nz]], v[[2, 1, 0]]);
        assert_eq!(v[[2, 1, nz + 1]], v[[2, 1, 1]]);
        assert!(bs.periodic(2) && !bs.periodic(0));
        assert_eq!(bs.normal_faces(2, g.nz), FaceRange { lo: 0, hi: 5 });
        assert_eq!(bs.normal_faces(0, g.nx), FaceRange { lo: 1, hi: 3 });
        let mut p = distinct(&g, 0.0);
        bs.fill_scalar(&g, &mut p, true);
        assert_eq!(p[[1, 1, -1]], p[[1, 1, nz - 1]]);
        assert_eq!(p[[1, 1, nz + 1]], p[[1, 1, 1]]);
        assert_eq!(p[[-1, 1, 1]], p[[0, 1, 1]], "even at a wall");
    }

    #[test]
    fn outflow_on_z_max_extends_velocity_and_zeroes_the_pressure_there() {
        let mut sides = [const { Boundary::NoSlip }; 6];
        sides[5] = Boundary::Outflow;
        let (g, bs, [u, _, w]) = filled3(sides, WallTime::At(0.0));
        let nz = g.nz as isize;
        let before = distinct(&g, 0.75)[[1, 1, nz]];
        assert_eq!(w[[1, 1, nz]], before, "the outflow face is the solvers'");
        assert_eq!(w[[1, 1, nz + 1]], w[[1, 1, nz]]);
        assert_eq!(w[[1, 1, nz + 2]], w[[1, 1, nz]]);
        assert_eq!(u[[1, 1, nz]], u[[1, 1, nz - 1]]);
        assert_eq!(bs.normal_faces(2, g.nz), FaceRange { lo: 1, hi: 6 });
        assert!(bs.has_pressure_reference());
        let mut p = distinct(&g, 0.0);
        bs.fill_scalar(&g, &mut p, true);
        assert_eq!(p[[1, 2, nz]], -p[[1, 2, nz - 1]]);
        assert_eq!(p[[1, 2, -1]], p[[1, 2, 0]]);
        let mut rho = distinct(&g, 0.0);
        bs.fill_scalar(&g, &mut rho, false);
        assert_eq!(rho[[1, 2, nz]], rho[[1, 2, nz - 1]]);
        assert_eq!(rho[[1, 2, nz + 1]], rho[[1, 2, nz - 2]]);
    }

    #[test]
    fn edge_ghosts_take_the_later_axis_rule() {
        // An x–z edge ghost of v: filled along x first (odd), then along z from the x-ghost
        // column (odd again).
        let (g, _, [_, v, _]) = filled3([const { Boundary::NoSlip }; 6], WallTime::At(0.0));
        let nz = g.nz as isize;
        assert_eq!(v[[-1, 1, nz]], -v[[-1, 1, nz - 1]]);
        assert_eq!(v[[-1, 1, nz - 1]], -v[[0, 1, nz - 1]]);
    }

    #[test]
    #[should_panic(expected = "w is filled exactly on a three-dimensional grid")]
    fn a_three_dimensional_grid_needs_w() {
        let g = grid3();
        let bs = BoundarySet::new(&set3([const { Boundary::NoSlip }; 6]), &g);
        let (mut u, mut v) = (Field::zeros(&g), Field::zeros(&g));
        bs.fill_velocity(&g, &mut u, &mut v, 0.0, false);
    }
}
