"""Shared machinery of the report sections: the jinja2 environment and number filters.

A section is a class with ``title``, ``anchor``, a template pair
``templates/<name>.html.j2`` / ``templates/<name>.md.j2`` rendered with :meth:`context`,
and :meth:`to_json` (every number the page shows, machine-readable).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import jinja2

from treeimpact.compare.studies.sobol import verdict_text
from treeimpact.compare.studies.study_inputs import INPUTS
from treeimpact.compare.studies.sweep.maps import INPUT_LABELS, OUTPUT_LABELS

from .glossary import tip

TEMPLATES = Path(__file__).with_name("templates")


def num(v, digits: int = 4) -> str:
    """``v`` with ``digits`` significant digits; n/a for None/NaN; ints as they are."""
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return "n/a"
        if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-3):
            return f"{v:.{digits - 1}e}"
        return plain(v, digits)
    return str(v)


def plain(v: float, digits: int) -> str:
    """A finite ``v`` rounded to ``digits`` significant digits, written without a power of
    ten (130, not 1.3e+02) and without trailing zeros (0.86, not 0.860)."""
    rounded = float(f"{v:.{digits}g}")
    if rounded == 0:
        return "0"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(rounded))))
    text = f"{rounded:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def span(values, digits: int = 3, sep: str = "-") -> str:
    """The range of ``values`` as 'low-high' (:func:`num` at ``digits``, the ends joined by
    ``sep``), one value when its ends print the same (17.7 J, not 17.7-17.7 J); n/a when
    there is none."""
    values = [v for v in values if v is not None]
    if not values:
        return "n/a"
    low, high = num(min(values), digits), num(max(values), digits)
    return low if low == high else f"{low}{sep}{high}"


#: The sensitivity study's dimensionless inputs, what their number is
#: (compare.studies.study_inputs.INPUTS gives the others' units).
_INPUT_WORDS = {"root_share": "of the static flexibility at the clamp",
                "e_over_g": "(E / G, 1)", "restitution": "(e, 1)"}


def input_value(v, key: str) -> str:
    """A held (measured) input ``key`` of the sensitivity study at its value ``v``, with
    its unit: 'clamp mass 4 kg', 'root compliance 0.86 of the static flexibility at the clamp', the pad as its
    collision time in ms."""
    unit = INPUTS[key][2] if key in INPUTS else ""
    if unit == "log10 s" and isinstance(v, (int, float)):
        return f"{input_name(key)} (its collision time {num(1e3 * 10.0 ** v, 3)} ms)"
    words = _INPUT_WORDS.get(key, "" if unit == "1" else unit)
    return f"{input_name(key)} {num(v, 3)} {words}".rstrip()


def share(v, signed: bool = False) -> str:
    """A Sobol index ``v`` (a share of variance, 1) to two decimals ('0.62'; ``signed``:
    '+0.05'), n/a for None/NaN."""
    if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "n/a"
    return f"{v:+.2f}" if signed else f"{v:.2f}"


def pct(v, digits: int = 2) -> str:
    """A relative difference ``v`` as a signed percentage with ``digits`` decimals; "" for
    None/NaN."""
    if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
        return ""
    return f"{100 * v:+.{digits}f} %"


def frac(v, digits: int = 0) -> str:
    """A fraction or an unsigned relative error ``v`` as a percentage with ``digits``
    decimals; n/a for None/NaN."""
    if v is None or isinstance(v, bool) or not isinstance(v, (int, float)) \
            or not math.isfinite(v):
        return "n/a"
    return f"{100 * v:.{digits}f} %"


def short(v, digits: int = 3) -> str:
    """A number ``v`` as a reader needs it: ``digits`` significant digits, powers of ten as
    3.06e-4 (no padded exponent); ints, words and None as they are."""
    if isinstance(v, bool) or not isinstance(v, float):
        return "n/a" if v is None else str(v)
    if not math.isfinite(v):
        return "n/a"
    if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-2):
        mantissa, exp = f"{v:.{digits - 1}e}".split("e")
        if "." in mantissa:
            mantissa = mantissa.rstrip("0").rstrip(".")
        return f"{mantissa}e{int(exp)}"
    return f"{v:.{digits}g}"


#: A decimal number of more digits than a reader needs, in free text (a reason, an error).
_LONG_NUMBER = re.compile(r"(?<![\w.])[-+]?\d+\.\d{5,}(?:[eE][-+]?\d+)?(?![\w.])")


def tidy(text) -> str:
    """Free text (a reason, an error) with every long decimal number rounded to 4
    significant digits: 'a1 = -1.4782888969718704 m/s' reads 'a1 = -1.478 m/s'."""
    if text is None:
        return ""
    return _LONG_NUMBER.sub(lambda m: short(float(m.group(0)), 4), str(text))


def cost(v) -> str:
    """A cost ``v`` (s per simulated second): 3 significant digits below 100, whole seconds
    from
    100 on ('5070', never '5.07e+03'); n/a for None/NaN."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "n/a"
    return f"{v:.0f}" if abs(v) >= 100 else f"{v:.3g}"


