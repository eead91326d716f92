"""The ray engine's buildings against Sionna RT 2.2, scene by scene (the results page's table).

    python experiments/tracer_compare.py [--scenes urban district] [--freqs-ghz 3.5 4.9 28]
        [--altitudes 20 100] [--pols v h] [--samples 8e6] [--reference map|paths] [--step N]
        [--coefficient p526 sionna] [--runs N] [--sites K ...] [--json FILE] [--figure FILE]

For each scene ([`rainuav.radio.reference.tracer_scenes`][rainuav.radio.reference.tracer_scenes]; by
default the held-back ones, on which no choice of the methods was made), frequency, UAV altitude and
polarisation: the building effect (map with buildings minus without, dB) of the ray engine against
the tracer's, site by site, on the pixels the tracer covers (no ground, isotropic antennas;
[`rainuav.radio.reference.comparison.compare()`][rainuav.radio.reference.comparison.compare];
``--engine hybrid``: rainuav's hybrid engine, the parabolic equation in each cell's cone). Prints
one line a site: pixels compared, the tracer's shadow pixels (effect below -6 dB), |engine - tracer|
in the shadow (median, 90th percentile), the median signed difference (negative: the engine's shadow
deeper), the median |difference| in the light, the share of pixels where shadow and light agree, and
the tracer's own noise (median, from two halves of its rays) and the pixels left out because their
halves differ by more than twice the tolerance. The targets: shadow within 3 dB median
and 8 dB p90, light within 0.5 dB, 95% agreement. ``--figure``: the building effect of both and
their difference for the first case's first site. ``--reference paths``: against the tracer's path
solver at the centre of every ``--step``-th pixel
([`rainuav.radio.reference.tracer_paths`][rainuav.radio.reference.tracer_paths]: its exact paths,
where the radio map is a Monte Carlo estimate that is dark and scattered in deep shadows; its
"noise" is then the difference between two candidate searches; ``--runs``: how many runs of its
candidate search, combined as the union of the paths they find, the halves the unions of the even
and of the odd runs). ``--sites``: only these sites of each scene. ``--coefficient``: the
tracer's wedge coefficient, ITU-R P.526-15's (``p526``, which a full-wave solution supports on a
concrete corner: ``experiments/wedge_fullwave.py``) and its own as released (``sionna``); by
default both, one row each, side by side.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from rainuav.radio.reference import tracer
from rainuav.radio.reference.comparison import compare
from rainuav.radio.reference.tracer_scenes import HELD_BACK, SCENES, scene


def _figure(path: Path, scn, samples: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    w, wo = tracer.isotropic_scenario(scn), tracer.isotropic_scenario(scn, buildings=False)
    ours = 10 * np.log10(tracer.engine_gain(w)[0] / tracer.engine_gain(wo)[0])
    tw, two = tracer.tracer_gain(w, samples=samples), tracer.tracer_gain(wo, samples=samples)
    with np.errstate(divide="ignore", invalid="ignore"):
        ref = 10 * np.log10(tw.gain[0] / two.gain[0])
    ok = tw.covered[0] & two.covered[0] & ~tracer.inside_buildings(w)
    ref = np.where(ok, ref, np.nan)
    a = scn.area
    ext = (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6), layout="constrained")
    for axis, v, title, cmap, lim in (
        (ax[0], ours, "ray engine", "viridis", (-40, 5)),
        (ax[1], ref, "Sionna RT 2.2 (blank: not covered)", "viridis", (-40, 5)),
        (ax[2], ours - ref, "engine - tracer", "RdBu", (-20, 20)),
    ):
        im = axis.imshow(v, origin="lower", extent=ext, cmap=cmap, vmin=lim[0], vmax=lim[1])
        axis.set_title(title)
        axis.set_xlabel("east, m")
        fig.colorbar(im, ax=axis, label="dB")
    ax[0].set_ylabel("north, m")
    s = w.sites[0]
    for axis in ax:
        axis.plot([s.x_m], [s.y_m], "k^", ms=8)
    fig.suptitle(f"building effect, {scn.name}: {path.name} ({time.strftime('%Y-%m-%d')}, "
                 f"{platform.processor() or platform.machine()})")  # fmt: skip
    fig.savefig(path, dpi=80)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=list(HELD_BACK), choices=sorted(SCENES))
    ap.add_argument("--freqs-ghz", nargs="+", type=float, default=[3.5, 4.9, 28.0])
    ap.add_argument("--altitudes", nargs="+", type=float, default=[20.0, 100.0])
    ap.add_argument("--pols", nargs="+", default=["v", "h"], choices=["v", "h"])
    ap.add_argument("--samples", type=float, default=8e6)
    ap.add_argument(
        "--engine", default="ray", choices=["ray", "hybrid", "pe"],
        help="rainuav's engine (hybrid: the parabolic equation in each cell's cone)",
    )  # fmt: skip
    ap.add_argument(
        "--reference", default="map", choices=["map", "paths"],
        help="the tracer's radio map, or its path solver at the pixel centres",
    )  # fmt: skip
    ap.add_argument(
        "--step", type=int, default=1,
        help="with --reference paths: every STEP-th pixel in both directions",
    )  # fmt: skip
    ap.add_argument(
        "--coefficient", nargs="+", default=["p526", "sionna"], choices=["p526", "sionna"],
        help="the tracer's wedge coefficient: ITU-R P.526-15's, its own as released, or both "
             "(one row each, side by side)",
    )  # fmt: skip
    ap.add_argument(
        "--runs", type=int, default=2,
        help="with --reference paths: the path solver's runs (even), their paths' union",
    )  # fmt: skip
    ap.add_argument("--sites", type=int, nargs="+", default=None, help="only these sites")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--figure", type=Path, default=None)
    args = ap.parse_args()
    samples = int(args.samples)
    print(f"# {platform.processor() or platform.machine()}, {samples:.0e} rays a site, "
          f"engine {args.engine}, reference {args.reference} (step {args.step}, "
          f"{args.runs} runs)")  # fmt: skip
    head = (
        "scene     GHz  alt pol site coef   pixels shadow  med   p90   bias light agree noise noisy"
    )
    print(head)
    rows = []
    for name in args.scenes:
        for f in args.freqs_ghz:
            for alt in args.altitudes:
                for pol in args.pols:
                    t = time.perf_counter()
                    scn = scene(name, f * 1e9, alt, pol)
                    sites = list(range(len(scn.sites))) if args.sites is None else args.sites
                    scn = scn.replace(sites=[scn.sites[k] for k in sites])
                    both = {
                        c: compare(
                            scn, samples=samples, engine=args.engine, reference=args.reference,
                            step=args.step, coefficient=c, runs=args.runs,
                        ).rows()
                        for c in args.coefficient
                    }  # fmt: skip
                    for i, k in enumerate(sites):
                        for c, found in both.items():
                            r = found[i]
                            rows.append({"scene": name, "freq_ghz": f, "altitude_m": alt,
                                         "pol": pol, "site": k, "coefficient": c, **r})  # fmt: skip
                            print(f"{name:8} {f:5.1f} {alt:4.0f}  {pol}  {k:3d} {c:6} "
                                  f"{r['pixels']:6.0f} {r['shadow_pixels']:6.0f} "
                                  f"{r['shadow_median']:5.2f} {r['shadow_p90']:5.2f} "
                                  f"{r['shadow_bias']:6.2f} {r['light_median']:5.2f} "
                                  f"{r['classes_agree']:5.3f} {r['noise_median']:5.2f} "
                                  f"{r['noisy']:5.0f}",
                                  flush=True)  # fmt: skip
                    print(f"#   {time.perf_counter() - t:.1f} s", flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1))
    if args.figure is not None:
        first = scene(args.scenes[0], args.freqs_ghz[0] * 1e9, args.altitudes[0], args.pols[0])
        _figure(args.figure, first, samples)


if __name__ == "__main__":
    main()
