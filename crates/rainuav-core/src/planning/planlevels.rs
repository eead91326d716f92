//! The exact planner with altitude as a decision: the UAV flies on a stack of levels (one
//! signal map and one not-flyable mask per flight altitude) and has six moves, the four of
//! the plane (one step east, north, west, south on its level) and a climb or a descent of
//! one level; the signal is one array over (time, level, north, east), [`LevelSignal`]: one
//! slice for a signal that does not change, several for a storm that moves).
//!
//! **Clock.** The flight's clock ticks once per horizontal move (`dt_s` seconds). A climb
//! from level `k` to `k + 1` lasts `climb[k]` ticks and the descent back `descend[k]`, whole
//! numbers (the caller rounds the gap over the vertical speed up to whole moves). A move that
//! starts at tick `tau` and lasts `d` ticks lands at tick `tau + d`, and reads the signal at
//! that instant (`t0_s + (tau + d) dt_s`; between two slices linear in time, as
//! [`crate::planning::planner::bracket`]). The horizon `max_steps` is in ticks: the flight is cut when its
//! clock reaches it (one level: `max_steps` moves, the plane's horizon).
//!
//! **Costs.** A move's reward is its duration in ticks times the base reward of the level,
//! point and instant it lands on (`-1 - mu shortfall` and the other kinds of
//! [`crate::planning::planner::NavTask::base_reward`]). A move past the band lasts as long as the last gap on that side
//! (one tick without one). Leaving the area or the band of levels, or entering a not-flyable
//! cell of a level, ends the flight with the out-of-bounds penalty, as leaving the area does
//! in the plane. The flight arrives when its horizontal position comes within the tolerance
//! of the destination, at any level.
//!
//! **Exact.** A backward programme over (tick, level, lattice point). A move's reward and
//! terminal bonus depend only on where and when it lands, so the programme keeps, per tick,
//! `B` (the base reward at every level and point) and `W` (the value there, or the terminal
//! bonus where a move into it ends the flight); a state's value is the best over its six
//! moves of `d B[tau + d][target] + W[tau + d][target]`, read at fixed offsets of the lattice
//! (a stencil the compiler vectorises). Only the last `max(d) + 1` ticks are kept.

use crate::error::{CoreError, Result};
use crate::memory::check_memory_for;
use crate::planning::planner::{NavTask, Tap, blend};
use ndarray::{ArrayView2, ArrayView3, Axis};

mod signal;
mod solve;
mod stencil;

pub use signal::LevelSignal;
use stencil::{Row, Sampler, Vertical, stencil_row};

const MEMORY_HINT: &str = "use fewer levels, fewer max_steps, a larger step_m or a smaller area";

/// An optimal plan among levels.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelPlan {
    /// Optimal undiscounted return.
    pub return_: f64,
    /// Actions (0 = +x, 1 = +y, 2 = -x, 3 = -y, 4 = climb, 5 = descend).
    pub actions: Vec<u8>,
    /// Positions visited `[x, y, level]`, from the start.
    pub path: Vec<[f64; 3]>,
    /// The tick each position is reached at (0 at the start).
    pub ticks: Vec<usize>,
}

/// The task among levels: one [`NavTask`] (the geometry, rewards and horizon every level
/// shares), the signal of every level ([`LevelSignal`], lowest level first), each level's
/// not-flyable mask, and the durations of the climbs and descents between neighbouring levels
/// in ticks (horizontal moves).
#[derive(Debug, Clone)]
pub struct LevelTask<'a> {
    /// The geometry, rewards and horizon.
    pub task: NavTask,
    /// The signal (K, L, H, W) and the flight's clock.
    pub signal: LevelSignal<'a>,
    /// Pixels a UAV may not enter (non-zero), (L, H', W') over the area (terrain or obstacles
    /// within the clearance of each level's height): a move into one is a move out of the
    /// area.
    pub blocked: Option<ArrayView3<'a, u8>>,
    /// Ticks of the climb from level `k` to `k + 1` (L - 1 values, each >= 1).
    pub climb: Vec<usize>,
    /// Ticks of the descent from level `k + 1` to `k` (L - 1 values, each >= 1).
    pub descend: Vec<usize>,
}

/// The number of moves.
pub const LEVEL_MOVES: usize = 6;

/// A start level meaning "the best level" ([`LevelTask::optimal`]).
pub const ANY_LEVEL: usize = usize::MAX;

