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
//! [`crate::planner::bracket`]). The horizon `max_steps` is in ticks: the flight is cut when its
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
use crate::planner::{NavTask, Tap, blend};

mod signal;
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

    /// The backward programme (module docs) and the replay of its policy.
    fn solve(&self, src: Source<'_, '_, '_>, start: [f64; 2], level: usize) -> Result<LevelPlan> {
        let t0 = &self.levels[0];
        t0.check_start(start)?;
        let nl = self.levels.len();
        if level != ANY_LEVEL && level >= nl {
            return Err(CoreError::invalid(
                "start level",
                format!("must be one of the {nl} levels"),
                level,
            ));
        }
        check_memory_for("max_steps", MEMORY_HINT, self.plan_bytes(start)?)?;
        let (i_lo, i_hi, j_lo, j_hi) = t0.lattice(start);
        let ni = (i_hi - i_lo + 1) as usize;
        let nj = (j_hi - j_lo + 1) as usize;
        let n = ni * nj;
        let total = n * nl;
        let [x0, x1, y0, y1] = t0.extent;
        // The lattice's coordinates along each axis (clamped where a move into them leaves
        // the area: the position its reward is read at).
        let xs: Vec<f64> = (i_lo..=i_hi)
            .map(|i| start[0] + t0.step_m * i as f64)
            .collect();
        let ys: Vec<f64> = (j_lo..=j_hi)
            .map(|j| start[1] + t0.step_m * j as f64)
            .collect();
        // Per state: whether it is flown on (live), else what a move into it adds.
        let mut live = vec![false; total];
        let mut extra = vec![0.0f64; total];
        for (ii, &qx) in xs.iter().enumerate() {
            for (jj, &qy) in ys.iter().enumerate() {
                let out = qx < x0 || qx > x1 || qy < y0 || qy > y1;
                let ring = ii == 0 || jj == 0 || ii + 1 == ni || jj + 1 == nj;
                let goal = (qx - t0.goal[0]).hypot(qy - t0.goal[1]) <= t0.tol_m;
                for (l, task) in self.levels.iter().enumerate() {
                    let s = l * n + ii * nj + jj;
                    extra[s] = if out || task.blocked_at(qx, qy) {
                        -task.out_of_bounds_penalty
                    } else if goal {
                        task.goal_reward
                    } else if ring {
                        // Beyond the table the horizon cuts (as in the plane): unreachable.
                        f64::NEG_INFINITY
                    } else {
                        live[s] = true;
                        0.0
                    };
                }
            }
        }
        let keep = self.longest() + 1;
        let t_max = t0.max_steps;
        let still = matches!(src, Source::Static(_));
        // B and W of tick `tau` sit in slot `tau % keep` (B in slot 0 for a static signal).
        let mut b_ring = vec![vec![0.0f64; total]; if still { 1 } else { keep }];
        let mut w_ring = vec![extra.clone(); keep];
        let b_slot = |tau: usize| if still { 0 } else { tau % keep };
        let taps: Vec<(Vec<Tap>, Vec<Tap>)> = (0..nl)
            .map(|l| {
                let (h, w) = src.map(0, l).dim();
                let tx = xs.iter().map(|&x| Tap::new(x.clamp(x0, x1), x0, x1, w));
                let ty = ys.iter().map(|&y| Tap::new(y.clamp(y0, y1), y0, y1, h));
                (tx.collect(), ty.collect())
            })
            .collect();
        let mut sampler = Sampler::default();
        let mut fill_b = |tau: usize, b: &mut [f64]| {
            let (k0, k1, f) = src.bracket(tau);
            let (v0, v1) = sampler.values(k0, k1, src, &taps, n);
            for (l, task) in self.levels.iter().enumerate() {
                let (b, v0) = (&mut b[l * n..(l + 1) * n], &v0[l * n..(l + 1) * n]);
                match v1 {
                    None => task.base_rewards(v0.iter().copied(), b),
                    Some(v1) => {
                        let v1 = &v1[l * n..(l + 1) * n];
                        let sig = v0.iter().zip(v1).map(|(a, c)| blend(*a, *c, f));
                        task.base_rewards(sig, b);
                    }
                }
            }
        };
        // Ticks at and past the horizon: value 0 (W holds the terminal bonus already).
        if still {
            fill_b(0, &mut b_ring[0]);
        } else {
            for tau in (t_max..t_max + keep - 1).rev() {
                fill_b(tau, &mut b_ring[tau % keep]);
            }
        }
        let mut policy = vec![0u8; t_max * total];
        let mut at_start = vec![f64::NEG_INFINITY; nl];
        let pen = t0.out_of_bounds_penalty;
        let (si, sj) = ((-i_lo) as usize, (-j_lo) as usize);
        for tau in (0..t_max).rev() {
            let mut w_out = std::mem::take(&mut w_ring[tau % keep]);
            let (b1, w1) = (&b_ring[b_slot(tau + 1)], &w_ring[(tau + 1) % keep]);
            let pol = &mut policy[tau * total..(tau + 1) * total];
            for l in 0..nl {
                // The vertical moves from level l: (duration, B and W at their landing, the
                // level they land on, or None past the band).
                let vertical = [true, false].map(|up| {
                    let d = self.duration(l, up);
                    let to = if up {
                        Some(l + 1).filter(|&k| k < nl)
                    } else {
                        l.checked_sub(1)
                    };
                    (
                        d as f64,
                        &b_ring[b_slot(tau + d)],
                        &w_ring[(tau + d) % keep],
                        to,
                    )
                });
                for ii in 1..ni - 1 {
                    // Only the states within tau moves of the start can be flown at tick tau.
                    let r = tau as i64 - (ii as i64 - si as i64).abs();
                    if r < 0 {
                        continue;
                    }
                    let lo = (sj as i64 - r).max(1) as usize;
                    let hi = ((sj as i64 + r) as usize).min(nj - 2);
                    let base = l * n + ii * nj;
                    let row = base + lo..base + hi + 1;
                    stencil_row(
                        Row {
                            b: b1,
                            w: w1,
                            nj,
                            range: row.clone(),
                        },
                        vertical.map(|(d, b, w, to)| match to {
                            Some(k) => Vertical::Level(
                                d,
                                &b[row.start + k * n - l * n..],
                                &w[row.start + k * n - l * n..],
                            ),
                            None => Vertical::Out(d, &b[row.clone()], pen),
                        }),
                        (&live[row.clone()], &extra[row.clone()]),
                        (&mut w_out[row.clone()], &mut pol[row.clone()]),
                    );
                    if tau == 0 && ii == si && (lo..=hi).contains(&sj) {
                        at_start[l] = w_out[base + sj];
                        if !live[base + sj] {
                            at_start[l] = f64::NEG_INFINITY;
                        }
                    }
                }
            }
            w_ring[tau % keep] = w_out;
            if !still && tau > 0 {
                fill_b(tau, &mut b_ring[tau % keep]);
            }
        }
        // The start level: the given one, or the best of those the start may be flown at.
        let level = if level == ANY_LEVEL {
            (0..nl)
                .filter(|&l| !self.levels[l].blocked_at(start[0], start[1]))
                .max_by(|&a, &b| at_start[a].total_cmp(&at_start[b]).then(b.cmp(&a)))
                .ok_or_else(|| {
                    CoreError::invalid(
                        "start_m",
                        "is not flyable at any level",
                        format!("{start:?}"),
                    )
                })?
        } else {
            level
        };
        // Replay, summing each move's reward as the environment does.
        let idx =
            |l: usize, i: i64, j: i64| l * n + ((i - i_lo) as usize) * nj + (j - j_lo) as usize;
        let mut state = (level, 0i64, 0i64);
        let mut tick = 0usize;
        let mut plan = LevelPlan {
            return_: 0.0,
            actions: Vec::new(),
            path: vec![[start[0], start[1], level as f64]],
            ticks: vec![0],
        };
        while tick < t_max {
            let a = policy[tick * total + idx(state.0, state.1, state.2)] as usize;
            let (r, term, next, pos, d) = self.step(src, start, state, a, tick);
            tick += d;
            plan.actions.push(a as u8);
            plan.path.push(pos);
            plan.ticks.push(tick);
            plan.return_ += r;
            if term {
                break;
            }
            state = next;
        }
        Ok(plan)
    }
}

#[cfg(test)]
mod tests;
