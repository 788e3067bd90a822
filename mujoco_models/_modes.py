"""The natural frequencies and static stiffness of MuJoCo's trunk, from the compiled model
(the engine interface's ``modes``). SI units."""

from __future__ import annotations

import mujoco
import numpy as np
import scipy.linalg

from treeimpact.analytic.continuum.modes import beam_reference
from treeimpact.analytic.engine.interface import chain_modes, check_choice
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario

from . import _builder, _flex
from ._matrices import engine_trunk_matrices, flex_trunk_matrices, impact_jacobian
from ._setup import PLACEHOLDER_DT, _trunk_spec
from ._warnings import compile_spec, mujoco_warnings


@mujoco_warnings
def modes(scenario: Scenario, *, trunk="chain", segments=None, n_modes: int = 3) -> dict:
    """Static stiffness at a (N/m) and the lowest ``n_modes`` natural frequencies (rad/s) of
    MuJoCo's ``trunk`` ("chain" or "flex", of ``segments`` segments, None: the default
    count) for ``scenario`` from
    the engine: ``mj_fullM`` at rest with the compiled hinge stiffnesses and the impact
    point's ``mj_jacSite`` (chain, :func:`analytic.engine.interface.chain_modes`) or the
    rod's bending Hessian (flex, :func:`flex_modes`); ``beam``: the continuous beam."""
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    check_choice("trunk", trunk, ("chain", "flex", "cable"))
    tspec, _ = _trunk_spec(scenario, trunk, segments, "distributed")
    spec, _ = _builder.build_spec(f"{scenario.name}-{trunk}-modes", tspec, scenario, "linear",
                                  PLACEHOLDER_DT)
    m = compile_spec(spec)
    if trunk == "flex":
        return flex_modes(scenario, m, tspec.flex, n_modes)
    M, K = engine_trunk_matrices(m)
    return chain_modes(scenario, M, np.diag(K), impact_jacobian(m), n_modes)


def flex_modes(scenario: Scenario, m: mujoco.MjModel, rod: _flex.FlexTrunk, n_modes) -> dict:
    """The flex trunk's static stiffness at a, 1 / (K^-1)_aa (N/m), and its lowest
    frequencies, eig(K, M) (rad/s), beside the beam's."""

    M, K = flex_trunk_matrices(m, rod)
    n = len(K)
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= n:
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed [1, {n}]")
    a = n - rod.segments + rod.clamp_vertex - 1  # the clamp vertex's slide among the dofs
    static = float(1.0 / np.linalg.solve(K, np.eye(n)[a])[a])
    w2 = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": static, "omegas": [float(v) for v in np.sqrt(w2)],
                      "segments": rod.segments},
            "beam": beam_reference(scenario, n_modes)}
