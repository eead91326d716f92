//! The signal a UAV reads: a stack of maps (S, H, W) sampled at many points, each point
//! between its own two slices. Bilinear in space (pixel-centred, edge values held, as
//! [`crate::planning::planner::bilinear`])
//! and linear in time, operation for operation as `rainuav.nav.field.SignalSeries` (and a bank
//! of storms, whose worlds' slices are one stack): the observation of every UAV in flight is
//! one call.

use crate::error::{CoreError, Result};
use ndarray::ArrayView3;

/// The points' values: point `n` at `(x[n], y[n])`, slice `k0[r]` and `k1[r]` mixed as
/// `(1 - f[r]) v0 + f[r] v1` (`v0` alone where `k0[r] == k1[r]`). `k0`, `k1` and `f` have
/// one value per row of consecutive points: as many as the points (a row each), or any
/// divisor `R` of their number (`r = n / (N / R)`: one instant per UAV for all the points
/// it reads, passed once). Serial: one decision's observation is about 10^4 points, where
/// waking a thread pool costs more than it saves.
///
/// ```
/// use ndarray::Array3;
/// use rainuav_core::planning::sampling::sample_slices;
/// // Two 2x2 slices, 0 dB then 10 dB, over a 2 m square; halfway between them in time.
/// let s = Array3::from_shape_fn((2, 2, 2), |(k, _, _)| 10.0 * k as f64);
/// let v = sample_slices(&s.view(), [0.0, 2.0, 0.0, 2.0], &[1.0], &[1.0], &[0], &[1], &[0.5]);
/// assert_eq!(v.unwrap(), vec![5.0]);
/// // Two points of one row: one slice pair and weight for both.
/// let v = sample_slices(&s.view(), [0.0, 2.0, 0.0, 2.0], &[0.5, 1.5], &[1.0, 1.0], &[0], &[1], &[0.25]);
/// assert_eq!(v.unwrap(), vec![2.5, 2.5]);
/// ```
pub fn sample_slices(
    slices: &ArrayView3<'_, f64>,
    extent: [f64; 4],
    x: &[f64],
    y: &[f64],
    k0: &[i64],
    k1: &[i64],
    f: &[f64],
) -> Result<Vec<f64>> {
    let n = x.len();
    if y.len() != n {
        return Err(CoreError::invalid(
            "y",
            format!("must have {n} values"),
            y.len(),
        ));
    }
    let rows = k0.len();
    if rows == 0 && n > 0 || rows > 0 && n % rows != 0 {
        return Err(CoreError::invalid(
            "k0",
            format!("must have one value per row of points: a divisor of {n}"),
            rows,
        ));
    }
    for (name, len) in [("k1", k1.len()), ("f", f.len())] {
        if len != rows {
            return Err(CoreError::invalid(
                name,
                format!("must have {rows} values (as k0)"),
                len,
            ));
        }
    }
    let (s, h, w) = slices.dim();
    if h == 0 || w == 0 {
        return Err(CoreError::invalid(
            "slices",
            "must not be empty",
            format!("{h}x{w}"),
        ));
    }
    let in_stack = |k: &i64| usize::try_from(*k).is_ok_and(|k| k < s);
    if let Some(bad) = k0.iter().chain(k1).find(|k| !in_stack(k)) {
        return Err(CoreError::invalid(
            "k0/k1",
            format!("must be slices in 0..{s}"),
            bad,
        ));
    }
    let standard = slices.as_standard_layout();
    let flat = standard
        .as_slice()
        .ok_or_else(|| CoreError::Internal("a standard-layout stack is contiguous".into()))?;
    let mut out = vec![0.0; n];
    if n == 0 {
        return Ok(out);
    }
    let m = n / rows;
    let row = |r: usize, dst: &mut [f64]| {
        let (b0, b1) = (k0[r] as usize * h * w, k1[r] as usize * h * w);
        for (i, v) in (r * m..).zip(dst.iter_mut()) {
            let p = Corners::new(extent, h, w, x[i], y[i]);
            let v0 = p.mix(flat, b0);
            *v = if k0[r] == k1[r] {
                v0
            } else {
                (1.0 - f[r]) * v0 + f[r] * p.mix(flat, b1)
            };
        }
    };
    out.chunks_mut(m).enumerate().for_each(|(r, d)| row(r, d));
    Ok(out)
}

/// The four pixel centres around a point (offsets within a slice) and its bilinear weights,
/// computed once for both slices; the operations of [`bilinear`] in its order.
struct Corners {
    at: [usize; 4],
    tx: f64,
    ty: f64,
}

impl Corners {
    fn new(extent: [f64; 4], h: usize, w: usize, x: f64, y: f64) -> Self {
        let [x0, x1, y0, y1] = extent;
        let fx = ((x - x0) / (x1 - x0) * w as f64 - 0.5).clamp(0.0, w as f64 - 1.0);
        let fy = ((y - y0) / (y1 - y0) * h as f64 - 0.5).clamp(0.0, h as f64 - 1.0);
        // fx, fy >= 0 after the clamp: truncation is the floor (without a libm call).
        let j0 = (fx as usize).min(w.saturating_sub(2));
        let i0 = (fy as usize).min(h.saturating_sub(2));
        let (j1, i1) = ((j0 + 1).min(w - 1), (i0 + 1).min(h - 1));
        Corners {
            at: [i0 * w + j0, i0 * w + j1, i1 * w + j0, i1 * w + j1],
            tx: fx - j0 as f64,
            ty: fy - i0 as f64,
        }
    }

