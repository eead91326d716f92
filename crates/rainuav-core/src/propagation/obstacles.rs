//! Buildings as prisms (docs/physics.md section 12): footprint polygons (rings of vertices, holes
//! included, even-odd rule) extruded from the terrain to a flat roof `top` metres above it.
//! Boxes are the four-cornered case ([`Prisms::from_boxes`]).
//!
//! A bucket grid over the footprints' bounding boxes finds the prisms near a point or in a box;
//! the prisms parted by roof height, a grid of buckets a tier with each bucket's tallest roof
//! ([`crate::propagation::tiers`]), find those along a segment, so a path reads only the buildings it can
//! cross and that reach its rays.

use crate::error::{CoreError, Result};
use crate::propagation::grid::Buckets;
use crate::propagation::tiers::Tiers;

/// A box-shaped building: `[x0, x1, y0, y1, height]`, metres.
pub type Building = [f64; 5];

/// One prism: its rings (a range of [`Prisms`]'s rings), roof height above the terrain and
/// bounding box `[x0, x1, y0, y1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prism {
    /// First and one-past-last ring.
    pub rings: [usize; 2],
    /// Roof height above the terrain, m.
    pub top: f64,
    /// `[x0, x1, y0, y1]`, m.
    pub bbox: [f64; 4],
}

/// Buildings as prisms, with a bucket grid over them.
#[derive(Debug, Clone, Default)]
pub struct Prisms {
    xy: Vec<[f64; 2]>,
    rings: Vec<[usize; 2]>,
    items: Vec<Prism>,
    grid: Buckets,
    tiers: Tiers,
    /// The tallest roof above the terrain, m (0: none).
    top_max: f64,
}

impl Prisms {
    /// Prisms from rings of vertices: `xy` every vertex (rings not closed: the last vertex
    /// joins the first), `ring_starts` (R + 1 offsets into `xy`), `prism_rings` (P + 1
    /// offsets into the rings: each prism's outer ring and holes) and `tops` (P roof heights
    /// above the terrain, m).
    pub fn new(
        xy: Vec<[f64; 2]>,
        ring_starts: &[usize],
        prism_rings: &[usize],
        tops: &[f64],
    ) -> Result<Self> {
        let bad = |why: &str| CoreError::invalid("footprints", why.to_string(), "a bad value");
        if !xy.iter().flatten().all(|v| v.is_finite() && v.abs() < 1e7) {
            return Err(bad("vertices must be finite, within 1e7 m"));
        }
        let monotone = |o: &[usize], end: usize| {
            !o.is_empty()
                && o[0] == 0
                && o.windows(2).all(|w| w[0] <= w[1])
                && o[o.len() - 1] == end
        };
        if !monotone(ring_starts, xy.len()) || ring_starts.windows(2).any(|w| w[1] - w[0] < 3) {
            return Err(bad(
                "ring_starts must run from 0 to the vertex count, 3 or more a ring",
            ));
        }
        let n_rings = ring_starts.len() - 1;
        if !monotone(prism_rings, n_rings)
            || prism_rings.windows(2).any(|w| w[1] == w[0])
            || tops.len() + 1 != prism_rings.len()
        {
            return Err(bad(
                "prism_rings must run from 0 to the ring count, one a height",
            ));
        }
        if !tops
            .iter()
            .all(|t| t.is_finite() && (0.0..=1000.0).contains(t))
        {
            return Err(bad("heights must be in 0..1000 m"));
        }
        let rings: Vec<[usize; 2]> = ring_starts.windows(2).map(|w| [w[0], w[1]]).collect();
        let items: Vec<Prism> = prism_rings
            .windows(2)
            .zip(tops)
            .map(|(w, &top)| {
                let mut bbox = [
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                ];
                for r in &rings[w[0]..w[1]] {
                    for p in &xy[r[0]..r[1]] {
                        bbox = [
                            bbox[0].min(p[0]),
                            bbox[1].max(p[0]),
                            bbox[2].min(p[1]),
                            bbox[3].max(p[1]),
                        ];
                    }
                }
                Prism {
                    rings: [w[0], w[1]],
                    top,
                    bbox,
                }
            })
            .collect();
        let top_max = items.iter().map(|p| p.top).fold(0.0, f64::max);
        let boxes: Vec<[f64; 4]> = items.iter().map(|p| p.bbox).collect();
        let tops: Vec<f64> = items.iter().map(|p| p.top).collect();
        let grid = Buckets::build(&boxes, 0.0)?;
        let tiers = Tiers::build(&boxes, &tops)?;
        Ok(Prisms {
            xy,
            rings,
            items,
            grid,
            tiers,
            top_max,
        })
    }

