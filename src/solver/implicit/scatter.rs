//! Where the entries of a group of nodes' 3x3 blocks are stored in the tangent's pattern
//! (docs/solver.md, "Implicit"): found once per group, so that adding an element's, a
//! patch's or a contact pair's stiffness is a walk over stored places.

use super::linear::Pattern;
use nalgebra::Matrix3;

/// Where the lower-triangle entries of the 3x3 blocks of a group of nodes (an element, a
/// patch, one node) are stored, found once: for every pair `(a, b)` of its nodes with `a`
/// stored after `b` (or `a = b`), in that order, and every column `e` of the block, the place of its
/// first stored row ([`Scatter::SKIP`] where the column is held). A binary search per column
/// and block was the largest single cost of the assembly.
pub struct Scatter {
    pub nodes: Vec<usize>,
    /// Where each node's unknowns are stored: a block `(a, b)` is stored where `a` comes after
    /// `b` (the lower triangle).
    rank: Vec<usize>,
    places: Vec<u32>,
}

impl Scatter {
    const SKIP: u32 = u32::MAX;

    pub fn new(pattern: &Pattern, held: &[bool], nodes: &[usize]) -> Self {
        let mut places = Vec::new();
        let rank: Vec<usize> = nodes.iter().map(|&n| pattern.position(3 * n)).collect();
        for (&na, &ra) in nodes.iter().zip(&rank) {
            for (&nb, &rb) in nodes.iter().zip(&rank) {
                if ra < rb {
                    continue;
                }
                for e in 0..3 {
                    let j = 3 * nb + e;
                    let first = if na == nb { e } else { 0 };
                    let place = pattern
                        .place(3 * na + first, j)
                        .filter(|_| !held[j])
                        .map_or(Self::SKIP, |p| {
                            u32::try_from(p).expect("fewer than 4e9 tangent entries")
                        });
                    places.push(place);
                }
            }
        }
        Self {
            nodes: nodes.to_vec(),
            rank,
            places,
        }
    }

    /// Adds `block(a, b)`, the 3x3 block of local nodes `(a, b)`, for every pair of the
    /// group, skipping held rows and columns.
    pub fn add(
        &self,
        held: &[bool],
        values: &mut [f64],
        block: impl Fn(usize, usize) -> Matrix3<f64>,
    ) {
        self.add_within(held, values, 0, block);
    }

    /// [`Self::add`] to the places `offset..offset + part.len()` only, `part` holding them
    /// (a column's run of places lies within one such range where it starts a column).
    pub fn add_within(
        &self,
        held: &[bool],
        part: &mut [f64],
        offset: usize,
        block: impl Fn(usize, usize) -> Matrix3<f64>,
    ) {
        let within = offset..offset + part.len();
        let mut places = self.places.iter();
        for (a, (&na, &ra)) in self.nodes.iter().zip(&self.rank).enumerate() {
            for (b, (&nb, &rb)) in self.nodes.iter().zip(&self.rank).enumerate() {
                if ra < rb {
                    continue;
                }
                // a held column's SKIP lies beyond every stored place, so within no part
                let columns = [(); 3].map(|_| *places.next().expect("a place per column"));
                if !columns.iter().any(|&p| within.contains(&(p as usize))) {
                    continue;
                }
                let k = block(a, b);
                for (e, &start) in columns.iter().enumerate() {
                    if !within.contains(&(start as usize)) {
                        continue;
                    }
                    let start = start as usize - offset;
                    let first = if na == nb { e } else { 0 };
                    for d in first..3 {
                        // a node's three unknowns are stored one after the other
                        if !held[3 * na + d] {
                            part[start + (d - first)] += k[(d, e)];
                        }
                    }
                }
            }
        }
    }
}
