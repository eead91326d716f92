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
use crate::planner::{NavTask, Tap, bilinear, bilinear_taps, blend, bracket, check_clock};
use ndarray::{ArrayView4, Axis};

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
    fn validate(&self, levels: usize) -> Result<()> {
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
enum Source<'b, 'a, 'c> {
    Static(&'b [NavTask<'a>]),
    Time(&'b LevelTimeline<'c>, [f64; 4]),
}

impl Source<'_, '_, '_> {
    /// The slices around tick `tick`'s instant and the later one's weight.
    fn bracket(&self, tick: usize) -> (usize, usize, f64) {
        match self {
            Source::Static(_) => (0, 0, 0.0),
            Source::Time(tl, _) => bracket(tl.t_s, tl.t0_s + tick as f64 * tl.dt_s),
        }
    }

    /// Slice `k`'s map of level `l`.
    fn map(&self, k: usize, l: usize) -> ndarray::ArrayView2<'_, f64> {
        match self {
            Source::Static(levels) => levels[l].sir_db.view(),
            Source::Time(tl, _) => tl.slices.index_axis(Axis(0), k).index_axis_move(Axis(0), l),
        }
    }

    /// Slice `k`'s signal of level `l` at `(x, y)`.
    fn sample(&self, k: usize, l: usize, x: f64, y: f64) -> f64 {
        let extent = match self {
            Source::Static(levels) => levels[l].extent,
            Source::Time(_, extent) => *extent,
        };
        bilinear(&self.map(k, l), extent, x, y)
    }

    /// The signal of level `l` at `(x, y)` at tick `tick`.
    fn signal(&self, l: usize, x: f64, y: f64, tick: usize) -> f64 {
        let (k0, k1, f) = self.bracket(tick);
        let v0 = self.sample(k0, l, x, y);
        if k0 == k1 {
            v0
        } else {
            blend(v0, self.sample(k1, l, x, y), f)
        }
    }
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

/// The stencil input of one row: `B` and `W` of the next tick over the whole stack, the
/// lattice's row length and the row's states.
struct Row<'a> {
    b: &'a [f64],
    w: &'a [f64],
    nj: usize,
    range: std::ops::Range<usize>,
}

/// A vertical move from a row: onto a level (its duration and the landing tick's `B` and `W`
/// from the row's first state on), or out of the band (duration, `B` of the row, penalty).
enum Vertical<'a> {
    Level(f64, &'a [f64], &'a [f64]),
    Out(f64, &'a [f64], f64),
}

