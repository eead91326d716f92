//! The prisms a segment of a line of sight meets ([`Prisms`]' tiers walked along it).

use super::Prisms;

impl Prisms {
    /// The prisms whose bounding box the segment `a -> b` meets where the straight line from
    /// height `za` over `a` to `zb` over `b` is no higher than their roof plus `lift` (an upper
    /// bound of the terrain under them), each once, in index order: the only prisms that can
    /// stand in that line's way.
    pub fn near_segment_under(
        &self,
        (a, za): ([f64; 2], f64),
        (b, zb): ([f64; 2], f64),
        lift: f64,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.each_under((a, za), (b, zb), lift, |k| {
            out.push(k);
            true
        });
        out.sort_unstable();
    }

    /// The prisms [`Prisms::near_segment_under`] finds, handed to `visit` in no set order
    /// until it returns false; whether it never did (a line of sight stops at the first
    /// building in its way without listing the rest).
    pub fn each_under(
        &self,
        (a, za): ([f64; 2], f64),
        (b, zb): ([f64; 2], f64),
        lift: f64,
        visit: impl FnMut(u32) -> bool,
    ) -> bool {
        let line = |t: f64| za + (zb - za) * t;
        self.each_over(a, b, |lo, hi| line(lo).min(line(hi)), lift, visit)
    }

    /// The prisms whose bounding box the segment `a -> b` meets, each once, in index order.
    pub fn near_segment(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<u32>) {
        self.near_segment_over(a, b, |_, _| f64::NEG_INFINITY, 0.0, out);
    }

    /// The prisms whose bounding box the segment `a -> b` (points `a + t (b - a)`) meets on
    /// some `lo..=hi` where their roof plus `lift` reaches `floor(lo, hi)`, each once, in index
    /// order. `floor(lo, hi)` is the lowest (m above sea level) a prism standing over
    /// `t in lo..=hi` must reach to matter to the caller, or less (and no higher over an
    /// interval than over any part of it): a tier or bucket whose tallest roof stays below it
    /// is not read, nor a prism whose box does.
    pub fn near_segment_over(
        &self,
        a: [f64; 2],
        b: [f64; 2],
        floor: impl Fn(f64, f64) -> f64,
        lift: f64,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        self.each_over(a, b, floor, lift, |k| {
            out.push(k);
            true
        });
        out.sort_unstable();
    }

    /// The prisms [`Prisms::near_segment_over`] finds, handed to `visit` in no set order until
    /// it returns false; whether it never did.
    fn each_over(
        &self,
        a: [f64; 2],
        b: [f64; 2],
        floor: impl Fn(f64, f64) -> f64,
        lift: f64,
        visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.items.is_empty() || floor(0.0, 1.0) > self.top_max + lift {
            return true;
        }
        let d = [b[0] - a[0], b[1] - a[1]];
        // A micrometre's tolerance along the segment keeps a box it grazes.
        let tol = 1e-6 / (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-9);
        let inv = d.map(|v| {
            if v.abs() < 1e-12 {
                f64::INFINITY
            } else {
                1.0 / v
            }
        });
        // The parameters in 0..=1 where the segment is within the box.
        let inside = |bb: &[f64; 4]| {
            let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
            for ax in 0..2 {
                let (v0, v1) = (bb[2 * ax], bb[2 * ax + 1]);
                if inv[ax].is_infinite() {
                    if a[ax] < v0 - 1e-6 || a[ax] > v1 + 1e-6 {
                        return None;
                    }
                } else {
                    let (u, v) = ((v0 - a[ax]) * inv[ax], (v1 - a[ax]) * inv[ax]);
                    lo = lo.max(u.min(v) - tol);
                    hi = hi.min(u.max(v) + tol);
                }
            }
            (lo <= hi).then_some((lo.max(0.0), hi.min(1.0)))
        };
        let item = |k: u32| (self.items[k as usize].bbox, self.items[k as usize].top);
        self.tiers.along(a, d, inside, floor, item, lift, visit)
    }
}
