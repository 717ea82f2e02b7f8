"""Language model programs (LMPs): prompt file -> LLM -> code -> sandbox -> return value.

An LMP is a Python-styled prompt file in ``prompts/`` (see :mod:`capmj.agents.prompt_files`), a
system prompt (``prompts/system.txt``) and the name of the variable its code must set
(``ret_val`` for ``parse_obj_name`` / ``parse_position``, ``judge`` for ``parse_completion``; the
planner sets nothing, it acts).  One :class:`LMPSession` serves one attempt of one episode: it
owns the API environment, numbers and records every call, and synthesises functions that code
calls but nobody defined (``parse_function``), recursively up to ``max_fn_depth``.  Every
LLM-written program takes one step, :meth:`LMPSession.run_answer` (extract -> prepare -> run; its
first half :meth:`LMPSession.prepare_answer`): the helper LMPs, the planner and the reporters.  The static
code preparation it relies on (benign-import removal, undefined-call scan) is in
:mod:`capmj.agents.lmp.codeprep`.

Everything an LMP does goes to the recorder under ``llm/attempt{k}/{lmp}/{n}/`` (``prompt``,
``completion``, ``code``, ``result`` or ``error``) and to the in-memory :attr:`LMPSession.transcript`.

"""

from __future__ import annotations

import ast
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from capmj.agents.lmp.codeprep import RESERVED, bound_names, function_defs, strip_benign_imports, undefined_calls
from capmj.agents.prompt_files import PromptFile, load_prompt, load_system_prompt, object_names, prompts_dir
from capmj.agents.sandbox import SandboxBudget, extract_code, run_code
from capmj.agents.sandbox.located import WRITTEN_END, WRITTEN_START, located_error
from capmj.agents.sandbox.sizes import preview, text_length
from capmj.errors import (FunctionNotWritten, HelperCallsExceeded, LLMError, PlanError, ReturnNotSet,
                          TextBudgetExceeded, describe, inner_text)
from capmj.record import NullRecorder, Recorder

__all__ = ["ACTION_FUNCTIONS", "DEFAULT_EPISODE_MAX_HELPER_CALLS", "Draft", "HelperCallCap", "LMPCall", "LMPSession",
           "find_llm_error", "messages_text"]

ACTION_FUNCTIONS = frozenset({"put_first_on_second", "stack_objects_in_order", "reset"})
"""API functions that change the scene (the robot moves, or ``reset`` restores the initial scene):
only the planner's code may call them, never a helper LMP."""


DEFAULT_EPISODE_MAX_HELPER_CALLS = 200
"""Helper LMP calls one episode's code may make, all attempts together (``episode_max_helper_calls``).

Why a default cap: a plan loop calling a helper whose code loops calling helpers multiplies, and
without a cap one episode asked the LLM 250 000 times.  CapRavens-style plans call a helper a few
times per attempt (helpers calling one more at most), so this is far above any plan that works."""


@dataclass
class HelperCallCap:
    """Counts the helper LMP calls of one episode and refuses every call past ``limit`` (None: no
    cap) with :class:`~capmj.errors.HelperCallsExceeded`, before the LLM is asked.

    Counted: ``parse_obj_name``, ``parse_position``, ``parse_question`` (from the plan or from a
    helper's code), ``parse_function`` and a plan's ``parse_completion``; the planner's own
    requests and the reporter's verdict after a plan are not.  Once refused, ``exceeded`` holds the
    error and every later call is refused too; the agent ends the episode as over its LLM budget."""

    limit: int | None = DEFAULT_EPISODE_MAX_HELPER_CALLS
    used: int = 0
    exceeded: HelperCallsExceeded | None = None

    def take(self, lmp: str) -> None:
        """Count one call of ``lmp``; raises HelperCallsExceeded past the limit."""
        if self.exceeded is not None:
            raise HelperCallsExceeded(str(self.exceeded))
        self.used += 1
        if self.limit is not None and self.used > self.limit:
            self.exceeded = HelperCallsExceeded(
                f"helper LMP call budget of {self.limit} calls per episode exceeded by a call of {lmp} "
                "(episode_max_helper_calls)")
            raise HelperCallsExceeded(str(self.exceeded))


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
class Draft:
    """An answer's code on its way to the sandbox, as far as it got: None (none found yet), the
    extracted code, then the prepared code (what an error's line number refers to)."""

    code: str | None = None


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
    partial: str | None = None
    cut: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass
