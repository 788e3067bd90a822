"""The commands of ``treeimpact``, one module each. Every module has ``NAME`` (the command),
``HELP`` (its one-line help), ``add_arguments(parser)`` and ``run(args) -> exit code``;
:mod:`treeimpact.compare.cli` builds the parser from them and dispatches."""

from __future__ import annotations

from . import contact, identify, modes, paper, report, scenario, simulate, sweep

#: The commands in the order ``treeimpact --help`` lists them.
COMMANDS = {m.NAME: m for m in (paper, simulate, modes, report, contact, identify, scenario,
                                sweep)}
