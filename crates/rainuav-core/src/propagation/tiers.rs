//! The prisms parted by roof height into tiers, each a grid of buckets that keeps each bucket's
//! tallest roof, for the queries along a segment ([`crate::propagation::obstacles::Prisms::near_segment_over`]).
//!
//! A line of sight only meets the buildings tall enough to reach it. Walking a tier's grid along
//! the segment ([`Buckets::walk`]), a bucket is left (with every prism listed in it) where its
//! tallest roof stays below the lowest the caller needs there: a long leg toward a receiver
//! above the roofs reads the few towers near it and the buildings near its low end. The tiers:
//! the lowest up to the median roof, each next one up to twice the last one's limit. In a city
//! of low blocks and a few towers nearly every bucket of one grid would hold a tower and be
//! opened by a line above every block; a tier's buckets are as tall as its own prisms, and a
//! line above a tier's limit leaves it unread. Each tier's grid is sized to its own prisms (about
//! two buckets a prism): a sparse tier of towers has large buckets, and a leg crosses few (a
//! hierarchy of boxes a tier, which this replaced, has wide, overlapping nodes there: on the
//! district of 10 000 footprints it tested about 58 nodes and 20 prisms a line of sight).

use std::cell::Cell;

use crate::error::Result;
use crate::propagation::grid::Buckets;

/// How far (m) each prism's box is grown when listed in the buckets: a segment that grazes a
/// box within the queries' tolerance (a micrometre) finds it in the bucket it is walked through.
const MARGIN_M: f64 = 1e-3;

thread_local! {
    /// This thread's walk number and each prism's last walk: a prism listed in several buckets
    /// is read once a walk.
    static SEEN: Cell<(u32, Vec<u32>)> = const { Cell::new((0, Vec::new())) };
}

/// One tier: its prisms' grid (its `bounds` the tier's box), each bucket's tallest roof (m above
/// the terrain) and the tier's.
#[derive(Debug, Clone)]
struct Tier {
    grid: Buckets,
    tops: Vec<f64>,
    top: f64,
}

/// The tiers (none for no prisms).
#[derive(Debug, Clone, Default)]
pub(crate) struct Tiers {
    tiers: Vec<Tier>,
    n: usize,
}

impl Tiers {
    /// The tiers over boxes `[x0, x1, y0, y1]` with their roofs `tops`.
    pub(crate) fn build(boxes: &[[f64; 4]], tops: &[f64]) -> Result<Self> {
        let n = boxes.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&p, &q| tops[p as usize].total_cmp(&tops[q as usize]));
        let mut tiers = Vec::new();
        let mut lo = 0;
        let mut limit = if n > 0 {
            tops[order[n / 2] as usize]
        } else {
            0.0
        };
        while lo < n {
            let hi = lo + order[lo..].partition_point(|&i| tops[i as usize] <= limit);
            let hi = hi.max(lo + 1);
            limit = 2.0 * limit.max(1.0);
            let ids = &order[lo..hi];
            let tier_boxes: Vec<[f64; 4]> = ids.iter().map(|&i| boxes[i as usize]).collect();
            let mut grid = Buckets::build(&tier_boxes, MARGIN_M)?;
            for id in &mut grid.ids {
                *id = ids[*id as usize];
            }
            let cell_tops: Vec<f64> = (0..grid.len())
                .map(|k| {
                    grid.at(k)
                        .iter()
                        .map(|&i| tops[i as usize])
                        .fold(0.0, f64::max)
                })
                .collect();
            let top = cell_tops.iter().copied().fold(0.0, f64::max);
            tiers.push(Tier {
                grid,
                tops: cell_tops,
                top,
            });
            lo = hi;
        }
        Ok(Tiers { tiers, n })
    }

    /// Hands `visit` (until it returns false) every prism `i` (its box and roof `item(i)`)
    /// whose box the segment `a + t d` meets, as `inside(box)` says (`Some((lo, hi))`, the
    /// parameters along it), and whose roof plus `lift` reaches `floor(lo, hi)`, each once, in
    /// no set order; a tier or bucket is left by the same two tests (`floor` must be no
    /// higher over an interval than over any part of it). Whether `visit` never returned false.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn along(
        &self,
        a: [f64; 2],
        d: [f64; 2],
        inside: impl Fn(&[f64; 4]) -> Option<(f64, f64)>,
        floor: impl Fn(f64, f64) -> f64,
        item: impl Fn(u32) -> ([f64; 4], f64),
        lift: f64,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.tiers.is_empty() {
            return true;
        }
        // Taken, not borrowed: a `visit` that walks again gets marks of its own.
        let (mut walk, mut seen) = SEEN.take();
        seen.resize(seen.len().max(self.n), 0);
        walk = walk.wrapping_add(1);
        if walk == 0 {
            seen.fill(0);
            walk = 1;
        }
        let open = self.tiers.iter().all(|tier| {
            let Some(span) = inside(&tier.grid.bounds) else {
                return true;
            };
            if tier.top + lift < floor(span.0, span.1) {
                return true;
            }
            tier.grid.walk(a, d, span, |k, t_in, t_out| {
                if tier.tops[k] + lift < floor(t_in, t_out) {
                    return true;
                }
                for &i in tier.grid.at(k) {
                    if std::mem::replace(&mut seen[i as usize], walk) == walk {
                        continue;
                    }
                    let (b, top) = item(i);
                    if inside(&b).is_some_and(|(lo, hi)| top + lift >= floor(lo, hi)) && !visit(i) {
                        return false;
                    }
                }
                true
            })
        });
        SEEN.set((walk, seen));
        open
    }
}

