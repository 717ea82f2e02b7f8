"""Static checks of generated task code: parse, imports, names (issue #9, confined in #25).

They read the code as an AST and never execute it, so ``import os`` or ``open(...)`` is
rejected before anything runs.  What a task may import and reference is the allow-list of
names in :mod:`capmj.confine.allowlist`, checked by :mod:`capmj.confine.names`; this module
wraps those findings as the generator's ``parse``/``imports``/``names`` check results.
Execution (and with it the registry's validation of the task object) happens only in the
jail (:mod:`capmj.confine.jail`).  A module the compiler itself cannot take (``RecursionError`` on
a 1 200-term sum, ``MemoryError``, NUL bytes) fails ``parse`` with its reason: a candidate never
crashes the generator.
"""

from __future__ import annotations

import ast
import json
import re
from typing import Any

from capmj.confine.allowlist import IMPORTABLE
from capmj.confine.names import import_findings, name_findings
from capmj.taskcheck import CheckResult

STATIC_CHECKS = ("parse", "imports", "names")


def extract_code(answer: str) -> str:
    """The code of an LLM answer: the longest fenced block (```python or bare), else the text."""
    blocks = re.findall(r"```[a-zA-Z0-9_+-]*[ \t]*\n(.*?)```", answer, re.DOTALL)
    return (max(blocks, key=len) if blocks else answer).strip() + "\n"


def _without_js_extras(text: str) -> str:
    """``text`` without what a small model adds to JSON: ``// comments``, ``...`` items, trailing commas.

    Outside strings only (a goal text may hold "...", a URL's ``//`` or ", ,"): the commas left
    around a dropped item are merged as they are written, never by a pass over the whole text."""
    out: list[str] = []
    i, in_string = 0, False

    def last() -> str:
        """The last character written that is not white space ("" at the start)."""
        return next((ch for ch in reversed(out) if not ch.isspace()), "")

    while i < len(text):
        c = text[i]
        if in_string:
            out.append(c)
            if c == "\\" and i + 1 < len(text):
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_string = False
        elif c == '"':
            in_string = True
            out.append(c)
        elif text.startswith("//", i):
            while i < len(text) and text[i] != "\n":
                i += 1
            continue
        elif text.startswith("...", i):
            i += 3
            continue
        elif c == "," and last() in (",", "[", "{"):
            pass  # a second comma, or one right after an opening bracket
        elif c in "]}":
            while out and out[-1].isspace():
                out.pop()
            if out and out[-1] == ",":
                out.pop()
            out.append(c)
        else:
            out.append(c)
        i += 1
    return "".join(out)


def extract_json(answer: str) -> Any:
    """The first JSON value of an LLM answer (fenced or bare); raises ``ValueError``.

    An answer that is JSON but for ``// comments``, ``...`` placeholders or trailing commas is read
    without them (models write such objects; the candidate would otherwise stop at a proposal the
    answer holds)."""
    text = answer.strip()
    fenced = re.search(r"```(?:json)?\s*\n(.*?)```", text, re.DOTALL)
    if fenced:
        text = fenced.group(1).strip()
    starts = [i for i in (text.find("{"), text.find("[")) if i >= 0]
    if not starts:
        raise ValueError(f"no JSON value in the answer: {answer[:200]!r}")
    text = text[min(starts):]
    try:
        return json.JSONDecoder().raw_decode(text)[0]
    except json.JSONDecodeError as exc:
        try:
            return json.JSONDecoder().raw_decode(_without_js_extras(text))[0]
        except json.JSONDecodeError:
            raise exc from None


CONTEXT_LINES = 3
"""Lines shown up to a syntax error's line: the cause is often the line before (an unclosed
bracket, a continuation without one), and a small model repairs what it is shown."""


def _lines_before(code: str, lineno: int | None) -> str:
    lines = code.splitlines()
    if not lineno or lineno > len(lines):
        return ""
    first = max(1, lineno - CONTEXT_LINES + 1)
    return "".join(f"\n{'>' if i == lineno else ' '} {i:4d} | {lines[i - 1]}" for i in range(first, lineno + 1))


def static_checks(code: str) -> tuple[CheckResult, ...]:
    """``parse``, ``imports`` and ``names`` in order; after a failure the rest are skipped."""
    try:
        tree = ast.parse(code)
        compile(tree, "<task>", "exec")
    except SyntaxError as e:
        msg = f"SyntaxError: {e.msg} (line {e.lineno})" + (f": {e.text.strip()}" if e.text else "")
        msg += _lines_before(code, e.lineno)
        return _parse_failed(msg)
    except (RecursionError, MemoryError, ValueError) as e:  # nested too deeply for the compiler, NUL bytes ...
        return _parse_failed(f"{type(e).__name__}: the code cannot be compiled ({str(e)[:120] or 'no message'}); "
                             "write shorter expressions and shallower nesting")
    out = [CheckResult("parse", "pass", f"{len(code.splitlines())} lines")]
    try:
        return _names(tree, out)
    except (RecursionError, MemoryError) as e:  # the checks walk the tree recursively too
        return (*out, CheckResult("imports", "fail", f"{type(e).__name__}: the code is nested too deeply to check"),
                CheckResult("names", "skip"))


def _parse_failed(msg: str) -> tuple[CheckResult, ...]:
    return (CheckResult("parse", "fail", msg), CheckResult("imports", "skip"), CheckResult("names", "skip"))


def _names(tree: ast.AST, out: list[CheckResult]) -> tuple[CheckResult, ...]:
    bad = import_findings(tree)
    out.append(CheckResult("imports", "fail", f"{'; '.join(map(str, bad))}; a task may import only "
                                              f"{', '.join(IMPORTABLE)} (and only their listed names)") if bad
               else CheckResult("imports", "pass", "only allowed modules and names"))
    if bad:
        return (*out, CheckResult("names", "skip"))
    bad = name_findings(tree)
    out.append(CheckResult("names", "fail", "; ".join(map(str, bad[:5]))) if bad
               else CheckResult("names", "pass", "no forbidden names"))
    return tuple(out)


__all__ = ["STATIC_CHECKS", "extract_code", "extract_json", "static_checks"]
