"""The maps and figures of a sweep (matplotlib, PNG), one module per kind; their public names
in one place (``from treeimpact.compare.studies.sweep.maps import validity_maps``):

* :mod:`.discrepancy` - the long tables the maps are drawn from;
* :mod:`.map_cells` - what every map shares: the colour scale, axes, heatmap cells, panels;
* :mod:`.validity_maps` - discrepancy from the paper's model (or the rung below) per target;
* :mod:`.identification_maps` - the identification procedure's errors per target;
* :mod:`.sensitivity_figure` - the sensitivity study's Morris mu* per input and tree.

Design notes and measured figures: docs/sweeps.md.
"""

from .discrepancy import (
    axis_names,
    discrepancies,
    identification_errors,
    numeric_axes,
    relevant_axes,
)
from .identification_maps import MAPPED_IDENT_KEYS, identification_maps
from .map_cells import (
    DEFAULT_TOLERANCE,
    LINEAR_FRACTION,
    MAP_VMAX,
    MAX_FIGURE_WIDTH,
    NO_VALUE,
    colour_scale,
    point_text,
)
from .sensitivity_figure import INPUT_LABELS, OUTPUT_LABELS, sensitivity_figure
from .validity_maps import validity_maps

__all__ = ["DEFAULT_TOLERANCE", "INPUT_LABELS", "LINEAR_FRACTION", "MAPPED_IDENT_KEYS",
           "MAP_VMAX", "MAX_FIGURE_WIDTH", "NO_VALUE", "OUTPUT_LABELS", "axis_names",
           "colour_scale", "discrepancies", "identification_errors", "identification_maps",
           "numeric_axes", "point_text", "relevant_axes", "sensitivity_figure",
           "validity_maps"]