#[cfg(test)]
mod tests {
    use super::Tiers;
    use crate::propagation::obstacles::{Building, Prisms};

    #[test]
    // Long: 3 000 random boxes and 300 segments across them, each segment's hand-on checked against
    // every box it meets.
    fn the_tiers_hand_on_each_prism_met_once_and_leave_a_tier_below_the_line() {
        // 3 000 boxes, roofs 1-200 m (most low, a few towers), some 400 m wide (listed in
        // many buckets): tiers up to the median roof, then doubling. 300 segments across the
        // area, every box met (no roof test): each handed on exactly once, as a scan finds
        // them; with the line at 30 m, only the roofs that reach it are read.
        let mut u = crate::test_stream(9);
        let (boxes, tops): (Vec<[f64; 4]>, Vec<f64>) = (0..3000)
            .map(|k| {
                let (x, y) = (3000.0 * u(), 3000.0 * u());
                let top = if u() < 0.06 {
                    40.0 + 160.0 * u()
                } else {
                    1.0 + 20.0 * u()
                };
                let w = if k % 100 == 0 { 400.0 } else { 30.0 };
                ([x, x + w, y, y + 30.0], top)
            })
            .unzip();
        let tiers = Tiers::build(&boxes, &tops).unwrap();
        assert!(tiers.tiers.len() >= 4, "{} tiers", tiers.tiers.len());
        let item = |i: u32| (boxes[i as usize], tops[i as usize]);
        let mut met = 0;
        for n in 0..300 {
            let a = [3400.0 * u() - 200.0, 3400.0 * u() - 200.0];
            let mut b = [3400.0 * u() - 200.0, 3400.0 * u() - 200.0];
            if n % 7 == 0 {
                b[1] = a[1]; // along a row of buckets
            }
            let d = [b[0] - a[0], b[1] - a[1]];
            // Where the segment is within a box (the slab test of `Prisms::each_over`).
            let inside = |bb: &[f64; 4]| {
                let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
                for ax in 0..2 {
                    if d[ax] == 0.0 {
                        if a[ax] < bb[2 * ax] || a[ax] > bb[2 * ax + 1] {
                            return None;
                        }
                    } else {
                        let u = (bb[2 * ax] - a[ax]) / d[ax];
                        let v = (bb[2 * ax + 1] - a[ax]) / d[ax];
                        (lo, hi) = (lo.max(u.min(v)), hi.min(u.max(v)));
                    }
                }
                (lo <= hi).then_some((lo, hi))
            };
            let mut seen = vec![0; boxes.len()];
            tiers.along(
                a,
                d,
                inside,
                |_, _| f64::NEG_INFINITY,
                item,
                0.0,
                |i| {
                    seen[i as usize] += 1;
                    true
                },
            );
            for (k, bb) in boxes.iter().enumerate() {
                let want = usize::from(inside(bb).is_some());
                assert_eq!(seen[k], want, "box {k} on {a:?} -> {b:?}");
                met += want;
            }
            let mut read = Vec::new();
            tiers.along(
                a,
                d,
                inside,
                |_, _| 30.0,
                item,
                0.0,
                |i| {
                    read.push(i);
                    true
                },
            );
            read.sort_unstable();
            let tall: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&k| tops[k as usize] >= 30.0 && inside(&boxes[k as usize]).is_some())
                .collect();
            assert_eq!(read, tall);
        }
        assert!(met > 3000, "{met} boxes met");
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
