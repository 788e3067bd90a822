"""MuJoCo's warnings while the engine works: told on stderr as treeimpact's own one-line
warnings, never on stdout (JSON) and never in a MUJOCO_LOG.TXT in the user's working
directory (MuJoCo's default handler), or collected while a rollout steps (a diverged run's
message carries the first).

MuJoCo has one warning handler per process (``mujoco.set_mju_user_warning``). Ours is
installed only while an engine call needs it (:func:`mujoco_warnings`, also a decorator)
and the previous handler is put back when the outermost such call returns: importing the
engine changes nothing, and a user's own handler is theirs again afterwards.
"""

from __future__ import annotations

import functools
import sys
import threading
import warnings
from contextlib import contextmanager

import mujoco

#: The kinds of warning already told on stderr in this process (each is told once).
_WARNED: set[str] = set()
#: The collectors of the rollouts stepping now (:func:`collected_warnings`).
_COLLECTING: list[list[str]] = []
#: Engine calls inside :func:`mujoco_warnings` now, and the handler found by the first.
_SCOPE = {"depth": 0, "previous": None}
_LOCK = threading.Lock()


def tell(text: str) -> None:
    """Tell MuJoCo's warning ``text`` on stderr, ``treeimpact: warning: mujoco: TEXT``, once
    per kind (the text before " Time =") in this process."""
    kind = text.split(" Time =")[0]
    if kind not in _WARNED:
        _WARNED.add(kind)
        print(f"treeimpact: warning: mujoco: {text}", file=sys.stderr, flush=True)


def _handler(message: str) -> None:
    """MuJoCo's warning ``message`` on one line: collected while a rollout steps, else told."""
    text = " ".join(message.split())
    if _COLLECTING:  # MuJoCo does not say which model warned: every rollout stepping now
        for seen in _COLLECTING:
            seen.append(text)
        return
    tell(text)


@contextmanager
def _installed():
    with _LOCK:
        if _SCOPE["depth"] == 0:
            _SCOPE["previous"] = mujoco.get_mju_user_warning()
            mujoco.set_mju_user_warning(_handler)
        _SCOPE["depth"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _SCOPE["depth"] -= 1
            if _SCOPE["depth"] == 0:
                mujoco.set_mju_user_warning(_SCOPE["previous"])
                _SCOPE["previous"] = None


def mujoco_warnings(func=None):
    """MuJoCo's warnings told on stderr (:func:`tell`) for the duration of a ``with`` block,
    or of every call of ``func`` when used as a decorator; nested and concurrent uses share
    one installation, undone when the last ends.

    Args:
        func: the function to wrap (decorator use), or None for a context manager.

    Returns:
        The wrapped function, or a context manager.
    """
    if func is None:
        return _installed()

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with _installed():
            return func(*args, **kwargs)

    return wrapper


@contextmanager
def collected_warnings():
    """MuJoCo's warnings collected, not told, while the block steps: yields the list they
    are appended to (one line each, in order)."""
    seen: list[str] = []
    with _installed():
        with _LOCK:
            _COLLECTING.append(seen)
        try:
            yield seen
        finally:
            with _LOCK:  # by identity: another rollout's list may be equal to this one
                _COLLECTING[:] = [c for c in _COLLECTING if c is not seen]


@mujoco_warnings
def compile_spec(spec: mujoco.MjSpec) -> mujoco.MjModel:
    """``spec.compile()`` with a compiler warning (a UserWarning since MuJoCo 4.0; 3.x raised)
    told on stderr like the runtime ones; the shipped models compile without any (tested).

    Args:
        spec: the model as built (:mod:`mujoco_models._builder`).

    Returns:
        The compiled model.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = spec.compile()
    for w in caught:
        tell(" ".join(f"compiler: {w.message}".split()))
    return model
