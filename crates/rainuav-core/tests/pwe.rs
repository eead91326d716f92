//! Accuracy tests of the split-step march against analytic solutions (docs/physics.md section 4).

use ndarray::Array2;
use num_complex::{Complex32, Complex64};
use rainuav_core::propagation::pwe::{
    Ground, MarchSpec, Marcher, Propagator, Recording, StepMedium, StepObstacle,
};
use rainuav_core::wavenumber;

const F: f64 = 4.9e9;

fn spec(
    nx: usize,
    ny: usize,
    d: f64,
    dz: f64,
    propagator: Propagator,
    ground: Ground,
) -> MarchSpec {
    MarchSpec {
        nx,
        ny,
        dx_m: d,
        dy_m: d,
        dz_m: dz,
        freq_hz: F,
        propagator,
        ground,
        absorber: 0.0,
        x_absorber_every: 1,
    }
}

/// Paraxial Gaussian beam `1/q exp(-(x^2 + y^2)/(w0^2 q))`, `q = 1 - j z/zR`, centred at
/// (0, yc), tilted by transverse wavenumber `kt` (Galilean shift: the envelope moves by
/// `kt/k0` per metre of range and picks up `exp(-j kt (y - yc)) exp(+j kt^2 z / (2 k0))`).
fn analytic(x: f64, y: f64, z: f64, w0: f64, yc: f64, kt: f64) -> Complex64 {
    let k0 = wavenumber(F);
    let zr = k0 * w0 * w0 / 2.0;
    let q = Complex64::new(1.0, -z / zr);
    let eta = y - yc - kt / k0 * z;
    let env = (-(x * x + eta * eta) / (w0 * w0 * q)).exp() / q;
    let phase = Complex64::from_polar(1.0, -kt * (y - yc) + kt * kt * z / (2.0 * k0));
    env * phase
}

fn field_from(
    nx: usize,
    ny: usize,
    d: f64,
    f: impl Fn(f64, f64) -> Complex64,
) -> Array2<Complex32> {
    Array2::from_shape_fn((nx, ny), |(ix, iy)| {
        let x = (ix as f64 - (nx / 2) as f64) * d;
        let v = f(x, iy as f64 * d);
        Complex32::new(v.re as f32, v.im as f32)
    })
}

fn rel_l2(a: &Array2<Complex32>, b: &Array2<Complex32>) -> f64 {
    let mut num = 0.0f64;
    let mut den = 0.0f64;
    for (p, q) in a.iter().zip(b) {
        num += ((p - q).norm() as f64).powi(2);
        den += (q.norm() as f64).powi(2);
    }
    (num / den).sqrt()
}

fn power(a: &Array2<Complex32>) -> f64 {
    a.iter().map(|z| z.norm_sqr() as f64).sum()
}

fn clear(_: usize) -> StepMedium<'static> {
    StepMedium::Uniform(Complex64::new(1.0, 0.0))
}
fn nothing(_: usize) -> StepObstacle<'static> {
    StepObstacle::None
}

fn march(spec: MarchSpec, u0: &Array2<Complex32>, steps: usize, n: Complex64) -> Array2<Complex32> {
    let mut m = Marcher::new(spec, u0.view()).unwrap();
    let medium = move |_: usize| StepMedium::Uniform(n);
    let mut rec = Recording {
        record_rows: &[],
        row_offsets: None,
        rows: None,
        column: None,
    };
    m.advance(steps, &medium, &nothing, &mut rec).unwrap();
    m.into_field()
}

/// Narrow propagator on a periodic grid against the analytic paraxial beam after 3.6
/// Rayleigh ranges (w0 = 2 m, zR = 205 m, 150 steps of 5 m). The split-step is exact for
/// the paraxial equation in free space, so what remains is complex64 rounding (~1e-6) and
/// the periodic images of the beam's tails (exp(-25) at the edges): 1e-3 is the bar
/// and leaves two orders of margin.
#[test]
fn narrow_matches_analytic_gaussian_beam() {
    let (n, d, w0) = (256, 0.25, 2.0);
    let yc = 128.0 * d;
    let u0 = field_from(n, n, d, |x, y| analytic(x, y, 0.0, w0, yc, 0.0));
    let got = march(
        spec(n, n, d, 5.0, Propagator::Narrow, Ground::None),
        &u0,
        150,
        Complex64::new(1.0, 0.0),
    );
    let want = field_from(n, n, d, |x, y| analytic(x, y, 750.0, w0, yc, 0.0));
    let err = rel_l2(&got, &want);
    assert!(err < 1e-3, "relative L2 error {err}");
}

