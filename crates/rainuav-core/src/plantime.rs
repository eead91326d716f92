//! The exact planner in space-time: the navigation MDP of `planner` on a signal that changes
//! in time (a storm that moves).
//!
//! Move `t` (0-based) of a flight that takes off at `t0_s` ends at `tau_t = t0_s + (t + 1) dt_s`
//! (`dt_s = step_m / speed_m_s`), and earns the base reward of the signal at the new position
//! and that instant. The signal at `(x, y, tau)` is the bilinear value of the two slices around
//! `tau`, blended linearly in time (held before the first slice and after the last), operation
//! for operation as `rainuav.nav.field.SignalSeries`. The backward programme over (steps left,
//! lattice point) was already indexed by time; only its rewards now depend on the step, so each
//! step's rewards are one pass over the lattice's signal values of the two slices around its
//! instant (each slice sampled once per plan).

use crate::error::{CoreError, Result};
use crate::memory::check_memory_for;
use crate::planner::{MOVES, NavTask, Plan, bilinear};
use ndarray::ArrayView3;

const MEMORY_HINT: &str = "each plan keeps max_steps bytes per lattice point; use fewer max_steps, a larger step_m \
     or a smaller area";

/// The signal in time and the flight's clock.
#[derive(Debug, Clone)]
pub struct Timeline<'a> {
    /// Signal (K, H, W), dB, at the instants `t_s`.
    pub slices: ArrayView3<'a, f64>,
    /// (K,) instants of the slices, s, strictly increasing.
    pub t_s: &'a [f64],
    /// Take-off time, s.
    pub t0_s: f64,
    /// Duration of one move, s.
    pub dt_s: f64,
}

