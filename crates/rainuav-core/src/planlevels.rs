//! The exact planner with altitude as a decision: the UAV flies on a stack of levels (one
//! signal map and one not-flyable mask per flight altitude) and has six moves, the four of
//! the plane (one step east, north, west, south on its level) and a climb or a descent of
//! one level.
//!
//! **Costs.** A move's reward is its duration, in units of one horizontal move, times the
//! base reward of the level and point it lands on (`-1 - mu shortfall` and the other kinds of
//! [`NavTask::base_reward`]): a horizontal move lasts 1, a climb the gap between the two
//! levels over the climb speed (in horizontal moves' time), a descent the gap over the
//! descent speed. A move past the band lasts as long as the last gap on that side. Leaving the area or
//! the band of levels, or entering a not-flyable cell of a level, ends the flight with the
//! out-of-bounds penalty, as leaving the area does in the plane. The flight arrives when its
//! horizontal position comes within the tolerance of the destination, at any level.
//!
//! **Exact.** A backward programme over (moves left, level, lattice point), as
//! [`crate::planner`]'s in the plane; one level is the plane's task (climbs and descents
//! then leave the band).

use crate::error::{CoreError, Result};
use crate::memory::check_memory_for;
use crate::planner::NavTask;

/// An optimal plan among levels.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelPlan {
    /// Optimal undiscounted return.
    pub return_: f64,
    /// Actions (0 = +x, 1 = +y, 2 = -x, 3 = -y, 4 = climb, 5 = descend).
    pub actions: Vec<u8>,
    /// Positions visited `[x, y, level]`, from the start.
    pub path: Vec<[f64; 3]>,
}

