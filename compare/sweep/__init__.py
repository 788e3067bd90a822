"""Parameter sweeps: a grid of points run on every target, resumable, into one table, and the
maps drawn from it (issue 6). The studies built on sweeps are in :mod:`..studies`, the
model-validity study (``treeimpact sweep``) in :mod:`..validity`.

* :mod:`.grid` - ``--grid`` specs (``restitution=0:0.9:10``, ``segments=1,2,4``), names and ratios;
* :mod:`.apply` - a grid point applied to a scenario (``dataclasses.replace``, validated);
* :mod:`.run` - the runner: process pool or Dask, resumable CSV/Parquet table;
* :mod:`.maps` - validity maps (discrepancy vs analytic, tolerance contour, dominating rung)
  and identification maps.
"""

from .grid import Axis, Grid, parse_axis, parse_grid
from .run import SweepResult, make_targets, read_table, run_sweep

__all__ = ["Axis", "Grid", "SweepResult", "make_targets", "parse_axis", "parse_grid",
           "read_table", "run_sweep"]
