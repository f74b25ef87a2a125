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
//! | Axis        | 0                 | odd reflection   | even                      | even      | even      |
//! | Periodic    | wraps             | wraps            | wraps                     | wraps     | wraps     |
//! | Outflow     | from the solvers  | constant         | constant                  | even      | odd (p=0) |
//!
//! Wall values are second-order accurate (the wall lies half a cell from the tangential
//! unknowns). The *homogeneous* variant (wall speed 0) serves implicit solves for corrections:
//! the full condition is affine in the unknowns, so a correction obeys the homogeneous one.

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

/// The two sides normal to one axis, with the cell counts along (`n`) and across (`m`) it.
struct Frame {
    n: isize,
    m: isize,
    lo_side: Side,
    hi_side: Side,
}

impl Frame {
    fn new(grid: &Grid, axis: usize) -> Frame {
        let (nx, ny) = (grid.nx as isize, grid.ny as isize);
        if axis == 0 {
            Frame {
                n: nx,
                m: ny,
                lo_side: Side::XMin,
                hi_side: Side::XMax,
            }
        } else {
            Frame {
                n: ny,
                m: nx,
                lo_side: Side::YMin,
                hi_side: Side::YMax,
            }
        }
    }
}

/// The boundary conditions of a run, ready to fill ghosts.
///
/// A moving wall's speed is an input that may change between steps
/// ([`BoundarySet::set_wall_speed`], e.g. an FMU's lid-speed input): the speeds live in one cell
/// shared by every copy of the set, so the copies stages keep follow the change.
#[derive(Clone, Debug)]
pub struct BoundarySet {
    sides: [Boundary; 4],
    lx: f64,
    ly: f64,
    /// Each side's moving-wall speed as `f64` bits (the scene's until set).
    speeds: Arc<[AtomicU64; 4]>,
}

impl BoundarySet {
    /// From the scene's boundary conditions.
    pub fn new(b: &Boundaries, grid: &Grid) -> Self {
        let sides = Side::ALL.map(|s| b.get(s).clone());
        let speeds = Arc::new(sides.clone().map(|b| {
            AtomicU64::new(match b {
                Boundary::MovingWall { speed, .. } => speed.to_bits(),
                _ => 0f64.to_bits(),
            })
        }));
        BoundarySet {
            sides,
            lx: grid.x1() - grid.x0,
            ly: grid.y1() - grid.y0,
            speeds,
        }
    }

    /// The speed of the moving wall on `side` (its profile and motion multiply it), if the side
    /// is one.
    pub fn moving_wall_speed(&self, side: Side) -> Option<f64> {
        matches!(self.get(side), Boundary::MovingWall { .. })
            .then(|| f64::from_bits(self.speeds[side as usize].load(Ordering::Relaxed)))
    }

