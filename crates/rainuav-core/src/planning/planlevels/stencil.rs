//! The inner loops of the planner among levels: one row of the backward programme read as a
//! stencil, and each level's signal sampled once a slice at the plan's lattice.

use super::signal::LevelSignal;
use crate::planning::planner::{Tap, bilinear_taps};

/// The stencil input of one row: `B` and `W` of the next tick over the whole stack, the
/// lattice's row length and the row's states.
pub(super) struct Row<'a> {
    pub(super) b: &'a [f64],
    pub(super) w: &'a [f64],
    pub(super) nj: usize,
    pub(super) range: std::ops::Range<usize>,
}

/// A vertical move from a row: onto a level (its duration and the landing tick's `B` and `W`
/// from the row's first state on), or out of the band (duration, `B` of the row, penalty).
pub(super) enum Vertical<'a> {
    Level(f64, &'a [f64], &'a [f64]),
    Out(f64, &'a [f64], f64),
}

/// One row of the backward programme: each state's best move (first best in action order)
/// and its value, or where it is not flown its terminal bonus.
pub(super) fn stencil_row(
    row: Row<'_>,
    vertical: [Vertical<'_>; 2],
    (live, extra): (&[bool], &[f64]),
    (w_out, pol): (&mut [f64], &mut [u8]),
) {
    let Row { b, w, nj, range } = row;
    let m = range.len();
    let u = |s: usize| b[s] + w[s];
    for k in 0..m {
        let s = range.start + k;
        let mut v = u(s + nj);
        let mut a = 0u8;
        let c = u(s + 1);
        if c > v {
            v = c;
            a = 1;
        }
        let c = u(s - nj);
        if c > v {
            v = c;
            a = 2;
        }
        let c = u(s - 1);
        if c > v {
            v = c;
            a = 3;
        }
        for (move_, vert) in [(4u8, &vertical[0]), (5u8, &vertical[1])] {
            let c = match vert {
                Vertical::Level(d, tb, tw) => d * tb[k] + tw[k],
                Vertical::Out(d, tb, pen) => d * tb[k] - pen,
            };
            if c > v {
                v = c;
                a = move_;
            }
        }
        w_out[k] = if live[k] { v } else { extra[k] };
        pol[k] = a;
    }
}

/// Each level's signal at a plan's lattice for the one or two slices in use, sampled once per
/// slice (the backward programme walks time backwards, so a slice once left is not needed
/// again).
#[derive(Default)]
pub(super) struct Sampler {
    slots: [Option<(usize, Vec<f64>)>; 2],
}

impl Sampler {
    /// The samples of slices `k0` and (where it differs) `k1` at the lattice of `taps` (per
    /// level, x then y), `n` points a level.
    pub(super) fn values(
        &mut self,
        k0: usize,
        k1: usize,
        src: &LevelSignal<'_>,
        taps: &[(Vec<Tap>, Vec<Tap>)],
        n: usize,
    ) -> (&[f64], Option<&[f64]>) {
        for slot in &mut self.slots {
            if slot.as_ref().is_some_and(|(k, _)| *k != k0 && *k != k1) {
                *slot = None;
            }
        }
        for k in [k0, k1] {
            if !self.slots.iter().flatten().any(|(kk, _)| *kk == k) {
                let mut v = Vec::with_capacity(n * taps.len());
                for (l, (tx, ty)) in taps.iter().enumerate() {
                    let map = src.map(k, l);
                    for &a in tx {
                        v.extend(ty.iter().map(|&c| bilinear_taps(&map, a, c)));
                    }
                }
                let free = self
                    .slots
                    .iter()
                    .position(Option::is_none)
                    .expect("a free slot");
                self.slots[free] = Some((k, v));
            }
        }
        let find = |k: usize| {
            self.slots
                .iter()
                .flatten()
                .find(|(kk, _)| *kk == k)
                .map(|(_, v)| v.as_slice())
                .expect("sampled")
        };
        (find(k0), (k1 != k0).then(|| find(k1)))
    }
}
