"""The Rust sampler of signals in time (``rainuav._sampling.in_time``, what every UAV's
observation reads) against the numpy convention it replaces: bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from rainuav._sampling import bilinear, in_time
from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalField


def numpy_in_time(values, extent, x, y, k0, k1, f):
    """The numpy reading: each slice bilinear (rainuav._sampling.bilinear), mixed in time."""
    v0, v1 = bilinear(values, extent, x, y, k0), bilinear(values, extent, x, y, k1)
    return np.where(k0 == k1, v0, (1.0 - f) * v0 + f * v1)


@pytest.mark.parametrize("shape", [(7, 30, 40), (3, 1, 5), (2, 6, 1), (4, 2, 2)])
def test_in_time_is_the_numpy_reading_bit_for_bit(shape) -> None:
    """Random stacks, points inside and beyond the area (edge values held), equal slices and
    mixed ones, maps one pixel wide: the same float64 values to the last bit (the Rust core
    does the same operations in the same order)."""
    rng = np.random.default_rng(1)
    s = shape[0]
    values = rng.normal(0.0, 10.0, shape)
    extent = (-100.0, 900.0, 50.0, 650.0)
    n = 5000
    x, y = rng.uniform(-300.0, 1100.0, n), rng.uniform(-100.0, 800.0, n)
    k0 = rng.integers(0, s, n)
    k1 = np.where(rng.random(n) < 0.3, k0, rng.integers(0, s, n))
    f = rng.random(n)
    got = in_time(values, extent, x, y, k0, k1, f)
    np.testing.assert_array_equal(got, numpy_in_time(values, extent, x, y, k0, k1, f))
    # Broadcast shapes: (N, M) points, one slice pair per row.
    xs, ys = x[:600].reshape(20, 30), y[:600].reshape(20, 30)
    r0, r1, rf = k0[:20, None], k1[:20, None], f[:20, None]
    got = in_time(values, extent, xs, ys, r0, r1, rf)
    r0, r1, rf = (np.broadcast_to(a, xs.shape) for a in (r0, r1, rf))
    want = numpy_in_time(values, extent, xs, ys, r0, r1, rf)
    np.testing.assert_array_equal(got, want)


def test_fields_read_through_it_as_before() -> None:
    """A series and a bank read the numpy values at points and instants (between slices,
    on a slice, before the first and after the last)."""
    rng = np.random.default_rng(2)
    t = np.array([0.0, 5.0, 10.0, 20.0])
    ext = (0.0, 1000.0, 0.0, 800.0)
    db = rng.normal(0.0, 5.0, (3, 4, 16, 20))
    bank = SignalField.bank(db, t, ext)
    x, y = rng.uniform(0, 1000, (64, 50)), rng.uniform(0, 800, (64, 50))
    tau = np.r_[rng.uniform(-5.0, 25.0, 60), 0.0, 5.0, 20.0, 30.0][:, None]
    world = rng.integers(0, 3, (64, 1))
    for w in range(3):
        series = SignalField.series(db[w], t, ext)
        k0, k1, f = (np.broadcast_to(a, x.shape) for a in series.brackets(tau))
        want = numpy_in_time(db[w], ext, x, y, k0, k1, f)
        np.testing.assert_array_equal(series(x, y, tau), want)
        rows = world[:, 0] == w
        np.testing.assert_array_equal(bank(x, y, tau, world)[rows], want[rows])
        # One instant for every point (the slice pair crosses once).
        k0, k1, f = (np.broadcast_to(a, x.shape) for a in series.brackets(7.5))
        np.testing.assert_array_equal(series(x, y, 7.5), numpy_in_time(db[w], ext, x, y, k0, k1, f))
        # Fixed points (a whole-area grid, every slice sampled once, then mixed per row)
        # read as the points themselves.
        pts = np.stack([x[0], y[0]], axis=-1)
        at = series.at_points(pts, tau[:, 0])
        np.testing.assert_array_equal(at, series(pts[:, 0], pts[:, 1], tau))
        np.testing.assert_array_equal(bank.at_points(pts, tau[:, 0], world[:, 0])[rows], at[rows])


def test_brackets_kept_for_the_same_instants_are_the_computed_ones() -> None:
    """A series keeps its last instants' brackets (an observation asks for them twice: (N, 1)
    for the window, (N,) for the grid): asked again in either shape, or after other instants,
    they equal a fresh series' brackets, and nobody can write into the kept arrays."""
    t = np.array([0.0, 5.0, 10.0, 20.0])
    series = SignalField.series(np.zeros((4, 2, 2)), t, (0.0, 1.0, 0.0, 1.0))
    rng = np.random.default_rng(3)
    a, b = rng.uniform(-5.0, 25.0, (2, 40))
    for tau in (a[:, None], a, b, a, a[:7], 5.0):
        got = series.brackets(tau)
        want = SignalField.series(np.zeros((4, 2, 2)), t, (0.0, 1.0, 0.0, 1.0)).brackets(tau)
        for g, w in zip(got, want, strict=True):
            assert g.shape == np.shape(tau)
            np.testing.assert_array_equal(g, w)
            assert not g.flags.writeable


def test_bad_slices_are_refused_in_one_line() -> None:
    v = np.zeros((2, 3, 3))
    ext = (0.0, 1.0, 0.0, 1.0)
    with pytest.raises(InvalidInputError, match=r"k0/k1 must be slices in 0\.\.2"):
        in_time(v, ext, [0.5], [0.5], [2], [0], [0.0])
    with pytest.raises(InvalidInputError, match="k0/k1"):
        in_time(v, ext, [0.5], [0.5], [0], [-1], [0.0])