    /// Set the speed of the moving wall on `side` from the next fill on, for this set and every
    /// copy of it. Refused for a side that is not a moving wall or a speed that is not finite.
    pub fn set_wall_speed(&self, side: Side, speed: f64) -> Result<(), String> {
        if !matches!(self.get(side), Boundary::MovingWall { .. }) {
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
    pub fn get(&self, side: Side) -> &Boundary {
        &self.sides[side as usize]
    }

    /// Whether x (or y, `axis = 1`) is periodic.
    pub fn periodic(&self, axis: usize) -> bool {
        let s = if axis == 0 { Side::XMin } else { Side::YMin };
        *self.get(s) == Boundary::Periodic
    }

    /// Whether the pressure is fixed somewhere (an outflow side); else it is defined up to a constant.
    pub fn has_pressure_reference(&self) -> bool {
        self.sides.contains(&Boundary::Outflow)
    }

    /// Unknown u faces along x (`axis = 0`) or v faces along y (`axis = 1`).
    pub fn normal_faces(&self, axis: usize, n: usize) -> FaceRange {
        let (lo_side, hi_side) = if axis == 0 {
            (Side::XMin, Side::XMax)
        } else {
            (Side::YMin, Side::YMax)
        };
        let n = n as isize;
        let lo = match self.get(lo_side) {
            Boundary::Periodic | Boundary::Outflow => 0,
            _ => 1,
        };
        let hi = match self.get(hi_side) {
            Boundary::Periodic => n,
            Boundary::Outflow => n + 1,
            _ => n,
        };
        FaceRange { lo, hi }
    }

    /// Tangential wall velocity on `side` at position `s` along it (from its start) and time `t`.
    fn wall_speed(&self, side: Side, s: f64, t: f64) -> f64 {
        match self.get(side) {
            Boundary::MovingWall {
                profile, motion, ..
            } => {
                let len = if matches!(side, Side::XMin | Side::XMax) {
                    self.ly
                } else {
                    self.lx
                };
                let speed = f64::from_bits(self.speeds[side as usize].load(Ordering::Relaxed));
                speed * profile.factor(s, len) * motion.factor(t)
            }
            _ => 0.0,
        }
    }

    /// Fill the velocity ghosts (and boundary normal faces) for time `t`.
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
        let w = if homogeneous {
            WallTime::Homogeneous
        } else {
            WallTime::At(t)
        };
        self.fill_velocity_at(grid, u, v, w);
    }

    /// Fill the velocity ghosts with the wall speeds of `when`.
    pub fn fill_velocity_at(&self, grid: &Grid, u: &mut Field, v: &mut Field, when: WallTime) {
        // Pass 1: x-sides (u normal, v tangential) over all padded rows.
        self.fill_normal(grid, u, 0);
        self.fill_tangential(grid, v, 0, when);
        // Pass 2: y-sides (v normal, u tangential) over all padded columns, corners included.
        self.fill_normal(grid, v, 1);
        self.fill_tangential(grid, u, 1, when);
    }

    /// Normal component `f` along `axis`: boundary face and ghosts.
    fn fill_normal(&self, grid: &Grid, f: &mut Field, axis: usize) {
        let Frame {
            n,
            m,
            lo_side,
            hi_side,
        } = Frame::new(grid, axis);
        // Accessor along the normal direction `a` at transverse position `b`.
        let at = |a: isize, b: isize| if axis == 0 { (a, b) } else { (b, a) };
        let lo = self.get(lo_side).clone();
        let hi = self.get(hi_side).clone();
        for b in -G..(m + 1 + G) {
            if lo == Boundary::Periodic {
                f[at(n, b)] = f[at(0, b)];
                for g in 1..=G {
                    f[at(-g, b)] = f[at(n - g, b)];
                    f[at(n + g, b)] = f[at(g, b)];
                }
                continue;
            }
            match lo {
                Boundary::Outflow => {
                    for g in 1..=G {
                        f[at(-g, b)] = f[at(0, b)];
                    }
                }
                _ => {
                    f[at(0, b)] = 0.0;
                    for g in 1..=G {
                        f[at(-g, b)] = -f[at(g, b)];
                    }
                }
            }
            match hi {
                Boundary::Outflow => {
                    for g in 1..=G {
                        f[at(n + g, b)] = f[at(n, b)];
                    }
                }
                _ => {
                    f[at(n, b)] = 0.0;
                    for g in 1..=G {
                        f[at(n + g, b)] = -f[at(n - g, b)];
                    }
                }
            }
        }
    }

    /// Tangential component `f` at the sides normal to `axis`.
    fn fill_tangential(&self, grid: &Grid, f: &mut Field, axis: usize, when: WallTime) {
        let Frame {
            n,
            m,
            lo_side,
            hi_side,
        } = Frame::new(grid, axis);
        let at = |a: isize, b: isize| if axis == 0 { (a, b) } else { (b, a) };
        // The tangential component along a side normal to `axis` lives at the faces of the
        // transverse direction: its position along the wall is s = b·h.
        let h = if axis == 0 { grid.dy } else { grid.dx };
        for b in -G..(m + 1 + G) {
            let s = b as f64 * h;
            for (side, first, dir) in [(lo_side, 0isize, -1isize), (hi_side, n - 1, 1)] {
                let bc = self.get(side);
                for g in 1..=G {
                    let ghost = first + dir * g;
                    let mirror = first - dir * (g - 1);
                    let val = match bc {
                        Boundary::Periodic => f[at(if dir < 0 { ghost + n } else { ghost - n }, b)],
                        Boundary::NoSlip => -f[at(mirror, b)],
                        Boundary::MovingWall { .. } => {
                            let w = match when {
                                WallTime::Homogeneous => 0.0,
                                WallTime::At(t) => self.wall_speed(side, s, t),
                                WallTime::Blend { t0, t1, theta } => {
                                    (1.0 - theta) * self.wall_speed(side, s, t0)
                                        + theta * self.wall_speed(side, s, t1)
                                }
                            };
                            2.0 * w - f[at(mirror, b)]
                        }
                        Boundary::FreeSlip | Boundary::Axis => f[at(mirror, b)],
                        Boundary::Outflow => f[at(first, b)],
                    };
                    f[at(ghost, b)] = val;
                }
            }
        }
    }

    /// Fill ghosts of a cell-centred scalar with even reflection at walls (zero normal
    /// gradient), wrapping at periodic sides; `dirichlet_outflow` makes it odd (zero on the
    /// boundary) at outflow sides, as for the pressure.
    pub fn fill_scalar(&self, grid: &Grid, f: &mut Field, dirichlet_outflow: bool) {
        for axis in 0..2 {
            let Frame {
                n,
                m,
                lo_side,
                hi_side,
            } = Frame::new(grid, axis);
            let at = |a: isize, b: isize| if axis == 0 { (a, b) } else { (b, a) };
            for b in -G..(m + 1 + G) {
                for (side, first, dir) in [(lo_side, 0isize, -1isize), (hi_side, n - 1, 1)] {
                    let bc = self.get(side);
                    for g in 1..=G {
                        let ghost = first + dir * g;
                        let mirror = first - dir * (g - 1);
                        f[at(ghost, b)] = match bc {
                            Boundary::Periodic => {
                                f[at(if dir < 0 { ghost + n } else { ghost - n }, b)]
                            }
                            Boundary::Outflow if dirichlet_outflow => -f[at(mirror, b)],
                            _ => f[at(mirror, b)],
                        };
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Geometry;
    use crate::scene::{WallMotion, WallProfile};

    fn set(x0: Boundary, x1: Boundary, y0: Boundary, y1: Boundary) -> Boundaries {
        Boundaries {
            x_min: x0,
            x_max: x1,
            y_min: y0,
            y_max: y1,
        }
    }

    #[test]
    fn moving_lid_ghost_gives_wall_speed_on_the_wall() {
        let g = Grid::new(Geometry::Planar, 4, 4, (0.0, 1.0), (0.0, 1.0));
        let lid = Boundary::MovingWall {
            speed: 2.0,
            profile: WallProfile::Uniform,
            motion: WallMotion::Steady,
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
}
