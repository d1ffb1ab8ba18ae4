//! Whether a blank's mesh is one sheet, checked on every blank read from a file before anything
//! is built on it (docs/meshes.md, "Checked at load").
//!
//! The cells of a sheet meet edge to edge: every edge belongs to one cell (the border, a hole's
//! included) or to two; no node lies on a cell without being one of its corners; the cells
//! around a node are joined along edges; neighbours can be numbered to run their shared edge in
//! opposite directions, and then do not fold back over each other; no cell is a sliver or a
//! speck. A mesh that breaks one of these still runs, but not as the sheet that was drawn: a
//! hanging node or an unmerged seam is a slit that opens under load, a duplicate or folded cell
//! doubles the sheet's stiffness and mass, a sliver collapses the explicit time step.
//!
//! The checks run in this order — single nodes and cells (coordinates, distinct corners,
//! slivers, specks), duplicates, edges, orientation, folds, nodes on cells, the cells around
//! each node — and stop at the first defect (in the order of the cells, or of the nodes), so
//! that the message names its root cause: a hanging node, say, also leaves the cells at the
//! ends of its edge touching at a point only, which is reported only when nothing else is
//! wrong. Cost: O(n log n) in the number of cells — one sort of the edges, a breadth-first pass
//! for the orientation, a uniform grid over the cells walked once with the nodes, and a
//! union-find over the corners.

use super::{six_digits, Cell, Mesh};
use nalgebra::Vector3;
use std::fmt;

/// Largest coordinate (mm) taken as a place on a blank or a tool **(choice)**: a kilometre. A
/// node beyond is a coordinate written wrong or a file in another unit, and its cells' areas and
/// sizes lose all meaning long before they overflow.
pub const COORDINATE_LIMIT: f64 = 1e6;

/// A cell is a sliver when its smallest height is under this fraction of its longest edge
/// **(choice)**: its corners lie on one line, or two at one point, to 0.1 % of its size, and its
/// stable time step is a thousandth of a sound cell's.
pub const SLIVER: f64 = 1e-3;

/// A cell is a speck when its longest edge is under this fraction of the median cell's
/// **(choice)**: a fragment left by the mesher, which would set the time step of the whole run.
pub const SPECK: f64 = 1e-3;

/// A node lies on a cell when it is within this fraction of the local size — the cell's longest
/// edge, or the node's own smallest cell's where that is shorter **(choice)**. Ten times finer
/// than [`SLIVER`]: in a mesh without slivers no node comes that close to a cell of which it is
/// not a corner, and the files of meshers (eight or more significant digits) put a hanging node
/// on its edge far closer than that.
pub const ON_CELL: f64 = 1e-4;

/// Neighbours whose normals (the mesh's orientation made consistent) turn by more than this
/// across their shared edge fold back over each other **(choice, degrees)**: a sharp crease of
/// a pre-shaped blank turns by 90°, an element inverted onto its neighbour by 180°.
pub const FOLD_DEG: f64 = 150.0;

/// A node or a cell of the mesh, for naming it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    Node(usize),
    Cell(usize),
}

/// How a defect's message names the nodes and cells it is about.
pub trait Naming {
    /// `node 12`, `element 7`: the item alone.
    fn name(&self, item: Item) -> String;
    /// The item and where it is written (`element 7 (line 40)`), for the items other than the
    /// one the message is placed at.
    fn name_at(&self, item: Item) -> String {
        self.name(item)
    }
}

/// Names by index in the mesh: for meshes made in memory.
pub struct ByIndex;

impl Naming for ByIndex {
    fn name(&self, item: Item) -> String {
        match item {
            Item::Node(n) => format!("node {n}"),
            Item::Cell(t) => format!("element {t}"),
        }
    }
}

/// What makes a mesh something other than one sheet: the first defect found.
#[derive(Clone, Debug, PartialEq)]
pub enum Defect {
    /// A coordinate beyond [`COORDINATE_LIMIT`].
    FarNode { node: usize, position: Vector3<f64> },
    /// A cell naming one node at two corners.
    RepeatedNode { cell: usize, node: usize },
    /// A cell whose smallest height is under [`SLIVER`] of its longest edge.
    Sliver {
        cell: usize,
        height: f64,
        longest: f64,
    },
    /// A cell whose longest edge is under [`SPECK`] of the median cell's.
    Speck {
        cell: usize,
        longest: f64,
        median: f64,
    },
    /// A cell on the same nodes as an earlier one.
    Duplicate { cell: usize, first: usize },
    /// A third cell on one edge.
    NonManifold {
        cell: usize,
        edge: (usize, usize),
        others: [usize; 2],
    },
    /// No numbering runs every shared edge once each way.
    NonOrientable {
        cell: usize,
        neighbour: usize,
        edge: (usize, usize),
    },
    /// Neighbours whose normals turn by more than [`FOLD_DEG`] across their shared edge.
    Fold {
        cell: usize,
        neighbour: usize,
        edge: (usize, usize),
        angle_deg: f64,
    },
    /// Two nodes at one point.
    Coincident {
        node: usize,
        other: usize,
        distance: f64,
    },
    /// A node on a border edge of a cell of which it is not a corner.
    Hanging {
        node: usize,
        cell: usize,
        edge: (usize, usize),
    },
    /// A node inside a cell, or on an edge that cell shares, without being one of its corners.
    Overlap { node: usize, cell: usize },
    /// Cells around a node that touch only at it.
    Pinched { node: usize, cells: [usize; 2] },
}

impl Defect {
    /// The node or cell the message is placed at.
    pub fn subject(&self) -> Item {
        match *self {
            Defect::FarNode { node, .. }
            | Defect::Coincident { node, .. }
            | Defect::Hanging { node, .. }
            | Defect::Overlap { node, .. }
            | Defect::Pinched { node, .. } => Item::Node(node),
            Defect::RepeatedNode { cell, .. }
            | Defect::Sliver { cell, .. }
            | Defect::Speck { cell, .. }
            | Defect::Duplicate { cell, .. }
            | Defect::NonManifold { cell, .. }
            | Defect::NonOrientable { cell, .. }
            | Defect::Fold { cell, .. } => Item::Cell(cell),
        }
    }