/// One row of the backward programme: each state's best move (first best in action order)
/// and its value, or where it is not flown its terminal bonus.
fn stencil_row(
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
struct Sampler {
    slots: [Option<(usize, Vec<f64>)>; 2],
}

impl Sampler {
    /// The samples of slices `k0` and (where it differs) `k1` at the lattice of `taps` (per
    /// level, x then y), `n` points a level.
    fn values(
        &mut self,
        k0: usize,
        k1: usize,
        src: Source<'_, '_, '_>,
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

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{Array2, Array4};

    fn level(s: &Array2<f64>, max_steps: usize) -> NavTask<'_> {
        crate::planner::test_task(s, max_steps)
    }

    /// Every action sequence until the clock reaches the horizon, by recursion.
    fn brute(
        t: &LevelTask<'_>,
        tl: Option<&LevelTimeline<'_>>,
        start: [f64; 2],
        state: (usize, i64, i64),
        tick: usize,
    ) -> f64 {
        if tick >= t.levels[0].max_steps {
            return 0.0;
        }
        (0..LEVEL_MOVES)
            .map(|a| {
                let (r, term, next, _, d) = match tl {
                    Some(tl) => t.transition_in_time(tl, start, state, a, tick),
                    None => t.transition(start, state, a, tick),
                };
                r + if term {
                    0.0
                } else {
                    brute(t, tl, start, next, tick + d)
                }
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    fn maps(seed: usize) -> Vec<Array2<f64>> {
        (0..3)
            .map(|k| {
                Array2::from_shape_fn((3, 4), |(i, j)| {
                    ((i * 7 + j * 3 + 5 * k + seed) % 11) as f64 * 2.0
                })
            })
            .collect()
    }

    #[test]
    fn matches_brute_force_on_three_levels() {
        // Three levels with different signal, a not-flyable cell on the middle one; every
        // start level, horizons 1-7 ticks (climbs of 2 and 1 ticks, descents of 3 and 2).
        let maps = maps(0);
        let mut wall = Array2::<u8>::zeros((3, 4));
        wall[(1, 2)] = 1;
        for max_steps in 1..=7 {
            let mut levels: Vec<NavTask<'_>> = maps.iter().map(|m| level(m, max_steps)).collect();
            levels[1].blocked = Some(wall.view());
            let task = LevelTask {
                levels,
                climb: vec![2, 1],
                descend: vec![3, 2],
            };
            for start in [[0.0, 0.0], [17.0, 12.0], [40.0, 30.0]] {
                for l in 0..3 {
                    let want = brute(&task, None, start, (l, 0, 0), 0);
                    let plan = task.optimal(start, l).unwrap();
                    assert!(
                        (plan.return_ - want).abs() < 1e-9,
                        "{max_steps} {start:?} {l}: {} vs {want}",
                        plan.return_
                    );
                }
            }
        }
    }

    #[test]
    fn matches_brute_force_in_space_time() {
        // Three slices of three levels that differ strongly in time, take-offs and move
        // durations that land between slices and on them.
        let slices = Array4::from_shape_fn((3, 3, 3, 4), |(k, l, i, j)| {
            ((i * 7 + j * 3 + k * 5 + l * 4) % 11) as f64 * 2.0 - 4.0 * k as f64
        });
        let maps: Vec<Array2<f64>> = (0..3)
            .map(|l| {
                slices
                    .index_axis(Axis(0), 0)
                    .index_axis(Axis(0), l)
                    .to_owned()
            })
            .collect();
        let mut wall = Array2::<u8>::zeros((3, 4));
        wall[(2, 1)] = 1;
        let times = [0.0, 1.5, 4.0];
        for (t0, dt) in [(0.0, 1.0), (0.7, 0.6), (-1.0, 2.0)] {
            let tl = LevelTimeline {
                slices: slices.view(),
                t_s: &times,
                t0_s: t0,
                dt_s: dt,
            };
            for max_steps in [1, 3, 6] {
                let mut levels: Vec<NavTask<'_>> =
                    maps.iter().map(|m| level(m, max_steps)).collect();
                levels[2].blocked = Some(wall.view());
                let task = LevelTask {
                    levels,
                    climb: vec![2, 1],
                    descend: vec![1, 3],
                };
                for start in [[0.0, 0.0], [17.0, 12.0], [3.0, 28.0]] {
                    for l in 0..3 {
                        let want = brute(&task, Some(&tl), start, (l, 0, 0), 0);
                        let plan = task.optimal_in_time(&tl, start, l).unwrap();
                        assert!(
                            (plan.return_ - want).abs() < 1e-9,
                            "t0 {t0} dt {dt} {max_steps} {start:?} {l}: {} vs {want}",
                            plan.return_
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn one_slice_is_the_static_plan() {
        let maps = maps(3);
        let levels: Vec<NavTask<'_>> = maps.iter().map(|m| level(m, 8)).collect();
        let task = LevelTask {
            levels,
            climb: vec![2, 3],
            descend: vec![3, 4],
        };
        let stack = Array4::from_shape_fn((1, 3, 3, 4), |(_, l, i, j)| maps[l][(i, j)]);
        let tl = LevelTimeline {
            slices: stack.view(),
            t_s: &[5.0],
            t0_s: 0.0,
            dt_s: 1.0,
        };
        for start in [[0.0, 0.0], [17.0, 12.0]] {
            let a = task.optimal(start, 1).unwrap();
            let b = task.optimal_in_time(&tl, start, 1).unwrap();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn any_level_is_the_best_start_level() {
        let maps = maps(1);
        let levels: Vec<NavTask<'_>> = maps.iter().map(|m| level(m, 6)).collect();
        let task = LevelTask {
            levels,
            climb: vec![2, 2],
            descend: vec![3, 3],
        };
        for start in [[0.0, 0.0], [17.0, 12.0]] {
            let best = (0..3)
                .map(|l| task.optimal(start, l).unwrap().return_)
                .fold(f64::NEG_INFINITY, f64::max);
            let any = task.optimal(start, ANY_LEVEL).unwrap();
            assert!((any.return_ - best).abs() < 1e-9);
        }
    }

    /// The plane (one level), static and in time: brute force over every sequence of the
    /// four moves of the plane, each move's signal read at its landing instant, for horizons
    /// shorter and longer than the area is wide (the table cut at the horizon), from corners
    /// and inside. A vertical move leaves the band: never better than the plane's moves.
    #[test]
    fn one_level_is_the_plane_static_and_in_time() {
        fn plane(
            t: &NavTask<'_>,
            sig: &dyn Fn(f64, f64, usize) -> f64,
            start: [f64; 2],
            i: i64,
            j: i64,
            tick: usize,
        ) -> f64 {
            if tick == t.max_steps {
                return 0.0;
            }
            (0..4)
                .map(|a| {
                    let (r, term, (ti, tj), _) =
                        t.transition_with(start, i, j, a, |x, y| sig(x, y, tick + 1));
                    r + if term {
                        0.0
                    } else {
                        plane(t, sig, start, ti, tj, tick + 1)
                    }
                })
                .fold(f64::NEG_INFINITY, f64::max)
        }
        let slices = ndarray::Array3::from_shape_fn((3, 3, 4), |(k, i, j)| {
            ((i * 5 + j * 3 + 2 * k) % 7) as f64 * 3.0
        });
        let one = slices.clone().insert_axis(Axis(1));
        let s0 = slices.index_axis(Axis(0), 0).to_owned();
        let times = [0.0, 1.5, 4.0];
        for (t0, dt) in [(0.0, 1.0), (0.7, 0.6), (-1.0, 2.0)] {
            let tl = LevelTimeline {
                slices: one.view(),
                t_s: &times,
                t0_s: t0,
                dt_s: dt,
            };
            let src = Source::Time(&tl, [0.0, 40.0, 0.0, 30.0]);
            for max_steps in 1..=7 {
                let flat = level(&s0, max_steps);
                let task = LevelTask {
                    levels: vec![flat.clone()],
                    climb: vec![],
                    descend: vec![],
                };
                for start in [[0.0, 0.0], [40.0, 30.0], [17.0, 12.0], [3.0, 28.0]] {
                    let still = |x: f64, y: f64, _: usize| flat.sir_at(x, y);
                    let moving = |x: f64, y: f64, tick: usize| src.signal(0, x, y, tick);
                    let a = task.optimal(start, 0).unwrap();
                    let want = plane(&flat, &still, start, 0, 0, 0);
                    assert!((a.return_ - want).abs() < 1e-9, "{} vs {want}", a.return_);
                    assert!(a.actions.iter().all(|&m| m < 4) && a.actions.len() <= max_steps);
                    assert_eq!(a.ticks, (0..=a.actions.len()).collect::<Vec<_>>());
                    let b = task.optimal_in_time(&tl, start, 0).unwrap();
                    let want = plane(&flat, &moving, start, 0, 0, 0);
                    assert!(
                        (b.return_ - want).abs() < 1e-9,
                        "t0 {t0} dt {dt}: {} vs {want}",
                        b.return_
                    );
                }
            }
        }
    }

    #[test]
    fn never_enters_a_blocked_pixel_and_goes_round_a_wall() {
        // A wall of not-flyable pixels across column 2 (x 20..30) but for the top row: the
        // shortest way from (5, 5) to (35, 5) is 3 moves east through the wall; the plan goes
        // up to the gap, across and back down, never through.
        let s = Array2::from_elem((4, 4), 20.0);
        let mut wall = Array2::<u8>::zeros((4, 4));
        for i in 0..3 {
            wall[(i, 2)] = 1;
        }
        let mut t = level(&s, 30);
        t.extent = [0.0, 40.0, 0.0, 40.0];
        t.goal = [35.0, 5.0];
        t.blocked = Some(wall.view());
        fn one<'a>(t: &NavTask<'a>) -> LevelTask<'a> {
            LevelTask {
                levels: vec![t.clone()],
                climb: vec![],
                descend: vec![],
            }
        }
        let plan = one(&t).optimal([5.0, 5.0], 0).unwrap();
        assert!(plan.return_ > 0.0, "arrives: {}", plan.return_);
        for p in &plan.path {
            assert!(!t.blocked_at(p[0], p[1]), "entered {p:?}");
        }
        // Up three rows to the gap, across, down three rows: 3 + 3 + 3 = 9 moves.
        assert_eq!(plan.actions.len(), 9);
        // Without the wall, three moves east.
        t.blocked = None;
        assert_eq!(one(&t).optimal([5.0, 5.0], 0).unwrap().actions.len(), 3);
    }

    #[test]
    fn climbs_over_a_wall_when_it_pays() {
        // Level 0 has a wall across the way; level 1 is clear but costs a climb and a
        // descent is never needed (arrival at any level).
        let s = Array2::from_elem((1, 5), 20.0);
        let mut wall = Array2::<u8>::zeros((1, 5));
        wall[(0, 2)] = 1;
        let mk = |s| NavTask {
            extent: [0.0, 50.0, 0.0, 10.0],
            goal: [45.0, 5.0],
            ..level(s, 10)
        };
        let mut low = mk(&s);
        low.blocked = Some(wall.view());
        let task = LevelTask {
            levels: vec![low, mk(&s)],
            climb: vec![2],
            descend: vec![2],
        };
        let plan = task.optimal([5.0, 5.0], 0).unwrap();
        // One climb and four moves east (climbing first or after the first move: a tie).
        let mut sorted = plan.actions.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 0, 0, 0, 4]);
        assert!((plan.return_ - (100.0 - 2.0 - 4.0)).abs() < 1e-9);
        assert_eq!(*plan.ticks.last().unwrap(), 6);
        assert!(
            plan.path
                .iter()
                .all(|p| !(p[2] == 0.0 && (20.0..30.0).contains(&p[0])))
        );
    }

    #[test]
    fn a_climb_lands_on_the_slice_of_its_arrival() {
        // Level 1 is in outage until t = 3 s, then clear; level 0 always in outage. A climb
        // of 3 ticks taken at once lands at t = 3 and pays nothing over its duration; the
        // planner's reward for it equals 3 x the base reward of level 1 at t = 3.
        let mut slices = Array4::<f64>::from_elem((2, 2, 1, 5), -20.0);
        slices[(1, 1, 0, 0)] = 30.0;
        let tl = LevelTimeline {
            slices: slices.view(),
            t_s: &[0.0, 3.0],
            t0_s: 0.0,
            dt_s: 1.0,
        };
        let z = Array2::<f64>::zeros((1, 5));
        let mk = || NavTask {
            extent: [0.0, 50.0, 0.0, 10.0],
            goal: [45.0, 5.0],
            ..level(&z, 3)
        };
        let task = LevelTask {
            levels: vec![mk(), mk()],
            climb: vec![3],
            descend: vec![3],
        };
        let (r, term, next, _, d) = task.transition_in_time(&tl, [5.0, 5.0], (0, 0, 0), 4, 0);
        assert_eq!((term, next, d), (false, (1, 0, 0), 3));
        assert!((r + 3.0).abs() < 1e-12);
    }
}
