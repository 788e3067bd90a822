"""The errors every layer raises: bad input, a simulation with no numbers to report, and a
run that ended but not with what was asked (its result outside the model's validity among them).

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


class NotAchieved(RuntimeError):
    """The run ended with numbers, but not with what was asked (a contact target the step
    cannot hold, a record that could not be fitted); the message is one line saying what was
    achieved instead and what would achieve the target."""


class OutsideValidity(NotAchieved, SimulationDiverged):
    """A result the model cannot represent (x_max beyond the small deflection of eq 1, the
    clamp height): the model's validity failed, not a solver; the message is one line. Also
    a SimulationDiverged for the callers that only ask whether a run has numbers to report
    (a fit's trial point, a sweep's row); the command line words it as outside the model's
    validity (exit 4), never as diverged."""


class ImplausibleInput(UserWarning):
    """An input inside its allowed range but outside what fruit trees, harvesters and pads
    show (a release angle typed in radians, a diameter in centimetres): the run goes on,
    and the message is one line naming the field, its plausible range and its source."""
