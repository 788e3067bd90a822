"""The public API's runs and trees, re-exported by :mod:`treeimpact` (docs/api.md; its
records and identification: :mod:`.api_records`, its sweeps, studies and the report:
:mod:`.api_studies`, how each is called: :mod:`.api_call`): one function per job, in SI
units (angles in degrees, named ``_deg``), each a thin call into the module that does the
work, returning the typed results of :mod:`treeimpact.compare.interface.api_results`. Its defaults
are the command line's. Each runs with one BLAS thread (the library's matrices are small:
analytic.threads), the caller's own setting put back when it returns.

Bad input raises :class:`treeimpact.ParameterError` in one line naming the keyword argument
as typed (``t_end``, not the command line's ``--t-end``) and its allowed range; a run with
no numbers to report raises :class:`treeimpact.SimulationDiverged`.
"""

from __future__ import annotations

import dataclasses
import functools

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.scenario import shipped_scenarios

from ..runs.backends import BACKENDS, ENGINES, get_backend
from ..runs.backends import engines as engines_of
from ..runs.cache import resolve_scenario
from ..runs.contact_settings import contact_settings as settings
from ..runs.names import did_you_mean
from ..tree.ladder import build_ladder
from ..tree.scenario import RENAMED as TREE_RENAMED
from ..tree.scenario import TreeInputs, check_keywords
from ..tree.scenario import tree_scenario as build_tree_scenario
from .api_call import api_function
from .api_results import Modes, Simulation, modes_of, simulation_of


@api_function
def simulate(scenario, backend: str = "analytic", **options) -> Simulation:
    """Run one scenario on one backend.

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name (``shipped_scenarios()``)
            or the path of a scenario file (TOML).
        backend: ``analytic`` (the paper's exact model, eqs 12-35; default), ``soft`` (the
            1-DOF trunk with the spring-dashpot pad), ``beam`` (the continuum trunk),
            ``mujoco`` or ``bullet`` (:func:`backends`).
        **options: the backend's own options, as the ``simulate`` command's flags with
            underscores (docs/cli.md): e.g. ``restitution`` (1), ``t_end`` (s),
            ``contact_stiffness`` (N/m), ``contact_duration`` (s), ``trunk="chain"``,
            ``segments``, ``elements``, ``dt`` (s), ``trunk_damping_model``.

    Returns:
        :class:`Simulation`: its ``metrics`` (:class:`Metrics`, SI), ``model``
        (:class:`Model`), ``scenario`` as run and ``trajectory``.

    Raises:
        ParameterError: an unknown backend or option (with what it may have meant), a value
            out of its range, or a run beyond the budget (TREEIMPACT_MAX_STEPS, ...).
        SimulationDiverged: the run has no physical numbers to report.
    """
    scen = _resolve_name(scenario) if isinstance(scenario, str) else resolve_scenario(scenario)
    as_run, result = get_backend(backend).run(scen, **options)
    return simulation_of(result, as_run)


@functools.lru_cache(maxsize=32)
def _shipped(name: str) -> Scenario:
    """The shipped scenario ``name`` (:func:`resolve_scenario`), kept for the next call:
    package data, read and validated once a process (~0.15 ms a run otherwise, a tenth of
    the soft SDOF's, benchmarks/bench_exact.py). Scenarios are frozen, so sharing is safe."""
    return resolve_scenario(name)


def _resolve_name(name: str) -> Scenario:
    """The scenario named ``name``: a shipped one from :func:`_shipped`, else read."""
    return _shipped(name) if name in _shipped_names() else resolve_scenario(name)


@functools.lru_cache(maxsize=1)
def _shipped_names() -> frozenset:
    """The shipped scenarios' names (package data: listed once a process)."""
    return frozenset(shipped_scenarios())


