"""Studies: a base case and the axes to sweep ([`spec`][rainuav.studies.spec], read from TOML;
``paper-sweeps.toml``, ``mmwave.toml``, ``storms.toml`` and ``altitude.toml`` ship with the
package), run case by case in parallel worker processes and resumably
([`run`][rainuav.studies.run]). ``python -m rainuav.study`` is the CLI.
"""

from __future__ import annotations

from rainuav.studies.run import run_study
from rainuav.studies.spec import Case, Study, load_study

__all__ = ["Case", "Study", "load_study", "run_study"]