    /// What is wrong, to follow the subject's name (`element 7 is a sliver: ...`).
    pub fn predicate(&self, names: &dyn Naming) -> String {
        let node = |n: usize| names.name(Item::Node(n));
        let at = |item: Item| names.name_at(item);
        let edge = |(a, b): (usize, usize)| format!("from {} to {}", node(a), node(b));
        match *self {
            Defect::FarNode { node: _, position } => format!(
                "lies at ({}, {}, {}) mm, beyond {} mm of the origin: a coordinate written \
                 wrong, or a length unit other than mm",
                six_digits(position.x),
                six_digits(position.y),
                six_digits(position.z),
                six_digits(COORDINATE_LIMIT)
            ),
            Defect::RepeatedNode { node: n, .. } => format!(
                "names {} twice: a cell's corners are distinct nodes (write a triangle as a \
                 3-node element, not as a collapsed quadrilateral)",
                node(n)
            ),
            Defect::Sliver {
                height, longest, ..
            } => format!(
                "is a sliver: its smallest height, {} mm, is {} of its longest edge ({} mm), \
                 under {SLIVER} (corners nearly on one line, or two nearly at one point)",
                six_digits(height),
                six_digits(height / longest),
                six_digits(longest)
            ),
            Defect::Speck {
                longest, median, ..
            } => format!(
                "is a speck: its longest edge, {} mm, is under {SPECK} of the median element's \
                 ({} mm): a fragment left by the mesher, or a coordinate written wrong",
                six_digits(longest),
                six_digits(median)
            ),
            Defect::Duplicate { first, .. } => format!(
                "has the same nodes as {}: the sheet is doubled there (a duplicate element)",
                at(Item::Cell(first))
            ),
            Defect::NonManifold {
                edge: e,
                others: [a, b],
                ..
            } => format!(
                "shares its edge {} with two elements already, {} and {}: an edge of a sheet \
                 belongs to one element or two (a non-manifold edge)",
                edge(e),
                at(Item::Cell(a)),
                at(Item::Cell(b))
            ),
            Defect::NonOrientable {
                neighbour, edge: e, ..
            } => format!(
                "cannot be numbered to run its edge {} opposite to {} while every other shared \
                 edge runs once each way: the sheet has no consistent side (non-orientable, a \
                 Möbius band)",
                edge(e),
                at(Item::Cell(neighbour))
            ),
            Defect::Fold {
                neighbour,
                edge: e,
                angle_deg,
                ..
            } => format!(
                "folds back over {}: across their edge {} their normals turn by {}°, more than \
                 {FOLD_DEG}° (an inverted or overlapping element)",
                at(Item::Cell(neighbour)),
                edge(e),
                six_digits(angle_deg)
            ),
            Defect::Coincident {
                other, distance, ..
            } => format!(
                "coincides with {}, {} mm apart, but they are two nodes: the elements on \
                 either side are not joined there, a slit that opens under load (merge the \
                 duplicate nodes; a cut meant as one must open by a width)",
                at(Item::Node(other)),
                six_digits(distance)
            ),
            Defect::Hanging { cell, edge: e, .. } => format!(
                "lies on the edge {} of {} without being one of its nodes (a hanging node, a \
                 T-junction): the elements on either side are not joined along that edge, a \
                 slit that opens under load",
                edge(e),
                at(Item::Cell(cell))
            ),
            Defect::Overlap { cell, .. } => format!(
                "lies on {} without being one of its nodes: elements overlap there",
                at(Item::Cell(cell))
            ),
            Defect::Pinched { cells: [a, b], .. } => format!(
                "is the only point where {} and {} meet: the elements around a node of a sheet \
                 are joined along edges (two pieces touching at a corner)",
                at(Item::Cell(a)),
                at(Item::Cell(b))
            ),
        }
    }
}

impl fmt::Display for Defect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let subject = ByIndex.name(self.subject());
        write!(f, "{subject} {}", self.predicate(&ByIndex))
    }
}

/// Cells joined by shared edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Piece {
    /// Its first cell.
    pub first: usize,
    /// How many cells it has.
    pub cells: usize,
}

/// A mesh found to be one sheet, or several apart from each other.
#[derive(Clone, Debug, PartialEq)]
pub struct Sheet {
    /// The cells numbered against their neighbours, to be turned round ([`Cell::reversed`]) so
    /// that every shared edge runs once each way; of two ways to number a piece, the one that
    /// keeps most of its area as the file numbers it.
    pub turned: Vec<usize>,
    /// The pieces, in the order of their first cells: more than one where parts of the mesh
    /// share no edge.
    pub pieces: Vec<Piece>,
}

impl Sheet {
    /// Turns the cells of [`Sheet::turned`] round.
    pub fn orient(&self, mesh: &mut Mesh) {
        for &t in &self.turned {
            mesh.cells[t] = mesh.cells[t].reversed();
        }
    }
}

/// The checks of single nodes and cells that any mesh read from a file needs, tool or blank:
/// coordinates within [`COORDINATE_LIMIT`], no node twice in a cell. The readers run them
/// before [`Mesh::validate`], whose areas would otherwise report them as something else.
pub fn check_elements(mesh: &Mesh) -> Result<(), Defect> {
    if let Some(node) = mesh
        .nodes
        .iter()
        .position(|x| x.iter().any(|c| c.abs() > COORDINATE_LIMIT))
    {
        return Err(Defect::FarNode {
            node,
            position: mesh.nodes[node],
        });
    }
    for (cell, c) in mesh.cells.iter().enumerate() {
        let n = c.nodes();
        if let Some(k) = (1..n.len()).find(|&k| n[..k].contains(&n[k])) {
            return Err(Defect::RepeatedNode { cell, node: n[k] });
        }
    }
    Ok(())
}

