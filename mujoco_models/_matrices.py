"""The trunk's matrices as MuJoCo compiled them: the mass matrix at rest (``mj_fullM``), the
hinge stiffnesses or the flex rod's bending Hessian, the impact point's Jacobian and the
highest natural frequency. SI units."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from . import _flex


def _mass_matrix_at_rest(mjmodel: mujoco.MjModel) -> np.ndarray:
    """The full generalised mass matrix (``mj_fullM``) at the initial configuration."""
    data = mujoco.MjData(mjmodel)
    mujoco.mj_forward(mjmodel, data)
    M = np.zeros((mjmodel.nv, mjmodel.nv))
    mujoco.mj_fullM(mjmodel, data, M)
    return M


def _hinges(mjmodel: mujoco.MjModel) -> list[int]:
    """Ids of the trunk's hinge joints (named hinge_*)."""
    return [j for j in range(mjmodel.njnt)
            if mujoco.mj_id2name(mjmodel, mujoco.mjtObj.mjOBJ_JOINT, j).startswith("hinge_")]


def engine_trunk_matrices(mjmodel: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the trunk's hinges from the engine: ``mj_fullM`` at rest (kg m^2) and the
    joint stiffnesses (N m/rad)."""
    hinges = _hinges(mjmodel)
    dofs = [int(mjmodel.jnt_dofadr[j]) for j in hinges]
    M = _mass_matrix_at_rest(mjmodel)
    return M[np.ix_(dofs, dofs)], np.diag(mjmodel.jnt_stiffness[hinges])


def flex_trunk_matrices(mjmodel: mujoco.MjModel, rod: _flex.FlexTrunk
                        ) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the flex trunk's dofs (root hinge if any, vertex slides): ``mj_fullM`` at
    rest and the rod's bending Hessian (:func:`mujoco_models._flex.stiffness_matrix`)."""
    root, verts = _flex.flex_dofs(mjmodel)
    dofs = ([root] if root is not None else []) + verts  # slides and hinges: qpos = dof adr
    M = _mass_matrix_at_rest(mjmodel)
    return M[np.ix_(dofs, dofs)], _flex.stiffness_matrix(rod, root is not None)


def highest_frequency(M: np.ndarray, K: np.ndarray) -> float:
    """Largest omega (rad/s) of K v = omega^2 M v."""
    # lazy: +118 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    w2 = scipy.linalg.eigh(K, M, eigvals_only=True)
    return float(math.sqrt(w2[-1]))


def impact_jacobian(m: mujoco.MjModel) -> np.ndarray:
    """d x(a) / d theta of the trunk's hinges from ``mj_jacSite`` at rest (m/rad)."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    jac = np.zeros((3, m.nv))
    mujoco.mj_jacSite(m, d, jac, None,
                      mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "impact_point"))
    return jac[0, [int(m.jnt_dofadr[j]) for j in _hinges(m)]]
