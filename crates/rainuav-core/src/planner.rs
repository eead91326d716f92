//! Exact planner for the UAV navigation MDP (docs/physics.md section 6, `rainuav.nav`).
//!
//! Moves are deterministic on the lattice `start + step (i, j)`, so the finite-horizon
//! optimum is a backward dynamic programme over (steps left, lattice point): `V_T = 0`,
//! `V_t(s) = max_a [r(s, a) + (terminal ? 0 : V_{t+1}(s'))]`. Rewards, the SIR interpolation,
//! leaving the area and arriving follow `rainuav.env` operation for operation, so a plan
//! replayed in the environment earns the same return.

use crate::error::{CoreError, Result, check_range};
use crate::memory::check_memory_for;
use ndarray::ArrayView2;
use std::str::FromStr;

const PLAN_MEMORY_HINT: &str = "each plan keeps max_steps bytes per lattice point; use fewer max_steps, a larger step_m \
     or a smaller area";

/// Base reward kinds (see `rainuav.env`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RewardKind {
    /// `-1 - mu max(0, sir_min - SIR)`.
    Shortfall,
    /// `-1 - mu [SIR < sir_min]`.
    Outage,
    /// `-1 + mu 10^(SIR/10)`.
    Linear,
}

impl FromStr for RewardKind {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "shortfall" => Ok(RewardKind::Shortfall),
            "outage" => Ok(RewardKind::Outage),
            "linear" => Ok(RewardKind::Linear),
            _ => Err(CoreError::invalid(
                "reward",
                "must be 'shortfall', 'outage' or 'linear'",
                format!("{s:?}"),
            )),
        }
    }
}

/// The task: map, geometry and rewards.
#[derive(Debug, Clone)]
pub struct NavTask<'a> {
    /// SIR map (H, W), dB.
    pub sir_db: ArrayView2<'a, f64>,
    /// (x_min, x_max, y_min, y_max).
    pub extent: [f64; 4],
    /// Destination.
    pub goal: [f64; 2],
    /// Move length.
    pub step_m: f64,
    /// Arrival tolerance.
    pub tol_m: f64,
    /// Horizon.
    pub max_steps: usize,
    /// SIR weight.
    pub mu: f64,
    /// Reward kind.
    pub reward: RewardKind,
    /// Minimum SIR.
    pub sir_min_db: f64,
    /// Paid on arrival.
    pub goal_reward: f64,
    /// Charged on leaving.
    pub out_of_bounds_penalty: f64,
    /// Pixels a UAV may not enter (non-zero), (H', W') over `extent` (terrain or obstacles
    /// within the clearance of the flight height): a move into one is a move out of the area.
    pub blocked: Option<ArrayView2<'a, u8>>,
}

/// An optimal plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Optimal undiscounted return.
    pub return_: f64,
    /// Actions (0 = +x, 1 = +y, 2 = -x, 3 = -y).
    pub actions: Vec<u8>,
    /// Positions visited, starting at the start (the last one clamped if the plan leaves).
    pub path: Vec<[f64; 2]>,
}

pub(crate) const MOVES: [(i64, i64); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];

/// A map (H, W) over `extent` at (x, y): pixel-centred bilinear, edge values beyond the outermost
/// centres, operation for operation as `rainuav._sampling.bilinear`.
pub fn bilinear(s: &ArrayView2<'_, f64>, extent: [f64; 4], x: f64, y: f64) -> f64 {
    let [x0, x1, y0, y1] = extent;
    let (h, w) = s.dim();
    bilinear_taps(s, Tap::new(x, x0, x1, w), Tap::new(y, y0, y1, h))
}

/// One axis of [`bilinear`]: the two samples around a coordinate and the weight of the
/// second, which depend on that coordinate alone (so a lattice's taps are computed once per
/// row and column).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tap {
    lo: usize,
    hi: usize,
    t: f64,
}

impl Tap {
    /// The tap of coordinate `v` on `n` pixels spanning `a..b`.
    pub(crate) fn new(v: f64, a: f64, b: f64, n: usize) -> Tap {
        let f = ((v - a) / (b - a) * n as f64 - 0.5).clamp(0.0, n as f64 - 1.0);
        let lo = f.floor().min(n.saturating_sub(2) as f64) as usize;
        Tap {
            lo,
            hi: (lo + 1).min(n - 1),
            t: f - lo as f64,
        }
    }
}