/// Whether `mesh` (valid: [`Mesh::validate`]) is one sheet, or several apart; the first defect
/// otherwise. See the module's documentation.
pub fn check(mesh: &Mesh) -> Result<Sheet, Defect> {
    check_elements(mesh)?;
    let longest: Vec<f64> = mesh.cells.iter().map(|c| longest_edge(c, mesh)).collect();
    check_shapes(mesh, &longest)?;
    check_duplicates(mesh)?;
    let edges = Edges::new(mesh)?;
    let (turned, pieces) = orient(mesh, &edges)?;
    check_folds(mesh, &edges, &turned)?;
    check_nodes_on_cells(mesh, &edges, &longest)?;
    check_fans(mesh, &edges)?;
    Ok(Sheet {
        turned: (0..mesh.cells.len()).filter(|&t| turned[t]).collect(),
        pieces,
    })
}

fn longest_edge(cell: &Cell, mesh: &Mesh) -> f64 {
    cell.edges()
        .map(|(a, b)| (mesh.nodes[b] - mesh.nodes[a]).norm())
        .fold(0.0, f64::max)
}

/// The smallest height of a cell: twice the area of the triangle at each corner (the corner and
/// its two neighbours) over the longest edge, the smallest over the corners. For a triangle,
/// its height over its longest edge; it vanishes when corners come onto one line or one point.
fn smallest_height(cell: &Cell, mesh: &Mesh, longest: f64) -> f64 {
    let n = cell.nodes();
    let x = |k: usize| mesh.nodes[n[k % n.len()]];
    (0..n.len())
        .map(|k| {
            let (prev, at, next) = (x(k + n.len() - 1), x(k), x(k + 1));
            (prev - at).cross(&(next - at)).norm() / longest
        })
        .fold(f64::INFINITY, f64::min)
}

/// Slivers, then specks.
fn check_shapes(mesh: &Mesh, longest: &[f64]) -> Result<(), Defect> {
    for (cell, c) in mesh.cells.iter().enumerate() {
        let height = smallest_height(c, mesh, longest[cell]);
        // a cell of no size at all has no height (NaN)
        if height.is_nan() || height < SLIVER * longest[cell] {
            return Err(Defect::Sliver {
                cell,
                height,
                longest: longest[cell],
            });
        }
    }
    let median = median(longest);
    match longest.iter().position(|&l| l < SPECK * median) {
        Some(cell) => Err(Defect::Speck {
            cell,
            longest: longest[cell],
            median,
        }),
        None => Ok(()),
    }
}

fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    let middle = sorted.len() / 2;
    *sorted.select_nth_unstable_by(middle, f64::total_cmp).1
}

fn check_duplicates(mesh: &Mesh) -> Result<(), Defect> {
    // each cell's nodes sorted, packed in 32 bits each (a mesh has fewer than 2^32 nodes)
    let mut keys: Vec<(u128, usize)> = mesh
        .cells
        .iter()
        .enumerate()
        .map(|(t, c)| {
            let mut nodes = [u32::MAX; 4];
            for (k, &n) in c.nodes().iter().enumerate() {
                nodes[k] = n as u32;
            }
            nodes.sort_unstable();
            let key = nodes.iter().fold(0u128, |key, &n| key << 32 | n as u128);
            (key, t)
        })
        .collect();
    keys.sort_unstable();
    // the first repeat in the order of the cells, and the first cell it repeats
    match keys
        .chunk_by(|a, b| a.0 == b.0)
        .filter_map(|group| group.get(1).map(|repeat| (repeat.1, group[0].1)))
        .min()
    {
        Some((cell, first)) => Err(Defect::Duplicate { cell, first }),
        None => Ok(()),
    }
}

/// One edge: as its first cell runs it, and the cells on it.
struct Edge {
    from: usize,
    to: usize,
    /// The first cell, and the second where there is one.
    cells: [usize; 2],
    shared: bool,
    /// Whether the second cell runs it the same way as the first.
    same_way: bool,
}

/// An edge's key: its nodes in increasing order, 32 bits each.
fn edge_key(a: usize, b: usize) -> u64 {
    (a.min(b) as u64) << 32 | a.max(b) as u64
}

/// The edges of the mesh, sorted by their keys.
struct Edges {
    keys: Vec<u64>,
    list: Vec<Edge>,
}

impl Edges {
    /// The edges; a third cell on an edge is a defect (the first such cell in order).
    fn new(mesh: &Mesh) -> Result<Self, Defect> {
        // (key, cell and whether it runs the edge from the lower node): 16 bytes to sort
        let mut uses: Vec<(u64, u64)> = mesh
            .cells
            .iter()
            .enumerate()
            .flat_map(|(t, c)| {
                c.edges()
                    .map(move |(a, b)| (edge_key(a, b), (t as u64) << 1 | (a < b) as u64))
            })
            .collect();
        uses.sort_unstable();
        let cell = |u: &(u64, u64)| (u.1 >> 1) as usize;
        let run = |u: &(u64, u64)| {
            let (low, high) = ((u.0 >> 32) as usize, (u.0 & 0xFFFF_FFFF) as usize);
            if u.1 & 1 == 1 {
                (low, high)
            } else {
                (high, low)
            }
        };
        let mut keys = Vec::with_capacity(uses.len() / 2 + 4);
        let mut list = Vec::with_capacity(uses.len() / 2 + 4);
        // the first third cell on an edge, in the order of the cells
        let mut third: Option<Defect> = None;
        for group in uses.chunk_by(|u, v| u.0 == v.0) {
            let (first, (from, to)) = (cell(&group[0]), run(&group[0]));
            if let [_, second, extra, ..] = group {
                let t = cell(extra);
                if !matches!(third, Some(Defect::NonManifold { cell: c, .. }) if c < t) {
                    third = Some(Defect::NonManifold {
                        cell: t,
                        edge: run(extra),
                        others: [first, cell(second)],
                    });
                }
            }
            keys.push(group[0].0);
            list.push(Edge {
                from,
                to,
                cells: [first, group.get(1).map_or(first, cell)],
                shared: group.len() > 1,
                same_way: group.get(1).is_some_and(|u| run(u).0 == from),
            });
        }
        match third {
            Some(defect) => Err(defect),
            None => Ok(Self { keys, list }),
        }
    }

