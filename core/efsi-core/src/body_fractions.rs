//! Each body's volume fraction in a scene of several bodies, as the state carries it to the
//! probes and outputs.
//!
//! The VOF stage of a scene of several bodies (`solids: [ … ]` with more than one entry)
//! transports each body's fraction `φ_k` on a window of the grid that follows it. It adds a
//! [`BodyFractions`] to the state ([`crate::Stage::init_state`]) and, after its initialization
//! and every step, copies each window into it: the window's first cell and its cells per axis,
//! and `φ_k` on the window's interior cells, x fastest. The state's solid fraction stays the
//! sum `Σ_k φ_k`; this resource is what tells the bodies apart, for the per-body probes
//! (`light.solid_x`, …) and the `body_id` array of the VTK files. Its storage scales with the
//! bodies' extent, not with the grid times the number of bodies.
//!
//! It is a copy, not the stage's record: it holds no checkpointed array (the stage's own record
//! carries the windows): a state restored from a checkpoint holds the bodies' names and no
//! values ([`BodyFraction::is_set`] false) until the stage, restored from its record, publishes
//! them again ([`crate::Stage::restored`]); the contact stage reads them at the start of the
//! next step. A snapshot (a step's rollback)
//! copies it with the rest of the state.

use crate::field::Field;
use crate::state::StateResource;

/// One body's fraction on its window of the grid.
#[derive(Clone, Debug, Default)]
pub struct BodyFraction {
    /// The body's name (the scene's `solids[k].name`).
    pub name: String,
    /// The grid cell of the window's first cell.
    pub lo: [usize; 3],
    /// The window's cells along each axis (1 along z in two dimensions).
    pub n: [usize; 3],
    /// `φ_k` on the window's cells, x fastest, then y, then z (`n[0]·n[1]·n[2]` values; none
    /// before the stage has set them).
    pub phi: Vec<f64>,
    /// The body's strain energy `∫ w_k W_k(B_k) dV` at the last step's end (per radian in
    /// axisymmetric geometry), set by the elastic stage for a body with a law; 0 for a body
    /// without one (it stores none).
    pub elastic_energy: f64,
}

impl BodyFraction {
    /// A body named `name` whose fraction is not set yet.
    pub fn named(name: impl Into<String>) -> Self {
        BodyFraction {
            name: name.into(),
            ..Default::default()
        }
    }

    /// Whether the stage has set the fraction.
    pub fn is_set(&self) -> bool {
        !self.phi.is_empty()
    }

    /// Set the window (first cell `lo`, `n` cells per axis) and its values, x fastest; the
    /// storage is reused (it grows only with the window).
    pub fn set(&mut self, lo: [usize; 3], n: [usize; 3], values: impl Iterator<Item = f64>) {
        self.lo = lo;
        self.n = n;
        self.phi.clear();
        self.phi.extend(values);
        debug_assert_eq!(self.phi.len(), n.iter().product::<usize>());
    }

    /// `φ_k` at grid cell `at` (0 outside the window, and before the fraction is set).
    pub fn at(&self, at: [isize; 3]) -> f64 {
        let mut index = 0;
        for a in (0..3).rev() {
            let i = at[a] - self.lo[a] as isize;
            if i < 0 || i >= self.n[a] as isize {
                return 0.0;
            }
            index = index * self.n[a] + i as usize;
        }
        self.phi.get(index).copied().unwrap_or(0.0)
    }

    /// The window's cells as grid cells, in storage order (x fastest), each with its `φ_k`.
    pub fn cells(&self) -> impl Iterator<Item = ([isize; 3], f64)> + '_ {
        let [nx, ny, _] = self.n;
        let lo = self.lo.map(|v| v as isize);
        self.phi.iter().enumerate().map(move |(c, &f)| {
            let at = [c % nx, (c / nx) % ny, c / (nx * ny)];
            ([0, 1, 2].map(|a| lo[a] + at[a] as isize), f)
        })
    }

    /// Write `φ_k` into the interior cells of `out`, a field of the grid, zero elsewhere
    /// (ghosts included).
    pub fn fill(&self, out: &mut Field) {
        out.fill(0.0);
        for (at, f) in self.cells() {
            out[at] = f;
        }
    }
}