/// [`bilinear`] from the taps of x (columns) and y (rows).
pub(crate) fn bilinear_taps(s: &ArrayView2<'_, f64>, tx: Tap, ty: Tap) -> f64 {
    s[(ty.lo, tx.lo)] * (1.0 - tx.t) * (1.0 - ty.t)
        + s[(ty.lo, tx.hi)] * tx.t * (1.0 - ty.t)
        + s[(ty.hi, tx.lo)] * (1.0 - tx.t) * ty.t
        + s[(ty.hi, tx.hi)] * tx.t * ty.t
}

impl NavTask<'_> {
    /// Checks the task.
    pub fn validate(&self) -> Result<()> {
        let (h, w) = self.sir_db.dim();
        if h == 0 || w == 0 {
            return Err(CoreError::invalid(
                "sir_db",
                "must not be empty",
                format!("{h}x{w}"),
            ));
        }
        if self.sir_db.iter().any(|v| !v.is_finite()) {
            return Err(CoreError::invalid(
                "sir_db",
                "must be finite everywhere",
                "NaN or inf",
            ));
        }
        let [x0, x1, y0, y1] = self.extent;
        if !(x1 > x0 && y1 > y0) || self.extent.iter().any(|v| !v.is_finite()) {
            return Err(CoreError::invalid(
                "extent_m",
                "must be finite with x_max > x_min and y_max > y_min",
                format!("{:?}", self.extent),
            ));
        }
        if !(self.goal[0] >= x0 && self.goal[0] <= x1 && self.goal[1] >= y0 && self.goal[1] <= y1) {
            return Err(CoreError::invalid(
                "goal_m",
                "must lie inside the area",
                format!("{:?}", self.goal),
            ));
        }
        check_range(
            "step_m",
            self.step_m,
            f64::MIN_POSITIVE,
            1e9,
            "must be finite and > 0",
        )?;
        check_range(
            "tol_m",
            self.tol_m,
            f64::MIN_POSITIVE,
            1e9,
            "must be finite and > 0",
        )?;
        if let Some(b) = &self.blocked
            && (b.nrows() == 0 || b.ncols() == 0)
        {
            return Err(CoreError::invalid(
                "blocked",
                "must not be empty",
                format!("{:?}", b.dim()),
            ));
        }
        if self.max_steps == 0 || self.max_steps > 100_000 {
            return Err(CoreError::invalid(
                "max_steps",
                "must be within 1..100000",
                self.max_steps,
            ));
        }
        Ok(())
    }

    /// SIR at (x, y): bilinear, edge-clamped, exactly as `rainuav.env.SirField`.
    pub fn sir_at(&self, x: f64, y: f64) -> f64 {
        bilinear(&self.sir_db, self.extent, x, y)
    }

    /// Whether the pixel holding `(x, y)` (a point inside the area) may not be entered
    /// (`rainuav.nav.field`'s pixel lookup: the cell `floor((x - x0) / (x1 - x0) W)`, clamped).
    pub fn blocked_at(&self, x: f64, y: f64) -> bool {
        let Some(b) = &self.blocked else {
            return false;
        };
        let [x0, x1, y0, y1] = self.extent;
        let (h, w) = b.dim();
        let j = ((x - x0) / (x1 - x0) * w as f64)
            .floor()
            .clamp(0.0, (w - 1) as f64) as usize;
        let i = ((y - y0) / (y1 - y0) * h as f64)
            .floor()
            .clamp(0.0, (h - 1) as f64) as usize;
        b[(i, j)] != 0
    }

    /// b(q') from the SIR there.
    pub fn base_reward(&self, sir: f64) -> f64 {
        match self.reward {
            RewardKind::Shortfall => -1.0 - self.mu * (self.sir_min_db - sir).max(0.0),
            RewardKind::Outage => -1.0 - self.mu * if sir < self.sir_min_db { 1.0 } else { 0.0 },
            RewardKind::Linear => -1.0 + self.mu * 10f64.powf(sir / 10.0),
        }
    }

    /// [`Self::base_reward`] of each signal value of `sig`, into `out` (the same operations,
    /// the kind chosen once).
    pub(crate) fn base_rewards(&self, sig: impl Iterator<Item = f64>, out: &mut [f64]) {
        let (mu, min) = (self.mu, self.sir_min_db);
        let pairs = out.iter_mut().zip(sig);
        match self.reward {
            RewardKind::Shortfall => pairs.for_each(|(o, s)| *o = -1.0 - mu * (min - s).max(0.0)),
            RewardKind::Outage => {
                pairs.for_each(|(o, s)| *o = -1.0 - mu * if s < min { 1.0 } else { 0.0 })
            }
            RewardKind::Linear => pairs.for_each(|(o, s)| *o = -1.0 + mu * 10f64.powf(s / 10.0)),
        }
    }

    /// The transition from lattice offset `(i, j)` of `start` by action `a`:
    /// `(reward, terminal, new offset, position after the move (clamped if it left))`.
    pub fn transition(
        &self,
        start: [f64; 2],
        i: i64,
        j: i64,
        a: usize,
    ) -> (f64, bool, (i64, i64), [f64; 2]) {
        self.transition_with(start, i, j, a, |x, y| self.sir_at(x, y))
    }

    /// `transition` with the signal read by `signal(x, y)` at the (clamped) new position:
    /// the one move rule the static and the space-time planners share.
    pub(crate) fn transition_with(
        &self,
        start: [f64; 2],
        i: i64,
        j: i64,
        a: usize,
        signal: impl Fn(f64, f64) -> f64,
    ) -> (f64, bool, (i64, i64), [f64; 2]) {
        let [x0, x1, y0, y1] = self.extent;
        let (ni, nj) = (i + MOVES[a].0, j + MOVES[a].1);
        let qx = start[0] + self.step_m * ni as f64;
        let qy = start[1] + self.step_m * nj as f64;
        let out = qx < x0 || qx > x1 || qy < y0 || qy > y1 || self.blocked_at(qx, qy);
        let (cx, cy) = (qx.clamp(x0, x1), qy.clamp(y0, y1));
        let b = self.base_reward(signal(cx, cy));
        if out {
            return (b - self.out_of_bounds_penalty, true, (ni, nj), [cx, cy]);
        }
        if (qx - self.goal[0]).hypot(qy - self.goal[1]) <= self.tol_m {
            return (b + self.goal_reward, true, (ni, nj), [qx, qy]);
        }
        (b, false, (ni, nj), [qx, qy])
    }

    /// The plan a backward programme's `policy` (`t_max` rows of `n` lattice states, indexed
    /// by `idx`) gives from `start`: its actions, path and return, each move's reward from
    /// `step(t, i, j, a)` summed as the environment does.
    pub(crate) fn replay(
        &self,
        start: [f64; 2],
        policy: &[u8],
        n: usize,
        idx: impl Fn(i64, i64) -> usize,
        step: impl Fn(usize, i64, i64, usize) -> (f64, bool, (i64, i64), [f64; 2]),
    ) -> Plan {
        let (mut i, mut j) = (0i64, 0i64);
        let mut actions = Vec::new();
        let mut path = vec![start];
        let mut ret = 0.0;
        for t in 0..policy.len() / n {
            let a = policy[t * n + idx(i, j)] as usize;
            let (r, term, (ti, tj), pos) = step(t, i, j, a);
            actions.push(a as u8);
            path.push(pos);
            ret += r;
            if term {
                break;
            }
            i = ti;
            j = tj;
        }
        Plan {
            return_: ret,
            actions,
            path,
        }
    }

    /// Lattice offsets `(i_lo, i_hi, j_lo, j_hi)` the plan from `start` tabulates: those
    /// inside the area and reachable within the horizon, plus one ring.
    pub(crate) fn lattice(&self, start: [f64; 2]) -> (i64, i64, i64, i64) {
        let [x0, x1, y0, y1] = self.extent;
        let reach = self.max_steps as i64;
        let lo = |s: f64, a: f64| (((a - s) / self.step_m).ceil() as i64).max(-reach) - 1;
        let hi = |s: f64, b: f64| (((b - s) / self.step_m).floor() as i64).min(reach) + 1;
        (
            lo(start[0], x0),
            hi(start[0], x1),
            lo(start[1], y0),
            hi(start[1], y1),
        )
    }

    /// Number of lattice points of the plan from `start` (at most 50 million).
    pub(crate) fn lattice_points(&self, start: [f64; 2]) -> Result<usize> {
        let (i_lo, i_hi, j_lo, j_hi) = self.lattice(start);
        let n = ((i_hi - i_lo + 1) as usize).saturating_mul((j_hi - j_lo + 1) as usize);
        if n > 50_000_000 {
            return Err(CoreError::invalid(
                "step_m",
                "gives too many lattice points for the planner",
                n,
            ));
        }
        Ok(n)
    }

    /// Bytes the plan from `start` allocates: per lattice point the transition table (four
    /// rewards, four successors), the inside flag and two value arrays, and the policy,
    /// `max_steps` bytes per point.
    pub fn plan_bytes(&self, start: [f64; 2]) -> Result<usize> {
        let n = self.lattice_points(start)?;
        let per_point = 4 * size_of::<f64>() + 4 * size_of::<usize>() + 1 + 2 * size_of::<f64>();
        Ok(n.saturating_mul(per_point.saturating_add(self.max_steps)))
    }

    /// Exact optimal plans from many starts, computed in parallel (rayon). Refuses, before
    /// allocating anything, a batch whose plans in flight at once (one per worker thread)
    /// would need more than 80% of the available memory.
    pub fn optimal_many(&self, starts: &[[f64; 2]]) -> Result<Vec<Plan>> {
        use rayon::prelude::*;
        self.validate()?;
        let mut largest = 0usize;
        for &p in starts {
            self.check_start(p)?;
            largest = largest.max(self.plan_bytes(p)?);
        }
        let at_once = rayon::current_num_threads().min(starts.len()).max(1);
        check_memory_for(
            "max_steps",
            PLAN_MEMORY_HINT,
            largest.saturating_mul(at_once),
        )?;
        starts.par_iter().map(|&p| self.optimal(p)).collect()
    }

    pub(crate) fn check_start(&self, start: [f64; 2]) -> Result<()> {
        let [x0, x1, y0, y1] = self.extent;
        if !(start[0] >= x0 && start[0] <= x1 && start[1] >= y0 && start[1] <= y1) {
            return Err(CoreError::invalid(
                "start_m",
                "must lie inside the area",
                format!("{start:?}"),
            ));
        }
        Ok(())
    }

    /// The exact optimum from `start` (inside the area).
    pub fn optimal(&self, start: [f64; 2]) -> Result<Plan> {
        self.validate()?;
        let [x0, x1, y0, y1] = self.extent;
        if !(start[0] >= x0 && start[0] <= x1 && start[1] >= y0 && start[1] <= y1) {
            return Err(CoreError::invalid(
                "start_m",
                "must lie inside the area",
                format!("{start:?}"),
            ));
        }
        // Lattice offsets inside the area (and reachable within the horizon): the bounds of
        // `lattice()`, computed here in line. Calling `lattice()` and `lattice_points()` instead
        // made the whole plan 15-20% slower (200 starts on the paper map: 6.6-7.3 s against
        // 5.7 s, alternating builds): the optimiser then handled the table loops worse.
        let reach = self.max_steps as i64;
        let lo = |s: f64, a: f64| (((a - s) / self.step_m).ceil() as i64).max(-reach) - 1;
        let hi = |s: f64, b: f64| (((b - s) / self.step_m).floor() as i64).min(reach) + 1;
        let (i_lo, i_hi) = (lo(start[0], x0), hi(start[0], x1));
        let (j_lo, j_hi) = (lo(start[1], y0), hi(start[1], y1));
        let ni = (i_hi - i_lo + 1) as usize;
        let nj = (j_hi - j_lo + 1) as usize;
        let n = ni * nj;
        if n > 50_000_000 {
            return Err(CoreError::invalid(
                "step_m",
                "gives too many lattice points for the planner",
                n,
            ));
        }
        check_memory_for("max_steps", PLAN_MEMORY_HINT, self.plan_bytes(start)?)?;
        let idx = |i: i64, j: i64| ((i - i_lo) as usize) * nj + (j - j_lo) as usize;
        // Transition table: per state and action, reward and next state (usize::MAX = terminal).
        let mut rew = vec![0.0f64; n * 4];
        let mut next = vec![usize::MAX; n * 4];
        let mut inside = vec![false; n];
        for i in i_lo..=i_hi {
            for j in j_lo..=j_hi {
                let qx = start[0] + self.step_m * i as f64;
                let qy = start[1] + self.step_m * j as f64;
                let s = idx(i, j);
                inside[s] = !(qx < x0 || qx > x1 || qy < y0 || qy > y1);
                if !inside[s] {
                    continue;
                }
                for a in 0..4 {
                    let (r, term, (ti, tj), _) = self.transition(start, i, j, a);
                    if term {
                        rew[s * 4 + a] = r;
                    } else if (i_lo..=i_hi).contains(&ti) && (j_lo..=j_hi).contains(&tj) {
                        rew[s * 4 + a] = r;
                        next[s * 4 + a] = idx(ti, tj);
                    } else {
                        // Beyond the table, which the horizon cut: only states farther out
                        // than any step count allows lead there, so their values (now
                        // -inf) never reach a state the UAV can be in at that time.
                        rew[s * 4 + a] = f64::NEG_INFINITY;
                    }
                }
            }
        }
        // Backward induction; policy[t][s] for path extraction.
        let t_max = self.max_steps;
        let mut v_next = vec![0.0f64; n];
        let mut v = vec![0.0f64; n];
        let mut policy = vec![0u8; t_max * n];
        for t in (0..t_max).rev() {
            for s in 0..n {
                if !inside[s] {
                    continue;
                }
                let mut best = f64::NEG_INFINITY;
                let mut best_a = 0u8;
                for a in 0..4 {
                    let nx = next[s * 4 + a];
                    let val = rew[s * 4 + a] + if nx == usize::MAX { 0.0 } else { v_next[nx] };
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
        // Replay the policy to get the actions, path and return (summed as the env does).
        Ok(self.replay(start, &policy, n, idx, |_, i, j, a| {
            self.transition(start, i, j, a)
        }))
    }
}

/// The small task the planners' unit tests share: a 40 x 30 m area, 10 m moves, the
/// destination at (30, 20), a 10 dB threshold.
#[cfg(test)]
pub(crate) fn test_task(s: &ndarray::Array2<f64>, max_steps: usize) -> NavTask<'_> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    fn task(s: &Array2<f64>, max_steps: usize) -> NavTask<'_> {
        test_task(s, max_steps)
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
        let mut t = task(&s, 30);
        t.extent = [0.0, 40.0, 0.0, 40.0];
        t.goal = [35.0, 5.0];
        t.blocked = Some(wall.view());
        let plan = t.optimal([5.0, 5.0]).unwrap();
        assert!(plan.return_ > 0.0, "arrives: {}", plan.return_);
        for p in &plan.path {
            assert!(!t.blocked_at(p[0], p[1]), "entered {p:?}");
        }
        // Up three rows to the gap, across, down three rows: 3 + 3 + 3 = 9 moves.
        assert_eq!(plan.actions.len(), 9);
        // Without the wall, three moves east.
        t.blocked = None;
        assert_eq!(t.optimal([5.0, 5.0]).unwrap().actions.len(), 3);
    }

    /// Brute force over every action sequence of length <= 7 on a tiny map.
    #[test]
    fn matches_brute_force() {
        let s = Array2::from_shape_fn((3, 4), |(i, j)| ((i * 7 + j * 3) % 11) as f64 * 2.0);
        let t = task(&s, 7);
        let start = [0.0, 0.0];
        fn best(t: &NavTask<'_>, start: [f64; 2], i: i64, j: i64, left: usize) -> f64 {
            if left == 0 {
                return 0.0;
            }
            (0..4)
                .map(|a| {
                    let (r, term, (ti, tj), _) = t.transition(start, i, j, a);
                    r + if term {
                        0.0
                    } else {
                        best(t, start, ti, tj, left - 1)
                    }
                })
                .fold(f64::NEG_INFINITY, f64::max)
        }
        let want = best(&t, start, 0, 0, 7);
        let plan = t.optimal(start).unwrap();
        assert!(
            (plan.return_ - want).abs() < 1e-9,
            "{} vs {want}",
            plan.return_
        );
        assert!(plan.return_ > 0.0, "the goal is reachable in 5 moves");
        // Horizons shorter than the area is wide: the planner's table is cut at the
        // horizon (the edge once indexed past the table), from corners and inside.
        for max_steps in 1..=4 {
            let t = task(&s, max_steps);
            for start in [[0.0, 0.0], [40.0, 30.0], [17.0, 12.0], [3.0, 28.0]] {
                let want = best(&t, start, 0, 0, max_steps);
                let plan = t.optimal(start).unwrap();
                assert!(
                    (plan.return_ - want).abs() < 1e-9,
                    "max_steps {max_steps}, start {start:?}: {} vs {want}",
                    plan.return_
                );
                assert!(plan.actions.len() <= max_steps);
            }
        }
    }
}
