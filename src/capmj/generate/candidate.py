"""One candidate task from proposal to verdict: the conversation and the checks, in order.

Stages (the record's ``stage`` is the last one reached; ``accepted`` only after all of them):

1. ``propose``: bottom-up, the LLM proposes ``{name, goal, objects, why}``; top-down, the user's
   name and description are the proposal.
2. ``examples``: the LLM picks the 2 installed tasks most like the proposal.
3. ``write``: it receives their source and writes the module (the task API is in the system
   message, :func:`system_prompt`).
4. ``static``: parse, import allow-list, forbidden names (AST only, nothing runs), then with the
   code in the jail: load and the registry's validation (``load``, ``protocol``).  One repair
   round on failure, with the error or traceback.
5. ``runtime``: the remaining checker checks, computed here from the jailed task's answers.
6. ``reflection``: the LLM votes on the task against the acceptance criteria.  The vote is
   recorded; an ``accept`` vote never accepts a task by itself (the checks must pass first), a
   ``reject`` vote (duplicate, not feasible, not interesting) rejects it.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from capmj.errors import CapmjError
from capmj.generate import prompts
from capmj.generate.config import GENERATED_TAG, NAME_RE, GenerateConfig
from capmj.generate.conversation import Conversation
from capmj.confine.proxy import ModuleSource
from capmj.generate.isolate import run_isolated
from capmj.generate.library import LibraryTask, api_reference, similar
from capmj.confine.allowlist import allowed_imports_text
from capmj.generate.static import extract_code, extract_json, static_checks
from capmj.llm import LLMClient
from capmj.sim.objects import BLOCK_SIZES, KINDS
from capmj.sim.palette import COOL, WARM
from capmj.taskcheck import CheckResult
from capmj.tasks.spawn import DEFAULT_COLORS

STATIC_IN_WORKER = ("load", "protocol")


@dataclass
class CandidateRecord:
    """Everything ``generation.jsonl`` says about one candidate (one line)."""

    index: int
    mode: str
    stage: str = "propose"
    accepted: bool = False
    reason: str = ""
    name: str | None = None
    proposal: dict[str, Any] = field(default_factory=dict)
    examples: list[str] = field(default_factory=list)
    checks: list[dict[str, Any]] = field(default_factory=list)
    repaired: bool = False
    oracle_rate: float | None = None
    reflection: dict[str, Any] | None = None
    usage: dict[str, Any] = field(default_factory=dict)
    wall_s: dict[str, float] = field(default_factory=dict)
    code_path: str | None = None
    conversation: str | None = None
    goals: list[str] = field(default_factory=list)
    confinement: dict[str, Any] = field(default_factory=dict)
    """How the accepted attempt was confined: the static check, the guard, the jail, the sha256."""
    facts: dict[str, Any] | None = None
    """What the accepted task stated in the jail (name, tags, docstring, methods): the manifest's copy."""
    text: str | None = field(default=None, repr=False)
    """The exact text the accepted attempt's checks were run on; the package is built from it."""

    def to_dict(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "text"}

    def check(self, stage: str, attempt: int, r: CheckResult) -> None:
        self.checks.append({"stage": stage, "attempt": attempt, **r.to_dict()})


@dataclass(frozen=True)
class Context:
    """What every candidate of a run shares."""

    cfg: GenerateConfig
    client: LLMClient
    library: tuple[LibraryTask, ...]
    workdir: Path


def _library_lines(lib: tuple[LibraryTask, ...]) -> str:
    return "\n".join(f'- {t.name}: {t.summary} (e.g. "{t.goal}")' for t in lib) or "(none installed)"


def system_prompt(library: tuple[LibraryTask, ...]) -> str:
    """The first message of every candidate: the role, the whole task API and the installed library.

    Why everything static goes first: it is the same for every candidate and turn of a run, so a
    server's prefix cache (llama.cpp's slots, OpenAI's prompt caching) reads it once per run; a
    2-core server reading ~20 tokens/s would otherwise spend minutes per candidate re-reading the
    ~5k-token reference.  Each turn then adds only what is new: the proposal, the picked sources,
    a check's error.
    """
    task_api = prompts.render("task_api.txt", allowed_imports=allowed_imports_text(), api=api_reference())
    return prompts.render("system.txt", task_api=task_api, library=_library_lines(library))


def _proposal_lines(items: list[dict[str, Any]]) -> str:
    return "\n".join(f"- {json.dumps(i)}" for i in items) or "(none)"


