"""Pulling the Python out of an LLM answer, before it goes to the sandbox.

:func:`extract_code` prefers fenced ```` ```python ```` blocks, then bare fences, then the raw
answer when it looks like code, so that planners and LMPs accept the usual completion formats
(several blocks, truncated fences, unfenced code) and fail with a clear PlanError on prose.
It only handles text; running the code is :func:`~capmj.agents.sandbox.run_code`'s job.
"""

from __future__ import annotations

import ast
import re
import textwrap

from capmj.errors import NoCodeError

_FENCE = re.compile(r"```[ \t]*([\w+.-]*)[^\n]*\n(.*?)(?:```|\Z)", re.DOTALL)
_CODE_LINE = re.compile(
    r"^\s*(#|def |for |while |if |elif |else\s*:|try\s*:|except\b|return\b|import |from \S+ import"
    r"|[A-Za-z_][\w.]*(\[[^\]]*\])?\s*(,\s*[A-Za-z_]\w*\s*)*[-+*/%]?=[^=]"  # assignment
    r"|[A-Za-z_][\w.]*\(.*\)\s*$)"  # call
)


def _looks_like_code(text: str) -> bool:
    try:
        tree = ast.parse(text)
    except (SyntaxError, ValueError):
        lines = [ln for ln in text.splitlines() if ln.strip()]
        return bool(lines) and 2 * sum(bool(_CODE_LINE.match(ln)) for ln in lines) >= len(lines)
    trivial = (ast.Constant, ast.Name)
    return any(not (isinstance(st, ast.Expr) and isinstance(st.value, trivial)) for st in tree.body)


def extract_code(completion_text: str) -> str:
    """The Python in an LLM answer: ```python blocks, else bare ``` blocks, else raw code.

    Several blocks of the chosen kind are joined in order; an unclosed fence (truncated answer)
    runs to the end.  Raises PlanError("no code in completion") for prose-only answers.
    """
    if not isinstance(completion_text, str) or not completion_text.strip():
        raise NoCodeError("no code in completion")
    blocks = [(lang.lower(), body) for lang, body in _FENCE.findall(completion_text)]
    if blocks:
        tagged = [b for lang, b in blocks if lang in ("python", "py", "python3")]
        chosen = tagged or [b for lang, b in blocks if not lang]
        code = "\n\n".join(textwrap.dedent(b).strip("\n") for b in chosen if b.strip())
        if code.strip():
            return code + "\n"
        raise NoCodeError("no code in completion")
    raw = textwrap.dedent(completion_text).strip("\n")
    if _looks_like_code(raw):
        return raw + "\n"
    raise NoCodeError("no code in completion")