/// Without absorber, obstacles or evanescent content, both propagators conserve power to
/// complex64 rounding: 200 steps of ~log2(256) rounding errors of 6e-8 each, random-walk
/// accumulated, is ~1e-5; we allow 1e-4.
#[test]
fn energy_is_conserved() {
    let (n, d, w0) = (256, 0.25, 2.0);
    let u0 = field_from(n, n, d, |x, y| analytic(x, y, 0.0, w0, 32.0, 20.0));
    for prop in [Propagator::Wide, Propagator::Narrow] {
        let got = march(
            spec(n, n, d, 3.0, prop, Ground::None),
            &u0,
            200,
            Complex64::new(1.0, 0.0),
        );
        let ratio = power(&got) / power(&u0);
        assert!((ratio - 1.0).abs() < 1e-4, "{prop:?}: {ratio}");
    }
}

/// Homogeneous lossy medium: power falls by exactly exp(-k0 |Im n^2| d) (docs/physics.md); the
/// screen is applied in f64 and rounded once per step, so 1e-5 relative.
#[test]
fn homogeneous_rain_decay() {
    let (n, d, w0) = (128, 0.25, 2.0);
    let u0 = field_from(n, n, d, |x, y| analytic(x, y, 0.0, w0, 16.0, 0.0));
    let nr = Complex64::new(1.0 + 3e-6, -2e-6);
    let (steps, dz) = (100, 10.0);
    let clear_p = power(&march(
        spec(n, n, d, dz, Propagator::Wide, Ground::None),
        &u0,
        steps,
        Complex64::new(1.0, 0.0),
    ));
    let rain_p = power(&march(
        spec(n, n, d, dz, Propagator::Wide, Ground::None),
        &u0,
        steps,
        nr,
    ));
    let want = (-wavenumber(F) * (nr * nr).im.abs() * dz * steps as f64).exp();
    assert!(
        (rain_p / clear_p / want - 1.0).abs() < 1e-5,
        "{} vs {want}",
        rain_p / clear_p
    );
}

/// PEC ground: a beam tilted up from 12 m reflects off the ground; the march must equal the
/// analytic direct beam minus (pec-h) or plus (pec-v) its image. Narrow propagator, so the
/// only errors are complex64 rounding and the ground row itself (pec-h forces u(0) = 0,
/// exactly what the odd image gives): 1e-3 relative L2.
#[test]
fn pec_ground_matches_direct_plus_image() {
    let (nx, ny, d, w0, h) = (128, 256, 0.25, 2.0, 12.0);
    let k0 = wavenumber(F);
    let kt = -k0 * (3.0f64).to_radians().sin(); // aimed 3 degrees down, towards the ground
    for (ground, sign) in [(Ground::PecH, -1.0), (Ground::PecV, 1.0)] {
        let total = |x: f64, y: f64, z: f64| {
            analytic(x, y, z, w0, h, kt) + sign * analytic(x, -y, z, w0, h, kt)
        };
        let u0 = field_from(nx, ny, d, |x, y| total(x, y, 0.0));
        let got = march(
            spec(nx, ny, d, 4.0, Propagator::Narrow, ground),
            &u0,
            100,
            Complex64::new(1.0, 0.0),
        );
        let want = field_from(nx, ny, d, |x, y| total(x, y, 400.0));
        let err = rel_l2(&got, &want);
        assert!(err < 1e-3, "{ground:?}: relative L2 error {err}");
    }
}

/// Recording rows gives the same values as the final field at the last step.
#[test]
fn recorded_rows_match_field() {
    let (n, d) = (64, 0.25);
    let u0 = field_from(n, n, d, |x, y| analytic(x, y, 0.0, 2.0, 8.0, 0.0));
    let mut m = Marcher::new(
        spec(n, n, d, 5.0, Propagator::Wide, Ground::PecV),
        u0.view(),
    )
    .unwrap();
    let rows = [3usize, 40];
    let mut out = ndarray::Array3::<Complex32>::zeros((2, 7, n));
    let mut col = Array2::<Complex32>::zeros((7, n));
    {
        let mut rec = Recording {
            record_rows: &rows,
            row_offsets: None,
            rows: Some(out.view_mut()),
            column: Some((10, col.view_mut())),
        };
        m.advance(4, &clear, &nothing, &mut rec).unwrap();
        m.advance(3, &clear, &nothing, &mut rec).unwrap();
    }
    let f = m.field();
    for ix in 0..n {
        assert_eq!(out[(0, 6, ix)], f[(ix, 3)]);
        assert_eq!(out[(1, 6, ix)], f[(ix, 40)]);
    }
    for iy in 0..n {
        assert!((col[(6, iy)] - f[(10, iy)]).norm() <= 1e-6 * (1.0 + f[(10, iy)].norm()));
    }
}