def options_text(options: dict, units: dict | None = None, sep: str = ", ") -> str:
    """A run's ``options`` as 'name=value unit', sorted, numbers rounded (:func:`short`),
    units from ``units`` (name -> unit), joined by ``sep``; "defaults" when none."""
    units = units or {}
    if not options:
        return "defaults"
    return sep.join(f"{k}={short(v)}" + (f" {units[k]}" if units.get(k) not in (None, "", "1")
                                           else "")
                    for k, v in sorted(options.items()))


def input_name(key: str) -> str:
    """An unmeasured input of the sensitivity study in words ('pad contact duration' for
    log10_pad_duration), as its figure labels it; the key if unknown."""
    return INPUT_LABELS.get(key, key).replace("\n", " ")


def output_name(key: str) -> str:
    """An output ``key`` of the sensitivity study in words ('x_max gap' for gap.x_max)."""
    return OUTPUT_LABELS.get(key, key)


def deciding(output: dict, crossing: bool = False) -> str:
    """Which inputs decide a sensitivity output, in words: one input with its mu* and
    interval when its interval lies above every other's, else the inputs whose intervals
    overlap its, 'not separable'. mu* of a gap in percentage points, of a crossing
    (``crossing``) in decades of the duration."""
    names = output.get("deciding") or []
    if not names:
        return "no input moves it"
    idx = output["indices"]

    def one(n):
        if crossing:
            return (f"{input_name(n)} (mu* {idx[n]['mu_star']:.2f} "
                    f"+- {idx[n]['mu_star_conf']:.2f} decades)")
        return (f"{input_name(n)} (mu* {100 * idx[n]['mu_star']:.0f} "
                f"+- {100 * idx[n]['mu_star_conf']:.0f} points)")
    if len(names) == 1:
        return one(names[0])
    return (", ".join(one(n) for n in names[:-1]) + f" or {one(names[-1])}: not separable "
            "(their intervals overlap)")


def interval(low, high, digits: int = 3) -> str:
    """A 95 % interval 'low to high' with as many significant digits (3 to 6) as it takes
    for its ends to differ: '109.93 to 110.05', not '110 to 110'."""
    for d in range(digits, 7):
        a, b = num(low, d), num(high, d)
        if a != b:
            break
    return f"{a} to {b}"


def sobol_verdict(output: dict) -> str:
    """A Sobol output's verdict in words (compare.studies.sobol.verdict_text, the inputs
    named as the figure labels them); 'no value' for an output without one."""
    return verdict_text(output, input_name) if "order" in output else "no value"


_ENV = None


def environment() -> jinja2.Environment:
    """The report's jinja2 environment (created once): the templates folder, HTML
    autoescaping, undefined names as errors, and the number filters of this module."""
    global _ENV
    if _ENV is None:
        _ENV = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)),
                                  autoescape=jinja2.select_autoescape(["html.j2"]),
                                  undefined=jinja2.StrictUndefined, trim_blocks=True,
                                  lstrip_blocks=True, keep_trailing_newline=True)
        _ENV.filters["num"] = num
        _ENV.filters["pct"] = pct
        _ENV.filters["frac"] = frac
        _ENV.filters["short"] = short
        _ENV.filters["cost"] = cost
        _ENV.filters["tidy"] = tidy
        _ENV.filters["input_name"] = input_name
        _ENV.filters["output_name"] = output_name
        _ENV.filters["deciding"] = deciding
        _ENV.filters["span"] = span
        _ENV.filters["input_value"] = input_value
        _ENV.filters["sobol_verdict"] = sobol_verdict
        _ENV.filters["share"] = share
        _ENV.filters["tip"] = tip
        _ENV.globals["interval"] = interval
    return _ENV


class Section:
    """Base of every report section."""

    template = ""  # stem of templates/<template>.html.j2 and .md.j2
    title = ""
    anchor = ""

    def context(self) -> dict:  # pragma: no cover - abstract
        """The names the section's templates read."""
        raise NotImplementedError

    def to_json(self) -> dict:  # pragma: no cover - abstract
        """The section's data for report.json."""
        raise NotImplementedError

    def render(self, fmt: str) -> str:
        """The section rendered by its template in ``fmt`` ("html" or "md")."""
        tpl = environment().get_template(f"{self.template}.{fmt}.j2")
        return tpl.render(section=self, **self.context())
