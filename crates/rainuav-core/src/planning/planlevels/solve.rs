//! The backward programme over (tick, level, north, east) and the replay of its policy (module
//! docs of [`super`]).

use super::*;

impl LevelTask<'_> {
    /// The backward programme (module docs) and the replay of its policy.
    // Long: the backward programme over (tick, level, position) and the replay of its policy share
    // the value tables and the lattice; split, the tables would pass between the halves.
    pub(super) fn solve(&self, start: [f64; 2], level: usize) -> Result<LevelPlan> {
        let (t0, src) = (&self.task, &self.signal);
        t0.check_start(start)?;
        let nl = self.levels();
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
                for l in 0..nl {
                    let s = l * n + ii * nj + jj;
                    extra[s] = if out || self.blocked_at(l, qx, qy) {
                        -t0.out_of_bounds_penalty
                    } else if goal {
                        t0.goal_reward
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
        let still = !src.moves();
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
            match v1 {
                None => t0.base_rewards(v0.iter().copied(), b),
                Some(v1) => {
                    let sig = v0.iter().zip(v1).map(|(a, c)| blend(*a, *c, f));
                    t0.base_rewards(sig, b);
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
                .filter(|&l| !self.blocked_at(l, start[0], start[1]))
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
            let (r, term, next, pos, d) = self.transition(start, state, a, tick);
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
