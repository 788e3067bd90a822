"""Root pytest configuration shared by `tests` and `compare`.

OpenBLAS starts one thread per core for every small matrix operation; on the 2-core CI
machine those threads fight the test process itself and each call costs ~1 s. The suite
only handles matrices of a few hundred rows, so one BLAS thread is the fast choice.

The project installs one top-level package, `treeimpact`; an import of its folders by their
bare names (`analytic`, `compare.ladder`) fails here, so a test cannot pass on a second copy.
"""

import importlib.abc
import os
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


class _NoBareNames(importlib.abc.MetaPathFinder):
    """Refuse an import of the project's folders by their bare names (``analytic``,
    ``compare.ladder``, ...): installed they are subpackages of ``treeimpact`` only, and a
    bare import would load a second copy of a module. pytest itself imports the test files
    under ``compare/`` as ``compare.test_*`` (and ``compare.conftest``): those are let through."""

    def find_spec(self, fullname, path=None, target=None):
        top, _, rest = fullname.partition(".")
        leaf = rest.rpartition(".")[2]
        if top in _FOLDERS and not (top == "compare" and (not rest or leaf == "conftest"
                                                          or leaf.startswith("test_"))):
            raise ImportError(f"{fullname}: import it as treeimpact.{fullname} (the project "
                              "installs one top-level package, treeimpact)")
        return None


_FOLDERS = ("analytic", "compare", "mujoco_models", "bullet_models")
sys.meta_path.insert(0, _NoBareNames())