    /// Whether the edge between `a` and `b` belongs to one cell only.
    fn is_border(&self, a: usize, b: usize) -> bool {
        self.keys
            .binary_search(&edge_key(a, b))
            .is_ok_and(|e| !self.list[e].shared)
    }

    fn shared(&self) -> impl Iterator<Item = (usize, &Edge)> {
        self.list.iter().enumerate().filter(|(_, e)| e.shared)
    }
}

/// Per cell whether it is to be turned round for every shared edge to run once each way, and
/// the pieces; a defect where no numbering does that.
fn orient(mesh: &Mesh, edges: &Edges) -> Result<(Vec<bool>, Vec<Piece>), Defect> {
    let n = mesh.cells.len();
    let around = Neighbours::new(n, edges);
    let mut turned = vec![false; n];
    let mut seen = vec![false; n];
    let mut pieces = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    let mut members = Vec::new();
    for first in 0..n {
        if seen[first] {
            continue;
        }
        seen[first] = true;
        queue.push_back(first);
        members.clear();
        while let Some(t) = queue.pop_front() {
            members.push(t);
            for &(u, e) in around.of(t) {
                // running the edge the same way, one of the two is to be turned
                let want = turned[t] ^ edges.list[e].same_way;
                if !seen[u] {
                    seen[u] = true;
                    turned[u] = want;
                    queue.push_back(u);
                } else if turned[u] != want {
                    let edge = &edges.list[e];
                    return Err(Defect::NonOrientable {
                        cell: u.max(t),
                        neighbour: u.min(t),
                        edge: (edge.from, edge.to),
                    });
                }
            }
        }
        let area = |flag: bool| -> f64 {
            members
                .iter()
                .filter(|&&t| turned[t] == flag)
                .map(|&t| mesh.area(t))
                .sum()
        };
        if area(true) > area(false) {
            for &t in &members {
                turned[t] = !turned[t];
            }
        }
        pieces.push(Piece {
            first,
            cells: members.len(),
        });
    }
    Ok((turned, pieces))
}

/// Each cell's neighbours across shared edges, with the edge: `(neighbour, edge)`.
struct Neighbours {
    start: Vec<usize>,
    list: Vec<(usize, usize)>,
}

impl Neighbours {
    fn new(cells: usize, edges: &Edges) -> Self {
        let mut start = vec![0; cells + 1];
        for (_, edge) in edges.shared() {
            start[edge.cells[0] + 1] += 1;
            start[edge.cells[1] + 1] += 1;
        }
        for t in 0..cells {
            start[t + 1] += start[t];
        }
        let mut next = start.clone();
        let mut list = vec![(0, 0); start[cells]];
        for (e, edge) in edges.shared() {
            let [a, b] = edge.cells;
            list[next[a]] = (b, e);
            next[a] += 1;
            list[next[b]] = (a, e);
            next[b] += 1;
        }
        Self { start, list }
    }

    fn of(&self, t: usize) -> &[(usize, usize)] {
        &self.list[self.start[t]..self.start[t + 1]]
    }
}

/// Neighbours folding back over each other, the orientation made consistent: the first in the
/// order of the later cell of the two.
fn check_folds(mesh: &Mesh, edges: &Edges, turned: &[bool]) -> Result<(), Defect> {
    let normal = |t: usize| {
        let n = mesh.cells[t].area_vector(&mesh.nodes);
        if turned[t] {
            -n
        } else {
            n
        }
    };
    let fold = edges
        .shared()
        .map(|(_, edge)| (edge, normal(edge.cells[0]).angle(&normal(edge.cells[1]))))
        .filter(|(_, angle)| angle.to_degrees() > FOLD_DEG)
        .min_by_key(|(edge, _)| (edge.cells[1], edge.cells[0]));
    match fold {
        Some((edge, angle)) => Err(Defect::Fold {
            cell: edge.cells[1],
            neighbour: edge.cells[0],
            edge: (edge.from, edge.to),
            angle_deg: angle.to_degrees(),
        }),
        None => Ok(()),
    }
}

/// Where a node lies on a cell of which it is not a corner.
enum Contact {
    Corner(usize),
    Edge(usize, usize),
    Inside,
}

/// Nodes on cells of which they are not corners: coincident nodes, hanging nodes, overlaps;
/// the first in the order of the nodes.
fn check_nodes_on_cells(mesh: &Mesh, edges: &Edges, longest: &[f64]) -> Result<(), Defect> {
    // each node's local size: its smallest cell's longest edge (infinite: a node of no cell)
    let mut node_size = vec![f64::INFINITY; mesh.nodes.len()];
    for (t, c) in mesh.cells.iter().enumerate() {
        for &n in c.nodes() {
            node_size[n] = node_size[n].min(longest[t]);
        }
    }
    let boxes: Vec<(Vector3<f64>, Vector3<f64>)> = mesh
        .cells
        .iter()
        .enumerate()
        .map(|(t, c)| {
            let grow = Vector3::repeat(ON_CELL * longest[t]);
            let x = c.positions(&mesh.nodes);
            let lo = x.iter().fold(x[0], |lo, p| lo.inf(p));
            let hi = x.iter().fold(x[0], |hi, p| hi.sup(p));
            (lo - grow, hi + grow)
        })
        .collect();
    let grid = Grid::new(&boxes, median(longest));
    let mut first: Option<Defect> = None;
    let nodes = (0..mesh.nodes.len()).filter(|&n| node_size[n].is_finite());
    grid.for_each_pair(nodes.map(|n| (n, mesh.nodes[n])), |node, t| {
        let p = &mesh.nodes[node];
        let (lo, hi) = &boxes[t];
        let cell = &mesh.cells[t];
        if cell.nodes().contains(&node)
            || (0..3).any(|d| p[d] < lo[d] || p[d] > hi[d])
            || matches!(first.as_ref().map(Defect::subject), Some(Item::Node(n)) if n <= node)
        {
            return;
        }
        let tolerance = ON_CELL * longest[t].min(node_size[node]);
        first = match contact(mesh, cell, p, tolerance) {
            None => return,
            Some(Contact::Corner(other)) => Some(Defect::Coincident {
                node,
                other,
                distance: (mesh.nodes[other] - p).norm(),
            }),
            Some(Contact::Edge(a, b)) if edges.is_border(a, b) => Some(Defect::Hanging {
                node,
                cell: t,
                edge: (a, b),
            }),
            Some(Contact::Edge(..) | Contact::Inside) => Some(Defect::Overlap { node, cell: t }),
        };
    });
    match first {
        Some(defect) => Err(defect),
        None => Ok(()),
    }
}

