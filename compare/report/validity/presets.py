"""The studies ``treeimpact sweep --preset NAME`` runs, by name: the registry of presets.

A preset is registered beside its definition (:func:`register`): the validity study's
``default`` and ``full`` here, another kind of study in its own module with its own ``run``
(``design``: compare/report/validity/design_study.py), which
``compare/report/validity/__init__.py`` imports (its one registration line). Everything that
lists or checks a preset (the ``--preset`` and ``--with-study`` flags, the report's study
jobs) reads :data:`PRESETS`.
How to add a study: docs/architecture.md "Adding a study".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.runs.backends import ENGINES
from treeimpact.compare.studies.ident_study import CROWN_RATIOS, SAMPLING_SEEDS


@dataclass(frozen=True)
class Preset:
    """A named study: its tree, the validity sweep's grid, the engines and their coarser
    grid, the speed curves, the identification validation and the sensitivity part (each
    field's comment says what it holds)."""

    name: str
    scenario: str
    grid: tuple  # --grid specs of the validity sweep
    ladder: bool = True
    engines: tuple = ENGINES
    speed: bool = True
    speed_dts: tuple = (1e-4, 3e-5, 1e-5)  # s
    speed_durations: tuple = (1e-3, 5e-4)  # s: contact durations giving the stiffnesses
    backends: tuple = ("analytic", "soft")  # reference backends of the validity sweep
    engine_grid: tuple = ()  # --grid specs of a coarser engine check (its own sweep)
    map_metrics: tuple | None = None  # metrics drawn on the maps (None: every ladder metric)
    map_value: str = "rel"  # "rel": against the paper's model; "step": against the rung below
    identification: bool = False  # the identification validation (compare.studies.ident_study)
    ident_sampling_rungs: tuple = ("analytic",)  # its rate x noise grid on these rungs' records
    ident_sampling_seeds: tuple = SAMPLING_SEEDS  # ... with these seeds
    ident_crown_ratios: tuple = CROWN_RATIOS  # its e x crown grid's crown ratios
    ident_engine_rungs: tuple = ()  # engine chains on a corner of its e x crown grid
    sensitivity: int = 0  # Morris trajectories of the sensitivity study per tree (0: none)
    sensitivity_crossings: bool = False  # its crossing durations too (8 pads a point)
    sobol: int = 0  # Sobol base samples N per tree (a power of two; N x (inputs + 2) runs)
    expected: str = ""
    help: str = ""  # its entry in --preset's help: what it runs and what it costs
    notes: dict = field(default_factory=dict, compare=False)
    #: the study of another kind: ``run(out, scenario, *, workers, scheduler, progress,
    #: grid, retry_failed) -> paths`` (None: the validity study of the fields above)
    run: Callable | None = field(default=None, compare=False)
    folder: str = "study"  # its folder in a report's output (report --with-study) and its
    #                        progress line's name


PRESETS = {
    "default": Preset(
        "default", "central-leader",
        ("contact_duration=" + ",".join(f"{d:.3g}" for d in np.geomspace(2e-4, 2e-2, 8)),
         "crown_ratio=0:4:6"),
        ladder=False, speed=False, backends=("analytic", "soft", "beam"),
        engine_grid=("contact_duration=5e-4,5e-3", "crown_ratio=0,4"),
        map_metrics=("x_max", "energy_delivered", "crown_peak_acceleration"),
        map_value="step", identification=True, ident_crown_ratios=(0.0, 4.0),
        ident_sampling_rungs=(), sensitivity=30, sobol=256,
        # Sobol N = 256: 2048 evaluations per tree (8 per base sample with 6 inputs), one
        # evaluation (Newton + soft + beam) about 10 ms on one core inside a sweep: about
        # 60 CPU-s for the three trees (docs/sensitivity.md); N = 64 left the x_max gap
        # unsettled on two of three trees (issue 52 item 3)
        # the identification's cheap part, for make report's minute and its CPU budget with
        # the sensitivity study's 630 evaluations: no engine corner (the report fits both
        # engines' chains of every tree: its record fits), the lightest and heaviest crown
        # ratios, no sampling grid (the full preset's; docs/identification.md)
        help="default (contact duration x crown ratio on the analytic, soft and beam "
             "backends, engines on 2 x 2 points) took about 90 s on 2 cores beside make "
             "report's own runs at Sobol N = 64; N = 256 adds about 50 CPU-s",
        expected="about 90 s with 2 workers beside make report's own runs and the design "
                 "map at Sobol N = 64 (N = 256's 4608 more evaluations add about 50 CPU-s): 8 contact durations x 6 crown ratios on the analytic, soft and beam backends, "
                 "the engines' chains on 2 x 2 of them, the identification validation "
                 "(4 e x 2 crown ratios x 3 rungs) and the sensitivity study (30 Morris "
                 "trajectories per tree, 210 evaluations; Sobol N = 256, 2048 "
                 "evaluations per tree)"),
    "full": Preset(
        "full", "central-leader", ("restitution=0:0.9:10", "segments=1,2,4,8,16,32",
                                   "crown_ratio=0:4:9"),
        speed_dts=(1e-4, 5e-5, 2e-5, 1e-5, 5e-6), speed_durations=(2e-3, 1e-3, 5e-4),
        identification=True, ident_sampling_rungs=("analytic", "soft", "beam", *ENGINES),
        ident_engine_rungs=ENGINES, sensitivity=60, sensitivity_crossings=True,
        sobol=4096,  # 32768 evaluations per tree, about 7 CPU-minutes each
        help="full (restitution=0:0.9:10, segments=1,2,4,8,16,32, crown_ratio=0:4:9) about "
             "1.0 CPU-hours, 30 min with 2 workers",
        expected="about 1.0 CPU-hours: 30 minutes with 2 workers, 4 on 16 (measured on a "
                 "slice of the preset, 45 s of runs per (e, crown) pair: "
                 "benchmarks/bench_presets.py), and about 0.4 CPU-hours more for its Sobol "
                 "design (3 trees x 32768 evaluations of 13 ms); resumable"),
}


def register(preset: Preset) -> Preset:
    """Add ``preset`` to :data:`PRESETS` under its name (ValueError if the name is taken);
    returns it."""
    if preset.name in PRESETS:
        raise ValueError(f"preset {preset.name!r} is registered already")
    PRESETS[preset.name] = preset
    return preset


def get_preset(name: str) -> Preset:
    """The :class:`Preset` called ``name``; ParameterError naming --preset if none."""
    try:
        return PRESETS[name]
    except KeyError:
        raise ParameterError(f"--preset {name!r}: allowed {', '.join(PRESETS)}") from None
