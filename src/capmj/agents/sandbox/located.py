"""Where sandboxed code failed, said in words: which program (the plan, a helper's code), which
line, quoted, and whether that line lies in the functions ``parse_function`` wrote.

Every failure of :func:`~capmj.agents.sandbox.runtime.run_code` becomes a
:func:`located_error`, so the message an LLM is shown on a re-plan points at the line to change;
the parts stay on the error, so a nested program's failure can be told from the caller's.
"""

from __future__ import annotations

import types

from capmj.agents.sandbox.sizes import preview
from capmj.errors import PlanError, error_name

MAX_DETAIL_CHARS = 10_000
"""Most characters of an error's message shown (an error raised with a huge plan value in it is
cut, and its full text is never made)."""


def line_of(tb: types.TracebackType | None, filename: str) -> int | None:
    """Line of the innermost traceback entry that belongs to the sandboxed code."""
    line = None
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == filename:
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


WRITTEN_START = "# --- functions written by parse_function ---"
WRITTEN_END = "# --- end of written functions ---"
"""Markers around the functions ``parse_function`` wrote, prepended to the code that calls them."""


def _quote(code: str, line: int | None, limit: int = 160) -> str:
    lines = code.splitlines()
    if line is None or not 1 <= line <= len(lines):
        return ""
    text = lines[line - 1].strip()
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _region(code: str, line: int) -> str:
    """" (in the function f that parse_function wrote)" when ``line`` lies in that prefix."""
    lines = code.splitlines()
    if not lines or lines[0] != WRITTEN_START or WRITTEN_END not in lines:
        return ""
    if line > lines.index(WRITTEN_END):
        return ""
    for i in range(line - 1, -1, -1):
        if lines[i].startswith("def "):
            return f" (in {lines[i][4:].split('(')[0].strip()}(), written by parse_function)"
    return " (in the functions parse_function wrote)"


def _where(program: str, line: int | None, code: str) -> str:
    quoted = _quote(code, line)
    where = f"line {line} of {program}{_region(code, line)}" if line is not None else program
    return where + (f": `{quoted}`" if quoted else "")


def located_error(kind: type[PlanError], message: str, *, line: int | None, code: str,
                  program: str | None) -> PlanError:
    """A PlanError saying which program failed, at which line, quoting that line.

    Without ``program`` the classic ``"line N: message"`` form is kept.  The parts stay on the
    error (``program``, ``detail``) so that a caller whose API call ran this program (a helper
    LMP called from the plan) can say "in the code parse_obj_name wrote for this line, line 1".
    """
    if program is None:
        return kind(message, line=line, code=code)
    error = kind(f"{_where(program, line, code)}: {message}", code=code)
    error.line = line
    error.program, error.detail = program, message  # type: ignore[attr-defined]
    return error


def describe(exc: BaseException) -> str:
    """"ErrorClass: message"; a located error of a nested program reads "in <program>, line N"."""
    program = getattr(exc, "program", None)
    if isinstance(exc, PlanError) and program is not None:
        code, line = exc.code or "", exc.line
        where = f"{program} for this line" + (f", line {line}{_region(code, line)}" if line else "")
        quoted = _quote(code, line)
        return f"in {where}" + (f": `{quoted}`" if quoted else "") + f": {exc.detail}"  # type: ignore[attr-defined]
    detail = preview(exc, MAX_DETAIL_CHARS, as_repr=False) or preview(exc, MAX_DETAIL_CHARS)
    return f"{error_name(exc)}: {detail}"
