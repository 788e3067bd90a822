"""Checked-in files generated from the shipped scenarios (the engines' MJCF and URDF models).

:func:`regenerate_main` is the command both ``python -m treeimpact.mujoco_models.regenerate`` and
``python -m treeimpact.bullet_models.regenerate`` run: write every generated file whose content
changed, remove files of the same kind that no shipped scenario generates any more, or with
``--check`` only report both and exit 1 if anything would change.

Numbers are written at a fixed precision (URDF: :data:`URDF_DIGITS` significant digits;
MJCF: MuJoCo's writer, :data:`MJCF_DIGITS`), and a file counts as changed only when a
number differs by more than one unit in its last written digit (:func:`xml_differences`):
a BLAS kernel or numpy version that moves the 16th digit changes no file.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import xml.etree.ElementTree as ET
from collections.abc import Callable

URDF_DIGITS = 12  # significant digits of every number in a generated URDF
MJCF_DIGITS = 6  # significant digits of MuJoCo's XML writer (MjSpec.to_xml)
_ZERO = 1e-15  # SI: numbers this small are written round-off of zero (smallest model value 1e-9)


def fixed_digits(value: float, digits: int = URDF_DIGITS) -> str:
    """``value`` as text with ``digits`` significant digits (``-0`` written as ``0``)."""
    text = format(float(value), f".{digits}g")
    return "0" if text == "-0" else text


def _round_tokens(value: str, digits: int) -> str:
    out = []
    for token in value.split():
        try:
            out.append(fixed_digits(float(token), digits))
        except ValueError:
            out.append(token)
    return " ".join(out)


def fixed_precision_xml(text: str, digits: int) -> str:
    """``text`` (XML) with every number in its attributes written at ``digits`` significant
    digits, indented by two spaces, ending in a newline."""
    root = ET.fromstring(text)
    for element in root.iter():
        for key, value in element.attrib.items():
            element.set(key, _round_tokens(value, digits))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n"


def _ulp(x: float, digits: int) -> float:
    """One unit in the last of ``digits`` significant digits of ``x``."""
    return 10.0 ** (math.floor(math.log10(abs(x))) - digits + 1) if x else 0.0


def _tokens_differ(expected: str, actual: str, digits: int) -> bool:
    a, b = expected.split(), actual.split()
    if len(a) != len(b):
        return True
    for x, y in zip(a, b):
        try:
            fx, fy = float(x), float(y)
        except ValueError:
            if x != y:
                return True
            continue
        # one unit in the last written digit (of the larger number) is rounding, not a change
        if abs(fx - fy) > 1.01 * _ulp(max(abs(fx), abs(fy)), digits) + _ZERO:
            return True
    return False


def xml_differences(expected: str, actual: str, digits: int) -> list[str]:
    """Where two XML texts differ beyond ``digits`` significant digits, one line each:
    ``element path: attribute 'expected' != 'actual'`` (element tags, attribute sets and
    non-numeric text compared exactly)."""
    try:
        ra, rb = ET.fromstring(expected), ET.fromstring(actual)
    except ET.ParseError as exc:
        return [f"not parseable XML ({exc})"]
    out: list[str] = []

    def walk(ea: ET.Element, eb: ET.Element, path: str) -> None:
        here = f"{path}/{ea.tag}" + (f"[@name='{ea.get('name')}']" if ea.get("name") else "")
        if ea.tag != eb.tag:
            out.append(f"{here}: element {ea.tag!r} != {eb.tag!r}")
            return
        for key in sorted(set(ea.attrib) | set(eb.attrib)):
            va, vb = ea.get(key), eb.get(key)
            if va is None or vb is None or _tokens_differ(va, vb, digits):
                out.append(f"{here}: {key} {va!r} != {vb!r}")
        if _tokens_differ((ea.text or "").strip(), (eb.text or "").strip(), digits):
            out.append(f"{here}: text {ea.text!r} != {eb.text!r}")
        ca, cb = list(ea), list(eb)
        if len(ca) != len(cb):
            out.append(f"{here}: {len(ca)} child elements != {len(cb)}")
        for x, y in zip(ca, cb):
            walk(x, y, here)

    walk(ra, rb, "")
    return out


def file_differences(directory: pathlib.Path, files: dict[str, str], digits: int) -> dict[str, list[str]]:
    """File name -> differences between the checked-in file in ``directory`` and the
    generated text of ``files`` (name -> text), numbers compared to ``digits`` significant
    digits (missing files included); files that match are left out."""
    out = {}
    for name, text in files.items():
        path = directory / name
        diff = (xml_differences(path.read_text(encoding="utf-8"), text, digits)
                if path.exists() else ["missing"])
        if diff:
            out[name] = diff
    return out


def regenerate_main(argv, *, prog: str, generated: Callable[[], dict], directory: pathlib.Path,
                    suffix: str, kind: str, digits: int) -> int:
    """Sync ``directory`` with ``generated()`` (file name -> text); see the module docstring.

    Args:
        argv: the command line's arguments (``--check``: compare only, exit 1 on a
            difference).
        prog: the program's name in its usage line.
        generated: returns the files, name -> text.
        directory: the folder of the checked-in files.
        suffix: the files' suffix (``.xml``, ``.urdf``): others of it are stale.
        kind: the files' kind in the summary line (``MJCF``, ``URDF``).
        digits: significant digits at which numbers compare equal.

    Returns:
        The exit code: 0, or 1 when ``--check`` found a difference.
    """
    ap = argparse.ArgumentParser(prog=prog)
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    args = ap.parse_args(argv)
    files = generated()
    changed = file_differences(directory, files, digits)
    stale = sorted(p.name for p in directory.glob(f"*{suffix}") if p.name not in files)
    if args.check:
        for n, diff in changed.items():
            print(f"would change: {n}: {diff[0]}" + (f" (and {len(diff) - 1} more)" if len(diff) > 1 else ""))
        for n in stale:
            print(f"would remove: {n}")
        return 1 if changed or stale else 0
    directory.mkdir(exist_ok=True)
    for n in changed:
        (directory / n).write_text(files[n], encoding="utf-8")
    for n in stale:  # a model of no shipped scenario (renamed or removed)
        (directory / n).unlink()
    print(f"wrote {len(files)} {kind} files to {directory} ({len(changed)} changed, "
          f"{len(stale)} removed)")
    return 0
