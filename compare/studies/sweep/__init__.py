"""Parameter sweeps: a grid of points run on every target, resumable, into one table, and the
maps drawn from it (issue 6). The studies built on sweeps are in this package's parent,
:mod:`treeimpact.compare.studies`, the model-validity study (``treeimpact sweep``) in
:mod:`treeimpact.compare.report.validity`.

* :mod:`.grid` - ``--grid`` specs (``restitution=0:0.9:10``, ``segments=1,2,4``), names and ratios;
* :mod:`.apply` - a grid point applied to a scenario (``dataclasses.replace``, validated);
* :mod:`.plan` - targets, grid points applied and refused, rows grouped into tasks;
* :mod:`.execute` - one task run: a backend call, its columns or an analysis's;
* :mod:`.cost` - the cost model: tasks grouped into worker calls;
* :mod:`.journal` - the journal (resumable CSV), the Parquet table and the spec;
* :mod:`.run` - the runner: sweeps planned, run on one pool (processes or Dask), journaled;
* the maps, one module per kind (:mod:`.maps` names their public names): :mod:`.discrepancy`
  (the long tables), :mod:`.map_cells` (the shared colour scale, axes, cells and panels),
  :mod:`.validity_maps` (discrepancy vs analytic, tolerance contour, dominating rung),
  :mod:`.identification_maps`, :mod:`.sensitivity_figure`.
"""

from .grid import Axis, Grid, parse_axis, parse_grid
from .journal import read_table
from .plan import make_targets
from .run import SweepResult, run_sweep

__all__ = ["Axis", "Grid", "SweepResult", "make_targets", "parse_axis", "parse_grid",
           "read_table", "run_sweep"]
