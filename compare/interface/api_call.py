"""How every public API function is called (compare.interface.api, api_records,
api_studies): its refusals name keyword arguments for a Python caller and flags while a
command runs it (compare.runs.names.NAMING), and it runs with the library's BLAS thread
limit (analytic.threads), the caller's own setting put back when it returns."""

from __future__ import annotations

import functools
import re

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.threads import enter_limit, exit_limit

from ..runs.names import NAMING

_FLAG = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")


def keywords_of(text: str) -> str:
    """The message ``text`` of the package's with its command-line flags named as the API's
    keyword arguments (``--t-end`` -> ``t_end``); the run budget's flag named by its variable."""
    text = text.replace("--max-seconds, ", "").replace("--max-seconds", "TREEIMPACT_MAX_SECONDS")
    return _FLAG.sub(lambda m: m.group(1).replace("-", "_"), text)


def api_function(func):
    """``func`` as a public API function: a ParameterError it raises names keyword
    arguments, not flags (unless a command is calling: then its flags), and it runs with
    the library's BLAS thread limit (the caller's setting is back when it returns)."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        enter_limit()
        try:
            return func(*args, **kwargs)
        except ParameterError as exc:
            if NAMING.get() == "flag":  # a command's call: its refusal names the flags
                raise
            raise ParameterError(keywords_of(str(exc))) from None
        finally:
            exit_limit()
    return wrapper