/// Whether `p` lies within `tolerance` of `cell`: at a corner, on an edge, or inside.
fn contact(mesh: &Mesh, cell: &Cell, p: &Vector3<f64>, tolerance: f64) -> Option<Contact> {
    let x = |n: usize| mesh.nodes[n];
    if let Some(&corner) = cell
        .nodes()
        .iter()
        .find(|&&n| (x(n) - p).norm() <= tolerance)
    {
        return Some(Contact::Corner(corner));
    }
    if let Some((a, b)) = cell
        .edges()
        .find(|&(a, b)| distance_to_segment(p, &x(a), &x(b)) <= tolerance)
    {
        return Some(Contact::Edge(a, b));
    }
    cell.triangles()
        .iter()
        .any(|&[a, b, c]| (closest_on_triangle(p, &x(a), &x(b), &x(c)) - p).norm() <= tolerance)
        .then_some(Contact::Inside)
}

fn distance_to_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (a + ab * t - p).norm()
}

/// The point of the triangle `a b c` nearest `p` (Ericson, *Real-Time Collision Detection*,
/// 5.1.5: by the Voronoi region of `p`).
fn closest_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> Vector3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let scale = 1.0 / (va + vb + vc);
    a + ab * (vb * scale) + ac * (vc * scale)
}

/// A uniform grid of cubes over the cells' boxes: each cell listed in every cube its box meets,
/// so that the cells whose boxes may hold a point are those listed in its cube. Cubes are
/// keyed by a hash of their indices; two cubes of one hash only add candidates, which the
/// caller measures anyway.
struct Grid {
    side: f64,
    /// Added to every coordinate, so that the cubes' faces do not fall on the lines of a
    /// structured mesh (a box on a face is listed in the cubes on both sides).
    shift: f64,
    /// (cube's hash, cell), sorted.
    entries: Vec<(u64, usize)>,
}

impl Grid {
    /// Cubes of the median cell's size, doubled until the boxes fill at most 16 cubes each on
    /// the mean (a few cells much larger than the rest would fill a great many).
    fn new(boxes: &[(Vector3<f64>, Vector3<f64>)], median: f64) -> Self {
        let mut grid = Self {
            side: median,
            shift: 0.381_966 * median,
            entries: Vec::new(),
        };
        // counted in floating point: a far corner in cubes of a speck's size overflows integers
        let cubes = |grid: &Grid, (lo, hi): &(Vector3<f64>, Vector3<f64>)| -> f64 {
            let (a, b) = (grid.cube(lo), grid.cube(hi));
            (0..3).map(|d| (b[d] - a[d]) as f64 + 1.0).product()
        };
        let budget = (16 * boxes.len() + 64) as f64;
        while boxes.iter().map(|b| cubes(&grid, b)).sum::<f64>() > budget {
            grid.side *= 2.0;
        }
        for (t, (lo, hi)) in boxes.iter().enumerate() {
            let (a, b) = (grid.cube(lo), grid.cube(hi));
            for i in a[0]..=b[0] {
                for j in a[1]..=b[1] {
                    for k in a[2]..=b[2] {
                        grid.entries.push((hash([i, j, k]), t));
                    }
                }
            }
        }
        grid.entries.sort_unstable();
        grid
    }

    fn cube(&self, p: &Vector3<f64>) -> [i64; 3] {
        std::array::from_fn(|d| ((p[d] + self.shift) / self.side).floor() as i64)
    }

    /// Calls `visit(point, cell)` for each point of `points` and each cell listed in its cube:
    /// the points sorted by their cubes' hashes and walked along the sorted entries, rather
    /// than looked up one by one.
    fn for_each_pair(
        &self,
        points: impl Iterator<Item = (usize, Vector3<f64>)>,
        mut visit: impl FnMut(usize, usize),
    ) {
        let mut keyed: Vec<(u64, usize)> = points.map(|(n, p)| (hash(self.cube(&p)), n)).collect();
        keyed.sort_unstable();
        let mut start = 0;
        for group in keyed.chunk_by(|a, b| a.0 == b.0) {
            let key = group[0].0;
            start += self.entries[start..].partition_point(|e| e.0 < key);
            let cells = &self.entries[start..];
            let cells = &cells[..cells.partition_point(|e| e.0 == key)];
            for &(_, n) in group {
                for &(_, t) in cells {
                    visit(n, t);
                }
            }
        }
    }
}

