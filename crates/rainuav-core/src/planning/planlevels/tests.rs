//! Unit tests of [`super`].

use super::*;
use crate::planning::planner::bilinear;
use ndarray::{Array2, Array3, Array4, Axis};

fn level(max_steps: usize) -> NavTask {
    crate::planning::planner::test_task(max_steps)
}

/// Maps (H, W) of each level as one still signal (1, L, H, W).
fn stack(maps: &[Array2<f64>]) -> Array4<f64> {
    let (h, w) = maps[0].dim();
    Array4::from_shape_fn((1, maps.len(), h, w), |(_, l, i, j)| maps[l][(i, j)])
}

/// A task on a still stack, no masks.
fn still<'a>(
    task: NavTask,
    s: &'a Array4<f64>,
    climb: Vec<usize>,
    descend: Vec<usize>,
) -> LevelTask<'a> {
    LevelTask {
        task,
        signal: LevelSignal::still(s.view()),
        blocked: None,
        climb,
        descend,
    }
}

/// Masks (L, H, W): `wall` on level `on`, none elsewhere.
fn masks(levels: usize, on: usize, wall: &Array2<u8>) -> Array3<u8> {
    let (h, w) = wall.dim();
    Array3::from_shape_fn(
        (levels, h, w),
        |(l, i, j)| if l == on { wall[(i, j)] } else { 0 },
    )
}