class LMPSession:
    """LMP calls of one attempt: LLM client + API env + recorder + transcript.

    ``api`` maps API function names to callables (``PlannerAPI(ctx).functions()``);
    ``objects_text`` returns the current ``"objects = [...]"`` line.  ``complete(messages,
    purpose)`` is the LLM (``LLMClient.complete``).  ``rng`` feeds ``np.random`` in all code of
    the attempt (the agent passes one derived from the episode seed and the attempt).
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
    max_helper_depth: int = 2
    """How deep helper LMPs nest: the plan's parse_obj_name / parse_position (depth 1) may call
    them again (depth 2), as CapRavens' helper examples do (parse_position asks parse_obj_name for
    the objects it measures); deeper code gets an error naming the limit, so two helpers asking
    each other cannot loop."""
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    helper_cap: HelperCallCap = field(default_factory=HelperCallCap)
    """The episode's count of helper LMP calls (the agent shares one across its attempts)."""
    check: Callable[..., Any] | None = None
    """The plan's ``parse_completion(goal, context=None)``: the text reporter over the current scene
    (:func:`capmj.agents.report.text.plan_check`), bound by the agent that has one; None, plan code
    cannot call it."""
    _counters: dict[str, int] = field(default_factory=dict)
    _system: str | None = None
    _helper_depth: int = 0

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

    def stop_for(self, lmp: str) -> tuple[str, ...]:
        """The stop sequences of the LMP's prompt file (``#@ stop:``); none for a text prompt."""
        folder = Path(self.directory) if self.directory is not None else prompts_dir()
        return self.prompt(lmp).stop if (folder / f"{lmp}.py").is_file() else ()

    def ask(self, call: LMPCall, messages: list[dict[str, Any]], **sampling: Any) -> str:
        """Send ``messages`` (recording prompt and completion); LLMError propagates, and the text
        a stalled stream had delivered is recorded as ``partial``.  ``sampling`` (``temperature``,
        ``seed``) overrides the client's for this call; the LMP's stop sequences always apply."""
        self.record(call, "prompt", messages_text(messages))
        stop = self.stop_for(call.lmp)
        try:
            completion = self.complete(messages, purpose=f"{call.lmp}#{call.n}", **sampling,
                                       **({"stop": stop} if stop else {}))
        except LLMError as exc:
            self.record(call, "error", describe(exc))
            if exc.partial:
                self.record(call, "partial", exc.partial)
            raise
        call.cached = bool(getattr(completion, "cached", False))
        self.record(call, "completion", completion.text)
        if getattr(completion, "cut", None):
            self.record(call, "cut", completion.cut)
        return completion.text

    def messages(self, user: str) -> list[dict[str, Any]]:
        return [{"role": "system", "content": self.system_prompt}, {"role": "user", "content": user}]

    def helper_env(self, question: str | None = None) -> dict[str, Any]:
        """What helper LMP code may use: the read-only API (nothing that moves the robot), the
        helper LMPs themselves while the nesting is below :attr:`max_helper_depth`, and
        ``objects`` from the question's ``objects = [...]`` line when there is one."""
        env: dict[str, Any] = {k: v for k, v in self.api.items() if k not in ACTION_FUNCTIONS}
        if self._helper_depth < self.max_helper_depth:
            env["parse_obj_name"] = self.parse_obj_name
            env["parse_position"] = self.parse_position
            env["parse_question"] = self.parse_question
        if question is not None:
            names = object_names(question)
            if names is not None:
                env["objects"] = names
        return env

    def plan_env(self) -> dict[str, Any]:
        """What plan code may use: the whole API plus the helper LMPs (parse_obj_name,
        parse_position, parse_question) and, when the session has a :attr:`check`, the reporter's
        ``parse_completion`` (CapRavens' plans check themselves and retry)."""
        env: dict[str, Any] = dict(self.api)
        env["parse_obj_name"] = self.parse_obj_name
        env["parse_position"] = self.parse_position
        env["parse_question"] = self.parse_question
        if self.check is not None:
            env["parse_completion"] = self.check
        return env

    # -- code preparation --------------------------------------------------------------------
    def reserved(self) -> dict[str, str]:
        """Names never synthesised: :data:`RESERVED` plus every API function."""
        why = {n: "it is a read-only API function" for n in self.api}
        return {**why, **RESERVED}

    def refuse_reserved(self, missing: list[tuple[str, int, str]], env: Mapping[str, Any],
                        code: str, program: str) -> None:
        """PlanError for the first call of a reserved name that ``env`` does not provide."""
        reserved = self.reserved()
        for name, line, _site in missing:
            if name in reserved:
                have = sorted(n for n, v in env.items() if callable(v))
                raise located_error(
                    PlanError, f"NameError: {name}() cannot be called in {program}: "
                    f"{reserved[name]}. Functions available here: {', '.join(have)}",
                    line=line, code=code, program=program)

    def prepare(self, code: str, env: Mapping[str, Any], *, depth: int = 0,
                parent: LMPCall | None = None, program: str = "the code") -> str:
        """Drop benign imports, then prepend functions synthesised for undefined calls."""
        code, removed = strip_benign_imports(code, set(env))
        if removed and parent is not None:
            self.recorder.text(f"llm/attempt{self.attempt}/{parent.lmp}/{parent.n}/removed_imports",
                               "\n".join(removed))
        missing = undefined_calls(code, set(env))
        if not missing:
            return code
        self.refuse_reserved(missing, env, code, program)
        functions = self.synthesize(missing, set(env) | bound_names(ast.parse(code)), depth=depth,
                                    env=env, code=code, program=program)
        return f"{WRITTEN_START}\n{functions}{WRITTEN_END}\n{code}"

    def prepare_answer(self, call: LMPCall, text: str, env: Mapping[str, Any], *, program: str = "the code",
                       vet: Callable[[str], None] | None = None, draft: Draft | None = None) -> str:
        """The first half of the step every LLM-written program takes: the code of answer ``text``
        (:func:`~capmj.agents.sandbox.extract_code`), ``vet``-ted (it may raise), :meth:`prepare`-d for
        the names of ``env`` and recorded as the call's ``code``.  PlanError propagates; ``draft``
        holds the code as far as it got."""
        draft = draft if draft is not None else Draft()
        draft.code = extract_code(text)
        if vet is not None:
            vet(draft.code)
        draft.code = self.prepare(draft.code, env, parent=call, program=program)
        self.record(call, "code", draft.code)
        return draft.code

    def run_answer(self, call: LMPCall, text: str, env: dict[str, Any], *, filename: str, program: str | None = None,
                   budget: SandboxBudget | None = None, rng: np.random.Generator | None = None,
                   output: list[str] | None = None, draft: Draft | None = None) -> dict[str, Any]:
        """Extract -> prepare -> run: the code of answer ``text`` (:meth:`prepare_answer`) run in the
        sandbox with ``env`` (``budget``: the LMP budget unless given); the code's final namespace.
        ``program`` names the code in errors (unnamed: "the code" in preparation, none in the run).
        PlanError propagates, unrecorded (each caller says it its way); ``draft`` holds the code as
        far as it got."""
        draft = draft if draft is not None else Draft()
        code = self.prepare_answer(call, text, env, program=program or "the code", draft=draft)
        return run_code(code, env, budget=budget if budget is not None else self.lmp_budget, filename=filename,
                        output=output, program=program, rng=rng)

    def synthesize(self, missing: list[tuple[str, int, str]], known: set[str], *, depth: int,
                   env: Mapping[str, Any] | None = None, code: str = "",
                   program: str = "the code") -> str:
        """Source of the functions ``missing`` needs (and of helpers they call), depth-bounded."""
        env = env if env is not None else {}
        if depth >= self.max_fn_depth:
            names = ", ".join(m[0] for m in missing)
            raise FunctionNotWritten(f"function synthesis depth {self.max_fn_depth} reached; undefined: {names}")
        out: list[str] = []
        known = set(known)
        for name, line, site in missing:
            if name in known:
                continue
            try:
                source = self.parse_function(name, site)
            except PlanError as exc:
                raise located_error(PlanError, f"parse_function could not write {name}(): {inner_text(exc)}",
                                    line=line, code=code, program=program) from exc
            known.add(name)
            inner = undefined_calls(source, known)
            if inner:
                where = f"the function {name}() written by parse_function"
                self.refuse_reserved(inner, env, source, where)
                helper_src = self.synthesize(inner, known, depth=depth + 1, env=env, code=source,
                                             program=where)
                known |= bound_names(ast.parse(helper_src))
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
            return self.run_answer(call, text, self.helper_env(question), filename=f"<{lmp} {self.attempt}.{call.n}>",
                                   program=f"the code {lmp} wrote", rng=self.rng)
        except PlanError as exc:
            self.record(call, "error", describe(exc))
            raise

    def run_lmp(self, lmp: str, question: str, return_var: str, *, query: str | None = None) -> Any:
        """Generic helper LMP: the value of ``return_var`` after running the LMP's code.

        Counted by :attr:`helper_cap`.  A value whose text would pass the helper budget's
        ``max_text_chars`` is refused (:class:`~capmj.errors.TextBudgetExceeded`, raised to the
        caller, recorded as the call's result): the caller's record and log would hold that text."""
        self.helper_cap.take(lmp)
        call = self.next_call(lmp, query if query is not None else question)
        self._helper_depth += 1
        try:
            ns = self._ask_and_run(call, lmp, question)
        finally:
            self._helper_depth -= 1
        if return_var not in ns:
            exc = ReturnNotSet(f"{lmp} code did not set '{return_var}'")
            self.record(call, "error", describe(exc))
            raise exc
        value = ns[return_var]
        cap = self.lmp_budget.max_text_chars
        if text_length(value, cap, as_repr=True) is None:
            refused = TextBudgetExceeded(f"the value {lmp} returned would be more than {cap} characters of text "
                                         "(max_text_chars of the helper budget)")
            self.record(call, "result", f"refused: {preview(value, 200)}")
            raise refused
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

    def parse_question(self, description: str, context: str | None = None) -> Any:
        """The answer to a question about the scene (``ret_val``): a bool, a number or names.
        CapRavens' planner asks it ("is the blue block left of the bowl?", "how many ...")."""
        ctx = context if isinstance(context, str) and context.strip() else self.objects_text()
        question = f"{ctx.strip()}\n# {_sentence(description)}"
        return self.run_lmp("parse_question", question, "ret_val", query=str(description))

    def parse_function(self, name: str, site: str) -> str:
        """Source of ``def name(...)`` written for the call statement ``site``."""
        site = " ".join(site.split())
        question = f"# define function: {site if site.endswith('.') else site + '.'}"
        self.helper_cap.take("parse_function")
        call = self.next_call("parse_function", name)
        text = self.ask(call, self.messages(self.prompt("parse_function").render(question)))
        try:
            code = extract_code(text)
            source = function_defs(code, name, skip=set(self.reserved()))
        except PlanError as exc:
            self.record(call, "error", describe(exc))
            raise
        self.record(call, "code", source)
        return source


def _sentence(text: object) -> str:
    s = " ".join(str(text).split())
    return s if s.endswith((".", "?", "!")) else s + "."


def _short_repr(value: Any, limit: int = 2000) -> str:
    """``repr(value)`` cut to ``limit`` characters, made without ever making more (never raises)."""
    return preview(value, limit)
