"""What a name the user typed could have meant: nothing typed is guessed at (no flag or
keyword is ever abbreviated or renamed silently), but a name that is not one is refused with
the names it may have meant: a renamed one's new name, the flag of a paper symbol typed as
a name (``--e``: ``--restitution``), the names it starts, and close spellings.

Names are compared in their keyword form (``contact_stiffness``); ``style`` shows them as
flags (``--contact-stiffness``) for the command line or as keywords for the Python API.
"""

from __future__ import annotations

import contextvars
import difflib

#: How a refusal names what the user typed: ``"keyword"`` (``t_end``) from a call of the
#: Python API (compare.interface.api), ``"flag"`` (``--t-end``) while a command of the
#: command line runs (compare.interface.cli sets it): the commands call the same API.
NAMING = contextvars.ContextVar("treeimpact_naming", default="keyword")

#: The paper's symbols (docs/glossary.md) -> the name of the flag or keyword that sets them.
SYMBOLS = {"e": "restitution", "m": "impactor_mass", "l_e": "equivalent_length",
           "theta_r": "release_angle_deg", "theta": "release_angle_deg",
           "a": "clamp_height", "d": "diameter", "M_T": "dynamic_mass",
           "K_T": "equivalent_stiffness", "b": "damping_rate", "k_c": "contact_stiffness",
           "c_c": "contact_damping", "E": "youngs_modulus", "l": "length", "rho": "density",
           "m_c": "clamp_mass", "mu": "effective_mass", "T_c": "contact_duration",
           "t_c": "contact_duration", "u1": "impact_speed", "u_1": "impact_speed"}


def show(name: str, style: str = "flag") -> str:
    """``name`` (keyword form) as the user would type it: ``--contact-stiffness`` (``style``
    "flag") or ``contact_stiffness`` (any other)."""
    return "--" + name.replace("_", "-") if style == "flag" else name


def keyword(typed: str) -> str:
    """The keyword form of a typed flag or keyword (``--t-end=1`` -> ``t_end``)."""
    return typed.split("=", 1)[0].lstrip("-").replace("-", "_")


def suggestions(typed: str, known, renamed: dict | None = None) -> list[str]:
    """The names (keyword form) among ``known`` that ``typed`` may have meant, best first:
    its new name if ``renamed`` (old -> new) has it, the flag of a paper symbol, the known
    names it is the start of, and close spellings (difflib, at most three)."""
    name = keyword(typed)
    known = sorted(set(known))
    out = []
    if renamed and name in renamed:
        out.append(renamed[name])
    for sym in (name, name.lower()):
        target = SYMBOLS.get(sym) or next((v for k, v in SYMBOLS.items()
                                           if k.lower() == sym), None)
        if target in known:
            out.append(target)
            break
    if name:
        out += [k for k in known if k.startswith(name) and k != name]
    out += difflib.get_close_matches(name, known, n=3, cutoff=0.6)
    return list(dict.fromkeys(out))[:5]


def did_you_mean(typed: str, known, renamed: dict | None = None, style: str = "flag") -> str:
    """The end of a refusal of the ``typed`` name: ``"; did you mean --restitution?"``
    among the ``known`` names (``"; renamed: ..."`` for a removed spelling of ``renamed``),
    or ``""`` when nothing is close; names shown in ``style`` (:func:`show`)."""
    name = keyword(typed)
    found = suggestions(typed, known, renamed)
    if not found:
        return ""
    if renamed and name in renamed:
        new = show(renamed[name], style)
        rest = [show(f, style) for f in found[1:]]
        more = f" (or {', '.join(rest)})" if rest else ""
        return f"; {show(name, style)} was renamed: did you mean {new}?{more}"
    shown = [show(f, style) for f in found]
    return "; did you mean " + (shown[0] if len(shown) == 1 else
                                ", ".join(shown[:-1]) + " or " + shown[-1]) + "?"
