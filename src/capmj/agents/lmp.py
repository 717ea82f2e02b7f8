"""Language model programs (LMPs): prompt file -> LLM -> code -> sandbox -> return value.

An LMP is a Python-styled prompt file in ``prompts/`` (imports line, API docs, orientation notes,
rules, few-shot examples, then a ``<<QUESTION>>`` placeholder), a system prompt
(``prompts/system.txt``) and the name of the variable its code must set (``ret_val`` for
``parse_obj_name`` / ``parse_position``, ``judge`` for ``parse_completion``; the planner sets
nothing, it acts).  One :class:`LMPSession` serves one attempt of one episode: it owns the API
environment, numbers and records every call, and synthesises functions that code calls but nobody
defined (``parse_function``), recursively up to ``max_fn_depth``.

Prompt files carry machine-readable metadata on lines that start with ``#@``: these are stripped
before a prompt is sent, and let tests rebuild the scene of every few-shot example and execute it::

    #@ example: stack_in_zone
    #@ scene: {"objects": [["zone", "red", [0.5, 0.3]], ["block", "blue", [0.4, -0.1]]], ...}
    #@ expect: ["movable small blue block with obj_id 2"]
    objects = [...]
    # the blue blocks.
    ret_val = ...
    #@ end

Everything an LMP does goes to the recorder under ``llm/attempt{k}/{lmp}/{n}/`` (``prompt``,
``completion``, ``code``, ``result`` or ``error``) and to the in-memory :attr:`LMPSession.transcript`.
"""

from __future__ import annotations

import ast
import builtins
import json
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from capmj.agents.sandbox import FORBIDDEN_NAMES, PROVIDED_NAMES, SandboxBudget, extract_code, run_code
from capmj.errors import ConfigError, LLMError, PlanError
from capmj.record import NullRecorder, Recorder

__all__ = [
    "ACTION_FUNCTIONS",
    "Example",
    "LMPSession",
    "PromptFile",
    "QUESTION",
    "SANDBOX_GLOBALS",
    "find_llm_error",
    "load_prompt",
    "load_system_prompt",
    "messages_text",
    "object_names",
    "prompts_dir",
    "strip_benign_imports",
    "undefined_calls",
]

QUESTION = "<<QUESTION>>"
"""Placeholder in a prompt file replaced by the question of one call."""

META = "#@"
"""Prefix of metadata lines in prompt files (stripped before sending)."""

ACTION_FUNCTIONS = frozenset({"put_first_on_second", "stack_objects_in_order"})
"""API functions that move the robot: only the planner's code may call them, never a helper LMP."""

SANDBOX_GLOBALS = PROVIDED_NAMES
"""What run_code provides besides env (facades, shapely shortcuts, curated builtins)."""

# Modules the prompts "import" in their header: LLMs often repeat such lines; they are dropped
# when every name they bind is already available.  Any other import reaches the sandbox, which
# rejects it (and ends the attempt with a recorded error).
_BENIGN_MODULES = frozenset({"numpy", "math", "itertools", "shapely", "shapely.geometry",
                             "shapely.affinity", "env_utils", "plan_utils", "utils"})


# ------------------------------------------------------------------------------------------------
# prompt files
# ------------------------------------------------------------------------------------------------
def prompts_dir() -> Path:
    """The prompt folder: ``$CAPMJ_PROMPTS_DIR`` or ``prompts/`` of the source checkout."""
    env = os.environ.get("CAPMJ_PROMPTS_DIR")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "prompts"


@dataclass(frozen=True)
class Example:
    """One few-shot example of a prompt file, with the metadata a test needs to execute it."""

    id: str
    body: str
    """The example as it appears in the prompt (valid Python)."""
    meta: Mapping[str, str]
    """Raw metadata values by key (``scene``, ``expect``, ``check``, ``call``...)."""
    line: int
    """1-based line of the ``#@ example:`` marker in the prompt file."""

    def json(self, key: str, default: Any = None) -> Any:
        """A metadata value parsed as JSON (``default`` when absent)."""
        raw = self.meta.get(key)
        if raw is None:
            return default
        try:
            return json.loads(raw)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"example {self.id!r}: '#@ {key}:' is not JSON: {exc}") from None


@dataclass(frozen=True)
class PromptFile:
    """A parsed prompt file."""

    name: str
    path: Path
    raw: str
    template: str
    """The prompt without metadata lines, still containing :data:`QUESTION`."""
    examples: tuple[Example, ...]

    def render(self, question: str) -> str:
        return self.template.replace(QUESTION, question.rstrip("\n"))


