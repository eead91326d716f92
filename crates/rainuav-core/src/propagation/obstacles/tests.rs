//! Unit tests of [`super`].

use super::*;

#[test]
fn a_square_with_a_hole_holds_its_ring_and_not_its_courtyard() {
    // Outer 0..30 square, hole 10..20: even-odd.
    let xy = vec![
        [0.0, 0.0],
        [30.0, 0.0],
        [30.0, 30.0],
        [0.0, 30.0],
        [10.0, 10.0],
        [10.0, 20.0],
        [20.0, 20.0],
        [20.0, 10.0],
    ];
    let p = Prisms::new(xy, &[0, 4, 8], &[0, 2], &[12.0]).unwrap();
    assert_eq!(p.height_at(5.0, 5.0), 12.0);
    assert_eq!(p.height_at(15.0, 15.0), 0.0);
    assert_eq!(p.height_at(35.0, 5.0), 0.0);
    let mut t = Vec::new();
    p.crossings(0, [-10.0, 15.0], [40.0, 15.0], &mut t);
    t.sort_by(f64::total_cmp);
    let want = [0.2, 0.4, 0.6, 0.8];
    assert!(
        t.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
        "{t:?}"
    );
}

#[test]
fn the_bucket_grid_finds_what_a_scan_finds() {
    // A 20 x 20 block of boxes; every segment's candidates hold every box it crosses.
    let boxes: Vec<Building> = (0..400)
        .map(|k| {
            let (i, j) = ((k / 20) as f64, (k % 20) as f64);
            [
                j * 50.0,
                j * 50.0 + 20.0,
                i * 50.0,
                i * 50.0 + 30.0,
                10.0 + k as f64 / 10.0,
            ]
        })
        .collect();
    let p = Prisms::from_boxes(&boxes).unwrap();
    let mut near = Vec::new();
    let mut t = Vec::new();
    for (a, b) in [
        ([-5.0, -5.0], [990.0, 700.0]),
        ([500.0, 3.0], [501.0, 999.0]),
        ([999.0, 15.0], [0.0, 15.0]),
    ] {
        p.near_segment(a, b, &mut near);
        for k in 0..p.len() {
            t.clear();
            p.crossings(k, a, b, &mut t);
            if !t.is_empty() {
                assert!(near.contains(&(k as u32)), "box {k} missed on {a:?}->{b:?}");
            }
        }
    }
    assert_eq!(
        p.height_at(25.0 + 50.0 * 3.0 - 20.0, 10.0 + 50.0 * 2.0),
        10.0 + 4.3
    );
    // A box query finds exactly the boxes a scan of their bounding boxes finds.
    let q = [120.0, 333.0, 40.0, 260.0];
    p.near_box(q, &mut near);
    let scan: Vec<u32> = (0..p.len() as u32)
        .filter(|&k| {
            let b = p.items()[k as usize].bbox;
            b[0] <= q[1] && b[1] >= q[0] && b[2] <= q[3] && b[3] >= q[2]
        })
        .collect();
    assert_eq!(near, scan);
}

#[test]
fn bad_rings_are_errors() {
    let xy = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
    assert!(Prisms::new(xy.clone(), &[0, 2], &[0, 1], &[1.0]).is_err());
    assert!(Prisms::new(xy.clone(), &[0, 3], &[0, 1], &[-1.0]).is_err());
    assert!(Prisms::new(xy, &[0, 3], &[0, 1], &[1.0, 2.0]).is_err());
}