/// Every action sequence until the clock reaches the horizon, by recursion.
fn brute(t: &LevelTask<'_>, start: [f64; 2], state: (usize, i64, i64), tick: usize) -> f64 {
    if tick >= t.task.max_steps {
        return 0.0;
    }
    (0..LEVEL_MOVES)
        .map(|a| {
            let (r, term, next, _, d) = t.transition(start, state, a, tick);
            r + if term {
                0.0
            } else {
                brute(t, start, next, tick + d)
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
    let s = stack(&maps(0));
    let mut wall = Array2::<u8>::zeros((3, 4));
    wall[(1, 2)] = 1;
    let m = masks(3, 1, &wall);
    for max_steps in 1..=7 {
        let task = LevelTask {
            blocked: Some(m.view()),
            ..still(level(max_steps), &s, vec![2, 1], vec![3, 2])
        };
        for start in [[0.0, 0.0], [17.0, 12.0], [40.0, 30.0]] {
            for l in 0..3 {
                let want = brute(&task, start, (l, 0, 0), 0);
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
    let mut wall = Array2::<u8>::zeros((3, 4));
    wall[(2, 1)] = 1;
    let m = masks(3, 2, &wall);
    let times = [0.0, 1.5, 4.0];
    for (t0, dt) in [(0.0, 1.0), (0.7, 0.6), (-1.0, 2.0)] {
        let tl = LevelSignal {
            slices: slices.view(),
            t_s: &times,
            t0_s: t0,
            dt_s: dt,
        };
        for max_steps in [1, 3, 6] {
            let task = LevelTask {
                task: level(max_steps),
                signal: tl.clone(),
                blocked: Some(m.view()),
                climb: vec![2, 1],
                descend: vec![1, 3],
            };
            for start in [[0.0, 0.0], [17.0, 12.0], [3.0, 28.0]] {
                for l in 0..3 {
                    let want = brute(&task, start, (l, 0, 0), 0);
                    let plan = task.optimal(start, l).unwrap();
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
fn one_slice_is_the_static_plan_at_any_instant() {
    // One slice stands for all time: its instant, the take-off and the tick do not matter.
    let s = stack(&maps(3));
    let task = still(level(8), &s, vec![2, 3], vec![3, 4]);
    let later = LevelTask {
        signal: LevelSignal {
            slices: s.view(),
            t_s: &[5.0],
            t0_s: 7.0,
            dt_s: 0.3,
        },
        ..task.clone()
    };
    for start in [[0.0, 0.0], [17.0, 12.0]] {
        let a = task.optimal(start, 1).unwrap();
        let b = later.optimal(start, 1).unwrap();
        assert_eq!(a, b);
    }
}

#[test]
fn any_level_is_the_best_start_level() {
    let s = stack(&maps(1));
    let task = still(level(6), &s, vec![2, 2], vec![3, 3]);
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
        t: &NavTask,
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
                    t.transition_with(None, (start, i, j), a, |x, y| sig(x, y, tick + 1));
                r + if term {
                    0.0
                } else {
                    plane(t, sig, start, ti, tj, tick + 1)
                }
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }
    let slices = Array3::from_shape_fn((3, 3, 4), |(k, i, j)| {
        ((i * 5 + j * 3 + 2 * k) % 7) as f64 * 3.0
    });
    let one = slices.clone().insert_axis(Axis(1));
    let s0 = one.slice(ndarray::s![0..1, .., .., ..]).to_owned();
    let times = [0.0, 1.5, 4.0];
    let extent = [0.0, 40.0, 0.0, 30.0];
    for (t0, dt) in [(0.0, 1.0), (0.7, 0.6), (-1.0, 2.0)] {
        let tl = LevelSignal {
            slices: one.view(),
            t_s: &times,
            t0_s: t0,
            dt_s: dt,
        };
        for max_steps in 1..=7 {
            let flat = level(max_steps);
            let task = still(flat, &s0, vec![], vec![]);
            let moving_task = LevelTask {
                signal: tl.clone(),
                ..task.clone()
            };
            for start in [[0.0, 0.0], [40.0, 30.0], [17.0, 12.0], [3.0, 28.0]] {
                let first = s0.index_axis(Axis(0), 0).index_axis_move(Axis(0), 0);
                let at_rest = |x: f64, y: f64, _: usize| bilinear(&first, extent, x, y);
                let moving = |x: f64, y: f64, tick: usize| tl.signal(extent, 0, x, y, tick);
                let a = task.optimal(start, 0).unwrap();
                let want = plane(&flat, &at_rest, start, 0, 0, 0);
                assert!((a.return_ - want).abs() < 1e-9, "{} vs {want}", a.return_);
                assert!(a.actions.iter().all(|&m| m < 4) && a.actions.len() <= max_steps);
                assert_eq!(a.ticks, (0..=a.actions.len()).collect::<Vec<_>>());
                let b = moving_task.optimal(start, 0).unwrap();
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
    let s = Array4::from_elem((1, 1, 4, 4), 20.0);
    let mut wall = Array2::<u8>::zeros((4, 4));
    for i in 0..3 {
        wall[(i, 2)] = 1;
    }
    let m = masks(1, 0, &wall);
    let t = NavTask {
        extent: [0.0, 40.0, 0.0, 40.0],
        goal: [35.0, 5.0],
        ..level(30)
    };
    let task = LevelTask {
        blocked: Some(m.view()),
        ..still(t, &s, vec![], vec![])
    };
    let plan = task.optimal([5.0, 5.0], 0).unwrap();
    assert!(plan.return_ > 0.0, "arrives: {}", plan.return_);
    for p in &plan.path {
        assert!(
            !t.blocked_at(Some(&wall.view()), p[0], p[1]),
            "entered {p:?}"
        );
    }
    // Up three rows to the gap, across, down three rows: 3 + 3 + 3 = 9 moves.
    assert_eq!(plan.actions.len(), 9);
    // Without the wall, three moves east.
    let open = still(t, &s, vec![], vec![]);
    assert_eq!(open.optimal([5.0, 5.0], 0).unwrap().actions.len(), 3);
}

#[test]
fn climbs_over_a_wall_when_it_pays() {
    // Level 0 has a wall across the way; level 1 is clear but costs a climb and a
    // descent is never needed (arrival at any level).
    let s = Array4::from_elem((1, 2, 1, 5), 20.0);
    let mut wall = Array2::<u8>::zeros((1, 5));
    wall[(0, 2)] = 1;
    let m = masks(2, 0, &wall);
    let t = NavTask {
        extent: [0.0, 50.0, 0.0, 10.0],
        goal: [45.0, 5.0],
        ..level(10)
    };
    let task = LevelTask {
        blocked: Some(m.view()),
        ..still(t, &s, vec![2], vec![2])
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
    let task = LevelTask {
        task: NavTask {
            extent: [0.0, 50.0, 0.0, 10.0],
            goal: [45.0, 5.0],
            ..level(3)
        },
        signal: LevelSignal {
            slices: slices.view(),
            t_s: &[0.0, 3.0],
            t0_s: 0.0,
            dt_s: 1.0,
        },
        blocked: None,
        climb: vec![3],
        descend: vec![3],
    };
    let (r, term, next, _, d) = task.transition([5.0, 5.0], (0, 0, 0), 4, 0);
    assert_eq!((term, next, d), (false, (1, 0, 0), 3));
    assert!((r + 3.0).abs() < 1e-12);
}

#[test]
fn a_mask_or_clock_that_does_not_fit_is_refused_by_name() {
    let s = stack(&maps(0));
    let wrong = Array3::<u8>::zeros((2, 3, 4));
    let task = LevelTask {
        blocked: Some(wrong.view()),
        ..still(level(4), &s, vec![1, 1], vec![1, 1])
    };
    let err = task.optimal([0.0, 0.0], 0).unwrap_err().to_string();
    assert!(err.contains("blocked"), "{err}");
    let short = still(level(4), &s, vec![1], vec![1, 1]);
    let err = short.optimal([0.0, 0.0], 0).unwrap_err().to_string();
    assert!(err.contains("climb"), "{err}");
    let backwards = LevelTask {
        signal: LevelSignal {
            slices: s.view(),
            t_s: &[0.0],
            t0_s: 0.0,
            dt_s: 0.0,
        },
        ..short.clone()
    };
    let err = backwards.optimal([0.0, 0.0], 0).unwrap_err().to_string();
    assert!(err.contains("dt_s"), "{err}");
}