def _propose(ctx: Context, conv: Conversation, rec: CandidateRecord) -> dict[str, Any]:
    cfg = ctx.cfg
    if cfg.mode == "top-down":
        # the candidate number makes the N conversations differ (else the cache answers all alike)
        return {"name": cfg.name, "goal": cfg.description, "objects": [],
                "why": f"requested by the user (candidate {rec.index + 1} of {cfg.n})"}
    ex = prompts.proposal_examples()
    text = prompts.render(
        "propose.txt", index=rec.index + 1, count=cfg.n, kinds=", ".join(KINDS), sizes=", ".join(BLOCK_SIZES),
        colors=", ".join(DEFAULT_COLORS), warm=", ".join(c for c in DEFAULT_COLORS if c in WARM),
        cool=", ".join(c for c in DEFAULT_COLORS if c in COOL),
        accepted=_proposal_lines(ex["accepted"]), rejected=_proposal_lines(ex["rejected"]))
    problem = ""
    for purpose in ("generate.propose", "generate.propose_repair"):
        answer = conv.ask(text, purpose)
        try:
            prop = extract_json(answer)
        except ValueError as e:
            problem = f"{type(e).__name__}: {e}"
        else:
            if isinstance(prop, dict) and all(isinstance(prop.get(k), str) and prop[k] for k in ("name", "goal")):
                return prop
            problem = f"the proposal must be a JSON object with 'name' and 'goal', got {str(prop)[:200]}"
        text = prompts.render("propose_repair.txt", problem=problem)
    raise ValueError(f"no usable proposal after the repair round: {problem}")


EXAMPLES = 2
"""Installed tasks whose source the writing turn shows: two teach the structure; a third cost a
small local model ~1 000 more prompt tokens (a minute of reading) for little."""


def _pick_examples(ctx: Context, conv: Conversation, prop: dict[str, Any]) -> list[str]:
    """Ask which installed tasks (listed in the system message) are most like the proposal."""
    text = prompts.render("pick.txt", name=prop["name"], goal=prop["goal"], objects=json.dumps(prop.get("objects", [])),
                          why=prop.get("why", ""))
    answer = conv.ask(text, "generate.pick_examples")
    known = {t.name for t in ctx.library if t.example}
    try:
        picked = [n for n in extract_json(answer) if isinstance(n, str) and n in known]
    except (ValueError, TypeError):
        picked = []
    picked = list(dict.fromkeys(picked))[:EXAMPLES]
    if len(picked) < EXAMPLES:  # unusable picks: fill deterministically by word overlap
        picked += [n for n in similar(prop["name"], prop["goal"], ctx.library) if n not in picked][: EXAMPLES - len(picked)]
    return picked


def _write(ctx: Context, conv: Conversation, prop: dict[str, Any], examples: list[str]) -> str:
    by = {t.name: t for t in ctx.library}
    sources = "\n\n".join(f"# ===== {n} =====\n{by[n].example}" for n in examples)
    text = prompts.render("examples.txt", sources=sources, name=prop["name"], goal=prop["goal"])
    return extract_code(conv.ask(text, "generate.write"))


def _failure(results: list[CheckResult]) -> CheckResult | None:
    return next((r for r in results if r.outcome in ("fail", "error")), None)


