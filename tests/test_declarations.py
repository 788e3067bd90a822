"""Each backend declares itself beside its definition (issue 51 item 3): the analytic
references in analytic.references, each engine in its package's ``declaration`` module;
compare's registry (compare.runs.backends) is made from those declarations alone, and
reading them loads neither numpy nor an engine."""

from __future__ import annotations

import importlib
import subprocess
import sys

from treeimpact.analytic.references import REFERENCES
from treeimpact.compare.runs.backends import BACKENDS, ENGINE_FOLDERS, ENGINE_REGISTRY


def test_the_registry_is_made_from_the_declarations():
    """The backends are the references then the engines, in their declarations' order, each
    with what its declaration says (the engines' simulate and modes their package's own)."""
    engines = [importlib.import_module(f"treeimpact.{f}").DECLARATION for f in ENGINE_FOLDERS]
    assert list(BACKENDS) == [d.name for d in REFERENCES] + [d.name for d in engines]
    for d in REFERENCES:
        b = BACKENDS[d.name]
        assert (b.simulate_ref, b.modes_ref, b.description, b.run_cost, b.engine) == (
            d.simulate, d.modes, d.description, d.run_cost, False)
    for folder, d in zip(ENGINE_FOLDERS, engines):
        b = BACKENDS[d.name]
        assert (b.simulate_ref, b.modes_ref, b.description, b.run_cost, b.engine) == (
            f"treeimpact.{folder}:simulate", f"treeimpact.{folder}:modes", d.description,
            d.run_cost, True)
        assert ENGINE_REGISTRY[d.name].label == d.label


def test_each_declared_function_is_the_backends_own():
    """What a reference's strings name is a function of the module that defines it (a typo
    or a moved function fails here, not at a user's run), with that module's OPTIONS."""
    for d in REFERENCES:
        b = BACKENDS[d.name]
        for ref in (d.simulate, d.modes):
            module, name = ref.split(":")
            func = b._load(ref)
            assert callable(func) and func.__module__ == module, ref
        assert b.options() is importlib.import_module(d.simulate.split(":")[0]).OPTIONS


def test_reading_the_declarations_loads_no_numpy_and_no_engine():
    """The declarations are plain data: the command line lists the backends without numpy,
    MuJoCo or PyBullet imported (a fresh interpreter)."""
    code = ("import sys; import treeimpact.analytic.references; "
            + "; ".join(f"import treeimpact.{f}.declaration" for f in ENGINE_FOLDERS)
            + "; print(sorted(m for m in ('numpy', 'mujoco', 'pybullet') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