@api_function
def modes(scenario, backend: str = "analytic", **options) -> Modes:
    """The static stiffness and natural frequencies of a backend's trunk beside the
    continuous beam's.

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name or a TOML path.
        backend: ``analytic`` (the 1-DOF trunk; default), ``soft``, ``beam`` (its mesh),
            ``mujoco`` or ``bullet`` (their hinged chains).
        **options: the trunk options of the ``modes`` command: ``segments``, ``elements``,
            ``beam_theory``, ``trunk``.

    Returns:
        :class:`Modes`: ``model`` and ``beam``, each a :class:`TrunkModes` (static stiffness
        at the clamp height in N/m, natural frequencies in rad/s).

    Raises:
        ParameterError: an unknown backend or option, or a value out of its range.
    """
    return modes_of(get_backend(backend).modes(resolve_scenario(scenario), **options))


def backends() -> dict[str, str]:
    """The backends by name.

    Returns:
        dict: backend name -> one line saying what it is (their options: docs/cli.md).

    Raises:
        Nothing.
    """
    return {name: b.description for name, b in BACKENDS.items()}


@api_function
def ladder(scenario, *, engines=None, segments: int | None = None):
    """The scenario run as the discrepancy ladder, one assumption per rung, each step judged
    against ``compare/runs/tolerances.toml`` (docs/ladder.md).

    Args:
        scenario: a :class:`Scenario`, a shipped scenario's name or a TOML path.
        engines: the engines whose rungs run (default: MuJoCo and Bullet; ``()``: the
            analytic rungs only).
        segments: the engines' chain segments (default: the fewest within 0.5 % of the
            beam).

    Returns:
        ``treeimpact.compare.tree.ladder.Ladder``: ``checks()`` the verdicts with their reasons,
        ``table()`` every rung's values and steps.

    Raises:
        ParameterError: an unknown engine or a bad segment count.
    """
    return build_ladder(resolve_scenario(scenario),
                        engines=ENGINES if engines is None else tuple(engines),
                        segments=segments)


@api_function
def tree_scenario(name: str, **measured) -> Scenario:
    """A scenario for your own tree from what you measured (the ``scenario`` command's):
    a pendulum test's M_T, K_T and b, or the tree's geometry and a crown mass estimate.

    Args:
        name: the scenario's name.
        **measured: the test (``clamp_height`` a, m; ``diameter`` d, m; ``impactor_mass``
            m, kg; ``equivalent_length`` l_e, m; ``release_angle_deg`` theta_r, deg), then
            one of two ways: the tree measured (``dynamic_mass`` M_T, kg;
            ``equivalent_stiffness`` K_T, N/m, or ``x_max`` m and ``tau`` s with ``a1``
            m/s and ``a2`` m/s^2, the regression of Figs 4-5; ``damping_rate`` b, 1/s, or
            ``a1`` and ``a2``; ``youngs_modulus`` E, Pa, required) or from its geometry
            (``crown_mass`` m_f, kg; the root spring, the damping and, when left out, E and
            ``density`` assumed as analytic.model.registry declares them), and the choices
            (``length``, ``density``, ``clamp_mass``, ``restitution``,
            ``contact_duration``, ``t_end``: the shipped trees' when left out), as
            :class:`compare.tree.scenario.TreeInputs` names them.

    Returns:
        :class:`Scenario`: measured, the trunk calibrated to M_T, K_T and b (eqs 7, 8, 42);
        from its geometry, M_T, K_T and C_T of eqs 7, 8, 10 with the assumptions; its notes
        saying what was given, chosen, calibrated or assumed (each assumption's value,
        range and reason), its t_end one the analytic model's x_max and separation fit in.

    Raises:
        ParameterError: an unknown, missing, contradictory or out-of-range input, named;
            the two ways mixed (naming the keywords given).
        TypeError: an input that is not a number (a bool, a text), or a name not a text.
        OutsideValidity: a tree whose analytic x_max lies beyond the clamp height.
    """
    known = {f.name for f in dataclasses.fields(TreeInputs)} - {"name"}
    unknown = sorted(set(measured) - known)
    if unknown:
        raise ParameterError(f"{unknown[0]}: not an input of tree_scenario"
                             f"{did_you_mean(unknown[0], known, TREE_RENAMED, style='keyword')}")
    check_keywords(name, measured)
    return build_tree_scenario(TreeInputs(name=name, **{k: float(v) for k, v in
                                                        measured.items() if v is not None}))


