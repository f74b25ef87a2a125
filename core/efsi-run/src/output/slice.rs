//! Plane slices of a three-dimensional field: the cell values of a box interpolated to a
//! plane normal to one axis — what a run's `output.slices` write and what `efsi plot --slice`
//! draws.
//!
//! # The rule
//!
//! A plane `x_a = s` normal to axis `a` cuts the box's cells into the plane's cells: the
//! in-plane cells of the grid, in VTK's order (the lower remaining axis fastest). A cell-centred
//! value `q` is interpolated linearly along `a` between the two cell layers whose centres
//! bracket the plane,
//!
//! ```text
//! q(s) = (1 − f) q_l + f q_{l+1},   f = (s − c_l) / (c_{l+1} − c_l),   c_l ≤ s < c_{l+1},
//! ```
//!
//! so a field linear along `a` is reproduced to round-off, and a plane through a layer of
//! centres takes that layer's values exactly. Within half a cell of a wall (before the first
//! centre or past the last) the plane takes the values of the layer next to it: a bounded
//! field (a volume fraction) stays within its bounds. Every component of an array is
//! interpolated alike: the velocity keeps its three components.

/// The two layers of cells along an axis whose centres bracket the plane at `at`, and the
/// weight `f` of the second: the plane's values are `(1 − f) q_l + f q_{l+1}` (see the module
/// docs). `nodes` are the axis' node coordinates, ascending (at least two).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layers {
    /// The layer at or below the plane.
    pub lower: usize,
    /// The layer above it (`lower` itself within half a cell of a wall).
    pub upper: usize,
    /// The weight of `upper`, in [0, 1).
    pub weight: f64,
}

impl Layers {
    /// The layers around the plane at `at` of an axis with node coordinates `nodes`.
    pub fn around(nodes: &[f64], at: f64) -> Layers {
        let centre = |l: usize| 0.5 * (nodes[l] + nodes[l + 1]);
        let n = nodes.len().saturating_sub(1).max(1);
        let last = n - 1;
        let clamp = |l: usize| Layers {
            lower: l,
            upper: l,
            weight: 0.0,
        };
        if nodes.len() < 2 || at <= centre(0) {
            return clamp(0);
        }
        if at >= centre(last) {
            return clamp(last);
        }
        // The last layer whose centre is at or below the plane: 0 ≤ lower < last.
        let lower = (0..last).rev().find(|&l| centre(l) <= at).unwrap_or(0);
        let (lo, hi) = (centre(lower), centre(lower + 1));
        Layers {
            lower,
            upper: lower + 1,
            weight: (at - lo) / (hi - lo),
        }
    }

    /// `(1 − f) a + f b`, or `a` itself when the plane is on a layer of centres (`f` = 0).
    fn mix(&self, a: f64, b: f64) -> f64 {
        if self.weight == 0.0 {
            a
        } else {
            (1.0 - self.weight) * a + self.weight * b
        }
    }
}

/// The plane normal to `axis` (0, 1, 2 for X, Y, Z) through `layers` of the cell values
/// `values` of a box of `cells` cells (X fastest, `components` per cell): the plane's cells in
/// VTK's order, each interpolated between the two layers (see the module docs).
pub fn plane_values(
    values: &[f64],
    components: usize,
    cells: [usize; 3],
    axis: usize,
    layers: Layers,
) -> Vec<f64> {
    let [n0, n1, _] = cells;
    // The in-plane axes, the lower one fastest.
    let (a1, a2) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let mut out = Vec::with_capacity(cells[a1] * cells[a2] * components);
    for q2 in 0..cells[a2] {
        for q1 in 0..cells[a1] {
            let at = |layer: usize| {
                let mut c = [0; 3];
                (c[a1], c[a2], c[axis]) = (q1, q2, layer);
                ((c[2] * n1 + c[1]) * n0 + c[0]) * components
            };
            let (lo, hi) = (at(layers.lower), at(layers.upper));
            for k in 0..components {
                out.push(layers.mix(values[lo + k], values[hi + k]));
            }
        }
    }
    out
}

