"""A new engine is one folder plus one registration (issue 42 item 2; docs/engines.md,
"Adding an engine"): a fake engine package written into a temporary folder, registered
with one :func:`compare.runs.backends.register_engine` call and nothing else edited, runs its
rungs of a ladder, and the ladder's verdicts catch the error it was built with."""

from __future__ import annotations

import sys
import textwrap

import pytest

from treeimpact.compare.runs import backends
from treeimpact.compare.runs.backends import Backend, Engine, engine_registered

#: The fake engine: the analytic soft-contact SDOF (the ``soft`` rung's own backend) with
#: its x_max raised by X_MAX_ERROR and every other metric left as the soft rung's.
X_MAX_ERROR = 0.03
FAKE = textwrap.dedent(f'''
    """A fake engine: the soft-contact SDOF with x_max off by {X_MAX_ERROR}."""
    import dataclasses

    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.engine.interface import ENGINE_OPTIONS

    OPTIONS = ENGINE_OPTIONS


    def simulate(scenario, **options):
        r = simulate_soft(scenario)  # the scenario as run: e, pad and t_end applied
        metrics = {{**r.metrics, "x_max": r.metrics["x_max"] * (1 + {X_MAX_ERROR!r})}}
        return dataclasses.replace(r, backend="fake", metrics=metrics)
''')


@pytest.fixture
def fake_engine(tmp_path, monkeypatch):
    """The fake engine's folder on sys.path and its one registration, both undone after."""
    (tmp_path / "fake_engine").mkdir()
    (tmp_path / "fake_engine" / "__init__.py").write_text(FAKE)
    monkeypatch.syspath_prepend(str(tmp_path))
    before = (dict(backends.BACKENDS), dict(backends.ENGINE_REGISTRY))
    engine = Engine(Backend("fake", "fake_engine:simulate", None, "a test double",
                            run_cost=((None, 0.2),)),
                    label="Fake", folder="fake_engine", package="fake-engine")
    with engine_registered(engine):
        yield engine
    sys.modules.pop("fake_engine", None)
    assert (backends.BACKENDS, backends.ENGINE_REGISTRY) == before  # undone


def test_a_registered_fake_engine_runs_its_ladder_rungs_and_its_error_is_caught(fake_engine):
    """The fake engine's SDOF rung stands in the ladder beside the shipped rungs, judged
    against the soft rung: x_max exceeds its tolerance by the error put in (+3 %, the
    tolerance 0.5 %), every other metric of that rung agrees (the same soft solution)."""
    from treeimpact.compare.tree.ladder import build_ladder, failure_table

    assert "fake" in backends.engines() and backends.BACKENDS["fake"].engine
    ladder = build_ladder("central-leader", engines=("fake",))
    ids = [r.rung.id for r in ladder.rungs]
    assert {"soft", "fake-sdof"} <= set(ids) and ladder["fake-sdof"].ok
    assert ladder["fake-sdof"].rung.engine == "fake"
    sdof = [c for c in ladder.checks() if c.rung == "fake-sdof" and c.reference == "soft"]
    x_max = next(c for c in sdof if c.metric == "x_max")
    assert x_max.rel_diff == pytest.approx(X_MAX_ERROR, rel=1e-9)  # the error put in, exactly
    assert x_max.verdict == "exceeds"
    assert "fake-sdof" in failure_table(ladder, [x_max]).splitlines()[1]  # shown as a column
    others = [c for c in sdof if c.metric != "x_max" and c.tolerance is not None]
    assert others and all(c.rel_diff == 0.0 and c.verdict == "ok" for c in others)


def test_a_taken_name_is_refused_and_the_fake_engine_gives_no_contact_settings(fake_engine):
    """Registering a second engine called "mujoco" is refused; an engine registered without
    ``contact`` is not among ``treeimpact contact``'s engines."""
    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.runs.contact_settings import ENGINES

    with pytest.raises(ParameterError, match="already registered"):
        backends.register_engine(Engine(backends.BACKENDS["mujoco"], "again", "x", "x"))
    assert fake_engine.contact_side() is None and "fake" not in ENGINES
