//! What a drape hands back: the node grid, yarn directions and shear angles.

use nalgebra::Vector3;

use super::{DrapeReport, FailReason, NodeFailure};

/// Shear of one cell of the draped net.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellShear {
    /// Warp index of the cell's first corner: the cell has corners (i, j), (i+1, j),
    /// (i+1, j+1), (i, j+1).
    pub i: i64,
    /// Weft index of the cell's first corner.
    pub j: i64,
    /// Shear angle (degrees): 90° minus the angle between the warp (increasing i) and weft
    /// (increasing j) edges, averaged over the four corners. Positive when the yarns close.
    pub shear_deg: f64,
    /// Mean of the four corners (mm), to locate the cell on the tool.
    pub centre: [f64; 3],
}

/// The draped net. Nodes are indexed (i, j) with i along the warp and j along the weft,
/// both in −n..=n with n = `max_cells`; (0, 0) is the start point.
#[derive(Debug, Clone)]
pub struct DrapeResult {
    cell: f64,
    n: usize,
    nodes: Vec<Option<Vector3<f64>>>,
    report: DrapeReport,
}

impl DrapeResult {
    /// Assembles the result from the node grid (row-major in i, then j, each over −n..=n).
    pub(crate) fn new(
        cell: f64,
        n: usize,
        nodes: Vec<Option<Vector3<f64>>>,
        failures: Vec<NodeFailure>,
    ) -> Self {
        let placed = nodes.iter().filter(|p| p.is_some()).count();
        let unreached = nodes.len() - placed - failures.len();
        Self {
            cell,
            n,
            nodes,
            report: DrapeReport {
                placed,
                failures,
                unreached,
            },
        }
    }

    /// Cell side in the undeformed fabric (mm).
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// n: indices run over −n..=n in both directions.
    pub fn max_cells(&self) -> usize {
        self.n
    }

    /// How many nodes were placed, which failed and why, how many were never reached.
    pub fn report(&self) -> &DrapeReport {
        &self.report
    }

    /// Position (mm) of node (i, j), `None` if it is out of range or was not placed.
    pub fn node(&self, i: i64, j: i64) -> Option<[f64; 3]> {
        self.point(i, j).map(to_array)
    }

    /// Unit warp direction at node (i, j): central difference of its warp neighbours
    /// (one-sided at the net's edge), `None` if the node or both neighbours are missing.
    pub fn warp_direction(&self, i: i64, j: i64) -> Option<[f64; 3]> {
        self.direction(i, j, (1, 0)).map(to_array)
    }

    /// Unit weft direction at node (i, j), as [`DrapeResult::warp_direction`].
    pub fn weft_direction(&self, i: i64, j: i64) -> Option<[f64; 3]> {
        self.direction(i, j, (0, 1)).map(to_array)
    }

    /// Shear angle at a node (degrees): 90° minus the angle between its warp and weft
    /// directions. Central differences make it exactly 0 on a symmetry line of the tool, which
    /// the cell value (an average over a cell beside the line) is not.
    pub fn node_shear_deg(&self, i: i64, j: i64) -> Option<f64> {
        let warp = self.direction(i, j, (1, 0))?;
        let weft = self.direction(i, j, (0, 1))?;
        Some(shear_deg(&warp, &weft))
    }

    /// Shear angle of the cell with first corner (i, j) (see [`CellShear::shear_deg`]), `None`
    /// unless all four corners were placed.
    pub fn cell_shear_deg(&self, i: i64, j: i64) -> Option<f64> {
        self.cell_shear(i, j).map(|c| c.shear_deg)
    }

    /// Every complete cell with its shear.
    pub fn cells(&self) -> Vec<CellShear> {
        let n = self.n as i64;
        (-n..n)
            .flat_map(|i| (-n..n).map(move |j| (i, j)))
            .filter_map(|(i, j)| self.cell_shear(i, j))
            .collect()
    }

    /// The cell with the largest |shear|, `None` if no cell is complete.
    pub fn max_shear(&self) -> Option<CellShear> {
        self.cells()
            .into_iter()
            .max_by(|a, b| a.shear_deg.abs().total_cmp(&b.shear_deg.abs()))
    }

    /// The cells whose |shear| exceeds the locking angle (degrees), where a real fabric would
    /// wrinkle instead of shearing further. Errors if the angle is not a finite number ≥ 0.
    pub fn cells_exceeding(&self, locking_deg: f64) -> Result<Vec<CellShear>, String> {
        if !(locking_deg.is_finite() && locking_deg >= 0.0) {
            return Err(format!(
                "locking_deg must be a finite angle >= 0 degrees, got {locking_deg}"
            ));
        }
        Ok(self
            .cells()
            .into_iter()
            .filter(|c| c.shear_deg.abs() > locking_deg)
            .collect())
    }

    fn index(&self, i: i64, j: i64) -> Option<usize> {
        let n = self.n as i64;
        if i.abs() > n || j.abs() > n {
            return None;
        }
        let side = 2 * n + 1;
        Some(((i + n) * side + (j + n)) as usize)
    }

    fn point(&self, i: i64, j: i64) -> Option<Vector3<f64>> {
        self.index(i, j).and_then(|k| self.nodes[k])
    }

    /// Unit tangent along index offset `step` at (i, j).
    fn direction(&self, i: i64, j: i64, step: (i64, i64)) -> Option<Vector3<f64>> {
        let here = self.point(i, j)?;
        let ahead = self.point(i + step.0, j + step.1);
        let behind = self.point(i - step.0, j - step.1);
        let chord = match (ahead, behind) {
            (Some(a), Some(b)) => a - b,
            (Some(a), None) => a - here,
            (None, Some(b)) => here - b,
            (None, None) => return None,
        };
        chord.try_normalize(0.0)
    }

    fn cell_shear(&self, i: i64, j: i64) -> Option<CellShear> {
        let c00 = self.point(i, j)?;
        let c10 = self.point(i + 1, j)?;
        let c11 = self.point(i + 1, j + 1)?;
        let c01 = self.point(i, j + 1)?;
        let (bottom, top) = (c10 - c00, c11 - c01);
        let (left, right) = (c01 - c00, c11 - c10);
        let corners = [(bottom, left), (bottom, right), (top, right), (top, left)];
        let mean = corners.iter().map(|(u, v)| shear_deg(u, v)).sum::<f64>() / 4.0;
        Some(CellShear {
            i,
            j,
            shear_deg: mean,
            centre: to_array(0.25 * (c00 + c10 + c11 + c01)),
        })
    }
}

/// 90° minus the angle between two yarn directions, with atan2 for accuracy near 0 shear.
fn shear_deg(warp: &Vector3<f64>, weft: &Vector3<f64>) -> f64 {
    let angle = warp.cross(weft).norm().atan2(warp.dot(weft));
    90.0 - angle.to_degrees()
}

fn to_array(v: Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

impl DrapeReport {
    /// Nodes that were attempted and could not be placed.
    pub fn failed(&self) -> usize {
        self.failures.len()
    }

    /// Failed nodes for one reason.
    pub fn failed_for(&self, reason: FailReason) -> usize {
        self.failures.iter().filter(|f| f.reason == reason).count()
    }
}
