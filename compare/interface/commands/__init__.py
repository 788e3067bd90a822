"""The commands of ``treeimpact``, one module each. Every module has ``NAME`` (the command),
``add_arguments(parser)`` and ``run(args) -> exit code``; its one-line help is in
:data:`HELP` here, so that ``treeimpact --help`` lists the commands without importing them
(a command's module, and the numerics it imports, load when :data:`COMMANDS` is asked for
it: :mod:`treeimpact.compare.interface.cli` builds only the named command's parser)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from importlib import import_module
from types import ModuleType

#: The commands in the order ``treeimpact --help`` lists them, with their one-line help.
HELP = {
    "paper": "reproduce Table 1 and list the paper's discrepancies",
    "simulate": "simulate one scenario",
    "modes": "static stiffness at a and natural frequencies",
    "report": "write the discrepancy report (html, md, json)",
    "contact": ("MuJoCo's solref/solimp and Bullet's contactStiffness/Damping for a target e "
                "and touch duration, checked in each engine"),
    "identify": ("tree properties (M_T, K_T, C_T, e, E) from your own pendulum-test record, "
                 "with 95 %% intervals"),
    "scenario": ("write a scenario file for your own tree from measured M_T, K_T, b or from its "
                 "geometry and crown mass"),
    "sweep": "run a parameter sweep: validity maps and studies",
}


class _Commands(Mapping):
    """command name -> its module (``treeimpact.compare.interface.commands.NAME``), imported on the
    first look-up; iterated, the names of :data:`HELP` in its order."""

    def __getitem__(self, name: str) -> ModuleType:
        if name not in HELP:
            raise KeyError(name)
        return import_module(f"{__name__}.{name}")

    def __iter__(self) -> Iterator[str]:
        return iter(HELP)

    def __len__(self) -> int:
        return len(HELP)


#: command name -> its module, imported when looked up (:class:`_Commands`).
COMMANDS: Mapping[str, ModuleType] = _Commands()
