//! Where the planner among levels reads its signal: each level's one map, or the slices of
//! every level in time ([`LevelTimeline`]), linear in time between two slices.

use crate::error::{CoreError, Result};
use crate::planning::planner::{NavTask, bilinear, blend, bracket, check_clock};
use ndarray::{ArrayView4, Axis};

/// The signal of every level in time: slices (K, L, H, W) at the instants `t_s`.
#[derive(Debug, Clone)]
pub struct LevelTimeline<'a> {
    /// Signal (K, L, H, W), dB.
    pub slices: ArrayView4<'a, f64>,
    /// (K,) instants of the slices, s, strictly increasing.
    pub t_s: &'a [f64],
    /// Take-off time, s.
    pub t0_s: f64,
    /// Duration of one tick (one horizontal move), s.
    pub dt_s: f64,
}

impl LevelTimeline<'_> {
    pub(super) fn validate(&self, levels: usize) -> Result<()> {
        let (k, l, h, w) = self.slices.dim();
        if k == 0 || h == 0 || w == 0 || l != levels || self.t_s.len() != k {
            return Err(CoreError::invalid(
                "sinr_db",
                format!("must be (K, {levels}, H, W), non-empty, with one instant per slice"),
                format!("{:?} with {} instants", self.slices.dim(), self.t_s.len()),
            ));
        }
        if self.slices.iter().any(|v| !v.is_finite()) {
            return Err(CoreError::invalid(
                "sinr_db",
                "must be finite everywhere",
                "NaN or inf",
            ));
        }
        check_clock(self.t_s, self.t0_s, self.dt_s)
    }
}

/// Where the signal comes from: each level's one map, or the slices in time.
#[derive(Clone, Copy)]
pub(super) enum Source<'b, 'a, 'c> {
    Static(&'b [NavTask<'a>]),
    Time(&'b LevelTimeline<'c>, [f64; 4]),
}

impl Source<'_, '_, '_> {
    /// The slices around tick `tick`'s instant and the later one's weight.
    pub(super) fn bracket(&self, tick: usize) -> (usize, usize, f64) {
        match self {
            Source::Static(_) => (0, 0, 0.0),
            Source::Time(tl, _) => bracket(tl.t_s, tl.t0_s + tick as f64 * tl.dt_s),
        }
    }

    /// Slice `k`'s map of level `l`.
    pub(super) fn map(&self, k: usize, l: usize) -> ndarray::ArrayView2<'_, f64> {
        match self {
            Source::Static(levels) => levels[l].sir_db.view(),
            Source::Time(tl, _) => tl.slices.index_axis(Axis(0), k).index_axis_move(Axis(0), l),
        }
    }

    /// Slice `k`'s signal of level `l` at `(x, y)`.
    pub(super) fn sample(&self, k: usize, l: usize, x: f64, y: f64) -> f64 {
        let extent = match self {
            Source::Static(levels) => levels[l].extent,
            Source::Time(_, extent) => *extent,
        };
        bilinear(&self.map(k, l), extent, x, y)
    }

    /// The signal of level `l` at `(x, y)` at tick `tick`.
    pub(super) fn signal(&self, l: usize, x: f64, y: f64, tick: usize) -> f64 {
        let (k0, k1, f) = self.bracket(tick);
        let v0 = self.sample(k0, l, x, y);
        if k0 == k1 {
            v0
        } else {
            blend(v0, self.sample(k1, l, x, y), f)
        }
    }
}
