"""What the calibrated map still gets wrong: the residual (measured minus calibrated, dB) of one
cell as a field in (east, north, height), estimated by Gaussian-process regression
(scikit-learn's ``GaussianProcessRegressor``).

**Bins.** Rows are first averaged over the map's pixels and height bins of ``level_step_m``
(what a drive test does over fast fading): one point a bin, at the mean position of its rows.
Where a cell has more than ``MAX_POINTS`` bins, the bins are doubled in size until it has not
(the count is reported).

**The sample spread.** The rows of one bin scatter around the bin's mean by fast fading, the
UAV's antenna and airframe turning, and the receiver: their pooled standard deviation (the sum
of squares about each bin's mean over the rows less the bins, over the bins of two rows or more)
is the cell's ``sample_db``, the spread of one sample around the local mean. It also sets how
well each bin's mean is known: ``sample_db^2 / n`` on the diagonal for a bin of ``n`` rows
(scikit-learn's per-point ``alpha``), so a bin of one row weighs less than a bin of fifty.
A log of one row a bin (a drive test that logs one averaged value a pixel) does not show it: the
nugget below then is the sample spread, and the local mean's deviation leaves it out.

**Kernel.** ``C Matern(nu = 1.5) + White``: an amplitude (how far the calibrated map's local
mean is off, typically), one length scale across the ground and one in height (height only where
the log spans more than one height bin; the ratio of the two chosen among ``HEIGHT_RATIOS`` by
the likelihood), and a nugget: what the local mean varies from bin to bin that no smooth field
explains. The hyperparameters maximise the marginal likelihood on at most ``MAX_FIT`` bins
(drawn with the seed), then the field is conditioned on every bin with them fixed. Away from
the measurements the mean returns to 0 (the calibrated map) and the standard deviation to
``sqrt(amplitude^2 + nugget^2)``: the calibrated map's own spread, learned from the log.

**Scaled.** Where the caller knows how far the map is likely off at each point (the prior's
spread by mechanism and distance: a shadow is less sure than a lit street), the field may be
that scale times a stationary field, ``r(x) = s(x) W(x)``: fitted on the bins' residuals over
their scale (each bin's noise over its scale squared), its mean and deviation are ``s(x)`` times
``W``'s, so far from every measurement the deviation returns to the amplitude times the
pixel's own scale. Both models are fitted and the one of higher marginal likelihood of the
residuals themselves kept (the scaled one's less the Jacobian, the sum of ``log s`` over its
bins): the data choose, not an assumption. ``mean()``, ``std()`` and ``on_grid()`` then take
the scale at their points.

**Two scales.** A real log shows structure at two scales at once: a smooth trend over hundreds
of metres, and structure over a few tens of metres (the airframe's attitude along the path, a
row of trees, the ground's reflection) that repeats at the same place on flights at other
heights. One Matern takes the second for noise: its nugget. ``kernel="two-scale"`` fits
``C1 Matern(long) + C2 Matern(short) + White``, each Matern with its own length east, north and
in height (``KERNELS``). Short lags must be seen for the likelihood to tell a short field from a
nugget, so its fitting subset is ``MAX_FIT`` bins nearest to ``CLUSTERS`` centres drawn with the
seed and ``MAX_FIT`` more drawn at random (long lags), and its field is conditioned on up to
``TWO_SCALE_MAX_POINTS`` bins, so the map's own pixels resolve the short field. It is asked
for, not the default: on AERPAW's flights it closes the gap to the nearest logged samples at
held-out heights (within 0.1 dB of them, either way with the seed) and loses a little over
held-out stretches (the page "How far to trust a map").

**Standard deviation.** ``std()`` is the uncertainty of the local mean (the 10 m average the
map predicts) at a point: the field's posterior deviation and the nugget in quadrature. One
future sample there spreads by that and ``sample_db`` in quadrature."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from scipy.spatial import cKDTree

from rainuav.radio.measured.bins import bin_index, bin_points, bin_scale, sample_spread

if TYPE_CHECKING:  # scikit-learn is imported where a field is fitted (it takes seconds to load)
    from sklearn.gaussian_process import GaussianProcessRegressor

__all__ = [
    "CLUSTERS",
    "KERNELS",
    "MAX_FIT",
    "MAX_POINTS",
    "SHORT_MAX_M",
    "TWO_SCALE_MAX_POINTS",
    "ResidualField",
    "bin_index",
    "bin_points",
    "bin_scale",
    "fit_residual",
    "sample_spread",
]

MAX_POINTS = 2500
"""The most bins one cell's field is conditioned on."""
MAX_FIT = 150
"""The most bins its hyperparameters are fitted on."""
KERNELS = ("one-scale", "two-scale")
"""The residual fields' kernels (module docstring): one Matern with a nugget, or two."""
TWO_SCALE_MAX_POINTS = 5000
"""The most bins a two-scale field is conditioned on."""
CLUSTERS = 3
"""The centres a two-scale field's fitting subset gathers its neighbouring bins around."""
SHORT_MAX_M = 100.0
"""The longest length scale of a two-scale field's short component, m."""
HEIGHT_RATIOS = (1.0, 3.0, 10.0)
"""The ratios of the ground's length scale to the height's that are tried (the likeliest kept)."""
FAR = 4.0
"""Length scales beyond which a pixel's field is its prior (Matern 3/2: correlation 0.008)."""
GRID_POINTS = 625
"""The fewest map pixels the field is computed at where its length scales allow fewer
([`ResidualField.on_grid()`][rainuav.radio.measured.residual.ResidualField.on_grid])."""