/// The task among levels: one [`NavTask`] per level (the same geometry, rewards and
/// horizon; each its own signal and not-flyable mask), lowest first, and the durations of
/// the climbs and descents between neighbouring levels in horizontal moves.
#[derive(Debug, Clone)]
pub struct LevelTask<'a> {
    /// One task per level, lowest first.
    pub levels: Vec<NavTask<'a>>,
    /// Duration of the climb from level `k` to `k + 1`, in horizontal moves (L - 1 values).
    pub climb: Vec<f64>,
    /// Duration of the descent from level `k + 1` to `k`, in horizontal moves (L - 1 values).
    pub descend: Vec<f64>,
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
            for &d in v {
                crate::error::check_range(name, d, 1e-3, 1e4, "must be in 0.001..1e4 moves")?;
            }
        }
        Ok(())
    }

    /// The transition from level `l`, lattice offset `(i, j)` of `start`, by action `a`:
    /// `(reward, terminal, (level, i, j) after, position after [x, y, level])`.
    pub fn transition(
        &self,
        start: [f64; 2],
        l: usize,
        i: i64,
        j: i64,
        a: usize,
    ) -> (f64, bool, (usize, i64, i64), [f64; 3]) {
        let t = &self.levels[l];
        if a < 4 {
            let (r, term, (ti, tj), p) = t.transition(start, i, j, a);
            return (r, term, (l, ti, tj), [p[0], p[1], l as f64]);
        }
        let (x, y) = (
            start[0] + t.step_m * i as f64,
            start[1] + t.step_m * j as f64,
        );
        // Past the band, the duration of the last gap on that side (1 without one).
        let (to, dur) = if a == 4 {
            let to = Some(l + 1).filter(|&k| k < self.levels.len());
            let gap = l.min(self.climb.len().saturating_sub(1));
            (to, self.climb.get(gap).copied())
        } else {
            (
                l.checked_sub(1),
                self.descend.get(l.saturating_sub(1)).copied(),
            )
        };
        let dur = dur.unwrap_or(1.0);
        match to {
            Some(k) if !self.levels[k].blocked_at(x, y) => {
                let r = dur * self.levels[k].base_reward(self.levels[k].sir_at(x, y));
                (r, false, (k, i, j), [x, y, k as f64])
            }
            // Into a not-flyable cell of the next level: out of bounds there.
            Some(k) => {
                let r = dur * self.levels[k].base_reward(self.levels[k].sir_at(x, y));
                (
                    r - t.out_of_bounds_penalty,
                    true,
                    (k, i, j),
                    [x, y, k as f64],
                )
            }
            // Past the lowest or highest level: out of the band, where it is.
            None => {
                let r = dur * t.base_reward(t.sir_at(x, y));
                (
                    r - t.out_of_bounds_penalty,
                    true,
                    (l, i, j),
                    [x, y, l as f64],
                )
            }
        }
    }

    /// Bytes the plan allocates: per state six rewards and successors, two values, and the
    /// policy (a byte a state a move).
    pub fn plan_bytes(&self, start: [f64; 2]) -> Result<usize> {
        let n = self.levels[0].lattice_points(start)? * self.levels.len();
        let per = LEVEL_MOVES * (size_of::<f64>() + size_of::<usize>()) + 1 + 2 * size_of::<f64>();
        Ok(n.saturating_mul(per.saturating_add(self.levels[0].max_steps)))
    }

    /// The exact optimum from `start` on level `level`; [`ANY_LEVEL`]: on the level (of those
    /// where the start may be flown) whose optimum is best, the take-off's climb left to
    /// the autopilot.
    pub fn optimal(&self, start: [f64; 2], level: usize) -> Result<LevelPlan> {
        self.validate()?;
        let t0 = &self.levels[0];
        t0.check_start(start)?;
        if level != ANY_LEVEL && level >= self.levels.len() {
            return Err(CoreError::invalid(
                "start level",
                format!("must be one of the {} levels", self.levels.len()),
                level,
            ));
        }
        check_memory_for(
            "max_steps",
            "use fewer levels, fewer max_steps or a smaller area",
            self.plan_bytes(start)?,
        )?;
        let (i_lo, i_hi, j_lo, j_hi) = t0.lattice(start);
        let nj = (j_hi - j_lo + 1) as usize;
        let n = t0.lattice_points(start)?;
        let nl = self.levels.len();
        let total = n * nl;
        let idx =
            |l: usize, i: i64, j: i64| l * n + ((i - i_lo) as usize) * nj + (j - j_lo) as usize;
        let [x0, x1, y0, y1] = t0.extent;
        let mut rew = vec![0.0f64; total * LEVEL_MOVES];
        let mut next = vec![usize::MAX; total * LEVEL_MOVES];
        let mut inside = vec![false; total];
        for l in 0..nl {
            for i in i_lo..=i_hi {
                for j in j_lo..=j_hi {
                    let qx = start[0] + t0.step_m * i as f64;
                    let qy = start[1] + t0.step_m * j as f64;
                    let s = idx(l, i, j);
                    inside[s] = !(qx < x0 || qx > x1 || qy < y0 || qy > y1);
                    if !inside[s] {
                        continue;
                    }
                    for a in 0..LEVEL_MOVES {
                        let (r, term, (tl, ti, tj), _) = self.transition(start, l, i, j, a);
                        let k = s * LEVEL_MOVES + a;
                        if term {
                            rew[k] = r;
                        } else if (i_lo..=i_hi).contains(&ti) && (j_lo..=j_hi).contains(&tj) {
                            rew[k] = r;
                            next[k] = idx(tl, ti, tj);
                        } else {
                            // Beyond the table the horizon cuts (as in the plane).
                            rew[k] = f64::NEG_INFINITY;
                        }
                    }
                }
            }
        }
        let t_max = t0.max_steps;
        let mut v_next = vec![0.0f64; total];
        let mut v = vec![0.0f64; total];
        let mut policy = vec![0u8; t_max * total];
        for t in (0..t_max).rev() {
            for s in 0..total {
                if !inside[s] {
                    continue;
                }
                let (mut best, mut best_a) = (f64::NEG_INFINITY, 0u8);
                for a in 0..LEVEL_MOVES {
                    let k = s * LEVEL_MOVES + a;
                    let val = rew[k]
                        + if next[k] == usize::MAX {
                            0.0
                        } else {
                            v_next[next[k]]
                        };
                    if val > best {
                        best = val;
                        best_a = a as u8;
                    }
                }
                v[s] = best;
                policy[t * total + s] = best_a;
            }
            std::mem::swap(&mut v, &mut v_next);
        }
        // The start level: the given one, or the best of those the start may be flown at
        // (`v_next` holds the values with the whole horizon left).
        let level = if level == ANY_LEVEL {
            (0..nl)
                .filter(|&l| !self.levels[l].blocked_at(start[0], start[1]))
                .max_by(|&a, &b| {
                    v_next[idx(a, 0, 0)]
                        .total_cmp(&v_next[idx(b, 0, 0)])
                        .then(b.cmp(&a))
                })
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
        let (mut l, mut i, mut j) = (level, 0i64, 0i64);
        let mut plan = LevelPlan {
            return_: 0.0,
            actions: Vec::new(),
            path: vec![[start[0], start[1], level as f64]],
        };
        for t in 0..t_max {
            let a = policy[t * total + idx(l, i, j)] as usize;
            let (r, term, (tl, ti, tj), pos) = self.transition(start, l, i, j, a);
            plan.actions.push(a as u8);
            plan.path.push(pos);
            plan.return_ += r;
            if term {
                break;
            }
            (l, i, j) = (tl, ti, tj);
        }
        Ok(plan)
    }

    /// Exact plans from many `(start, level)`s in parallel (rayon), refusing before
    /// allocating a batch whose plans in flight at once would not fit in memory.
    pub fn optimal_many(&self, starts: &[([f64; 2], usize)]) -> Result<Vec<LevelPlan>> {
        use rayon::prelude::*;
        self.validate()?;
        let mut largest = 0usize;
        for &(p, _) in starts {
            self.levels[0].check_start(p)?;
            largest = largest.max(self.plan_bytes(p)?);
        }
        let at_once = rayon::current_num_threads().min(starts.len()).max(1);
        check_memory_for(
            "max_steps",
            "use fewer levels, fewer max_steps or a smaller area",
            largest.saturating_mul(at_once),
        )?;
        starts
            .par_iter()
            .map(|&(p, l)| self.optimal(p, l))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner::RewardKind;
    use ndarray::Array2;

    fn level(s: &Array2<f64>, max_steps: usize) -> NavTask<'_> {
        NavTask {
            sir_db: s.view(),
            extent: [0.0, 40.0, 0.0, 30.0],
            goal: [30.0, 20.0],
            step_m: 10.0,
            tol_m: 1.0,
            max_steps,
            mu: 0.5,
            reward: RewardKind::Shortfall,
            sir_min_db: 10.0,
            goal_reward: 100.0,
            out_of_bounds_penalty: 1000.0,
            blocked: None,
        }
    }

    /// Every action sequence up to the horizon, by recursion.
    fn brute(t: &LevelTask<'_>, start: [f64; 2], l: usize, i: i64, j: i64, left: usize) -> f64 {
        if left == 0 {
            return 0.0;
        }
        (0..LEVEL_MOVES)
            .map(|a| {
                let (r, term, (tl, ti, tj), _) = t.transition(start, l, i, j, a);
                r + if term {
                    0.0
                } else {
                    brute(t, start, tl, ti, tj, left - 1)
                }
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn matches_brute_force_on_three_levels() {
        // Three levels with different signal, a not-flyable cell on the middle one; every
        // start level, horizons 1-6.
        let maps: Vec<Array2<f64>> = (0..3)
            .map(|k| {
                Array2::from_shape_fn((3, 4), |(i, j)| ((i * 7 + j * 3 + 5 * k) % 11) as f64 * 2.0)
            })
            .collect();
        let mut wall = Array2::<u8>::zeros((3, 4));
        wall[(1, 2)] = 1;
        for max_steps in 1..=6 {
            let mut levels: Vec<NavTask<'_>> = maps.iter().map(|m| level(m, max_steps)).collect();
            levels[1].blocked = Some(wall.view());
            let task = LevelTask {
                levels,
                climb: vec![1.5, 2.0],
                descend: vec![2.5, 3.0],
            };
            for start in [[0.0, 0.0], [17.0, 12.0], [40.0, 30.0]] {
                for l in 0..3 {
                    let want = brute(&task, start, l, 0, 0, max_steps);
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
    fn any_level_is_the_best_start_level() {
        let maps: Vec<Array2<f64>> = (0..3)
            .map(|k| {
                Array2::from_shape_fn((3, 4), |(i, j)| ((i * 3 + j * 5 + 7 * k) % 11) as f64 * 2.0)
            })
            .collect();
        let levels: Vec<NavTask<'_>> = maps.iter().map(|m| level(m, 6)).collect();
        let task = LevelTask {
            levels,
            climb: vec![2.0, 2.0],
            descend: vec![3.0, 3.0],
        };
        for start in [[0.0, 0.0], [17.0, 12.0]] {
            let best = (0..3)
                .map(|l| task.optimal(start, l).unwrap().return_)
                .fold(f64::NEG_INFINITY, f64::max);
            let any = task.optimal(start, ANY_LEVEL).unwrap();
            assert!((any.return_ - best).abs() < 1e-9);
        }
    }

    #[test]
    fn one_level_is_the_plane() {
        // The same return as the planner in the plane (a vertical move leaves the band).
        let s = Array2::from_shape_fn((3, 4), |(i, j)| ((i * 5 + j * 3) % 7) as f64 * 3.0);
        let plane = level(&s, 9);
        let task = LevelTask {
            levels: vec![plane.clone()],
            climb: vec![],
            descend: vec![],
        };
        for start in [[0.0, 0.0], [17.0, 12.0]] {
            let a = plane.optimal(start).unwrap();
            let b = task.optimal(start, 0).unwrap();
            assert!((a.return_ - b.return_).abs() < 1e-9);
            assert_eq!(a.actions, b.actions);
        }
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
            climb: vec![2.0],
            descend: vec![2.0],
        };
        let plan = task.optimal([5.0, 5.0], 0).unwrap();
        // One climb and four moves east (climbing first or after the first move: a tie).
        let mut sorted = plan.actions.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 0, 0, 0, 4]);
        assert!((plan.return_ - (100.0 - 2.0 - 4.0)).abs() < 1e-9);
        assert!(
            plan.path
                .iter()
                .all(|p| !(p[2] == 0.0 && (20.0..30.0).contains(&p[0])))
        );
    }
}