/// The node coordinates of the plane at `at` normal to `axis` through the box with node
/// coordinates `nodes`: the box's along the other axes, `[at]` along the normal (a flat axis of
/// one cell layer, as VTK draws a plane in space).
pub fn plane_nodes(nodes: &[Vec<f64>; 3], axis: usize, at: f64) -> [Vec<f64>; 3] {
    let mut out = nodes.clone();
    out[axis] = vec![at];
    out
}

/// The letter of axis `a` (0, 1, 2): `x`, `y`, `z`.
pub fn axis_name(a: usize) -> &'static str {
    ["x", "y", "z"][a.min(2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field linear in x, y and z is reproduced on planes normal to each axis, between
    /// layers to round-off, on a layer of centres exactly; near a wall the next layer's values.
    #[test]
    fn a_linear_field_is_reproduced_on_the_plane() {
        let nodes = [
            (0..=4).map(|i| i as f64 * 0.25).collect::<Vec<_>>(),
            (0..=3).map(|j| -1.0 + j as f64 * 0.5).collect(),
            (0..=5).map(|k| 2.0 + k as f64 * 0.2).collect(),
        ];
        let cells = [4, 3, 5];
        let centre = |a: usize, i: usize| 0.5 * (nodes[a][i] + nodes[a][i + 1]);
        let q = |x: f64, y: f64, z: f64| 3.0 * x - 2.0 * y + 7.0 * z + 1.0;
        let mut values = Vec::new();
        for k in 0..5 {
            for j in 0..3 {
                for i in 0..4 {
                    let c = [centre(0, i), centre(1, j), centre(2, k)];
                    // Two components: q and −q.
                    values.extend([q(c[0], c[1], c[2]), -q(c[0], c[1], c[2])]);
                }
            }
        }
        for (axis, at) in [(0, 0.4), (1, -0.1), (2, 2.53), (2, 2.5)] {
            let layers = Layers::around(&nodes[axis], at);
            assert!(layers.upper == layers.lower + 1, "{axis} {at}");
            let plane = plane_values(&values, 2, cells, axis, layers);
            let (a1, a2) = [(1, 2), (0, 2), (0, 1)][axis];
            assert_eq!(plane.len(), 2 * cells[a1] * cells[a2]);
            for q2 in 0..cells[a2] {
                for q1 in 0..cells[a1] {
                    let mut p = [0.0; 3];
                    (p[a1], p[a2], p[axis]) = (centre(a1, q1), centre(a2, q2), at);
                    let got = plane[2 * (q2 * cells[a1] + q1)];
                    let want = q(p[0], p[1], p[2]);
                    assert!(
                        (got - want).abs() < 1e-13 * want.abs().max(1.0),
                        "{got} {want}"
                    );
                    assert_eq!(plane[2 * (q2 * cells[a1] + q1) + 1], -got);
                }
            }
        }
        // On a layer of centres: that layer's values, bit for bit.
        let on = Layers::around(&nodes[2], centre(2, 3));
        assert_eq!((on.lower, on.upper, on.weight), (3, 4, 0.0));
        let plane = plane_values(&values, 2, cells, 2, on);
        assert_eq!(plane, values[2 * 3 * 12..2 * 4 * 12].to_vec());
        // Within half a cell of a wall: the layer next to it.
        let wall = Layers::around(&nodes[0], 0.05);
        assert_eq!((wall.lower, wall.upper, wall.weight), (0, 0, 0.0));
        let top = Layers::around(&nodes[0], 1.0);
        assert_eq!((top.lower, top.upper), (3, 3));
        let plane = plane_values(&values, 2, cells, 0, top);
        assert_eq!(plane[0], values[2 * 3]);
    }
}