def _features(pts: np.ndarray, ratio: float) -> np.ndarray:
    """East, north and (where ``ratio``) height times ``ratio``: one isotropic length scale."""
    if ratio == 0:
        return pts[:, :2]
    return np.column_stack([pts[:, 0], pts[:, 1], pts[:, 2] * ratio])


@dataclass
class ResidualField:
    """One cell's residual field."""

    gp: GaussianProcessRegressor
    """The conditioned regressor (its kernel's hyperparameters fixed)."""
    height_ratio: float
    """How many times longer the field's length scale is across the ground than in height
    (0: the same at every height: the log spans one height bin)."""
    amplitude_db: float
    """The smooth field's standard deviation far from any measurement, dB."""
    noise_db: float
    """The nugget: the local mean's bin-to-bin variation no smooth field explains, dB."""
    sample_db: float
    """The spread of one sample around the local mean (module docstring), dB."""
    length_m: float
    """The length scale across the ground, m (in height: this over ``height_ratio``); a two-scale
    field's shortest across the ground (``components`` has them all)."""
    bins: int
    """The points it is conditioned on."""
    bin_m: float
    """The bins' width, m (the map's pixel, or larger where thinned)."""
    nugget_is_sample: bool = False
    """Whether the log showed no sample spread (one row a bin), so the nugget stands for it."""
    scaled: bool = False
    """Whether the field is the residual over a scale known at every point (module docstring,
    "Scaled"): its mean and deviation are then in units of that scale, which the callers
    multiply by."""
    kernel: str = "one-scale"
    """Its kernel (``KERNELS``)."""
    components: tuple[tuple[float, float, float, float], ...] = ()
    """A two-scale field's components, long first: amplitude (dB) and length scales east, north
    and in height (m) of each (empty for one scale: ``amplitude_db``, ``length_m`` and
    ``height_ratio`` say it)."""
    kernel_scores: dict[str, float] | None = None
    """Where the log chose the kernel (``kernel="auto"``,
    [`rainuav.radio.measured.choice`][rainuav.radio.measured.choice]): each candidate's held-out
    log predictive density per bin."""
    candidates: dict[str, ResidualField] | None = None
    """Those candidates' fields, so that a cross-validation fold chooses again on its own rows."""

    @property
    def reach_m(self) -> float:
        """The longest length scale across the ground, m: farther than ``FAR`` of them from
        every measurement, the field is its prior."""
        if not self.components:
            return self.length_m
        return max(max(c[1], c[2]) for c in self.components)

    def _x(self, pts: np.ndarray) -> np.ndarray:
        return _features(pts, self.height_ratio)

    def _scale(self, shape: Any, scale: Any) -> Any:
        """1 for a stationary field; a scaled field's ``scale`` at its points, of ``shape``."""
        if not self.scaled:
            return 1.0
        if scale is None:
            raise ValueError("a scaled field needs the scale at its points")
        return np.broadcast_to(np.asarray(scale, dtype=float), shape)

    def mean(self, pts: np.ndarray, scale: Any = None) -> np.ndarray:
        """The field's mean at points, dB.

        Args:
            pts: The points (N, 3): east, north, height, m.
            scale: The scale at each (N,), for a scaled field.

        Returns:
            (N,) dB.
        """
        return self._mean_w(pts) * self._scale(len(pts), scale)

    def _mean_w(self, pts: np.ndarray, chunk: int = 20000) -> np.ndarray:
        out = [self.gp.predict(self._x(pts[i : i + chunk])) for i in range(0, len(pts), chunk)]
        return np.concatenate(out) if out else np.zeros(0)

    @property
    def far_db(self) -> float:
        """The local mean's deviation far from every measurement, dB (module docstring)."""
        return (
            self.amplitude_db
            if self.nugget_is_sample
            else float(np.hypot(self.amplitude_db, self.noise_db))
        )

    def far_at(self, n: int, scale: Any = None) -> np.ndarray:
        """The local mean's deviation far from every measurement, dB.

        Args:
            n: How many points.
            scale: The scale at each (N,), for a scaled field.

        Returns:
            (n,) dB.
        """
        return np.full(n, self.far_db) * self._scale(n, scale)

    def std(self, pts: np.ndarray, scale: Any = None) -> np.ndarray:
        """The local mean's standard deviation at points, dB (the module's docstring).

        The field's posterior deviation with the nugget (scikit-learn's predictive deviation of a
        kernel with a white term).

        Args:
            pts: The points (N, 3): east, north, height, m.
            scale: The scale at each (N,), for a scaled field.

        Returns:
            (N,) dB.
        """
        return self._std_w(pts) * self._scale(len(pts), scale)

    def _std_w(self, pts: np.ndarray, chunk: int = 4000) -> np.ndarray:
        nugget = self.noise_db**2 if self.nugget_is_sample else 0.0
        out = []
        for i in range(0, len(pts), chunk):
            _, s = self.gp.predict(self._x(pts[i : i + chunk]), return_std=True)
            out.append(np.sqrt(np.maximum(s**2 - nugget, 0.0)))
        return np.concatenate(out) if out else np.zeros(0)

    def on_grid(
        self, x_m: np.ndarray, y_m: np.ndarray, h_m: np.ndarray, scale: Any = None
    ) -> tuple[Any, Any]:
        """The field's mean and standard deviation over a map's pixel centres.

        Both vary over the field's length scales, many pixels: they are computed every `k` pixels
        (`k` a quarter of the shorter length scale across the ground, in pixels, and at least enough
        for `GRID_POINTS` nodes; the last row and column always) and bilinear between; a scaled
        field's are then multiplied by each pixel's scale.

        Args:
            x_m: The pixel centres' east (W,), m.
            y_m: Their north (H,), m.
            h_m: Their heights (H, W), m.
            scale: Each pixel's scale (H, W), for a scaled field.

        Returns:
            `(mean, std)`, (H, W) each, dB.
        """
        mean, std = self._grid(x_m, y_m, h_m)
        u = self._scale(np.shape(mean), scale)
        return mean * u, std * u

    def _grid(self, x_m: np.ndarray, y_m: np.ndarray, h_m: np.ndarray) -> tuple[Any, Any]:
        gx, gy = np.meshgrid(x_m, y_m)
        h_m = np.broadcast_to(np.asarray(h_m, dtype=float), gx.shape)
        px = float(abs(x_m[1] - x_m[0])) if len(x_m) > 1 else 1.0
        k = max(1, min(int(self.length_m / (2 * px)), int(np.sqrt(gx.size / GRID_POINTS))))
        ri = np.unique(np.r_[np.arange(0, len(y_m), k), len(y_m) - 1])
        ci = np.unique(np.r_[np.arange(0, len(x_m), k), len(x_m) - 1])
        sub = np.ix_(ri, ci)
        pts = np.column_stack([gx[sub].ravel(), gy[sub].ravel(), h_m[sub].ravel()])
        # Farther than FAR length scales from every measurement the field is its prior (a
        # correlation under 1%): mean 0, deviation the amplitude.
        reach = self.reach_m
        tree = cKDTree(self.gp.X_train_ / reach)
        near = tree.query(self._x(pts) / reach, distance_upper_bound=FAR)[0] < FAR
        mean = np.zeros(len(pts))
        std = np.full(len(pts), self.far_db)
        mean[near], std[near] = self._mean_w(pts[near]), self._std_w(pts[near])
        mean, std = mean.reshape(len(ri), len(ci)), std.reshape(len(ri), len(ci))
        if k == 1:
            return mean, std
        at = np.column_stack([gy.ravel(), gx.ravel()])
        out = [RegularGridInterpolator((y_m[ri], x_m[ci]), v)(at).reshape(gx.shape)
               for v in (mean, std)]  # fmt: skip
        return out[0], out[1]


