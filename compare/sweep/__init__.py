"""Model-validity studies: parameter sweeps, validity maps, speed-accuracy curves (issue 6).

* :mod:`.grid` - ``--grid`` specs (``restitution=0:0.9:10``, ``segments=1,2,4``), names and ratios;
* :mod:`.apply` - a grid point applied to a scenario (``dataclasses.replace``, validated);
* :mod:`.run` - the runner: process pool or Dask, resumable CSV/Parquet table;
* :mod:`.maps` - validity maps (discrepancy vs analytic, tolerance contour, dominating rung)
  and identification maps;
* :mod:`.speed` - speed-accuracy curves per engine;
* :mod:`.study` - presets ``default`` and ``full``; study.html, study.md, results table;
* :mod:`.cli_support` - ``treeimpact sweep`` arguments and command.
"""

from .grid import Axis, Grid, parse_axis, parse_grid
from .run import SweepResult, make_targets, read_table, run_sweep
from .study import PRESETS, run_study, write_study

__all__ = ["Axis", "Grid", "PRESETS", "SweepResult", "make_targets", "parse_axis",
           "parse_grid", "read_table", "run_study", "run_sweep", "write_study"]
