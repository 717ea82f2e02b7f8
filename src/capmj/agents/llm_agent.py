"""The LLM agent: closed loop plan -> execute -> report -> (reset + re-plan) over LMPs.

Per episode (``act``)::

    for attempt k = 1 .. attempts:
        if k > 1: ctx.reset()                      # back to the episode's initial state
        plan = planner LMP(objects, goal [, previous plan + failure report])
        run plan in the sandbox (API + parse_obj_name / parse_position / parse_function)
        verdict = reporter (none | text | vlm)
        stop unless the plan raised or the verdict is False

CapRavens re-ran the *old* plan before the new one after a failed verdict; capmj resets the scene
and runs only the new plan.  Every attempt is recorded (code, error, verdict, report) in
``ctx.notes["llm"]["attempts"]`` and under ``llm/attempt{k}/`` in the episode log, with LLM usage
(calls, cached calls, tokens, cost) in ``ctx.notes["llm"]``, which the runner copies into the
episode result.  The full transcript (every prompt, completion and executed code) is kept in
``ctx.notes["llm_transcript"]`` and :attr:`LLMAgent.transcript`.

Failures: bad code (no code, syntax error, sandbox violation, endless loop, huge allocation,
an exception) ends *that* attempt with a recorded error, and the next attempt re-plans with the
error as report.  A provider failure (``LLMError`` after the client's retries) ends the episode's
attempts.  The last attempt's error is re-raised so that the runner records it in the result.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from capmj.agents.api import PlannerAPI
from capmj.agents.attribution import attempt_facts
from capmj.agents.base import EpisodeContext
from capmj.agents.llm_meter import LLMMeter, check_limits, parse_price
from capmj.agents.lmp import LMPCall, LMPSession, find_llm_error
from capmj.agents.planner import DEFAULT_PLAN_BUDGET, Feedback, PlanOutcome, plan_and_run
from capmj.agents.reporter import REPORTERS, Report, make_reporter
from capmj.agents.sandbox import SandboxBudget
from capmj.errors import ConfigError, LLMError
from capmj.llm import LLMClient, LLMConfig

__all__ = ["CACHE_ENV", "DEFAULT_LMP_BUDGET", "LLMAgent"]

CACHE_ENV = "CAPMJ_LLM_CACHE"
"""Default cache folder for LLM completions when ``cache_dir`` is not given."""

DEFAULT_LMP_BUDGET = SandboxBudget(wall_s=30.0, max_api_calls=1000)
"""Budget of one helper LMP's code (parse_obj_name, parse_position, parse_completion)."""


