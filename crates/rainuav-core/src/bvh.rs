//! A bounding-volume hierarchy over the prisms' footprint boxes, each node with the tallest
//! roof beneath it, for the queries along a segment ([`crate::obstacles::Prisms::near_segment_over`]).
//!
//! A line of sight only meets the buildings tall enough to reach it. Walking the hierarchy
//! along the segment, a node is left (with everything under it) where the segment misses its
//! box or where its tallest roof stays below the lowest the caller needs there: a long leg
//! toward a receiver above the roofs reads the few towers near it and the buildings near its
//! low end, not every bucket of a grid it crosses. Built by median splits of the boxes'
//! centres along the wider side, a few prisms a leaf.

/// Prisms a leaf holds at most.
const LEAF: usize = 4;

/// One node: its box `[x0, x1, y0, y1]`, tallest roof (m above the terrain), and either
/// its children (`first`, `first + 1`; `count == 0`) or its prisms (`order[first..first +
/// count]`).
#[derive(Debug, Clone, Copy)]
struct Node {
    bbox: [f64; 4],
    top: f64,
    first: u32,
    count: u32,
}

/// The hierarchy (empty for no prisms).
#[derive(Debug, Clone, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Bvh {
    /// The hierarchy over boxes `[x0, x1, y0, y1]` with their roofs `tops`.
    pub(crate) fn build(boxes: &[[f64; 4]], tops: &[f64]) -> Self {
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF + 1);
        if !boxes.is_empty() {
            nodes.push(Node {
                bbox: [0.0; 4],
                top: 0.0,
                first: 0,
                count: 0,
            });
            // (node, range of `order`) still to fill.
            let mut todo = vec![(0usize, 0usize, boxes.len())];
            while let Some((k, lo, hi)) = todo.pop() {
                let ids = &mut order[lo..hi];
                let mut bbox = [
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                ];
                let mut top = 0.0_f64;
                for &i in ids.iter() {
                    let b = boxes[i as usize];
                    bbox = [
                        bbox[0].min(b[0]),
                        bbox[1].max(b[1]),
                        bbox[2].min(b[2]),
                        bbox[3].max(b[3]),
                    ];
                    top = top.max(tops[i as usize]);
                }
                nodes[k].bbox = bbox;
                nodes[k].top = top;
                if ids.len() <= LEAF {
                    nodes[k].first = lo as u32;
                    nodes[k].count = ids.len() as u32;
                    continue;
                }
                let axis = usize::from(bbox[3] - bbox[2] > bbox[1] - bbox[0]);
                let centre = |i: u32| {
                    let b = boxes[i as usize];
                    b[2 * axis] + b[2 * axis + 1]
                };
                let mid = ids.len() / 2;
                ids.select_nth_unstable_by(mid, |&p, &q| centre(p).total_cmp(&centre(q)));
                let first = nodes.len();
                let empty = Node {
                    bbox: [0.0; 4],
                    top: 0.0,
                    first: 0,
                    count: 0,
                };
                nodes.extend([empty, empty]);
                nodes[k].first = first as u32;
                todo.push((first, lo, lo + mid));
                todo.push((first + 1, lo + mid, hi));
            }
        }
        Bvh { nodes, order }
    }

    /// Appends to `out` (unsorted) every prism `i` (its box and roof `item(i)`) whose box
    /// `inside(box)` says the segment meets, as `Some((lo, hi))` (the parameters along the
    /// segment), and whose roof plus `lift` reaches `floor(lo, hi)`; nodes are left by the
    /// same two tests.
    pub(crate) fn along(
        &self,
        inside: impl Fn(&[f64; 4]) -> Option<(f64, f64)>,
        floor: impl Fn(f64, f64) -> f64,
        item: impl Fn(u32) -> ([f64; 4], f64),
        lift: f64,
        out: &mut Vec<u32>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let reaches = |b: &[f64; 4], top: f64| {
            inside(b).is_some_and(|(lo, hi)| top + lift >= floor(lo, hi))
        };
        // Depth-first; the tree's depth is at most 2 log2(n), so 128 entries always suffice.
        let (mut stack, mut len) = ([0u32; 128], 1usize);
        while len > 0 {
            len -= 1;
            let n = &self.nodes[stack[len] as usize];
            if !reaches(&n.bbox, n.top) {
                continue;
            }
            if n.count == 0 {
                stack[len] = n.first;
                stack[len + 1] = n.first + 1;
                len += 2;
            } else {
                let ids = &self.order[n.first as usize..(n.first + n.count) as usize];
                out.extend(ids.iter().copied().filter(|&i| {
                    let (b, top) = item(i);
                    reaches(&b, top)
                }));
            }
        }
    }
}
