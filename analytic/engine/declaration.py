"""What an engine package declares about itself to the registry (compare.runs.backends),
beside its definition: the engine's one declaration, :class:`EngineDeclaration`, in its
package's ``declaration`` module. Plain data, importable without numpy or the engine, so
the command line reads every engine's name, options and costs cheaply (docs/engines.md,
"Adding an engine")."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class EngineDeclaration:
    """One engine, as its package declares it.

    Attributes:
        name: its backend name (``--backend``, the rung ids).
        label: its name as printed ("MuJoCo").
        description: one line for ``treeimpact simulate --help`` and the backends' list.
        package: the distribution whose version the provenance reports (its import name).
        distributions: the installed distributions to read that version from, first found
            first (() : ``package`` itself).
        run_cost: rough wall time (s) of one run of a shipped scenario on a 2-core machine,
            by trunk model ((trunk, s) pairs): what orders and groups parallel runs.
        variants: (option, values) whose values make separate speed-accuracy curves
            (compare.studies.speed), or None.
        shades: the report's line colours of its rungs (SDOF, chain, chain + full pendulum,
            its own elastic rod where it has one).
    """

    name: str
    label: str
    description: str
    package: str
    distributions: tuple = ()
    run_cost: tuple = ()
    variants: tuple | None = None
    shades: tuple = ()