@api_function
def paper(*, fit_contact: bool = False) -> dict:
    """The paper reproduced (docs/paper-discrepancies.md), as ``treeimpact paper --json``
    without its provenance: Table 1 recomputed beside the printed values, the restitution
    reproducing each measured quantity, the discrepancies between the printed equations and
    the printed numbers.

    Args:
        fit_contact: also fit each model (the paper's, the 1-DOF soft, the continuum, the
            continuum with the clamp mass free) to every measured number of each tree (about
            a minute; the command's ``--fit-contact``).

    Returns:
        dict: ``trees`` (tree -> quantity -> ``printed``, ``recomputed``, ``rel_diff``,
        ``how``; SI units), ``restitution_estimates`` (tree -> the e reproducing V, x0 and
        T0 each), ``discrepancies`` (``equation``, ``printed``, ``reproduces_table``,
        ``evidence``) and, with ``fit_contact``, ``contact_fit`` (tree -> ``measured``,
        ``fits`` by model, ``explained_by_none``).

    Raises:
        Nothing for its own inputs (the paper's numbers are package data).
    """
    # lazy: +304 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.paper.reproduction import reproduce

    res = reproduce()
    if fit_contact:
        # lazy: +425 ms at import otherwise (the engines' contact fit), which only
        # fit_contact needs
        from treeimpact.analytic.paper.contact_fit import fit_paper_trees

        res["contact_fit"] = fit_paper_trees()
    return res


@api_function
def contact_settings(*, mass: float | None = None, other_mass: float | None = None,
                     effective_mass: float | None = None, restitution: float | None = None,
                     touch_duration: float | None = None,
                     contact_stiffness: float | None = None,
                     contact_damping: float | None = None, dt: float | None = None,
                     engines=None) -> dict:
    """Engine contact settings for a target collision at a time step, each checked by
    simulating the two-body collision in its engine (docs/contact-settings.md), as
    ``treeimpact contact --json``.

    Args:
        mass: body 1's mass, kg (with ``other_mass``; or ``effective_mass`` alone).
        other_mass: body 2's mass, kg (None: body 2 fixed).
        effective_mass: the reduced mass m1 m2 / (m1 + m2), kg, instead of ``mass``.
        restitution: the target e of one collision, in (0, 1), with ``touch_duration``.
        touch_duration: the target touch duration, s (first touch to release).
        contact_stiffness: the pad's k_c, N/m, with ``contact_damping`` (N s/m), instead of
            ``restitution`` and ``touch_duration``.
        contact_damping: the pad's c_c, N s/m.
        dt: the engines' time step, s (default: MuJoCo's 0.002 where the law allows).
        engines: the engines to give settings for (default: every registered engine that
            gives contact settings, MuJoCo and Bullet).

    Returns:
        dict: ``inputs`` (the masses, ``dt``, the approach speed), ``target`` (the law:
        e, touch duration, k_c, c_c, damping ratio, contact duration) and, per engine, its
        settings and simulated collisions with ``holds_target`` (within 10 %) and, where
        not, ``what_holds``; or ``{"error", "largest_dt"}`` when it cannot hold ``dt``.

    Raises:
        ParameterError: an input out of its range, a missing or contradictory pair, an
            engine that gives no contact settings.
    """
    offered = engines_of(contact=True)
    chosen = offered if engines is None else tuple(engines)
    for name in chosen:
        if name not in offered:
            raise ParameterError(f"engines: {name!r} gives no contact settings; allowed "
                                 f"{', '.join(offered)}")
    return settings(mass=mass, other_mass=other_mass, effective_mass=effective_mass,
                    restitution=restitution, touch_duration=touch_duration,
                    contact_stiffness=contact_stiffness, contact_damping=contact_damping,
                    dt=dt, engines=chosen)


__all__ = ["backends", "contact_settings", "ladder", "modes", "paper", "simulate",
           "tree_scenario"]