def _kernel(spread: float, length: float, bounds: tuple[float, float]) -> Any:
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    return ConstantKernel(max(spread, 0.25), (1e-4, 1e4)) * Matern(
        length, (bounds[0], bounds[1]), nu=1.5
    ) + WhiteKernel(1.0, (1e-3, 1e2))


def _two_scale_kernel(spread: float, length: float, bounds: tuple[float, float], dims: int) -> Any:
    """The two-scale kernel (module docstring) on ``dims`` features (east, north[, height], m)."""
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    half = max(spread, 0.25) / 2
    long = [length, length, length / 3][:dims]
    short = [30.0] * dims
    return (
        ConstantKernel(half, (1e-4, 1e4)) * Matern(long, (bounds[0] / 2, bounds[1]), nu=1.5)
        + ConstantKernel(half, (1e-4, 1e4)) * Matern(short, (bounds[0] / 2, SHORT_MAX_M), nu=1.5)
        + WhiteKernel(1.0, (1e-3, 1e2))
    )


def _fit_subset(bp: np.ndarray, seed: int, local: bool) -> np.ndarray:
    """The bins the hyperparameters are fitted on: ``MAX_FIT`` drawn at random; for a two-scale
    field (``local``) also the ``MAX_FIT`` nearest to ``CLUSTERS`` random centres (short lags)."""
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(bp))
    if not local:
        return order[:MAX_FIT]
    tree = cKDTree(bp[:, :2])
    near = [tree.query(bp[c, :2], k=min(MAX_FIT // CLUSTERS, len(bp)))[1]
            for c in order[:CLUSTERS]]  # fmt: skip
    near_bins = np.unique(np.concatenate(near))
    rest = order[~np.isin(order, near_bins)][:MAX_FIT]
    return np.unique(np.r_[near_bins, rest])


def _components(kernel: Any) -> tuple[tuple[float, float, float, float], ...]:
    """A two-scale kernel's components, long first: amplitude, lengths east, north, height."""
    out = []
    for part in (kernel.k1.k1, kernel.k1.k2):
        ls = np.atleast_1d(part.k2.length_scale).astype(float)
        out.append((float(np.sqrt(part.k1.constant_value)), float(ls[0]), float(ls[1]),
                    float(ls[2]) if len(ls) > 2 else float("inf")))  # fmt: skip
    return tuple(sorted(out, key=lambda c: -max(c[1], c[2])))


def fit_residual(
    pts: np.ndarray,
    resid: np.ndarray,
    *,
    size_m: float,
    step_m: float,
    extent_m: float,
    seed: int = 0,
    like: ResidualField | None = None,
    max_points: int | None = None,
    scale: np.ndarray | None = None,
    kernel: str = "one-scale",
) -> ResidualField:
    """The residual field of one cell, fitted on its rows' residuals (the module's docstring).

    Args:
        pts: The rows' points (N, 3): east, north, height, m.
        resid: Their residuals, dB (N,).
        size_m: The bins' width, m.
        step_m: Their height, m.
        extent_m: The area's size, m (the longest length scale is 5 times it).
        seed: The fit's seed.
        like: A field whose hyperparameters and sample spread to reuse (a cross-validation fold);
            None: fitted here.
        max_points: The most bins it is conditioned on (default `MAX_POINTS`).
        scale: Each row's scale (N,), positive, dB: the scaled field is fitted beside the stationary
            one and kept where its marginal likelihood is higher.
        kernel: One of `KERNELS` (a `like` field's own where given).

    Returns:
        The [`ResidualField`][rainuav.radio.measured.residual.ResidualField].

    Raises:
        ValueError: An unknown kernel.
    """
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor

    sample = sample_spread(pts[:, 0], pts[:, 1], pts[:, 2], resid, size_m, step_m)
    unseen = not np.isfinite(sample)
    if like is not None:
        sample, unseen = like.sample_db, like.nugget_is_sample
    if unseen:
        sample = 0.0  # one row a bin: the spread is not seen (the nugget takes it)
    if like is not None:
        kernel = like.kernel
    if kernel not in KERNELS:
        raise ValueError(f"kernel must be one of {', '.join(KERNELS)} (got {kernel!r})")
    two = kernel == "two-scale"
    max_points = MAX_POINTS if max_points is None else max_points
    if two:  # the short field needs the pixels: the map's own bins, in every fold alike
        max_points = TWO_SCALE_MAX_POINTS
    bm = size_m
    while True:
        bp, bv, count = bin_points(pts[:, 0], pts[:, 1], pts[:, 2], resid, bm, step_m)
        if len(bv) <= max_points:
            break
        bm *= 2
    alpha = np.maximum(sample**2 / count, 1e-6)
    sb = bin_scale(pts, scale, bm, step_m, count)
    if like is not None:
        kern, ratio, scaled = like.gp.kernel_, like.height_ratio, like.scaled
        scaled = scaled and scale is not None
    else:
        in_height = np.ptp(np.round(bp[:, 2] / step_m)) >= 1
        pick = _fit_subset(bp, seed, two)
        best = None
        for scaled in (False, True) if scale is not None else (False,):
            u = sb if scaled else np.ones(len(bv))
            y, a = bv / u, alpha / u**2
            # the likelihood of the residuals themselves: that of y less the scale's Jacobian
            jac = float(np.sum(np.log(u[pick])))
            bounds = (2 * size_m, 5 * extent_m)
            if two:  # lengths of their own in height: the features in metres
                ratios: tuple[float, ...] = (1.0,) if in_height else (0.0,)
                dims = 3 if in_height else 2
                k0 = _two_scale_kernel(float(np.var(y)), extent_m / 10, bounds, dims)
            else:
                ratios = HEIGHT_RATIOS if in_height else (0.0,)
                k0 = _kernel(float(np.var(y)), extent_m / 10, bounds)
            for ratio in ratios:
                with warnings.catch_warnings():  # a bound reached is a result (a flat field)
                    warnings.simplefilter("ignore", ConvergenceWarning)
                    g = GaussianProcessRegressor(k0, alpha=a[pick], random_state=seed)
                    g.fit(_features(bp[pick], ratio), y[pick])
                lml = g.log_marginal_likelihood_value_ - jac
                if best is None or lml > best[0]:
                    best = (lml, g.kernel_, ratio, scaled)
        assert best is not None
        _, kern, ratio, scaled = best
    u = sb if scaled else np.ones(len(bv))
    gp = GaussianProcessRegressor(kern, alpha=alpha / u**2, optimizer=None)
    gp.fit(_features(bp, ratio), bv / u)
    nugget = float(np.sqrt(kern.k2.noise_level))
    if two:
        comps = _components(kern)
        amplitude = float(np.sqrt(sum(c[0] ** 2 for c in comps)))
        length = min(min(c[1], c[2]) for c in comps)
    else:
        comps = ()
        amplitude = float(np.sqrt(kern.k1.k1.constant_value))
        length = float(kern.k1.k2.length_scale)
    return ResidualField(
        gp=gp, height_ratio=float(ratio), amplitude_db=amplitude, noise_db=nugget,
        sample_db=nugget if unseen else float(sample), nugget_is_sample=bool(unseen),
        length_m=length, bins=len(bv), bin_m=bm, scaled=bool(scaled), kernel=kernel,
        components=comps,
    )  # fmt: skip