fn hash([i, j, k]: [i64; 3]) -> u64 {
    (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (k as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
}

/// Nodes where cells touch without a shared edge: the cells at a node, joined through the
/// shared edges at it, must make one group (a fan; a half-fan on the border).
fn check_fans(mesh: &Mesh, edges: &Edges) -> Result<(), Defect> {
    // corner `offset[t] + k`: corner k of cell t
    let mut offset = Vec::with_capacity(mesh.cells.len() + 1);
    let mut total = 0;
    for c in &mesh.cells {
        offset.push(total);
        total += c.nodes().len();
    }
    let corner = |t: usize, node: usize| {
        offset[t]
            + mesh.cells[t]
                .nodes()
                .iter()
                .position(|&n| n == node)
                .unwrap_or(0)
    };
    let mut joined = UnionFind::new(total);
    for (_, edge) in edges.shared() {
        let [a, b] = edge.cells;
        for node in [edge.from, edge.to] {
            joined.unite(corner(a, node), corner(b, node));
        }
    }
    // per node, the first corner's group and the cell of that corner
    let mut first: Vec<Option<(usize, usize)>> = vec![None; mesh.nodes.len()];
    let mut pinched: Option<(usize, [usize; 2])> = None;
    for (t, c) in mesh.cells.iter().enumerate() {
        for (k, &node) in c.nodes().iter().enumerate() {
            let group = joined.find(offset[t] + k);
            match first[node] {
                None => first[node] = Some((group, t)),
                Some((g, s)) if g != group && pinched.is_none_or(|(p, _)| node < p) => {
                    pinched = Some((node, [s, t]));
                }
                Some(_) => {}
            }
        }
    }
    match pinched {
        Some((node, cells)) => Err(Defect::Pinched { node, cells }),
        None => Ok(()),
    }
}

/// Disjoint sets with path halving (no ranks: the sets here are a handful of corners).
struct UnionFind(Vec<usize>);

impl UnionFind {
    fn new(n: usize) -> Self {
        Self((0..n).collect())
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }

    fn unite(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        self.0[a.max(b)] = a.min(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{rectangle, DiagonalPattern};
    use std::collections::BTreeMap;

    /// A mesh of the points `xy` (z = 0) and the cells of 3 or 4 corners.
    fn mesh(xy: &[[f64; 2]], cells: &[&[usize]]) -> Mesh {
        let mesh = Mesh {
            nodes: xy.iter().map(|p| Vector3::new(p[0], p[1], 0.0)).collect(),
            cells: cells
                .iter()
                .map(|c| match **c {
                    [a, b, c] => Cell::Triangle([a, b, c]),
                    [a, b, c, d] => Cell::Quad([a, b, c, d]),
                    _ => panic!("3 or 4 corners"),
                })
                .collect(),
            node_sets: BTreeMap::new(),
            element_sets: BTreeMap::new(),
            warp_directions: None,
        };
        mesh.validate().unwrap();
        mesh
    }

    /// Two unit squares side by side, on the edge from node 1 to node 4.
    fn two_squares() -> Vec<[f64; 2]> {
        vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ]
    }

    /// A 5 x 5 grid of unit squares without the middle one (a hole), every third square cut
    /// into two triangles, the cuts alternating.
    fn holed() -> Mesh {
        let node = |i: usize, j: usize| j * 6 + i;
        let xy: Vec<[f64; 2]> = (0..36).map(|n| [(n % 6) as f64, (n / 6) as f64]).collect();
        let mut cells: Vec<Vec<usize>> = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                let (a, b, c, d) = (
                    node(i, j),
                    node(i + 1, j),
                    node(i + 1, j + 1),
                    node(i, j + 1),
                );
                match (i, j, (i + j) % 3, i % 2) {
                    (2, 2, ..) => {}
                    (_, _, 0, 0) => cells.extend([vec![a, b, c], vec![a, c, d]]),
                    (_, _, 0, _) => cells.extend([vec![a, b, d], vec![b, c, d]]),
                    _ => cells.push(vec![a, b, c, d]),
                }
            }
        }
        let refs: Vec<&[usize]> = cells.iter().map(Vec::as_slice).collect();
        mesh(&xy, &refs)
    }

    #[test]
    fn a_sheet_of_quadrilaterals_and_triangles_with_a_hole_passes() {
        let sheet = check(&holed()).unwrap();
        assert_eq!(sheet.turned, Vec::<usize>::new());
        assert_eq!(sheet.pieces.len(), 1);
        // the hole's corners are on the border, not pinched
        let mesh = holed();
        assert!(mesh
            .cells
            .iter()
            .all(|c| c.area_vector(&mesh.nodes).z > 0.0));
    }

    #[test]
    fn every_rectangle_pattern_is_one_sheet() {
        for pattern in [
            DiagonalPattern::Quad,
            DiagonalPattern::Right,
            DiagonalPattern::Alternating,
            DiagonalPattern::Crossed,
        ] {
            for (nx, ny) in [(1, 1), (6, 18), (40, 3)] {
                let mesh = rectangle(150.0, 450.0, nx, ny, pattern);
                let sheet = check(&mesh).unwrap_or_else(|e| panic!("{pattern:?}: {e}"));
                assert_eq!(
                    sheet.pieces,
                    [Piece {
                        first: 0,
                        cells: mesh.cells.len()
                    }]
                );
                assert!(sheet.turned.is_empty());
            }
        }
    }

    #[test]
    fn a_curved_sheet_passes_and_a_crease_is_not_a_fold() {
        // the rectangle rolled onto a cylinder of radius 30 mm (a half-turn), and bent about
        // x = 0 by 90°
        let mut rolled = rectangle(90.0, 40.0, 12, 4, DiagonalPattern::Alternating);
        for x in &mut rolled.nodes {
            let angle = x.x / 30.0;
            *x = Vector3::new(30.0 * angle.sin(), x.y, 30.0 * (1.0 - angle.cos()));
        }
        check(&rolled).unwrap();
        let mut creased = rectangle(40.0, 40.0, 4, 4, DiagonalPattern::Quad);
        for x in &mut creased.nodes {
            if x.x > 0.0 {
                *x = Vector3::new(0.0, x.y, x.x);
            }
        }
        check(&creased).unwrap();
    }

    #[test]
    fn a_hanging_node_is_found_on_the_edge_it_lies_on() {
        // a square, and on its right two half-height squares whose shared node 6 lies on the
        // square's edge from node 1 to node 2
        let xy = [
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [2.0, 0.0],
            [2.0, 0.5],
            [1.0, 0.5],
            [2.0, 1.0],
        ];
        let m = mesh(&xy, &[&[0, 1, 2, 3], &[1, 4, 5, 6], &[6, 5, 7, 2]]);
        assert_eq!(
            check(&m).unwrap_err(),
            Defect::Hanging {
                node: 6,
                cell: 0,
                edge: (1, 2)
            }
        );
    }

    #[test]
    fn a_t_junction_is_a_hanging_node() {
        // a bar of three squares along x; a stem below butting into the middle square's lower
        // edge, its upper corners (nodes 10, 11) on that edge
        let mut xy: Vec<[f64; 2]> = (0..8)
            .map(|n| [(n % 4) as f64 * 10.0, 10.0 + (n / 4) as f64 * 10.0])
            .collect();
        xy.extend([[12.0, 0.0], [18.0, 0.0], [12.0, 10.0], [18.0, 10.0]]);
        let m = mesh(
            &xy,
            &[&[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[8, 9, 11, 10]],
        );
        let e = check(&m).unwrap_err();
        assert_eq!(
            e,
            Defect::Hanging {
                node: 10,
                cell: 1,
                edge: (1, 2)
            }
        );
        let text = e.to_string();
        assert!(
            text.starts_with("node 10 lies on the edge from node 1 to node 2 of element 1")
                && text.contains("hanging node"),
            "{text}"
        );
    }

    #[test]
    fn an_unmerged_seam_is_two_nodes_at_one_point() {
        // the two squares, the right one on its own copies (6, 7) of the nodes 1 and 4
        let mut xy = two_squares();
        xy.extend([[1.0, 0.0], [1.0, 1.0]]);
        let m = mesh(&xy, &[&[0, 1, 4, 3], &[6, 2, 5, 7]]);
        assert_eq!(
            check(&m).unwrap_err(),
            Defect::Coincident {
                node: 1,
                other: 6,
                distance: 0.0
            }
        );
        // a cut opened by a width is two pieces, not a defect
        xy[6][0] += 0.01;
        xy[7][0] += 0.01;
        let m = mesh(&xy, &[&[0, 1, 4, 3], &[6, 2, 5, 7]]);
        assert_eq!(check(&m).unwrap().pieces.len(), 2);
    }

    #[test]
    fn a_duplicate_cell_is_found_in_any_numbering() {
        let m = mesh(
            &two_squares(),
            &[&[0, 1, 4, 3], &[1, 2, 5, 4], &[4, 3, 0, 1]],
        );
        assert_eq!(
            check(&m).unwrap_err(),
            Defect::Duplicate { cell: 2, first: 0 }
        );
    }

    #[test]
    fn overlapping_cells_are_found() {
        // a square over the corner of another, no node in common
        let xy = [
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.5, 0.5],
            [1.5, 0.5],
            [1.5, 1.5],
            [0.5, 1.5],
        ];
        let m = mesh(&xy, &[&[0, 1, 2, 3], &[4, 5, 6, 7]]);
        assert_eq!(check(&m).unwrap_err(), Defect::Overlap { node: 2, cell: 1 });
        // a node on an edge two cells share: over them both
        let mut xy = two_squares();
        xy.extend([[1.0, 0.5], [1.5, 2.0], [1.2, 2.0]]);
        let m = mesh(&xy, &[&[0, 1, 4, 3], &[1, 2, 5, 4], &[6, 7, 8]]);
        assert!(
            matches!(check(&m).unwrap_err(), Defect::Overlap { node: 6, .. }),
            "{:?}",
            check(&m)
        );
    }

    #[test]
    fn a_cell_folded_onto_its_neighbour_is_found() {
        // the second square turned over onto the first, across their edge 1-4
        let mut xy = two_squares();
        xy[2] = [0.5, 0.0];
        xy[5] = [0.5, 1.0];
        let m = mesh(&xy, &[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
        let e = check(&m).unwrap_err();
        match e {
            Defect::Fold {
                cell: 1,
                neighbour: 0,
                angle_deg,
                ..
            } => assert!((angle_deg - 180.0).abs() < 1e-9, "{angle_deg}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn an_inverted_triangle_in_a_fan_is_a_fold() {
        // a fan of six triangles around node 0; node 0 moved out across the edge 1-2
        let mut xy = vec![[0.0, 0.0]];
        xy.extend((0..6).map(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_3;
            [a.cos(), a.sin()]
        }));
        let fan: Vec<Vec<usize>> = (0..6).map(|k| vec![0, 1 + k, 1 + (k + 1) % 6]).collect();
        let refs: Vec<&[usize]> = fan.iter().map(Vec::as_slice).collect();
        check(&mesh(&xy, &refs)).unwrap();
        xy[0] = [0.9, 0.6];
        let e = check(&mesh(&xy, &refs)).unwrap_err();
        assert!(matches!(e, Defect::Fold { .. }), "{e:?}");
    }

    #[test]
    fn slivers_and_specks_are_found() {
        // a triangle 10 mm long, 1e-3 mm high
        let m = mesh(&[[0.0, 0.0], [10.0, 0.0], [5.0, 1e-3]], &[&[0, 1, 2]]);
        match check(&m).unwrap_err() {
            Defect::Sliver {
                cell: 0,
                height,
                longest,
            } => assert!((height - 1e-3).abs() < 1e-12 && longest == 10.0),
            other => panic!("{other:?}"),
        }
        // a quadrilateral with a corner nearly on the line of its neighbours
        let m = mesh(
            &[[0.0, 0.0], [1.0, 0.0], [2.0, 1e-4], [1.0, 1.0]],
            &[&[0, 1, 2, 3]],
        );
        assert!(matches!(
            check(&m).unwrap_err(),
            Defect::Sliver { cell: 0, .. }
        ));
        // a sound triangle 1e-4 mm across beside a sheet of 1 mm squares
        let mut m = rectangle(10.0, 10.0, 10, 10, DiagonalPattern::Quad);
        let n = m.nodes.len();
        m.nodes.extend([
            Vector3::new(20.0, 0.0, 0.0),
            Vector3::new(20.0001, 0.0, 0.0),
            Vector3::new(20.0, 0.0001, 0.0),
        ]);
        m.cells.push(Cell::Triangle([n, n + 1, n + 2]));
        assert!(matches!(
            check(&m).unwrap_err(),
            Defect::Speck { cell: 100, .. }
        ));
    }

    #[test]
    fn a_third_cell_on_an_edge_is_non_manifold() {
        let mut xy = two_squares();
        xy.push([1.0, 0.5]);
        let m = Mesh {
            nodes: xy
                .iter()
                .map(|p| Vector3::new(p[0], p[1], 0.0))
                .chain([Vector3::new(0.5, 0.5, 1.0)])
                .collect(),
            ..mesh(&xy, &[&[0, 1, 4, 3], &[1, 2, 5, 4]])
        };
        let mut fin = m.clone();
        fin.cells.push(Cell::Triangle([1, 4, 7]));
        assert_eq!(
            check(&fin).unwrap_err(),
            Defect::NonManifold {
                cell: 2,
                edge: (1, 4),
                others: [0, 1]
            }
        );
    }

    #[test]
    fn a_moebius_band_is_not_orientable() {
        let (n, radius, half_width) = (24, 10.0, 2.0);
        let mut nodes = Vec::new();
        for i in 0..n {
            let u = std::f64::consts::TAU * i as f64 / n as f64;
            for v in [-half_width, half_width] {
                let r = radius + v * (u / 2.0).cos();
                nodes.push(Vector3::new(r * u.cos(), r * u.sin(), v * (u / 2.0).sin()));
            }
        }
        let mut cells: Vec<Cell> = (0..n - 1)
            .map(|i| Cell::Quad([2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1]))
            .collect();
        // the last strip joins the first with its sides swapped
        cells.push(Cell::Quad([2 * n - 2, 1, 0, 2 * n - 1]));
        let band = Mesh {
            nodes,
            cells,
            ..rectangle(1.0, 1.0, 1, 1, DiagonalPattern::Quad)
        };
        let band = Mesh {
            node_sets: BTreeMap::new(),
            ..band
        };
        band.validate().unwrap();
        assert!(matches!(
            check(&band).unwrap_err(),
            Defect::NonOrientable { .. }
        ));
    }

    #[test]
    fn cells_touching_at_a_corner_only_are_pinched() {
        let xy = [
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [2.0, 1.0],
            [2.0, 2.0],
            [1.0, 2.0],
        ];
        let m = mesh(&xy, &[&[0, 1, 2, 3], &[2, 4, 5, 6]]);
        assert_eq!(
            check(&m).unwrap_err(),
            Defect::Pinched {
                node: 2,
                cells: [0, 1]
            }
        );
    }

    #[test]
    fn far_nodes_and_repeated_nodes_are_found_before_anything_else() {
        let mut m = mesh(&two_squares(), &[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
        m.nodes[5].x = 1e200;
        let e = check_elements(&m).unwrap_err();
        assert_eq!(
            e.to_string(),
            "node 5 lies at (1e200, 1, 0) mm, beyond 1e6 mm of the origin: a coordinate \
             written wrong, or a length unit other than mm"
        );
        let mut m = mesh(&two_squares(), &[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
        m.cells[1] = Cell::Quad([1, 2, 2, 4]);
        assert_eq!(
            check(&m).unwrap_err(),
            Defect::RepeatedNode { cell: 1, node: 2 }
        );
    }

    #[test]
    fn cells_numbered_against_their_neighbours_are_turned_by_the_larger_area() {
        // the second of two squares numbered clockwise: equal areas keep the first's numbering
        let m = mesh(&two_squares(), &[&[0, 1, 4, 3], &[1, 4, 5, 2]]);
        let sheet = check(&m).unwrap();
        assert_eq!(sheet.turned, [1]);
        let mut oriented = m.clone();
        sheet.orient(&mut oriented);
        assert!(oriented
            .cells
            .iter()
            .all(|c| c.area_vector(&oriented.nodes).z > 0.0));
        // the first of three against the other two: it is turned
        let mut xy = two_squares();
        xy.extend([[3.0, 0.0], [3.0, 1.0]]);
        let m = mesh(&xy, &[&[0, 3, 4, 1], &[1, 2, 5, 4], &[2, 6, 7, 5]]);
        assert_eq!(check(&m).unwrap().turned, [0]);
    }

    #[test]
    fn pieces_apart_are_counted() {
        let mut xy = two_squares();
        xy.extend([[5.0, 0.0], [6.0, 0.0], [6.0, 1.0]]);
        let m = mesh(&xy, &[&[0, 1, 4, 3], &[1, 2, 5, 4], &[6, 7, 8]]);
        assert_eq!(
            check(&m).unwrap().pieces,
            [Piece { first: 0, cells: 2 }, Piece { first: 2, cells: 1 }]
        );
    }

    /// The cost on a large mesh, printed (`--nocapture`); no timing is asserted.
    #[test]
    fn a_large_mesh_is_checked_in_one_pass() {
        for (pattern, n) in [
            (DiagonalPattern::Quad, 500),
            (DiagonalPattern::Crossed, 250),
        ] {
            let mesh = rectangle(1000.0, 1000.0, n, n, pattern);
            let start = std::time::Instant::now();
            let sheet = check(&mesh).unwrap();
            println!(
                "conformity check of {} cells ({pattern:?}): {:.3} s",
                mesh.cells.len(),
                start.elapsed().as_secs_f64()
            );
            assert_eq!(sheet.pieces.len(), 1);
        }
    }
}
