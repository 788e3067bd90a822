"""A seeded fuzz of scenario fields and command-line options (issue 12): every case ends in
exit 0 with finite, plausible numbers, or exit 2/3 with exactly one line on stderr; never a
traceback, never past its time bound."""

from __future__ import annotations

import json
import math
import random
import re
import signal
import warnings
from pathlib import Path

import pytest

from treeimpact.analytic.model.plausible import implausible
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.interface.cli import main

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = (ROOT / "analytic" / "model" / "scenarios" / "central-leader.toml").read_text()
FIELDS = ("length", "clamp_height", "diameter", "density", "youngs_modulus", "clamp_mass",
          "crown_mass", "damping", "base_stiffness", "mass", "equivalent_length",
          "release_angle_deg", "restitution", "duration", "t_end")
CASES = 600  # ~10 s on one core: the analytic backend, a tenth on the soft contact
SECONDS_PER_CASE = 20  # a hang is a failure, not a wait


def _value(rng: random.Random, current: float) -> str:
    """A hostile replacement: a scale of the current value (near it, 0.1 .. 10, half the
    time; else 1e-12 .. 1e12), its negative, zero, a non-number, or a wrong type."""
    kind = rng.random()
    if kind < 0.5:
        return repr(current * 10 ** rng.uniform(-1, 1))
    if kind < 0.75:
        return repr(current * 10 ** rng.uniform(-12, 12))
    return rng.choice(["0", "-1", repr(-current), "nan", "inf", "-inf", '"x"', "true",
                       "[1, 2]", "1e308", "5e-324"])


def _case(seed: int) -> tuple[str, list[str]]:
    rng = random.Random(seed)
    text = SCENARIO
    for key in rng.sample(FIELDS, rng.randint(1, 3)):
        m = re.search(rf"(?m)^{key}\s*=\s*([0-9.eE+-]+)", text)
        text = text[:m.start(1)] + _value(rng, float(m.group(1))) + text[m.end(1):]
    args = []
    if rng.random() < 0.3:
        flag = rng.choice(["--restitution", "--t-end", "--contact-stiffness"])
        args += [flag, rng.choice(["-1", "0", "nan", "1e-308", "1e308", "0.5", "2", "1e9"])]
    if "--contact-stiffness" in args or rng.random() < 0.1:
        args += ["--backend", "soft"]
    return text, args


def _alarm(signum, frame):
    raise TimeoutError(f"a case ran past {SECONDS_PER_CASE} s")


@pytest.mark.parametrize("chunk", range(3))
def test_fuzzed_scenarios_and_flags_never_traceback_hang_or_print_garbage(chunk, tmp_path,
                                                                          capsys):
    previous = signal.signal(signal.SIGALRM, _alarm)
    outcomes = {0: 0, 2: 0, 3: 0}
    try:
        for seed in range(chunk * CASES // 3, (chunk + 1) * CASES // 3):
            text, args = _case(seed)
            path = tmp_path / f"case{seed}.toml"
            path.write_text(text)
            signal.alarm(SECONDS_PER_CASE)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("always")  # each case its own process's warnings
                    rc = main(["simulate", str(path), "--json", *args])
            finally:
                signal.alarm(0)
            out = capsys.readouterr()
            where = f"seed {seed}: {args} {out.err!r}"
            assert rc in outcomes, where
            outcomes[rc] += 1
            if rc == 0:  # nothing on stderr but the implausible inputs' own lines
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    said = implausible(load_scenario(path))
                assert out.err == "".join(f"treeimpact: warning: {i.text}; run as given\n"
                                          for i in said), where
                metrics = json.loads(out.out)["metrics"]
                a = json.loads(out.out)["scenario"]["trunk"]["clamp_height"]
                assert 0 < metrics["x_max"] <= a and math.isfinite(metrics["impact_loss"])
                assert metrics["ledger_residual"] <= 0.05, where
            else:
                errors = [line for line in out.err.splitlines()
                          if not line.startswith("treeimpact: warning: ")]  # an input's note
                assert out.out == "" and len(errors) == 1, where
                assert "Traceback" not in out.err, where
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert outcomes[0] > 0 and outcomes[2] > 0  # the fuzz reaches both sides of the limits
    import resource

    # the memory bound (2 GB, analytic.contact.timestep.MAX_BYTES) held for the whole process so far
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 < 2e9


def _number(rng: random.Random, typical: float) -> str:
    """A hostile number near ``typical`` or far from it, or a non-number."""
    kind = rng.random()
    if kind < 0.5:
        return repr(typical * 10 ** rng.uniform(-1, 1))
    if kind < 0.8:
        return repr(typical * 10 ** rng.uniform(-300, 300))
    return rng.choice(["0", "-1", "nan", "inf", "-inf", "1e308", "5e-324", "x"])


#: (flag, typical value) of the commands that take numbers without a scenario file.
CONTACT_FLAGS = (("--mass", 1.0), ("--other-mass", 1.0), ("--restitution", 0.5),
                 ("--touch-duration", 1e-3), ("--dt", 2e-5))
SCENARIO_FLAGS = (("--clamp-height", 0.315), ("--diameter", 0.126), ("--impactor-mass", 132.4),
                  ("--equivalent-length", 1.51), ("--release-angle-deg", 36.39),
                  ("--youngs-modulus", 9e9), ("--dynamic-mass", 110.0),
                  ("--equivalent-stiffness", 1.5e6), ("--damping-rate", 30.0))


@pytest.mark.parametrize("command, flags", [("contact", CONTACT_FLAGS),
                                            ("scenario", SCENARIO_FLAGS)])
def test_fuzzed_numbers_are_a_result_or_one_line_of_bad_input(command, flags, capsys):
    """Issue 35: extreme numbers gave exit 3 with an exception's name (ZeroDivisionError,
    OverflowError). Every case here ends in exit 0 or exit 2 with one line."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    codes = {0: 0, 2: 0}
    try:
        for seed in range(40):
            rng = random.Random(seed)
            argv = [command] + (["t"] if command == "scenario" else [])
            for flag, typical in flags:
                value = _number(rng, typical) if rng.random() < 0.4 else repr(typical)
                argv += [flag, value]
            if command == "contact":
                argv += ["--engine", rng.choice(["mujoco", "bullet", "both"])]
            signal.alarm(SECONDS_PER_CASE)
            try:
                rc = main(argv)
            finally:
                signal.alarm(0)
            out = capsys.readouterr()
            assert rc in codes, (argv, out.err)
            codes[rc] += 1
            if rc == 2:
                assert out.err.count("\n") == 1 and "Traceback" not in out.err, (argv, out.err)
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert codes[0] > 0 and codes[2] > 0, codes