    /// The bilinear value in the slice that starts at `base` of the flat stack.
    fn mix(&self, flat: &[f64], base: usize) -> f64 {
        let (tx, ty) = (self.tx, self.ty);
        let [a, b, c, d] = self.at.map(|o| flat[base + o]);
        a * (1.0 - tx) * (1.0 - ty) + b * tx * (1.0 - ty) + c * (1.0 - tx) * ty + d * tx * ty
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array3;

    #[test]
    fn a_plane_in_space_and_time_is_sampled_exactly() {
        // v = 2 x + 3 y + 5 t over pixel centres: bilinear in space and linear in time are exact
        // inside the outermost centres (tolerance: rounding).
        let (h, w) = (4usize, 5usize);
        let t = [0.0, 1.0, 2.0];
        let s = Array3::from_shape_fn((3, h, w), |(k, i, j)| {
            2.0 * (j as f64 + 0.5) + 3.0 * (i as f64 + 0.5) + 5.0 * t[k]
        });
        let (x, y) = ([0.7, 4.2, 2.5], [0.6, 3.1, 1.5]);
        let v = sample_slices(
            &s.view(),
            [0.0, 5.0, 0.0, 4.0],
            &x,
            &y,
            &[0, 1, 2],
            &[1, 2, 2],
            &[0.25, 0.5, 0.0],
        )
        .unwrap();
        let want = [
            2.0 * 0.7 + 3.0 * 0.6 + 5.0 * 0.25,
            2.0 * 4.2 + 3.0 * 3.1 + 5.0 * 1.5,
            2.0 * 2.5 + 3.0 * 1.5 + 10.0,
        ];
        for (a, b) in v.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn the_same_as_the_planners_reading_bit_for_bit() {
        // The planner samples one slice at a time (`planner::bilinear`); this sampler computes
        // the weights once for both slices: the same operations, so the same bits.
        let s = Array3::from_shape_fn((3, 7, 9), |(k, i, j)| ((k * 31 + i * 7 + j) as f64).sin());
        let e = [-3.0, 8.0, 1.0, 5.5];
        let mut next = crate::test_stream(12345);
        for _ in 0..2000 {
            let (x, y, f) = (-5.0 + 15.0 * next(), 0.0 + 7.0 * next(), next());
            let (k0, k1) = ((3.0 * next()) as i64, (3.0 * next()) as i64);
            let v = sample_slices(&s.view(), e, &[x], &[y], &[k0], &[k1], &[f]).unwrap()[0];
            let slice = |k: i64| s.index_axis(ndarray::Axis(0), k as usize);
            let v0 = crate::planning::planner::bilinear(&slice(k0), e, x, y);
            let v1 = crate::planning::planner::bilinear(&slice(k1), e, x, y);
            let want = if k0 == k1 {
                v0
            } else {
                (1.0 - f) * v0 + f * v1
            };
            assert_eq!(v.to_bits(), want.to_bits(), "{x} {y} {k0} {k1} {f}");
        }
    }

    #[test]
    fn one_slice_pair_per_row_is_the_per_point_call_bit_for_bit() {
        // Rows of m points sharing their instant (one UAV's window) against the same
        // instant repeated per point: a few short rows, and 40 UAVs' 11 x 11 windows.
        let s = Array3::from_shape_fn((4, 9, 11), |(k, i, j)| ((k * 17 + i * 5 + j) as f64).cos());
        let e = [0.0, 11.0, 0.0, 9.0];
        for (rows, m) in [(3usize, 5usize), (40, 121)] {
            let n = rows * m;
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37) % 12.0 - 0.5).collect();
            let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.91) % 10.0 - 0.5).collect();
            let k0: Vec<i64> = (0..rows as i64).map(|r| r % 4).collect();
            let k1: Vec<i64> = (0..rows as i64).map(|r| (r + r % 2) % 4).collect();
            let f: Vec<f64> = (0..rows).map(|r| r as f64 / rows as f64).collect();
            let each = |v: &[i64]| v.iter().flat_map(|&k| std::iter::repeat_n(k, m)).collect();
            let (k0p, k1p): (Vec<i64>, Vec<i64>) = (each(&k0), each(&k1));
            let fp: Vec<f64> = f.iter().flat_map(|&v| std::iter::repeat_n(v, m)).collect();
            let by_row = sample_slices(&s.view(), e, &x, &y, &k0, &k1, &f).unwrap();
            let by_point = sample_slices(&s.view(), e, &x, &y, &k0p, &k1p, &fp).unwrap();
            assert!(
                by_row
                    .iter()
                    .zip(&by_point)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
        // 7 points cannot be split in rows of equal length for 2 slice pairs.
        let x = [0.5; 7];
        assert!(sample_slices(&s.view(), e, &x, &x, &[0, 1], &[0, 1], &[0.0, 0.0]).is_err());
        assert!(sample_slices(&s.view(), e, &x, &x, &[], &[], &[]).is_err());
    }

    #[test]
    fn bad_points_and_slices_are_refused() {
        let s = Array3::<f64>::zeros((2, 3, 3));
        let e = [0.0, 1.0, 0.0, 1.0];
        assert!(sample_slices(&s.view(), e, &[0.5], &[], &[0], &[0], &[0.0]).is_err());
        assert!(sample_slices(&s.view(), e, &[0.5], &[0.5], &[2], &[0], &[0.0]).is_err());
        assert!(sample_slices(&s.view(), e, &[0.5], &[0.5], &[0], &[-1], &[0.0]).is_err());
        let empty = Array3::<f64>::zeros((1, 0, 3));
        assert!(sample_slices(&empty.view(), e, &[0.5], &[0.5], &[0], &[0], &[0.0]).is_err());
    }
}
