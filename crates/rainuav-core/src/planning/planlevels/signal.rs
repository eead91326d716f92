//! Where the planner among levels reads its signal: one array over (time, level, north,
//! east) and the flight's clock ([`LevelSignal`]), bilinear in space and linear in time
//! between two slices.

use crate::error::{CoreError, Result};
use crate::planning::planner::{bilinear, blend, bracket, check_clock};
use ndarray::{ArrayView2, ArrayView4, Axis};

/// The signal of every level: slices (K, L, H, W) at the instants `t_s`, and the flight's
/// clock. One slice is a signal that does not change (its instant is then never read).
#[derive(Debug, Clone)]
pub struct LevelSignal<'a> {
    /// Signal (K, L, H, W), dB (or the probability of outage, for the reward `Chance`).
    pub slices: ArrayView4<'a, f64>,
    /// (K,) instants of the slices, s, strictly increasing.
    pub t_s: &'a [f64],
    /// Take-off time, s.
    pub t0_s: f64,
    /// Duration of one tick (one horizontal move), s.
    pub dt_s: f64,
}

impl<'a> LevelSignal<'a> {
    /// A signal that does not change: one slice (1, L, H, W), taking off at 0 with ticks of
    /// one second.
    pub fn still(slices: ArrayView4<'a, f64>) -> LevelSignal<'a> {
        LevelSignal {
            slices,
            t_s: &[0.0],
            t0_s: 0.0,
            dt_s: 1.0,
        }
    }
}

impl LevelSignal<'_> {
    /// Checks the shape, the values and the clock.
    pub(super) fn validate(&self) -> Result<()> {
        let (k, l, h, w) = self.slices.dim();
        if k == 0 || l == 0 || h == 0 || w == 0 || self.t_s.len() != k {
            return Err(CoreError::invalid(
                "sinr_db",
                "must be (K, L, H, W), non-empty, with one instant per slice",
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

    /// Whether the signal changes in time (more than one slice).
    pub(super) fn moves(&self) -> bool {
        self.slices.dim().0 > 1
    }

    /// The slices around tick `tick`'s instant and the later one's weight.
    pub(super) fn bracket(&self, tick: usize) -> (usize, usize, f64) {
        if !self.moves() {
            return (0, 0, 0.0);
        }
        bracket(self.t_s, self.t0_s + tick as f64 * self.dt_s)
    }

    /// Slice `k`'s map of level `l`.
    pub(super) fn map(&self, k: usize, l: usize) -> ArrayView2<'_, f64> {
        self.slices
            .index_axis(Axis(0), k)
            .index_axis_move(Axis(0), l)
    }

    /// The signal of level `l` at `(x, y)` (over `extent`) at tick `tick`.
    pub(crate) fn signal(&self, extent: [f64; 4], l: usize, x: f64, y: f64, tick: usize) -> f64 {
        let (k0, k1, f) = self.bracket(tick);
        let v0 = bilinear(&self.map(k0, l), extent, x, y);
        if k0 == k1 {
            v0
        } else {
            blend(v0, bilinear(&self.map(k1, l), extent, x, y), f)
        }
    }
}
