//! The exact planner's task (docs/physics.md section 6, `rainuav.nav`): the geometry, the
//! rewards, the horizon and the one move rule, and the clock of a signal that changes in time.
//! The signal itself (one array over time, level, north and east) and the programme over
//! (tick, level, lattice point) are [`crate::planning::planlevels`]: the plane (one level, its
//! signal static or in time) is its case.
//!
//! Moves are deterministic on the lattice `start + step (i, j)`. Rewards, the SIR interpolation,
//! leaving the area and arriving follow `rainuav.env` operation for operation, so a plan
//! replayed in the environment earns the same return.

use crate::error::{CoreError, Result, check_range};
use ndarray::ArrayView2;
use std::str::FromStr;

/// Base reward kinds (see `rainuav.env`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RewardKind {
    /// `-1 - mu max(0, sir_min - SIR)`.
    Shortfall,
    /// `-1 - mu [SIR < sir_min]`.
    Outage,
    /// `-1 + mu 10^(SIR/10)`.
    Linear,
    /// `-1 - mu P`: the signal is the probability of outage (a map known with uncertainty).
    Chance,
}

impl FromStr for RewardKind {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "shortfall" => Ok(RewardKind::Shortfall),
            "outage" => Ok(RewardKind::Outage),
            "linear" => Ok(RewardKind::Linear),
            "chance" => Ok(RewardKind::Chance),
            _ => Err(CoreError::invalid(
                "reward",
                "must be 'shortfall', 'outage', 'linear' or 'chance'",
                format!("{s:?}"),
            )),
        }
    }
}

/// The task: geometry, rewards and horizon, the same at every level and instant (the signal
/// and the not-flyable masks are [`crate::planning::planlevels::LevelTask`]'s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavTask {
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

impl NavTask {
    /// Checks the task's numbers.
    pub fn validate(&self) -> Result<()> {
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
        if self.max_steps == 0 || self.max_steps > 100_000 {
            return Err(CoreError::invalid(
                "max_steps",
                "must be within 1..100000",
                self.max_steps,
            ));
        }
        Ok(())
    }

    /// Whether the pixel of `mask` (H', W', over the area) holding `(x, y)` (a point inside
    /// the area) may not be entered (`rainuav.nav.field`'s pixel lookup: the cell
    /// `floor((x - x0) / (x1 - x0) W)`, clamped); no mask: every pixel may.
    pub fn blocked_at(&self, mask: Option<&ArrayView2<'_, u8>>, x: f64, y: f64) -> bool {
        let Some(b) = mask else {
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
            RewardKind::Chance => -1.0 - self.mu * sir,
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
            RewardKind::Chance => pairs.for_each(|(o, s)| *o = -1.0 - mu * s),
        }
    }

    /// The transition from lattice offset `(i, j)` of `start` by action `a` on a level whose
    /// not-flyable pixels are `mask`, the signal read by `signal(x, y)` at the (clamped) new
    /// position: `(reward, terminal, new offset, position after the move (clamped if it
    /// left))`. The one move rule of the plane.
    pub(crate) fn transition_with(
        &self,
        mask: Option<&ArrayView2<'_, u8>>,
        (start, i, j): ([f64; 2], i64, i64),
        a: usize,
        signal: impl Fn(f64, f64) -> f64,
    ) -> (f64, bool, (i64, i64), [f64; 2]) {
        let [x0, x1, y0, y1] = self.extent;
        let (ni, nj) = (i + MOVES[a].0, j + MOVES[a].1);
        let qx = start[0] + self.step_m * ni as f64;
        let qy = start[1] + self.step_m * nj as f64;
        let out = qx < x0 || qx > x1 || qy < y0 || qy > y1 || self.blocked_at(mask, qx, qy);
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
}

/// The small task the planners' unit tests share: a 40 x 30 m area, 10 m moves, the
/// destination at (30, 20), a 10 dB threshold.
#[cfg(test)]
pub(crate) fn test_task(max_steps: usize) -> NavTask {
    NavTask {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bracket_holds_the_ends_and_hits_instants() {
        let times = [0.0, 1.0, 3.0];
        assert_eq!(bracket(&times, -1.0), (0, 0, 0.0));
        assert_eq!(bracket(&times, 1.0), (1, 1, 0.0));
        assert_eq!(bracket(&times, 2.0), (1, 2, 0.5));
        assert_eq!(bracket(&times, 9.0), (2, 2, 0.0));
        assert!(check_clock(&[0.0, 0.0, 1.0], 0.0, 1.0).is_err());
        assert!(check_clock(&times, 0.0, 0.0).is_err());
    }
}