    /// Boxes `[x0, x1, y0, y1, height]` as prisms (corners counter-clockwise).
    pub fn from_boxes(boxes: &[Building]) -> Result<Self> {
        for b in boxes {
            if !(b.iter().all(|v| v.is_finite()) && b[1] > b[0] && b[3] > b[2] && b[4] >= 0.0) {
                return Err(CoreError::invalid(
                    "buildings",
                    "must be finite boxes [x0 < x1, y0 < y1, height >= 0]",
                    format!("{b:?}"),
                ));
            }
        }
        let xy = boxes
            .iter()
            .flat_map(|b| [[b[0], b[2]], [b[1], b[2]], [b[1], b[3]], [b[0], b[3]]])
            .collect();
        let offsets: Vec<usize> = (0..=boxes.len()).map(|k| 4 * k).collect();
        let rings: Vec<usize> = (0..=boxes.len()).collect();
        let tops: Vec<f64> = boxes.iter().map(|b| b[4]).collect();
        Self::new(xy, &offsets, &rings, &tops)
    }

    /// These prisms and `other`'s together.
    pub fn join(self, other: &Prisms) -> Result<Self> {
        let mut xy = self.xy;
        let mut starts: Vec<usize> = self.rings.iter().map(|r| r[0]).collect();
        let mut prism_rings: Vec<usize> = self.items.iter().map(|p| p.rings[0]).collect();
        let mut tops: Vec<f64> = self.items.iter().map(|p| p.top).collect();
        let (nv, nr) = (xy.len(), starts.len());
        xy.extend_from_slice(&other.xy);
        starts.extend(other.rings.iter().map(|r| r[0] + nv));
        starts.push(xy.len());
        prism_rings.extend(other.items.iter().map(|p| p.rings[0] + nr));
        prism_rings.push(starts.len() - 1);
        tops.extend(other.items.iter().map(|p| p.top));
        Self::new(xy, &starts, &prism_rings, &tops)
    }

    /// How many prisms.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The prisms.
    pub fn items(&self) -> &[Prism] {
        &self.items
    }

    /// Prism `k`'s rings (its outer ring first, then its holes), each a slice of vertices
    /// (not closed: the last joins the first).
    pub fn rings_of(&self, k: usize) -> impl Iterator<Item = &[[f64; 2]]> + '_ {
        let p = self.items[k];
        self.rings[p.rings[0]..p.rings[1]]
            .iter()
            .map(move |r| &self.xy[r[0]..r[1]])
    }

    /// Hands `f` each edge of prism `k`'s rings, `(from, to)`, ring by ring in order.
    fn for_edges(&self, k: usize, mut f: impl FnMut([f64; 2], [f64; 2])) {
        let p = self.items[k];
        for r in &self.rings[p.rings[0]..p.rings[1]] {
            let ring = &self.xy[r[0]..r[1]];
            for w in ring.windows(2) {
                f(w[0], w[1]);
            }
            f(ring[ring.len() - 1], ring[0]);
        }
    }

    /// Whether prism `k`'s footprint holds `(x, y)` (even-odd over its rings).
    pub fn contains(&self, k: usize, x: f64, y: f64) -> bool {
        let b = self.items[k].bbox;
        if x < b[0] || x > b[1] || y < b[2] || y > b[3] {
            return false;
        }
        let mut inside = false;
        self.for_edges(k, |p, q| {
            if (p[1] > y) != (q[1] > y) && x < p[0] + (y - p[1]) / (q[1] - p[1]) * (q[0] - p[0]) {
                inside = !inside;
            }
        });
        inside
    }

    /// The tallest roof (m above the terrain) whose footprint holds `(x, y)`; 0: none.
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        if self.items.is_empty() {
            return 0.0;
        }
        let g = &self.grid;
        g.bucket(g.row(y), g.col(x))
            .iter()
            .filter(|&&k| self.contains(k as usize, x, y))
            .map(|&k| self.items[k as usize].top)
            .fold(0.0, f64::max)
    }

    /// The prisms whose bounding box meets the box `[x0, x1, y0, y1]`, each once, in index
    /// order.
    pub fn near_box(&self, bbox: [f64; 4], out: &mut Vec<u32>) {
        out.clear();
        if self.items.is_empty() {
            return;
        }
        let (c0, c1, r0, r1) = self.grid.range(bbox);
        for r in r0..=r1 {
            for c in c0..=c1 {
                out.extend_from_slice(self.grid.bucket(r, c));
            }
        }
        out.sort_unstable();
        out.dedup();
        out.retain(|&k| {
            let bb = self.items[k as usize].bbox;
            bb[0] <= bbox[1] && bb[1] >= bbox[0] && bb[2] <= bbox[3] && bb[3] >= bbox[2]
        });
    }

    /// The parameters `t` in 0..=1 where the segment `a -> b` crosses prism `k`'s edges,
    /// appended to `out` unsorted.
    pub fn crossings(&self, k: usize, a: [f64; 2], b: [f64; 2], out: &mut Vec<f64>) {
        let d = [b[0] - a[0], b[1] - a[1]];
        self.for_edges(k, |p, q| {
            let e = [q[0] - p[0], q[1] - p[1]];
            let den = d[0] * e[1] - d[1] * e[0];
            if den.abs() < 1e-12 {
                return;
            }
            let w = [p[0] - a[0], p[1] - a[1]];
            let t = (w[0] * e[1] - w[1] * e[0]) / den;
            let s = (w[0] * d[1] - w[1] * d[0]) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&s) {
                out.push(t);
            }
        });
    }
}

mod segment;
#[cfg(test)]
mod tests;