class LLMAgent:
    """Plans with an LLM through the planner API; optional reporter and re-planning.

    ``model`` is any litellm model string (``gpt-4o-mini``, ``ollama/qwen2.5-coder``,
    ``openai/<alias>`` with ``api_base`` for OpenAI-compatible local servers).
    """

    name = "llm"

    def __init__(self, model: str = "gpt-4o-mini", api_base: str | None = None, reporter: str = "none",
                 attempts: int = 1, temperature: float = 0.0, timeout_s: float = 60.0,
                 cache_dir: str | Path | None = None, max_tokens: int = 2048, *, cache_only: bool = False,
                 api_key: str | None = None, max_retries: int = 3, backoff_s: float = 1.0,
                 plan_budget: SandboxBudget | None = None, lmp_budget: SandboxBudget | None = None,
                 max_fn_depth: int = 3, prompts_dir: str | Path | None = None,
                 episode_max_tokens: int | None = None, episode_max_cost_usd: float | None = None,
                 price: str | None = None) -> None:
        if reporter not in REPORTERS:
            raise ConfigError(f"unknown reporter {reporter!r}; valid reporters: {', '.join(REPORTERS)}")
        try:
            attempts = int(attempts)
        except (TypeError, ValueError):
            raise ConfigError(f"attempts must be an integer >= 1, got {attempts!r}") from None
        if attempts < 1:
            raise ConfigError(f"attempts must be >= 1, got {attempts}")
        if max_fn_depth < 0:
            raise ConfigError(f"max_fn_depth must be >= 0, got {max_fn_depth}")
        if cache_dir is None and os.environ.get(CACHE_ENV, "").strip():
            cache_dir = os.environ[CACHE_ENV].strip()
        self.config = LLMConfig(model=model, api_base=api_base, api_key=api_key, temperature=float(temperature),
                                max_tokens=int(max_tokens), timeout_s=float(timeout_s), max_retries=int(max_retries),
                                backoff_s=float(backoff_s), cache_dir=Path(cache_dir) if cache_dir else None,
                                cache_only=bool(cache_only))
        self.price = parse_price(price)
        tokens, cost = check_limits(model, max_tokens=episode_max_tokens, max_cost_usd=episode_max_cost_usd,
                                    price=self.price)
        self.limits = {"max_tokens": tokens, "max_cost_usd": cost}
        self.reporter = reporter
        self.attempts = attempts
        self.plan_budget = plan_budget or DEFAULT_PLAN_BUDGET
        self.lmp_budget = lmp_budget or DEFAULT_LMP_BUDGET
        self.max_fn_depth = int(max_fn_depth)
        self.prompts_dir = Path(prompts_dir) if prompts_dir is not None else None
        self.transcript: list[LMPCall] = []
        self.client: LLMClient | None = None

    @property
    def model(self) -> str:
        return self.config.model

    def _client(self) -> LLMClient:
        return LLMClient(self.config)

    # ------------------------------------------------------------------ the loop
    def act(self, ctx: EpisodeContext) -> None:
        client = self.client = self._client()
        meter = self.meter = LLMMeter(self.model, price=self.price, **self.limits)
        ctx.notes["llm_calls"] = meter.calls
        transcript: list[LMPCall] = []
        self.transcript = transcript
        attempts: list[dict[str, Any]] = []
        notes: dict[str, Any] = {"model": self.model, "reporter": self.reporter, "max_attempts": self.attempts,
                                 "attempts": attempts}
        ctx.notes["llm"] = notes
        ctx.notes["llm_transcript"] = transcript
        self._usage(client, notes)
        goal = ctx.scene.goal
        reporter = make_reporter(self.reporter, self.prompts_dir)
        feedback: Feedback | None = None
        last_error: BaseException | None = None
        try:
            if reporter is not None:
                reporter.start(ctx)
            for k in range(1, self.attempts + 1):
                if k > 1:
                    ctx.reset()
                meter.attempt = k
                record, error, report, outcome = self._attempt(ctx, client, transcript, k, goal, reporter, feedback)
                attempts.append(record)
                self._usage(client, notes)
                self._record_attempt(ctx, record)
                last_error = error
                if meter.exceeded is not None:
                    notes["stopped"] = "llm budget"
                    last_error = error or meter.exceeded
                    break
                if isinstance(error, LLMError):
                    notes["stopped"] = "llm error"
                    break
                failed = error is not None or (report is not None and report.verdict is False)
                if not failed:
                    notes["stopped"] = "reporter: achieved" if report is not None and report.verdict else (
                        "reporter: unknown" if report is not None else "plan finished")
                    break
                if k == self.attempts:
                    notes["stopped"] = "attempts used up"
                    break
                feedback = Feedback(completion=outcome.completion or "", report=record["report"])
        finally:
            if reporter is not None:
                reporter.close()
            self._usage(client, notes)
            notes["spend"] = meter.summary()
            ctx.notes["llm_transcript"] = [c.to_dict() for c in transcript]  # plain data for logs
        if last_error is not None:
            raise last_error

    def _attempt(self, ctx: EpisodeContext, client: LLMClient, transcript: list[LMPCall], k: int, goal: str,
                 reporter: Any, feedback: Feedback | None
                 ) -> tuple[dict[str, Any], BaseException | None, Report | None, PlanOutcome]:
        api = PlannerAPI(ctx)
        complete = self.meter.wrap(client.complete)  # logged, counted, stopped by the episode's LLM budget
        session = LMPSession(complete=complete, api=api.functions(), objects_text=api.objects_text,
                             attempt=k, recorder=ctx.recorder, transcript=transcript, directory=self.prompts_dir,
                             lmp_budget=self.lmp_budget, max_fn_depth=self.max_fn_depth)
        calls_before = len(client.records)
        record: dict[str, Any] = {"attempt": k, "reset": k > 1, "code": None, "error": None, "verdict": None,
                                  "report": "", "primitives": 0, "llm_calls": 0, "api_calls": 0}
        outcome = PlanOutcome()
        error: BaseException | None = None
        report: Report | None = None
        try:
            plan_and_run(session, goal, feedback=feedback, budget=self.plan_budget, outcome=outcome)
        except Exception as exc:  # noqa: BLE001 - every failure ends this attempt, recorded
            llm_error = find_llm_error(exc)
            error = llm_error if llm_error is not None else exc
        if error is None and reporter is not None:
            try:
                ctx.world.settle(max_steps=1000)
                report = reporter.judge(session, ctx, goal)
            except Exception as exc:  # noqa: BLE001
                llm_error = find_llm_error(exc)
                if llm_error is not None:
                    error = llm_error
                else:
                    report = Report(reporter.mode, None, "", f"reporter failed: {type(exc).__name__}: {exc}")
        record["code"] = outcome.code
        record["primitives"] = ctx.primitives
        record["llm_calls"] = len(client.records) - calls_before
        record["api_calls"] = len(api.call_log)
        record["said"] = list(api.messages)
        if error is not None:
            record["error"] = f"{type(error).__name__}: {error}"
            record["error_kind"] = "llm" if isinstance(error, LLMError) else "plan"
            record["report"] = self._error_report(error, ctx)
            record.update(attempt_facts(transcript, k, record["error"], api.call_log))
        if report is not None:
            record["verdict"] = report.verdict
            record["report"] = report.text() + "\n" + self._scene_summary(ctx)
            if report.error:
                record["reporter_error"] = report.error
            if "predicate" not in record:  # the task's judgement of the state the reporter judged
                try:
                    record["predicate"] = bool(ctx.task.evaluate(ctx.scene, ctx.world.state()).success)
                except Exception:  # noqa: BLE001 - a fact for attribution only
                    pass
        ctx.recorder.text(f"llm/attempt{k}/api_calls", api.log_text())
        return record, error, report, outcome

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _scene_summary(ctx: EpisodeContext) -> str:
        """Object positions after the attempt (for the re-plan prompt)."""
        try:
            positions = {o.name: [round(float(v), 3) for v in ctx.world.pose(o.obj_id).pos]
                         for o in ctx.world.objects}
        except Exception:  # noqa: BLE001 - a summary is optional
            return ""
        lines = [f"{name}: {pos}" for name, pos in positions.items()]
        return "object positions [x, y, z] after the plan:\n" + "\n".join(lines)

    def _error_report(self, error: BaseException, ctx: EpisodeContext) -> str:
        head = f"the plan failed with {type(error).__name__}: {error}"
        return head + "\n" + self._scene_summary(ctx)

    @staticmethod
    def _record_attempt(ctx: EpisodeContext, record: dict[str, Any]) -> None:
        k = record["attempt"]
        rec = ctx.recorder
        if record.get("error"):
            rec.text(f"llm/attempt{k}/error", record["error"])
        verdict = record.get("verdict")
        rec.text(f"llm/attempt{k}/verdict",
                 {True: "achieved", False: "not achieved", None: "unknown"}[verdict]
                 + (f" (error: {record['error']})" if record.get("error") else ""))
        if record.get("report"):
            rec.text(f"llm/attempt{k}/report", record["report"])

    @staticmethod
    def _usage(client: LLMClient, notes: dict[str, Any]) -> None:
        u = client.usage()
        notes.update(calls=u.calls, cached_calls=u.cached_calls, failed_calls=u.failed_calls,
                     prompt_tokens=u.prompt_tokens, completion_tokens=u.completion_tokens,
                     cost_usd=round(u.cost_usd, 8), latency_s=round(u.latency_s, 3))
