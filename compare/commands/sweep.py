"""``treeimpact sweep``: a model-validity study over a grid (the arguments and the run live
in :mod:`treeimpact.compare.validity.cli_support`)."""

from __future__ import annotations

from ._common import add_budget_flag

NAME = "sweep"
HELP = "run a parameter sweep: validity maps and studies"


def add_arguments(sp) -> None:
    """The sweep's flags (compare.validity.cli_support) and the run budget, added to its
    subparser ``sp``."""
    from treeimpact.compare.validity.cli_support import add_sweep_arguments

    add_sweep_arguments(sp)
    add_budget_flag(sp)


def run(args) -> int:
    """Run the sweep of the parsed command line ``args``; its exit code (130 when
    interrupted, with how to resume)."""
    from treeimpact.compare.validity.cli_support import run_sweep_command

    return run_sweep_command(args)