impl Timeline<'_> {
    /// Checks the slices and the clock.
    pub fn validate(&self) -> Result<()> {
        let (k, h, w) = self.slices.dim();
        if k == 0 || h == 0 || w == 0 || self.t_s.len() != k {
            return Err(CoreError::invalid(
                "sinr_db",
                "must be (K, H, W), non-empty, with one instant per slice in t_s",
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

    /// The instant move `t` (0-based) ends at.
    pub fn time_of_move(&self, t: usize) -> f64 {
        self.t0_s + (t + 1) as f64 * self.dt_s
    }

    /// The slices around `tau` and the weight of the later one: `(k0, k1, f)`, `k0 == k1` at
    /// a slice's own instant and beyond the first or the last.
    pub fn bracket(&self, tau: f64) -> (usize, usize, f64) {
        bracket(self.t_s, tau)
    }

    /// The signal at `(x, y)` and the instant `tau`.
    pub fn signal_at(&self, extent: [f64; 4], x: f64, y: f64, tau: f64) -> f64 {
        let (k0, k1, f) = self.bracket(tau);
        let v0 = bilinear(&self.slices.index_axis(ndarray::Axis(0), k0), extent, x, y);
        if k0 == k1 {
            return v0;
        }
        let v1 = bilinear(&self.slices.index_axis(ndarray::Axis(0), k1), extent, x, y);
        blend(v0, v1, f)
    }
}

/// Checks a clock: instants finite and strictly increasing, a finite take-off, a move's
/// duration finite and > 0.
pub(crate) fn check_clock(t_s: &[f64], t0_s: f64, dt_s: f64) -> Result<()> {
    let increasing = t_s.windows(2).all(|p| p[1] > p[0]);
    if !increasing || t_s.iter().any(|v| !v.is_finite()) {
        return Err(CoreError::invalid(
            "t_s",
            "must be finite and strictly increasing",
            format!("{} instants", t_s.len()),
        ));
    }
    if !t0_s.is_finite() || t0_s.abs() > 1e12 {
        return Err(CoreError::invalid("t0_s", "must be finite", t0_s));
    }
    if !(dt_s.is_finite() && dt_s > 0.0 && dt_s < 1e9) {
        return Err(CoreError::invalid("dt_s", "must be finite and > 0", dt_s));
    }
    Ok(())
}

/// The slices of the instants `t` (increasing) around `tau` and the weight of the later one:
/// `(k0, k1, f)`, `k0 == k1` at a slice's own instant and beyond the first or the last.
pub(crate) fn bracket(t: &[f64], tau: f64) -> (usize, usize, f64) {
    let k = t.partition_point(|&v| v < tau);
    if k < t.len() && t[k] == tau {
        return (k, k, 0.0);
    }
    if k == 0 {
        return (0, 0, 0.0);
    }
    if k == t.len() {
        return (k - 1, k - 1, 0.0);
    }
    (k - 1, k, (tau - t[k - 1]) / (t[k] - t[k - 1]))
}

/// Linear in time between two slices' values.
pub(crate) fn blend(v0: f64, v1: f64, f: f64) -> f64 {
    (1.0 - f) * v0 + f * v1
}

/// A slice's signal at every point a plan's moves end on, kept for the next steps.
struct SliceValues {
    k: usize,
    values: Vec<f64>,
}

impl NavTask<'_> {
    /// Bytes the space-time plan from `start` allocates: the static plan's
    /// (:meth:`plan_bytes`), plus per lattice point and move a target and a bonus, and two
    /// slices' values and the step's rewards per point a move ends on.
    pub fn plan_bytes_in_time(&self, start: [f64; 2]) -> Result<usize> {
        let n = self.lattice_points(start)?;
        Ok(self
            .plan_bytes(start)?
            .saturating_add(n.saturating_mul(4 * 16 + 3 * 8 * 2)))
    }

    /// Exact space-time plans from many starts, in parallel; memory checked first (one plan
    /// in flight per worker thread).
    pub fn optimal_many_in_time(
        &self,
        tl: &Timeline<'_>,
        starts: &[[f64; 2]],
    ) -> Result<Vec<Plan>> {
        use rayon::prelude::*;
        self.validate()?;
        tl.validate()?;
        let mut largest = 0usize;
        for &p in starts {
            self.check_start(p)?;
            largest = largest.max(self.plan_bytes_in_time(p)?);
        }
        let at_once = rayon::current_num_threads().min(starts.len()).max(1);
        check_memory_for("max_steps", MEMORY_HINT, largest.saturating_mul(at_once))?;
        starts
            .par_iter()
            .map(|&p| self.optimal_in_time(tl, p))
            .collect()
    }

    /// The exact optimum from `start` when the signal changes in time (module docs).
    pub fn optimal_in_time(&self, tl: &Timeline<'_>, start: [f64; 2]) -> Result<Plan> {
        self.validate()?;
        tl.validate()?;
        self.check_start(start)?;
        check_memory_for("max_steps", MEMORY_HINT, self.plan_bytes_in_time(start)?)?;
        let [x0, x1, y0, y1] = self.extent;
        let (i_lo, i_hi, j_lo, j_hi) = self.lattice(start);
        let nj = (j_hi - j_lo + 1) as usize;
        let n = ((i_hi - i_lo + 1) as usize) * nj;
        let idx = |i: i64, j: i64| ((i - i_lo) as usize) * nj + (j - j_lo) as usize;
        // Points moves end on: every lattice point, then each terminal move's own end (the
        // clamped position of a move out of the area, or an arrival).
        let mut points: Vec<[f64; 2]> = Vec::with_capacity(n);
        for i in i_lo..=i_hi {
            for j in j_lo..=j_hi {
                points.push([
                    start[0] + self.step_m * i as f64,
                    start[1] + self.step_m * j as f64,
                ]);
            }
        }
        // Per state and move: the point it ends on, what is added to its base reward, and
        // the next state (usize::MAX: terminal).
        let mut target = vec![0usize; n * 4];
        let mut bonus = vec![0.0f64; n * 4];
        let mut next = vec![usize::MAX; n * 4];
        let mut inside = vec![false; n];
        for i in i_lo..=i_hi {
            for j in j_lo..=j_hi {
                let s = idx(i, j);
                let [qx, qy] = points[s];
                inside[s] = !(qx < x0 || qx > x1 || qy < y0 || qy > y1);
                if !inside[s] {
                    continue;
                }
                for (a, &(di, dj)) in MOVES.iter().enumerate() {
                    let (ti, tj) = (i + di, j + dj);
                    let (px, py) = (
                        start[0] + self.step_m * ti as f64,
                        start[1] + self.step_m * tj as f64,
                    );
                    let out = px < x0 || px > x1 || py < y0 || py > y1;
                    let arrived =
                        !out && (px - self.goal[0]).hypot(py - self.goal[1]) <= self.tol_m;
                    let k = s * 4 + a;
                    if out || arrived {
                        target[k] = points.len();
                        points.push([px.clamp(x0, x1), py.clamp(y0, y1)]);
                        bonus[k] = if out {
                            -self.out_of_bounds_penalty
                        } else {
                            self.goal_reward
                        };
                    } else if (i_lo..=i_hi).contains(&ti) && (j_lo..=j_hi).contains(&tj) {
                        target[k] = idx(ti, tj);
                        next[k] = idx(ti, tj);
                    } else {
                        // Beyond the horizon's table (see `NavTask::optimal`).
                        bonus[k] = f64::NEG_INFINITY;
                    }
                }
            }
        }
        let sample = |k: usize| SliceValues {
            k,
            values: points
                .iter()
                .map(|p| {
                    bilinear(
                        &tl.slices.index_axis(ndarray::Axis(0), k),
                        self.extent,
                        p[0],
                        p[1],
                    )
                })
                .collect(),
        };
        let mut cache: [Option<SliceValues>; 2] = [None, None];
        let take = |k: usize, cache: &mut [Option<SliceValues>; 2]| -> usize {
            if let Some(pos) = cache
                .iter()
                .position(|c| c.as_ref().is_some_and(|c| c.k == k))
            {
                return pos;
            }
            // Replace the entry not holding the other slice of the pair (the older one).
            let slot = if cache[0].is_none() { 0 } else { 1 };
            cache[slot] = Some(sample(k));
            slot
        };
        let mut b = vec![0.0f64; points.len()];
        let t_max = self.max_steps;
        let mut v_next = vec![0.0f64; n];
        let mut v = vec![0.0f64; n];
        let mut policy = vec![0u8; t_max * n];
        for t in (0..t_max).rev() {
            let (k0, k1, f) = tl.bracket(tl.time_of_move(t));
            // Keep the pair (k0, k1): an entry for another slice makes room.
            for c in cache.iter_mut() {
                if c.as_ref().is_some_and(|c| c.k != k0 && c.k != k1) {
                    *c = None;
                }
            }
            let s0 = take(k0, &mut cache);
            let s1 = take(k1, &mut cache);
            let v0 = &cache[s0].as_ref().expect("slice sampled").values;
            let v1 = &cache[s1].as_ref().expect("slice sampled").values;
            for (p, bp) in b.iter_mut().enumerate() {
                let sig = if k0 == k1 {
                    v0[p]
                } else {
                    blend(v0[p], v1[p], f)
                };
                *bp = self.base_reward(sig);
            }
            for s in 0..n {
                if !inside[s] {
                    continue;
                }
                let mut best = f64::NEG_INFINITY;
                let mut best_a = 0u8;
                for a in 0..4 {
                    let k = s * 4 + a;
                    let nx = next[k];
                    let val =
                        b[target[k]] + bonus[k] + if nx == usize::MAX { 0.0 } else { v_next[nx] };
                    if val > best {
                        best = val;
                        best_a = a as u8;
                    }
                }
                v[s] = best;
                policy[t * n + s] = best_a;
            }
            std::mem::swap(&mut v, &mut v_next);
        }
        // Replay: the rewards summed as the environment does, at each move's instant.
        Ok(self.replay(start, &policy, n, idx, |t, i, j, a| {
            self.transition_at(tl, start, i, j, a, t)
        }))
    }

    /// `transition` with the signal of move `t`'s instant: `(reward, terminal, new offset,
    /// position after the move)`.
    pub fn transition_at(
        &self,
        tl: &Timeline<'_>,
        start: [f64; 2],
        i: i64,
        j: i64,
        a: usize,
        t: usize,
    ) -> (f64, bool, (i64, i64), [f64; 2]) {
        let tau = tl.time_of_move(t);
        self.transition_with(start, i, j, a, |x, y| tl.signal_at(self.extent, x, y, tau))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{Array2, Array3};

    fn task(s: &Array2<f64>, max_steps: usize) -> NavTask<'_> {
        crate::planner::test_task(s, max_steps)
    }

    /// Brute force over every action sequence, the signal read at each move's instant.
    fn brute(
        t: &NavTask<'_>,
        tl: &Timeline<'_>,
        start: [f64; 2],
        i: i64,
        j: i64,
        step: usize,
    ) -> f64 {
        if step == t.max_steps {
            return 0.0;
        }
        (0..4)
            .map(|a| {
                let (r, term, (ti, tj), _) = t.transition_at(tl, start, i, j, a, step);
                r + if term {
                    0.0
                } else {
                    brute(t, tl, start, ti, tj, step + 1)
                }
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn matches_brute_force_in_space_time() {
        // Three slices that differ strongly, so the best path depends on when it flies.
        let slices = Array3::from_shape_fn((3, 3, 4), |(k, i, j)| {
            ((i * 7 + j * 3 + k * 5) % 11) as f64 * 2.0 - 4.0 * k as f64
        });
        let s0 = slices.index_axis(ndarray::Axis(0), 0).to_owned();
        let times = [0.0, 1.5, 4.0];
        for (t0, dt) in [(0.0, 1.0), (0.7, 0.6), (-1.0, 2.0)] {
            let tl = Timeline {
                slices: slices.view(),
                t_s: &times,
                t0_s: t0,
                dt_s: dt,
            };
            for max_steps in 1..=7 {
                let t = task(&s0, max_steps);
                for start in [[0.0, 0.0], [40.0, 30.0], [17.0, 12.0], [3.0, 28.0]] {
                    let want = brute(&t, &tl, start, 0, 0, 0);
                    let plan = t.optimal_in_time(&tl, start).unwrap();
                    assert!(
                        (plan.return_ - want).abs() < 1e-9,
                        "t0 {t0} dt {dt} max_steps {max_steps} start {start:?}: {} vs {want}",
                        plan.return_
                    );
                }
            }
        }
    }

    #[test]
    fn one_slice_is_the_static_plan() {
        let s = Array2::from_shape_fn((3, 4), |(i, j)| ((i * 7 + j * 3) % 11) as f64 * 2.0);
        let slices = s.clone().insert_axis(ndarray::Axis(0));
        let times = [5.0];
        let tl = Timeline {
            slices: slices.view(),
            t_s: &times,
            t0_s: 0.0,
            dt_s: 1.0,
        };
        let t = task(&s, 7);
        for start in [[0.0, 0.0], [17.0, 12.0]] {
            let a = t.optimal(start).unwrap();
            let b = t.optimal_in_time(&tl, start).unwrap();
            assert_eq!(a.return_.to_bits(), b.return_.to_bits());
            assert_eq!(a.actions, b.actions);
        }
    }

    #[test]
    fn bracket_holds_the_ends_and_hits_instants() {
        let slices = Array3::<f64>::zeros((3, 1, 1));
        let times = [0.0, 1.0, 3.0];
        let tl = Timeline {
            slices: slices.view(),
            t_s: &times,
            t0_s: 0.0,
            dt_s: 1.0,
        };
        assert_eq!(tl.bracket(-1.0), (0, 0, 0.0));
        assert_eq!(tl.bracket(1.0), (1, 1, 0.0));
        assert_eq!(tl.bracket(2.0), (1, 2, 0.5));
        assert_eq!(tl.bracket(9.0), (2, 2, 0.0));
        let bad = Timeline {
            t_s: &[0.0, 0.0, 1.0],
            ..tl.clone()
        };
        assert!(bad.validate().is_err());
    }
}
