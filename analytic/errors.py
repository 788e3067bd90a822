"""The two errors every layer raises: bad input and a simulation with no numbers to report.

The bottom floor of :mod:`treeimpact.analytic`: it imports nothing of the project.
"""


class ParameterError(ValueError):
    """A parameter is outside its allowed range; the message is one line."""


class SimulationDiverged(RuntimeError):
    """A simulation went non-finite or gained energy: it has no numbers to report."""


def one_line(exc: BaseException) -> str:
    """The first line of the message of ``exc`` (its type's name when empty)."""
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
