//! Criterion benchmarks of the exact planner among flight levels: one plan on seven levels of
//! a 200 x 200 map (10 m moves, a 300-tick horizon, climbs of 3 and descents of 5 ticks), on
//! maps and in time (61 slices), against the same programme on one level's slices (the plane:
//! the reference doing one level's work in the same run).
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use ndarray::Array4;
use rainuav_core::planning::planlevels::{LevelSignal, LevelTask};
use rainuav_core::planning::planner::{NavTask, RewardKind};

const LEVELS: usize = 7;
const SLICES: usize = 61;

/// A smooth synthetic SINR, dB: lobes that drift with time and change with height.
fn signal() -> Array4<f64> {
    Array4::from_shape_fn((SLICES, LEVELS, 200, 200), |(k, l, i, j)| {
        let (x, y) = (10.0 * j as f64, 10.0 * i as f64);
        let drift = 5.0 * k as f64;
        8.0 * ((x + drift) / 310.0).sin() * ((y - drift) / 270.0).cos() - 1.5 * l as f64
    })
}

const TASK: NavTask = NavTask {
    extent: [0.0, 2000.0, 0.0, 2000.0],
    goal: [1400.0, 1600.0],
    step_m: 10.0,
    tol_m: 10.0,
    max_steps: 300,
    mu: 10.0 / 43.0,
    reward: RewardKind::Shortfall,
    sir_min_db: -2.0,
    goal_reward: 2000.0,
    out_of_bounds_penalty: 10000.0,
};

fn bench(c: &mut Criterion) {
    let sig = signal();
    let times: Vec<f64> = (0..SLICES).map(|k| 5.0 * k as f64).collect();
    let first = sig.slice(ndarray::s![0..1, .., .., ..]);
    let task = |signal| LevelTask {
        task: TASK,
        signal,
        blocked: None,
        climb: vec![3; LEVELS - 1],
        descend: vec![5; LEVELS - 1],
    };
    let at_rest = task(LevelSignal::still(first));
    let moving = task(LevelSignal {
        slices: sig.view(),
        t_s: &times,
        t0_s: 0.0,
        dt_s: 1.0,
    });
    let one: Array4<f64> = sig.slice(ndarray::s![.., 3..4, .., ..]).to_owned();
    let plane = LevelTask {
        task: TASK,
        signal: LevelSignal {
            slices: one.view(),
            t_s: &times,
            t0_s: 0.0,
            dt_s: 1.0,
        },
        blocked: None,
        climb: vec![],
        descend: vec![],
    };
    let start = [305.0, 255.0];
    let mut g = c.benchmark_group("one_plan_200x200_300_ticks");
    g.sample_size(10);
    g.bench_function("7_levels_static", |b| {
        b.iter(|| at_rest.optimal(start, 0).expect("plans"))
    });
    g.bench_function("7_levels_61_slices", |b| {
        b.iter(|| moving.optimal(start, 0).expect("plans"))
    });
    g.bench_function("plane_61_slices_reference", |b| {
        b.iter(|| plane.optimal(start, 0).expect("plans"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
