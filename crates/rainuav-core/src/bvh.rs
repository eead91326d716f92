//! A bounding-volume hierarchy over the prisms' footprint boxes, each node with the tallest
//! roof beneath it, for the queries along a segment ([`crate::obstacles::Prisms::near_segment_over`]).
//!
//! A line of sight only meets the buildings tall enough to reach it. Walking the hierarchy
//! along the segment, a node is left (with everything under it) where the segment misses its
//! box or where its tallest roof stays below the lowest the caller needs there: a long leg
//! toward a receiver above the roofs reads the few towers near it and the buildings near its
//! low end, not every bucket of a grid it crosses. Built by median splits of the boxes'
//! centres along the wider side, a few prisms a leaf.
//!
//! The prisms are first parted by roof height into tiers, each with a hierarchy of its own:
//! the lowest tier up to the median roof, each next one up to twice the last one's limit. In a
//! city of low blocks and a few towers nearly every node of one hierarchy would hold a tower
//! and be opened by a line above every block; a tier's nodes are as tall as its own prisms,
//! and a line above a tier's limit leaves it at its root. The prisms handed on are the same;
//! only their order differs.

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

/// The hierarchies of the tiers (empty for no prisms).
#[derive(Debug, Clone, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Each tier's root node.
    roots: Vec<u32>,
}

impl Bvh {
    /// The hierarchy over boxes `[x0, x1, y0, y1]` with their roofs `tops`.
    pub(crate) fn build(boxes: &[[f64; 4]], tops: &[f64]) -> Self {
        let n = boxes.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&p, &q| tops[p as usize].total_cmp(&tops[q as usize]));
        let mut nodes = Vec::with_capacity(2 * n / LEAF + 8);
        let mut roots = Vec::new();
        if n > 0 {
            // (node, range of `order`) still to fill: first each tier's root (`order` is sorted
            // by roof: a tier is a range of it).
            let mut todo = Vec::new();
            let mut lo = 0;
            let mut limit = tops[order[n / 2] as usize];
            while lo < n {
                let hi = lo + order[lo..].partition_point(|&i| tops[i as usize] <= limit);
                let hi = hi.max(lo + 1);
                limit = 2.0 * limit.max(1.0);
                if hi > lo {
                    roots.push(nodes.len() as u32);
                    todo.push((nodes.len(), lo, hi));
                    nodes.push(Node {
                        bbox: [0.0; 4],
                        top: 0.0,
                        first: 0,
                        count: 0,
                    });
                }
                lo = hi;
            }
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
        Bvh {
            nodes,
            order,
            roots,
        }
    }