def _parse_prompt(name: str, path: Path, raw: str) -> PromptFile:
    kept: list[str] = []
    examples: list[Example] = []
    current: dict[str, Any] | None = None
    for lineno, line in enumerate(raw.splitlines(), start=1):
        if line.startswith(META):
            key, _, value = line[len(META):].strip().partition(":")
            key, value = key.strip(), value.strip()
            if key == "example":
                if current is not None:
                    raise ConfigError(f"{path}:{lineno}: example {value!r} starts inside "
                                      f"example {current['id']!r} (missing '#@ end')")
                current = {"id": value, "meta": {}, "lines": [], "line": lineno}
            elif key == "end":
                if current is None:
                    raise ConfigError(f"{path}:{lineno}: '#@ end' outside an example")
                body = "\n".join(current["lines"]).strip("\n") + "\n"
                examples.append(Example(current["id"], body, dict(current["meta"]), current["line"]))
                current = None
            elif current is not None:
                current["meta"][key] = value
            continue
        kept.append(line)
        if current is not None:
            current["lines"].append(line)
    if current is not None:
        raise ConfigError(f"{path}: example {current['id']!r} has no '#@ end'")
    template = re.sub(r"\n{3,}", "\n\n", "\n".join(kept)).strip("\n") + "\n"
    if QUESTION not in template:
        raise ConfigError(f"{path}: prompt has no {QUESTION} placeholder")
    ids = [e.id for e in examples]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{path}: duplicate example ids in {ids}")
    return PromptFile(name, path, raw, template, tuple(examples))


@lru_cache(maxsize=64)
def _load_cached(path: str, mtime_ns: int) -> PromptFile:
    p = Path(path)
    return _parse_prompt(p.stem, p, p.read_text(encoding="utf-8"))


def load_prompt(name: str, directory: Path | str | None = None) -> PromptFile:
    """Load ``<directory>/<name>.py`` (or ``name`` as given when it has a suffix)."""
    folder = Path(directory) if directory is not None else prompts_dir()
    path = folder / (name if Path(name).suffix else f"{name}.py")
    try:
        stat = path.stat()
    except FileNotFoundError:
        raise ConfigError(f"prompt file {path} not found (set CAPMJ_PROMPTS_DIR to the prompts "
                          "folder of a capmj checkout)") from None
    return _load_cached(str(path), stat.st_mtime_ns)


def load_system_prompt(directory: Path | str | None = None, name: str = "system.txt") -> str:
    folder = Path(directory) if directory is not None else prompts_dir()
    try:
        return (folder / name).read_text(encoding="utf-8").strip()
    except FileNotFoundError:
        raise ConfigError(f"system prompt {folder / name} not found") from None


# ------------------------------------------------------------------------------------------------
# code analysis
# ------------------------------------------------------------------------------------------------
def _bound_names(tree: ast.AST) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            names.add(node.id)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                names.add((alias.asname or alias.name).split(".")[0])
    return names


def undefined_calls(code: str, known: set[str] | frozenset[str]) -> list[tuple[str, int, str]]:
    """Functions ``code`` calls by a bare name that neither ``known`` nor the code itself binds.

    Returns ``(name, line, statement source)`` for the first call site of each, in order of
    appearance.  Unparseable code gives ``[]`` (the sandbox reports the syntax error).  Names the
    sandbox forbids (``eval``, ``open``...) are never offered for synthesis.
    """
    try:
        tree = ast.parse(code)
    except (SyntaxError, ValueError):
        return []
    bound = _bound_names(tree) | set(known) | SANDBOX_GLOBALS
    lines = code.splitlines()
    statements = [n for n in ast.walk(tree) if isinstance(n, ast.stmt)]
    found: dict[str, tuple[str, int, str]] = {}
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)]
    for call in sorted(calls, key=lambda c: (c.lineno, c.col_offset)):
        name = call.func.id  # type: ignore[attr-defined]
        if name in bound or name in found or name in FORBIDDEN_NAMES or name.startswith("_"):
            continue
        if hasattr(builtins, name):
            continue  # a real builtin the sandbox withholds on purpose: let it fail there
        # the innermost simple statement that contains the call, as the call site
        site = call.lineno
        end = getattr(call, "end_lineno", site) or site
        for st in statements:
            if isinstance(st, (ast.FunctionDef, ast.For, ast.While, ast.If, ast.Try)):
                continue
            if st.lineno <= call.lineno and (st.end_lineno or st.lineno) >= end:
                site, end = st.lineno, st.end_lineno or st.lineno
        snippet = "\n".join(ln.strip() for ln in lines[site - 1:end]).strip()
        found[name] = (name, call.lineno, snippet)
    return list(found.values())