def _checked(ctx: Context, conv: Conversation, rec: CandidateRecord, code: str) -> int | None:
    """Static then runtime checks, with one repair round on a static failure.

    Returns the attempt whose checks all passed, or None (``rec.reason`` says why).
    """
    cfg, name = ctx.cfg, rec.proposal["name"]
    path = ctx.workdir / "candidates" / f"{rec.index:03d}-{name}.py"
    path.parent.mkdir(parents=True, exist_ok=True)
    rec.code_path = str(path.relative_to(cfg.out))
    for attempt in (1, 2):
        rec.stage = "static"
        path.write_text(code, encoding="utf-8")
        static = list(static_checks(code))
        for r in static:
            rec.check("static", attempt, r)
        bad, run = _failure(static), None
        source = ModuleSource(cfg.module_of(name), code)  # what runs, what is hashed, what is packaged
        if bad is None:  # only now does the code run: in the jail
            run = run_isolated(source, name=name, seeds=tuple(range(cfg.seeds)), accept_rate=cfg.accept_rate,
                               tags=(GENERATED_TAG,), limits=cfg.limits)
            rec.wall_s["checks"] = rec.wall_s.get("checks", 0.0) + run.wall_s
            for r in run.results:
                rec.check("static" if r.name in STATIC_IN_WORKER else "runtime", attempt, r)
            if run.violation is not None:  # reached for the OS: hostile or careless, no second try
                rec.stage = "static" if run.violation.get("check") in STATIC_IN_WORKER else "runtime"
                rec.reason = f"{run.ended} (during {run.violation.get('check')})"
                return None
            bad = _failure([r for r in run.results if r.name in STATIC_IN_WORKER])
        if bad is not None:
            if attempt == 2:
                rec.reason = f"static check {bad.name} failed after the repair round: {bad.detail}"
                return None
            error = bad.detail + (f"\n{bad.data['traceback']}" if bad.data.get("traceback") else "")
            code = extract_code(conv.ask(prompts.render("repair.txt", check=bad.name, error=error), "generate.repair"))
            rec.repaired = True
            continue
        assert run is not None
        rec.stage = "runtime"
        by = {r.name: r for r in run.results}
        if "rate" in by["oracle_solves"].data:
            rec.oracle_rate = float(by["oracle_solves"].data["rate"])
        rec.goals = list(by["scenes"].data.get("goals", []))
        bad = _failure(list(run.results))
        if bad is not None:
            rec.reason = f"runtime check {bad.name}: {bad.detail}"
            return None
        rec.confinement = {"static": [r.name for r in static], "guard": "audit hook, no event refused",
                           "jail": run.jail, "sha256": source.sha256}
        rec.facts, rec.text = run.facts, source.text
        return attempt
    return None  # pragma: no cover - the loop always returns


def _reflect(ctx: Context, conv: Conversation, rec: CandidateRecord, attempt: int) -> None:
    """Ask for the vote and record it; a ``reject`` vote rejects, anything else leaves the checks' verdict."""
    rec.stage = "reflection"
    lines = "\n".join(f"- {c['name']}: {c['detail']}" for c in rec.checks if c["outcome"] == "pass" and c["attempt"] == attempt)
    answer = conv.ask(prompts.render("reflect.txt", name=rec.name, checks=lines), "generate.reflect")
    try:
        vote = extract_json(answer)
        rec.reflection = {"vote": str(vote.get("vote", "")).lower(), "reason": str(vote.get("reason", ""))}
    except (ValueError, AttributeError):
        rec.reflection = {"vote": "unreadable", "reason": answer[:300]}
    if rec.reflection["vote"] == "reject":
        rec.reason = f"reflection voted reject: {rec.reflection['reason']}"
        return
    rec.stage, rec.accepted = "accepted", True
    rec.reason = f"all checks passed (oracle rate {rec.oracle_rate:.2f}); reflection: {rec.reflection['vote']}"


def run_candidate(ctx: Context, index: int) -> CandidateRecord:
    """Take candidate ``index`` through every stage; never raises for the candidate's own faults."""
    rec = CandidateRecord(index, ctx.cfg.mode)
    conv = Conversation(ctx.client, system_prompt(ctx.library))
    t0 = time.perf_counter()
    try:
        prop = _propose(ctx, conv, rec)
        rec.proposal, rec.name = prop, prop["name"]
        if not NAME_RE.match(prop["name"]):
            raise ValueError(f"proposed name {prop['name']!r} is not kebab-case")
        if prop["name"] in {t.name for t in ctx.library}:
            raise ValueError(f"a task named {prop['name']!r} is already installed")
        rec.stage = "examples"
        rec.examples = _pick_examples(ctx, conv, prop)
        rec.stage = "write"
        code = _write(ctx, conv, prop, rec.examples)
        attempt = _checked(ctx, conv, rec, code)
        if attempt is not None:
            _reflect(ctx, conv, rec, attempt)
    except (ValueError, CapmjError) as e:  # LLM failures, unusable answers
        rec.reason = f"{rec.stage}: {type(e).__name__}: {e}"[:800]
    except Exception as e:  # noqa: BLE001 - a candidate must never end the run (and its journal)
        rec.reason = f"{rec.stage}: capmj failed on this candidate: {type(e).__name__}: {e}"[:800]
    finally:
        rec.usage = conv.usage
        rec.wall_s = {"checks": round(rec.wall_s.get("checks", 0.0), 3), "total": round(time.perf_counter() - t0, 3)}
        safe = rec.name if isinstance(rec.name, str) and NAME_RE.match(rec.name) else "unnamed"
        log = ctx.workdir / "conversations" / f"{index:03d}-{safe}.json"
        conv.save(log)
        rec.conversation = str(log.relative_to(ctx.cfg.out))
    return rec


__all__ = ["CandidateRecord", "Context", "run_candidate", "system_prompt"]
