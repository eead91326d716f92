"""Maps that learn from what is measured: a drive-test or flight log in
([`log`][rainuav.radio.measured.log]), the prior at its points
([`levels`][rainuav.radio.measured.levels]), the site parameters it says are wrong fitted
([`calibrate`][rainuav.radio.measured.calibrate]), what is still off estimated as a field with its
uncertainty ([`residual`][rainuav.radio.measured.residual]), and the corrected map out
([`correct`][rainuav.radio.measured.correct]:
[`correct_map()`][rainuav.radio.measured.correct.correct_map]), with outage as a probability
([`outage`][rainuav.radio.measured.outage])."""

from __future__ import annotations

from rainuav.radio.measured.correct import correct_map
from rainuav.radio.measured.log import MeasurementLog, read_log, rss_from_rsrp
from rainuav.radio.measured.outage import outage_probability

__all__ = [
    "MeasurementLog",
    "correct_map",
    "outage_probability",
    "read_log",
    "rss_from_rsrp",
]
