//! The exact planner with altitude as a decision: the UAV flies on a stack of levels (one
//! signal map and one not-flyable mask per flight altitude) and has six moves, the four of
//! the plane (one step east, north, west, south on its level) and a climb or a descent of
//! one level; the signal may change in time (a storm that moves, [`LevelTimeline`]).
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
//! [`NavTask::base_reward`]). A move past the band lasts as long as the last gap on that side
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

mod signal;
mod solve;
mod stencil;

pub use signal::LevelTimeline;
use signal::Source;
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

/// The task among levels: one [`NavTask`] per level (the same geometry, rewards and
/// horizon; each its own signal and not-flyable mask), lowest first, and the durations of
/// the climbs and descents between neighbouring levels in ticks (horizontal moves).
#[derive(Debug, Clone)]
pub struct LevelTask<'a> {
    /// One task per level, lowest first.
    pub levels: Vec<NavTask<'a>>,
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
    fn validate(&self) -> Result<()> {
        let Some(first) = self.levels.first() else {
            return Err(CoreError::invalid(
                "levels",
                "must hold at least one level",
                0,
            ));
        };
        for t in &self.levels {
            t.validate()?;
            if t.extent != first.extent
                || t.goal != first.goal
                || t.step_m != first.step_m
                || t.max_steps != first.max_steps
            {
                return Err(CoreError::invalid(
                    "levels",
                    "must share the area, destination, step and horizon",
                    "a level differs",
                ));
            }
        }
        for (name, v) in [("climb", &self.climb), ("descend", &self.descend)] {
            if v.len() + 1 != self.levels.len() {
                return Err(CoreError::invalid(
                    name,
                    format!(
                        "must hold one duration between each two levels ({})",
                        self.levels.len() - 1
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
    fn step(
        &self,
        src: Source<'_, '_, '_>,
        start: [f64; 2],
        (l, i, j): (usize, i64, i64),
        a: usize,
        tick: usize,
    ) -> (f64, bool, (usize, i64, i64), [f64; 3], usize) {
        let t = &self.levels[l];
        if a < 4 {
            let (r, term, (ti, tj), p) =
                t.transition_with(start, i, j, a, |x, y| src.signal(l, x, y, tick + 1));
            return (r, term, (l, ti, tj), [p[0], p[1], l as f64], 1);
        }
        let (x, y) = (
            start[0] + t.step_m * i as f64,
            start[1] + t.step_m * j as f64,
        );
        let up = a == 4;
        let d = self.duration(l, up);
        let to = if up {
            Some(l + 1).filter(|&k| k < self.levels.len())
        } else {
            l.checked_sub(1)
        };
        let land = tick + d;
        match to {
            Some(k) => {
                let r = d as f64 * self.levels[k].base_reward(src.signal(k, x, y, land));
                if self.levels[k].blocked_at(x, y) {
                    // Into a not-flyable cell of the next level: out of bounds there.
                    (
                        r - t.out_of_bounds_penalty,
                        true,
                        (k, i, j),
                        [x, y, k as f64],
                        d,
                    )
                } else {
                    (r, false, (k, i, j), [x, y, k as f64], d)
                }
            }
            // Past the lowest or highest level: out of the band, where it is.
            None => {
                let r = d as f64 * t.base_reward(src.signal(l, x, y, land));
                (
                    r - t.out_of_bounds_penalty,
                    true,
                    (l, i, j),
                    [x, y, l as f64],
                    d,
                )
            }
        }
    }

    /// The static task's transition (the signal of each level's map): see [`Self::step`].
    pub fn transition(
        &self,
        start: [f64; 2],
        state: (usize, i64, i64),
        a: usize,
        tick: usize,
    ) -> (f64, bool, (usize, i64, i64), [f64; 3], usize) {
        self.step(Source::Static(&self.levels), start, state, a, tick)
    }

    /// The transition with the signal of `tl`: see [`Self::step`].
    pub fn transition_in_time(
        &self,
        tl: &LevelTimeline<'_>,
        start: [f64; 2],
        state: (usize, i64, i64),
        a: usize,
        tick: usize,
    ) -> (f64, bool, (usize, i64, i64), [f64; 3], usize) {
        self.step(
            Source::Time(tl, self.levels[0].extent),
            start,
            state,
            a,
            tick,
        )
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
        let total = self.levels[0]
            .lattice_points(start)?
            .saturating_mul(self.levels.len());
        let keep = self.longest() + 1;
        let per = (2 * keep + 5) * size_of::<f64>() + 1;
        Ok(total.saturating_mul(per.saturating_add(self.levels[0].max_steps)))
    }

    /// The exact optimum from `start` on level `level` on each level's map; [`ANY_LEVEL`]:
    /// on the level (of those where the start may be flown) whose optimum is best, the
    /// take-off's climb left to the autopilot.
    pub fn optimal(&self, start: [f64; 2], level: usize) -> Result<LevelPlan> {
        self.validate()?;
        self.solve(Source::Static(&self.levels), start, level)
    }

    /// The exact optimum when the signal of every level changes in time (`tl`).
    pub fn optimal_in_time(
        &self,
        tl: &LevelTimeline<'_>,
        start: [f64; 2],
        level: usize,
    ) -> Result<LevelPlan> {
        self.validate()?;
        tl.validate(self.levels.len())?;
        self.solve(Source::Time(tl, self.levels[0].extent), start, level)
    }

    /// Exact plans from many `(start, level)`s in parallel (rayon), on each level's map or
    /// in time (`tl`), refusing before allocating a batch whose plans in flight at once
    /// would not fit in memory.
    pub fn optimal_many(
        &self,
        tl: Option<&LevelTimeline<'_>>,
        starts: &[([f64; 2], usize)],
    ) -> Result<Vec<LevelPlan>> {
        use rayon::prelude::*;
        self.validate()?;
        if let Some(tl) = tl {
            tl.validate(self.levels.len())?;
        }
        let mut largest = 0usize;
        for &(p, _) in starts {
            self.levels[0].check_start(p)?;
            largest = largest.max(self.plan_bytes(p)?);
        }
        let at_once = rayon::current_num_threads().min(starts.len()).max(1);
        check_memory_for("max_steps", MEMORY_HINT, largest.saturating_mul(at_once))?;
        let src = match tl {
            Some(tl) => Source::Time(tl, self.levels[0].extent),
            None => Source::Static(&self.levels),
        };
        starts
            .par_iter()
            .map(|&(p, l)| self.solve(src, p, l))
            .collect()
    }
}

#[cfg(test)]
mod tests;
