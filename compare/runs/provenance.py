"""Where a number came from: the code (treeimpact's version and the git commit of the
checkout it runs from), the engines and numerical libraries (their installed versions, read
without importing them), the scenario (a digest of every input) and the run's numerical
settings (time step, integrator, solver and contact settings). Every ``--json`` output, the
report, the studies and identify results carry it, so a number can be traced and rerun.
"""

from __future__ import annotations

import functools
import hashlib
import json
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from .backends import ENGINE_REGISTRY

#: The packages whose versions decide the numbers: the registered engines' (their
#: registration's ``package``, compare.runs.backends.ENGINE_REGISTRY) among the libraries'.
PACKAGES = ("treeimpact", "numpy", "scipy", *(e.package for e in ENGINE_REGISTRY.values()),
            "pandas")
#: The model-dict keys that are numerical settings of a run (docs/cli.md lists them).
SETTINGS = ("dt", "integrator", "solref", "solimp", "contact", "calibration", "elements",
            "segments", "trunk", "pendulum", "trunk_damping_model", "contact_stiffness",
            "contact_damping", "engine_contact_stiffness", "engine_contact_damping",
            "touch_duration", "samples")


#: The distributions a package's version is read from, the first installed (an engine's
#: registration's ``distributions``; a package not named here: its own name).
DISTRIBUTIONS = {e.package: e.distributions for e in ENGINE_REGISTRY.values()
                 if e.distributions}


def _version(name: str) -> str | None:
    for dist in DISTRIBUTIONS.get(name, (name,)):
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            continue
    return None


@functools.lru_cache(maxsize=1)
def code_version() -> dict:
    """treeimpact's version and, run from a git checkout, its commit and whether the work
    tree had uncommitted changes (None outside a checkout)."""
    root = Path(__file__).resolve().parents[2]
    commit = dirty = None
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"],
                             capture_output=True, text=True, timeout=5)
        if out.returncode == 0:
            commit = out.stdout.strip()
            status = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                     "--untracked-files=no"], capture_output=True, text=True,
                                    timeout=5)
            dirty = bool(status.stdout.strip()) if status.returncode == 0 else None
    except (OSError, subprocess.SubprocessError):
        pass
    return {"treeimpact": _version("treeimpact"), "git_commit": commit, "git_dirty": dirty}


@functools.lru_cache(maxsize=1)
def environment() -> dict:
    """Python and the installed versions of :data:`PACKAGES` (None: not installed)."""
    return {"python": platform.python_version(),
            **{name: _version(name) for name in PACKAGES if name != "treeimpact"}}


def scenario_digest(scenario) -> str:
    """SHA-1 of every input of a scenario (its dict as sorted JSON)."""
    text = json.dumps(scenario.to_dict(), sort_keys=True, default=str)
    return hashlib.sha1(text.encode()).hexdigest()


def provenance(scenario=None, result=None, **extra) -> dict:
    """The provenance record: code, environment, the ``scenario``'s name and digest, the
    run's backend and numerical settings (:data:`SETTINGS` of its ``result``'s model dict),
    and ``extra``; each part only when given."""
    out = {"code": code_version(), "environment": environment()}
    if scenario is not None:
        out["scenario"] = {"name": scenario.name, "sha1": scenario_digest(scenario)}
    if result is not None:
        model = result.model or {}
        out["run"] = {"backend": result.backend,
                      **{k: model[k] for k in SETTINGS if model.get(k) is not None}}
    return out | extra