def strip_benign_imports(code: str, available: set[str] | frozenset[str]) -> tuple[str, list[str]]:
    """Remove import lines that only re-import names the sandbox already provides.

    ``import numpy as np`` or ``from env_utils import get_obj_pos`` are harmless echoes of the
    prompt header; ``import os`` (or anything binding an unavailable name) is kept so that the
    sandbox rejects it.  Returns (code, removed lines).
    """
    try:
        tree = ast.parse(code)
    except (SyntaxError, ValueError):
        return code, []
    have = set(available) | SANDBOX_GLOBALS
    drop: list[tuple[int, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            ok = all(a.name in _BENIGN_MODULES and (a.asname or a.name).split(".")[0] in have
                     for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            ok = (node.level == 0 and node.module in _BENIGN_MODULES
                  and all(a.name != "*" and (a.asname or a.name) in have for a in node.names))
        else:
            continue
        if ok:
            drop.append((node.lineno, node.end_lineno or node.lineno))
    if not drop:
        return code, []
    lines = code.splitlines()
    removed: list[str] = []
    for start, end in sorted(drop, reverse=True):
        removed[:0] = lines[start - 1:end]
        # keep line numbers stable: replace with 'pass' (imports may sit inside a block)
        indent = re.match(r"\s*", lines[start - 1]).group(0)  # type: ignore[union-attr]
        lines[start - 1:end] = [f"{indent}pass  # removed: {lines[start - 1].strip()}"] + [""] * (end - start)
    return "\n".join(lines) + "\n", removed


def object_names(text: str) -> list[str] | None:
    """The names of the first ``objects = [...]`` line of ``text`` (None when there is none)."""
    for line in text.splitlines():
        if line.startswith("objects = "):
            try:
                names = ast.literal_eval(line.partition("=")[2].strip())
            except (ValueError, SyntaxError, MemoryError, RecursionError):
                return None
            if isinstance(names, (list, tuple)):
                return [str(n) for n in names]
    return None


def find_llm_error(exc: BaseException | None) -> LLMError | None:
    """The LLMError behind ``exc`` (a plan calling an LMP wraps it into a PlanError)."""
    seen = 0
    while exc is not None and seen < 20:
        if isinstance(exc, LLMError):
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def messages_text(messages: Sequence[Mapping[str, Any]]) -> str:
    """Messages rendered as readable text for logs (images summarised)."""
    out: list[str] = []
    for m in messages:
        content = m.get("content")
        if isinstance(content, list):
            parts = []
            for p in content:
                if p.get("type") == "text":
                    parts.append(str(p.get("text", "")))
                elif p.get("type") == "image_url":
                    url = str(p.get("image_url", {}).get("url", ""))
                    parts.append(f"<image {url[:30]}... {len(url)} chars>")
            content = "\n".join(parts)
        out.append(f"[{m.get('role')}]\n{content}")
    return "\n\n".join(out) + "\n"


# ------------------------------------------------------------------------------------------------
# the session
# ------------------------------------------------------------------------------------------------
@dataclass
class LMPCall:
    """One entry of a transcript."""

    attempt: int
    lmp: str
    n: int
    query: str
    prompt: str = ""
    completion: str | None = None
    code: str | None = None
    result: str | None = None
    error: str | None = None
    cached: bool | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass
class LMPSession:
    """LMP calls of one attempt: LLM client + API env + recorder + transcript.

    ``api`` maps API function names to callables (``PlannerAPI(ctx).functions()``);
    ``objects_text`` returns the current ``"objects = [...]"`` line.  ``complete(messages,
    purpose)`` is the LLM (``LLMClient.complete``).
    """

    complete: Callable[..., Any]
    api: Mapping[str, Callable[..., Any]]
    objects_text: Callable[[], str]
    attempt: int = 1
    recorder: Recorder = field(default_factory=NullRecorder)
    transcript: list[LMPCall] = field(default_factory=list)
    directory: Path | None = None
    lmp_budget: SandboxBudget = field(default_factory=lambda: SandboxBudget(wall_s=20.0))
    max_fn_depth: int = 3
    _counters: dict[str, int] = field(default_factory=dict)
    _system: str | None = None

    # -- plumbing --------------------------------------------------------------------------
    @property
    def system_prompt(self) -> str:
        if self._system is None:
            self._system = load_system_prompt(self.directory)
        return self._system

    def prompt(self, name: str) -> PromptFile:
        return load_prompt(name, self.directory)

    def next_call(self, lmp: str, query: str) -> LMPCall:
        n = self._counters.get(lmp, 0) + 1
        self._counters[lmp] = n
        call = LMPCall(self.attempt, lmp, n, query)
        self.transcript.append(call)
        return call

    def record(self, call: LMPCall, part: str, body: str) -> None:
        setattr(call, part, body)
        self.recorder.text(f"llm/attempt{self.attempt}/{call.lmp}/{call.n}/{part}", body)

    def ask(self, call: LMPCall, messages: list[dict[str, Any]]) -> str:
        """Send ``messages`` (recording prompt and completion); LLMError propagates."""
        self.record(call, "prompt", messages_text(messages))
        try:
            completion = self.complete(messages, purpose=f"{call.lmp}#{call.n}")
        except LLMError as exc:
            self.record(call, "error", f"{type(exc).__name__}: {exc}")
            raise
        call.cached = bool(getattr(completion, "cached", False))
        self.record(call, "completion", completion.text)
        return completion.text

    def messages(self, user: str) -> list[dict[str, Any]]:
        return [{"role": "system", "content": self.system_prompt}, {"role": "user", "content": user}]

    def helper_env(self, question: str | None = None) -> dict[str, Any]:
        """What helper LMP code may use: the read-only API (nothing that moves the robot), and
        ``objects`` from the question's ``objects = [...]`` line when there is one."""
        env: dict[str, Any] = {k: v for k, v in self.api.items() if k not in ACTION_FUNCTIONS}
        if question is not None:
            names = object_names(question)
            if names is not None:
                env["objects"] = names
        return env

    def plan_env(self) -> dict[str, Any]:
        """What plan code may use: the whole API plus the helper LMPs."""
        env: dict[str, Any] = dict(self.api)
        env["parse_obj_name"] = self.parse_obj_name
        env["parse_position"] = self.parse_position
        return env

    # -- code preparation --------------------------------------------------------------------
    def prepare(self, code: str, env: Mapping[str, Any], *, depth: int = 0,
                parent: LMPCall | None = None) -> str:
        """Drop benign imports, then prepend functions synthesised for undefined calls."""
        code, removed = strip_benign_imports(code, set(env))
        if removed and parent is not None:
            self.recorder.text(f"llm/attempt{self.attempt}/{parent.lmp}/{parent.n}/removed_imports",
                               "\n".join(removed))
        missing = undefined_calls(code, set(env))
        if not missing:
            return code
        functions = self.synthesize(missing, set(env) | _bound_names(ast.parse(code)), depth=depth)
        header = "# --- functions written by parse_function ---\n"
        return header + functions + "# --- end of written functions ---\n" + code

    def synthesize(self, missing: list[tuple[str, int, str]], known: set[str], *, depth: int) -> str:
        """Source of the functions ``missing`` needs (and of helpers they call), depth-bounded."""
        if depth >= self.max_fn_depth:
            names = ", ".join(m[0] for m in missing)
            raise PlanError(f"NameError: function synthesis depth {self.max_fn_depth} reached; "
                            f"undefined: {names}")
        out: list[str] = []
        known = set(known)
        for name, _line, site in missing:
            if name in known:
                continue
            source = self.parse_function(name, site)
            known.add(name)
            inner = undefined_calls(source, known)
            if inner:
                helper_src = self.synthesize(inner, known, depth=depth + 1)
                known |= _bound_names(ast.parse(helper_src))
                out.append(helper_src)
            out.append(source)
        return "".join(out)

    # -- the LMPs ----------------------------------------------------------------------------
    def _ask_and_run(self, call: Any, lmp: str, question: str) -> dict[str, Any]:
        """Prompt -> completion -> code -> sandbox; the code's final namespace.

        The question's ``objects = [...]`` line is also bound as ``objects`` for the code.  A
        rejected or failing program is recorded on the call and re-raised as ``PlanError``.
        """
        text = self.ask(call, self.messages(self.prompt(lmp).render(question)))
        try:
            code = extract_code(text)
            env = self.helper_env(question)
            code = self.prepare(code, env, parent=call)
            self.record(call, "code", code)
            return run_code(code, env, budget=self.lmp_budget, filename=f"<{lmp} {self.attempt}.{call.n}>")
        except PlanError as exc:
            self.record(call, "error", f"{type(exc).__name__}: {exc}")
            raise

    def run_lmp(self, lmp: str, question: str, return_var: str, *, query: str | None = None) -> Any:
        """Generic helper LMP: the value of ``return_var`` after running the LMP's code."""
        call = self.next_call(lmp, query if query is not None else question)
        ns = self._ask_and_run(call, lmp, question)
        if return_var not in ns:
            exc = PlanError(f"NameError: {lmp} code did not set '{return_var}'")
            self.record(call, "error", f"{type(exc).__name__}: {exc}")
            raise exc
        value = ns[return_var]
        self.record(call, "result", _short_repr(value))
        return value

    def parse_obj_name(self, description: str, context: str | None = None) -> Any:
        """Names of the objects matching ``description`` (``ret_val`` of the LMP)."""
        ctx = context if isinstance(context, str) and context.strip() else self.objects_text()
        question = f"{ctx.strip()}\n# {_sentence(description)}"
        return self.run_lmp("parse_obj_name", question, "ret_val", query=str(description))

    def parse_position(self, description: str, context: str | None = None) -> Any:
        """A position / list of positions / pose for ``description`` (``ret_val``)."""
        ctx = context if isinstance(context, str) and context.strip() else self.objects_text()
        question = f"{ctx.strip()}\n# {_sentence(description)}"
        return self.run_lmp("parse_position", question, "ret_val", query=str(description))

    def parse_completion(self, goal: str, context: str | None = None) -> tuple[bool | None, str]:
        """The text reporter: (judge, reason).  ``judge`` None when the code gave no bool."""
        ctx = context if isinstance(context, str) and context.strip() else self.objects_text()
        question = f"{ctx.strip()}\n# goal: {_sentence(goal)}"
        call = self.next_call("parse_completion", goal)
        try:
            ns = self._ask_and_run(call, "parse_completion", question)
        except PlanError as exc:
            return None, f"the checking code failed: {exc}"
        judge = ns.get("judge")
        reason = ns.get("reason")
        reason = reason if isinstance(reason, str) else ""
        if isinstance(judge, bool) or type(judge).__name__ == "bool_":
            verdict: bool | None = bool(judge)
        else:
            verdict = None
            self.record(call, "error", f"judge is {_short_repr(judge)}, not a bool")
        self.record(call, "result", f"judge = {verdict!r}\nreason = {reason!r}")
        return verdict, reason

    def parse_function(self, name: str, site: str) -> str:
        """Source of ``def name(...)`` written for the call statement ``site``."""
        site = " ".join(site.split())
        question = f"# define function: {site if site.endswith('.') else site + '.'}"
        call = self.next_call("parse_function", name)
        text = self.ask(call, self.messages(self.prompt("parse_function").render(question)))
        try:
            code = extract_code(text)
            source = _function_defs(code, name)
        except PlanError as exc:
            self.record(call, "error", f"{type(exc).__name__}: {exc}")
            raise
        self.record(call, "code", source)
        return source


def _function_defs(code: str, wanted: str) -> str:
    """Only the top-level function definitions of ``code``; one of them must be ``wanted``."""
    try:
        tree = ast.parse(code)
    except SyntaxError as exc:
        raise PlanError(f"SyntaxError: {exc.msg} (in the function written for {wanted})",
                        line=exc.lineno, code=code) from None
    lines = code.splitlines()
    parts: list[str] = []
    names: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            start = min([d.lineno for d in node.decorator_list] + [node.lineno])
            parts.append("\n".join(lines[start - 1:node.end_lineno]))
            names.append(node.name)
    if wanted not in names:
        raise PlanError(f"NameError: parse_function did not define '{wanted}' "
                        f"(defined: {names or 'nothing'})")
    return "\n\n".join(parts) + "\n\n"


def _sentence(text: object) -> str:
    s = " ".join(str(text).split())
    return s if s.endswith((".", "?", "!")) else s + "."


def _short_repr(value: Any, limit: int = 2000) -> str:
    try:
        text = repr(value)
    except Exception as exc:  # noqa: BLE001 - a broken __repr__ in LLM data must not crash logs
        text = f"<unrepresentable {type(value).__name__}: {exc}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."