impl LevelTask<'_> {
    /// The number of levels.
    pub fn levels(&self) -> usize {
        self.signal.slices.dim().1
    }

    /// Level `l`'s not-flyable mask.
    fn mask(&self, l: usize) -> Option<ArrayView2<'_, u8>> {
        self.blocked.as_ref().map(|b| b.index_axis(Axis(0), l))
    }

    /// Whether `(x, y)` may not be entered on level `l`.
    fn blocked_at(&self, l: usize, x: f64, y: f64) -> bool {
        self.task.blocked_at(self.mask(l).as_ref(), x, y)
    }

    fn validate(&self) -> Result<()> {
        self.task.validate()?;
        self.signal.validate()?;
        let nl = self.levels();
        if let Some(b) = &self.blocked {
            let (l, h, w) = b.dim();
            if l != nl || h == 0 || w == 0 {
                return Err(CoreError::invalid(
                    "blocked",
                    format!("must hold one non-empty mask a level ({nl})"),
                    format!("{:?}", b.dim()),
                ));
            }
        }
        for (name, v) in [("climb", &self.climb), ("descend", &self.descend)] {
            if v.len() + 1 != nl {
                return Err(CoreError::invalid(
                    name,
                    format!(
                        "must hold one duration between each two levels ({})",
                        nl - 1
                    ),
                    v.len(),
                ));
            }
            if let Some(&d) = v.iter().find(|&&d| !(1..=10_000).contains(&d)) {
                return Err(CoreError::invalid(name, "must be in 1..10000 ticks", d));
            }
        }
        Ok(())
    }

    /// Ticks of the climb (`up`) or descent from level `l`: past the band, the last gap on
    /// that side (one tick without one).
    fn duration(&self, l: usize, up: bool) -> usize {
        let v = if up { &self.climb } else { &self.descend };
        let gap = if up {
            l.min(v.len().saturating_sub(1))
        } else {
            l.saturating_sub(1)
        };
        v.get(gap).copied().unwrap_or(1)
    }

    /// The transition from level `l`, lattice offset `(i, j)` of `start`, by action `a`, the
    /// move starting at tick `tick`: `(reward, terminal, (level, i, j) after, position after
    /// [x, y, level], duration in ticks)`; the signal read at the landing tick.
    pub fn transition(
        &self,
        start: [f64; 2],
        (l, i, j): (usize, i64, i64),
        a: usize,
        tick: usize,
    ) -> (f64, bool, (usize, i64, i64), [f64; 3], usize) {
        let (t, sig) = (&self.task, &self.signal);
        if a < 4 {
            let (r, term, (ti, tj), p) =
                t.transition_with(self.mask(l).as_ref(), (start, i, j), a, |x, y| {
                    sig.signal(t.extent, l, x, y, tick + 1)
                });
            return (r, term, (l, ti, tj), [p[0], p[1], l as f64], 1);
        }
        let (x, y) = (
            start[0] + t.step_m * i as f64,
            start[1] + t.step_m * j as f64,
        );
        let up = a == 4;
        let d = self.duration(l, up);
        let to = if up {
            Some(l + 1).filter(|&k| k < self.levels())
        } else {
            l.checked_sub(1)
        };
        let land = tick + d;
        // Past the lowest or highest level: out of the band, where it is.
        let (k, out) = match to {
            Some(k) => (k, self.blocked_at(k, x, y)),
            None => (l, true),
        };
        let r = d as f64 * t.base_reward(sig.signal(t.extent, k, x, y, land));
        let r = if out { r - t.out_of_bounds_penalty } else { r };
        (r, out, (k, i, j), [x, y, k as f64], d)
    }

    fn longest(&self) -> usize {
        self.climb
            .iter()
            .chain(&self.descend)
            .copied()
            .max()
            .unwrap_or(1)
            .max(1)
    }

    /// Bytes the plan allocates: per state the policy (a byte a tick), the base rewards and
    /// values of the last `max(d) + 1` ticks, two slices' samples, the step's stencil input
    /// and the flags.
    pub fn plan_bytes(&self, start: [f64; 2]) -> Result<usize> {
        let total = self
            .task
            .lattice_points(start)?
            .saturating_mul(self.levels());
        let keep = self.longest() + 1;
        let per = (2 * keep + 5) * size_of::<f64>() + 1;
        Ok(total.saturating_mul(per.saturating_add(self.task.max_steps)))
    }

    /// The exact optimum from `start` on level `level`; [`ANY_LEVEL`]: on the level (of those
    /// where the start may be flown) whose optimum is best, the take-off's climb left to the
    /// autopilot.
    pub fn optimal(&self, start: [f64; 2], level: usize) -> Result<LevelPlan> {
        self.validate()?;
        self.solve(start, level)
    }

    /// Exact plans from many `(start, level)`s in parallel (rayon), refusing before
    /// allocating a batch whose plans in flight at once would not fit in memory.
    pub fn optimal_many(&self, starts: &[([f64; 2], usize)]) -> Result<Vec<LevelPlan>> {
        use rayon::prelude::*;
        self.validate()?;
        let mut largest = 0usize;
        for &(p, _) in starts {
            self.task.check_start(p)?;
            largest = largest.max(self.plan_bytes(p)?);
        }
        let at_once = rayon::current_num_threads().min(starts.len()).max(1);
        check_memory_for("max_steps", MEMORY_HINT, largest.saturating_mul(at_once))?;
        starts.par_iter().map(|&(p, l)| self.solve(p, l)).collect()
    }
}

#[cfg(test)]
mod tests;
