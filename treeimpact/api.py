"""treeimpact's public API, a plain module of re-exports (docs/api.md): every public name
and the module that defines it, read here. ``treeimpact`` hands these names on when first
used (``treeimpact.simulate`` is this module's ``simulate``), so ``import treeimpact`` and
the command line's start-up stay cheap; the implementation behind them is
:mod:`treeimpact.compare.interface.api` (runs and trees), ``api_records`` (records and
identification) and ``api_studies`` (sweeps, studies, the report), one function per job, and
:mod:`treeimpact.compare.interface.api_results` (the typed, SI results).
"""

from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.identify.pendulum_record import Record
from treeimpact.analytic.metrics import METRIC_UNITS
from treeimpact.analytic.model.calibration import MeasuredTree, calibrate_trunk
from treeimpact.analytic.model.parameters import Billet, Contact, Pendulum, Scenario, Trunk
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.compare.interface.api import (
    backends,
    contact_settings,
    ladder,
    modes,
    paper,
    simulate,
    tree_scenario,
)
from treeimpact.compare.interface.api_records import (
    identify,
    read_record,
    record_from_simulation,
)
from treeimpact.compare.interface.api_results import (
    Conclusion,
    Diagnosis,
    DiagnosisKind,
    Estimate,
    Identification,
    Metrics,
    Model,
    Modes,
    Simulation,
    TrunkModes,
)
from treeimpact.compare.interface.api_studies import (
    design_map,
    report,
    study,
    sweep,
    sweep_pages,
)

__all__ = sorted(name for name in dir() if not name.startswith("_"))
