"""One Markdown document per LLM attempt, in reading order, built from the texts the agent sent.

The LLM agent sends many small texts per attempt (``llm/attempt{k}/{lmp}/{n}/{part}`` and
``llm/attempt{k}/{api_calls|error|verdict|report}``).  Read one by one they are a maze (an
episode had ~44 of them); this module assembles each attempt into the order a reader wants:

1. the plan as a numbered code block, the line the error cites marked with ``>>``, and the error;
2. the verdict of the attempt and the reporter's reasoning;
3. the API calls the plan made (and what it printed);
4. every prompt and completion (planner first, then the helper LMPs in call order).

Texts that belong to no attempt (a reference agent's API calls, ...) go to one "other texts"
document.  Pure string functions: no rerun here.
"""

from __future__ import annotations

import re
from typing import Mapping, Sequence

_ATTEMPT = re.compile(r"^llm/attempt(\d+)/(.+)$")
_LINE = re.compile(r"\bline (\d+)\b")
_PART_ORDER = ("prompt", "completion", "code", "removed_imports", "printed", "identical_to", "result", "error")
REPORTER_LMPS = ("parse_completion", "vlm_reporter", "reporter_direct", "reporter_checked")
"""LMPs whose results are the reporter's verdict and reasoning (shown under "Verdict")."""


def error_line(error: str | None) -> int | None:
    """The 1-based plan line an error message cites (``line 7: ...``), if any."""
    m = _LINE.search(error or "")
    return int(m.group(1)) if m else None


def numbered(code: str, mark: int | None = None) -> str:
    """``code`` with right-aligned line numbers; line ``mark`` gets ``>>`` in the gutter."""
    lines = code.rstrip("\n").split("\n")
    w = len(str(len(lines)))
    return "\n".join(f"{'>>' if i == mark else '  '} {i:>{w}} | {ln}" for i, ln in enumerate(lines, start=1))


def _fence(body: str, lang: str = "text") -> list[str]:
    ticks = "````" if "```" in body else "```"
    return [f"{ticks}{lang}", body.rstrip("\n"), ticks]


def split_attempts(texts: Sequence[tuple[str, str]]) -> tuple[dict[int, dict[str, str]], list[tuple[str, str]]]:
    """``(key, body)`` texts in time order -> ({attempt: {rest_of_key: last body}}, other texts)."""
    attempts: dict[int, dict[str, str]] = {}
    other: list[tuple[str, str]] = []
    for key, body in texts:
        m = _ATTEMPT.match(key)
        if m:
            attempts.setdefault(int(m.group(1)), {})[m.group(2)] = body
        else:
            other.append((key, body))
    return attempts, other


def _calls(parts: Mapping[str, str]) -> list[tuple[str, int]]:
    """The LMP calls of an attempt as (lmp, n): planner first, then the others in order of n."""
    seen: list[tuple[str, int]] = []
    for key in parts:
        bits = key.split("/")
        if len(bits) == 3 and bits[1].isdigit() and (bits[0], int(bits[1])) not in seen:
            seen.append((bits[0], int(bits[1])))
    return sorted(seen, key=lambda c: (c[0] != "planner", c[1], c[0]))


def attempt_markdown(k: int, parts: Mapping[str, str]) -> str:
    """The reading-order Markdown of attempt ``k`` (see the module docstring)."""
    calls = _calls(parts)
    plans = [n for lmp, n in calls if lmp == "planner"]
    verdict = parts.get("verdict", "")
    head = verdict.splitlines()[0].split(" (error:")[0] if verdict else ""  # the error has its own section
    lines = [f"# Attempt {k}" + (f" — {head}" if head else "")]
    numbers: list[int | None] = [*plans] or [None]  # no planner call: one section for the attempt
    for n in numbers:
        base = f"planner/{n}/"
        code = parts.get(base + "code")
        err = parts.get(base + "error") or parts.get("error")
        mark = error_line(err)
        lines += ["", "## Plan" + (f" (planner call {n})" if n is not None and len(plans) > 1 else "")]
        if code:
            lines += [""] + _fence(numbered(code, mark), "python")
        elif n is not None and parts.get(base + "completion"):
            lines += ["", "_no code could be extracted; the completion:_", ""] + _fence(parts[base + "completion"])
        else:
            lines += ["", "_no plan_"]
        if err:
            where = ""
            if code and mark is not None and 1 <= mark <= len(code.splitlines()):
                where = f" — line {mark}: `{code.splitlines()[mark - 1].strip()}`"
            lines += ["", f"**Error**{where}", ""] + _fence(err)
    lines += ["", "## Verdict", "", verdict or "_none_"]
    if parts.get("report"):
        lines += ["", "### Reporter", ""] + _fence(parts["report"])
    for lmp, n in calls:
        if lmp in REPORTER_LMPS and (parts.get(f"{lmp}/{n}/result") or parts.get(f"{lmp}/{n}/error")):
            lines += ["", f"### {lmp} #{n}", ""] + _fence(parts.get(f"{lmp}/{n}/result") or parts[f"{lmp}/{n}/error"])
    lines += ["", "## API calls", ""] + (_fence(parts["api_calls"]) if parts.get("api_calls") else ["_none_"])
    for n in plans:
        if parts.get(f"planner/{n}/printed"):
            lines += ["", "### Printed", ""] + _fence(parts[f"planner/{n}/printed"])
    lines += ["", "## Prompts and completions"]
    for lmp, n in calls:
        lines += ["", f"### {lmp} #{n}"]
        for part in _PART_ORDER:
            body = parts.get(f"{lmp}/{n}/{part}")
            if body and not (lmp == "planner" and part in ("code", "error", "printed")):
                lines += ["", f"**{part}**", ""] + _fence(body)
    return "\n".join(lines) + "\n"


def other_markdown(texts: Sequence[tuple[str, str]]) -> str:
    """Texts outside any LLM attempt, one section each in time order."""
    lines = ["# Other texts"]
    for key, body in texts:
        lines += ["", f"## {key}", ""] + _fence(body)
    return "\n".join(lines) + "\n"


__all__ = ["REPORTER_LMPS", "attempt_markdown", "error_line", "numbered", "other_markdown", "split_attempts"]