    /// Hands `visit` (until it returns false) every prism `i` (its box and roof `item(i)`)
    /// whose box `inside(box)` says the segment meets, as `Some((lo, hi))` (the parameters
    /// along the segment), and whose roof plus `lift` reaches `floor(lo, hi)`, in no set
    /// order; nodes are left by the same two tests. Whether `visit` never returned false.
    pub(crate) fn along(
        &self,
        inside: impl Fn(&[f64; 4]) -> Option<(f64, f64)>,
        floor: impl Fn(f64, f64) -> f64,
        item: impl Fn(u32) -> ([f64; 4], f64),
        lift: f64,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let reaches =
            |b: &[f64; 4], top: f64| inside(b).is_some_and(|(lo, hi)| top + lift >= floor(lo, hi));
        // Depth-first from every tier's root; a tree's depth is at most 2 log2(n), so 128
        // entries always suffice.
        let (mut stack, mut len) = ([0u32; 128], self.roots.len());
        stack[..len].copy_from_slice(&self.roots);
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
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let (b, top) = item(i);
                    if reaches(&b, top) && !visit(i) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::Bvh;
    use crate::obstacles::{Building, Prisms};

    #[test]
    fn the_tiers_hold_every_prism_once_each_below_its_limit() {
        // 3 000 boxes, roofs 1-200 m (most low, a few towers): tiers up to the median roof, then
        // doubling; walked with nothing left out, every prism is handed on exactly once; a line
        // above a tier's tallest roof never reads it.
        let mut u = crate::test_stream(9);
        let (boxes, tops): (Vec<[f64; 4]>, Vec<f64>) = (0..3000)
            .map(|_| {
                let (x, y) = (3000.0 * u(), 3000.0 * u());
                let top = if u() < 0.06 {
                    40.0 + 160.0 * u()
                } else {
                    1.0 + 20.0 * u()
                };
                ([x, x + 30.0, y, y + 30.0], top)
            })
            .unzip();
        let bvh = Bvh::build(&boxes, &tops);
        assert!(bvh.roots.len() >= 4, "{} tiers", bvh.roots.len());
        let mut seen = vec![0; boxes.len()];
        let all = |_: &[f64; 4]| Some((0.0, 1.0));
        let item = |i: u32| (boxes[i as usize], tops[i as usize]);
        bvh.along(
            all,
            |_, _| f64::NEG_INFINITY,
            item,
            0.0,
            |i| {
                seen[i as usize] += 1;
                true
            },
        );
        assert!(seen.iter().all(|&n| n == 1));
        let mut read = Vec::new();
        bvh.along(
            all,
            |_, _| 30.0,
            item,
            0.0,
            |i| {
                read.push(i);
                true
            },
        );
        let tall = tops.iter().filter(|&&t| t >= 30.0).count();
        assert_eq!(read.len(), tall);
        assert!(read.iter().all(|&i| tops[i as usize] >= 30.0));
    }

    #[test]
    fn segment_queries_find_what_a_scan_finds() {
        // 2 000 boxes 3-80 m tall, overlapping at random; 400 segments, some vertical or
        // horizontal. near_segment: every box the segment meets (a scan of all of them);
        // near_segment_under: every box with a crossing point at or above the line (the only
        // ones in its way), and no box whose roof stays below the line over its box.
        let mut u = crate::test_stream(5);
        let boxes: Vec<Building> = (0..2000)
            .map(|_| {
                let (x, y) = (3000.0 * u(), 3000.0 * u());
                [
                    x,
                    x + 5.0 + 60.0 * u(),
                    y,
                    y + 5.0 + 60.0 * u(),
                    3.0 + 77.0 * u(),
                ]
            })
            .collect();
        let p = Prisms::from_boxes(&boxes).unwrap();
        let (mut near, mut t) = (Vec::new(), Vec::new());
        let mut found = 0;
        for n in 0..400 {
            let a = [3000.0 * u(), 3000.0 * u()];
            let mut b = [3000.0 * u(), 3000.0 * u()];
            match n % 10 {
                0 => b[0] = a[0],
                1 => b[1] = a[1],
                _ => {}
            }
            let (za, zb) = (60.0 * u(), 120.0 * u());
            let line = |t: f64| za + (zb - za) * t;
            // Where the segment is within a box (Liang-Barsky; lo > hi: it misses it).
            let clip = |bb: &[f64; 5]| {
                let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
                for (o, d, v0, v1) in [
                    (a[0], b[0] - a[0], bb[0], bb[1]),
                    (a[1], b[1] - a[1], bb[2], bb[3]),
                ] {
                    if d == 0.0 {
                        if o < v0 || o > v1 {
                            (lo, hi) = (1.0, 0.0);
                        }
                    } else {
                        let (t0, t1) = ((v0 - o) / d, (v1 - o) / d);
                        (lo, hi) = (lo.max(t0.min(t1)), hi.min(t0.max(t1)));
                    }
                }
                (lo, hi)
            };
            p.near_segment(a, b, &mut near);
            for (k, bb) in boxes.iter().enumerate() {
                let (lo, hi) = clip(bb);
                if lo <= hi {
                    assert!(near.contains(&(k as u32)), "box {k} missed on {a:?}->{b:?}");
                }
            }
            assert!(
                near.windows(2).all(|w| w[0] < w[1]),
                "in index order, each once"
            );
            p.near_segment_under((a, za), (b, zb), 0.0, &mut near);
            for k in 0..p.len() {
                t.clear();
                p.crossings(k, a, b, &mut t);
                let in_way = t.iter().any(|&t| boxes[k][4] >= line(t));
                if in_way {
                    assert!(near.contains(&(k as u32)), "box {k} in the way, missed");
                    found += 1;
                }
                // Above its roof by a millimetre wherever the segment is within its box: never
                // in the way.
                let (lo, hi) = clip(&boxes[k]);
                let over = lo > hi + 1e-6 || line(lo).min(line(hi)) > boxes[k][4] + 1e-3;
                if over {
                    assert!(!near.contains(&(k as u32)), "box {k} below the line, read");
                }
            }
        }
        assert!(found > 200, "{found} boxes in the way");
    }
}