/// The fractions of a scene's bodies, in the scene's order ([module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct BodyFractions {
    /// One per body.
    pub bodies: Vec<BodyFraction>,
}

impl BodyFractions {
    /// The index (1-based, the scene's order) of the body holding the largest fraction of
    /// cell `at` among those holding more than `least`; 0 where none does. Ties go to the body
    /// listed first.
    pub fn id_at(&self, at: [isize; 3], least: f64) -> usize {
        let mut best = (0, least);
        for (k, b) in self.bodies.iter().enumerate() {
            let f = b.at(at);
            if f > best.1 {
                best = (k + 1, f);
            }
        }
        best.0
    }
}

impl StateResource for BodyFractions {
    /// None: the VOF stage's record carries the windows ([module docs](self)).
    fn arrays(&self) -> Vec<(String, &Field)> {
        Vec::new()
    }
    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        Vec::new()
    }
    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(self.clone())
    }
    /// Copies the windows of the same bodies, reusing the storage (it grows only when a window
    /// outgrows it); `false`, copying nothing, for another type or other bodies.
    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        let Some(other) = (other as &dyn std::any::Any).downcast_ref::<BodyFractions>() else {
            return false;
        };
        if self.bodies.len() != other.bodies.len()
            || self
                .bodies
                .iter()
                .zip(&other.bodies)
                .any(|(a, b)| a.name != b.name)
        {
            return false;
        }
        for (a, b) in self.bodies.iter_mut().zip(&other.bodies) {
            a.set(b.lo, b.n, b.phi.iter().copied());
            a.elastic_energy = b.elastic_energy;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Geometry, Grid};

    #[test]
    fn a_window_reads_its_cells_and_zero_outside() {
        let mut b = BodyFraction::named("a");
        assert!(!b.is_set());
        // Cells 2..5 × 1..3 of a 6 × 4 grid.
        b.set([2, 1, 0], [3, 2, 1], (0..6).map(|v| v as f64 * 0.1));
        assert!(b.is_set());
        assert_eq!(b.at([2, 1, 0]), 0.0);
        assert_eq!(b.at([3, 1, 0]), 0.1);
        assert_eq!(b.at([2, 2, 0]), 0.30000000000000004);
        assert_eq!(b.at([4, 2, 0]), 0.5);
        assert_eq!(b.at([5, 2, 0]), 0.0);
        assert_eq!(b.at([4, 3, 0]), 0.0);
        assert_eq!(b.at([1, 1, 0]), 0.0);
        let grid = Grid::new(Geometry::Planar, 6, 4, (0.0, 1.0), (0.0, 1.0));
        let mut f = Field::filled(&grid, 7.0);
        b.fill(&mut f);
        assert_eq!(f[(4, 2)], 0.5);
        assert_eq!(f[(0, 0)], 0.0);
        assert_eq!(f[(-1, 0)], 0.0);
        // The body holding most of a cell names it; none above `least`: 0.
        let mut c = BodyFraction::named("b");
        c.set([4, 2, 0], [2, 2, 1], [0.6, 0.0, 0.0, 0.0].into_iter());
        let all = BodyFractions {
            bodies: vec![b.clone(), c],
        };
        assert_eq!(all.id_at([4, 2, 0], 1e-3), 2);
        assert_eq!(all.id_at([3, 2, 0], 1e-3), 1);
        assert_eq!(all.id_at([0, 0, 0], 1e-3), 0);
        // A copy of other bodies is refused; of the same ones, taken.
        let mut other = BodyFractions {
            bodies: vec![BodyFraction::named("x")],
        };
        assert!(!other.copy_from(&all));
        let mut same = BodyFractions {
            bodies: vec![BodyFraction::named("a"), BodyFraction::named("b")],
        };
        assert!(same.copy_from(&all));
        assert_eq!(same.bodies[1].at([4, 2, 0]), 0.6);
    }
}
