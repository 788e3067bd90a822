"""The report's pages written as one set (issue 54 item 9): ``report.html``, ``report.md``,
``report.json`` and the ``figures/`` they link are written into a temporary folder inside
the output folder, and only once all of them are written are they swapped into place, with
the stop signals held for the few renames of the swap. A reader of the output folder, and
an interrupt at any moment, so finds either the earlier report's complete set or the new
complete set, never a mix; no temporary folder is left behind (docs/report.md).

An interrupt (Ctrl-C, SIGTERM) before the swap leaves the earlier set as it was and removes
the new one; one that arrives during the swap is held until the new set is in place and is
then delivered: the command ends as interrupted (its one line, exit 130) with the new set
complete. Only a kill that cannot be caught (SIGKILL, power loss) mid-swap can leave a
mix; its temporary folders are removed by the next report (:func:`clear_leftovers`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path

#: The set's members in the output folder, in the order they are swapped: the figures
#: first, so that every page in place links figures that are.
MEMBERS = ("figures", "report.json", "report.md", "report.html")
#: The temporary folders' name prefixes, inside the output folder: the new set while it is
#: written, the earlier one while the swap moves it out.
STAGING, RETIRED = ".report-new-", ".report-old-"
#: The signals held during the swap (the ones that stop a command).
HELD = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def held_signals():
    """The body runs uncut by SIGINT and SIGTERM: a signal that arrives meanwhile is
    recorded and delivered again, to the handler it had, once the body is done (or has
    failed). In a thread other than the main one nothing is held: Python delivers signals
    to the main thread only."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list = []
    previous: dict = {}
    try:
        for s in HELD:
            if signal.getsignal(s) is not None:  # None: a handler not set from Python
                previous[s] = signal.signal(s, lambda signum, _frame: caught.append(signum))
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(caught):  # each signal once, in the order they came
            signal.raise_signal(s)


def clear_leftovers(out: Path) -> None:
    """Remove the temporary folders a report killed beyond catching (SIGKILL) left in its
    output folder ``out``."""
    for folder in [*out.glob(STAGING + "*"), *out.glob(RETIRED + "*")]:
        shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def staged(out: Path):
    """A new temporary folder inside ``out`` for the new set (yielded, a Path), removed if
    the body fails or is interrupted (signals held while it is removed: a second Ctrl-C
    cannot leave half of it); the body ends with :func:`swap_in`."""
    stage = Path(tempfile.mkdtemp(prefix=STAGING, dir=out))
    try:
        yield stage
    except BaseException:
        with held_signals():
            shutil.rmtree(stage, ignore_errors=True)
        raise


def swap_in(stage: Path, out: Path) -> dict:
    """Put the set written in ``stage`` (every name of :data:`MEMBERS` it holds) in place in
    ``out``, with the signals held: the earlier set's members are moved aside, the new ones
    renamed in, the earlier ones and ``stage`` removed. A failed rename (OSError) puts the
    earlier set back before the error goes on. Returns {member name: its Path in out}."""
    names = [n for n in MEMBERS if (stage / n).exists()]
    with held_signals():
        retired = Path(tempfile.mkdtemp(prefix=RETIRED, dir=out))
        moved: list = []
        placed: list = []
        try:
            for name in MEMBERS:  # the whole earlier set, also a member the new one lacks
                if (out / name).exists():
                    os.replace(out / name, retired / name)
                    moved.append(name)
            for name in names:
                os.replace(stage / name, out / name)
                placed.append(name)
        except OSError:
            _put_back(retired, out, moved, placed)
            raise
        finally:
            shutil.rmtree(retired, ignore_errors=True)
            shutil.rmtree(stage, ignore_errors=True)
    return {name: out / name for name in names}


def _put_back(retired: Path, out: Path, moved: list, placed: list) -> None:
    """After a failed swap: the new members ``placed`` in ``out`` removed and the earlier
    set's members ``moved`` from ``out`` into ``retired`` put back."""
    for name in placed:
        if (out / name).is_dir():
            shutil.rmtree(out / name, ignore_errors=True)
        else:
            (out / name).unlink(missing_ok=True)
    for name in moved:
        os.replace(retired / name, out / name)
