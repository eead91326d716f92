//! Criterion benchmarks of the queries along a segment among buildings: 10 000 boxes like a
//! city (94% 6-18 m, 6% towers 60-150 m, over 8.8 km), 1 000 legs from 25 m to a receiver at
//! 100 m. The buildings that can stand in each leg's way
//! ([`Prisms::near_segment_under`]: the tiers' buckets left where their roofs stay below the
//! leg) against every building whose box the leg meets ([`Prisms::near_segment`]: the same
//! buckets blind to the roofs), then the roofs under 25 m dropped.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use rainuav_core::propagation::obstacles::{Building, Prisms};

fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn bench(c: &mut Criterion) {
    let mut u = stream(1);
    let boxes: Vec<Building> = (0..10_000)
        .map(|_| {
            let (x, y) = (8800.0 * u(), 8800.0 * u());
            let h = if u() < 0.06 {
                60.0 + 90.0 * u()
            } else {
                6.0 + 12.0 * u()
            };
            [x, x + 10.0 + 20.0 * u(), y, y + 10.0 + 20.0 * u(), h]
        })
        .collect();
    let p = Prisms::from_boxes(&boxes).unwrap();
    let legs: Vec<([f64; 2], [f64; 2])> = (0..1000)
        .map(|_| ([8800.0 * u(), 8800.0 * u()], [8800.0 * u(), 8800.0 * u()]))
        .collect();
    let (za, zb) = (25.0, 100.0);
    let mut near = Vec::new();
    let mut g = c.benchmark_group("buildings_along_1000_legs");
    g.sample_size(20);
    g.bench_function("tiers_with_roofs", |b| {
        b.iter(|| {
            let mut n = 0;
            for &(a, q) in &legs {
                p.near_segment_under((a, za), (q, zb), 0.0, &mut near);
                n += near.len();
            }
            n
        })
    });
    g.bench_function("every_box_met_then_roofs", |b| {
        b.iter(|| {
            let mut n = 0;
            for &(a, q) in &legs {
                p.near_segment(a, q, &mut near);
                n += near
                    .iter()
                    .filter(|&&k| p.items()[k as usize].top >= za.min(zb))
                    .count();
            }
            n
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
