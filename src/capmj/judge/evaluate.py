"""Run a reporter over labelled cases: one plain record per judged state.

The reporter is the closed loop's own (:mod:`capmj.agents.report`), called exactly as
:class:`~capmj.agents.llm_agent.LLMAgent` calls it after a plan: an :class:`EpisodeContext` over
the episode's world, a fresh :class:`LMPSession` with the planner API and the LMP budget, the
scene settled.  Only the state differs: instead of wherever a plan ended, the case's layout is
placed and settled (after a VLM reporter has taken its "before" image of the initial scene).

``predicate`` is a reporter that answers with the task predicate itself: no LLM, every answer
right by construction.  It checks the pipeline (a case whose realised state no longer has its
label would show up as a wrong answer) and is the ceiling of the metrics.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.llm_agent.options import DEFAULT_LMP_BUDGET
from capmj.agents.lmp.meter import LLMMeter, parse_price
from capmj.agents.lmp.session import LMPSession, find_llm_error
from capmj.agents.report.confidence import assess
from capmj.agents.choices import REPORTER_PROMPTS, REPORTER_TABLE
from capmj.agents.report.registry import Reporter, make_reporter
from capmj.errors import ConfigError
from capmj.judge.cases import JudgeCase, Stage
from capmj.llm import LLMClient, LLMConfig
from capmj.llm.config import DEFAULT_TIMEOUT_S
from capmj.record import NullRecorder, Recorder
from capmj.tasks.protocol import episode_rng

__all__ = ["JUDGE_REPORTERS", "LLM_REPORTERS", "JudgeConfig", "Judge"]

LLM_REPORTERS: tuple[str, ...] = tuple(name for name, prompts in REPORTER_TABLE.items() if prompts)
"""The closed loop's LLM reporters: every ``--reporter`` of :data:`capmj.agents.choices.REPORTER_TABLE`
that has one (``none`` has none)."""

JUDGE_REPORTERS: tuple[str, ...] = (*LLM_REPORTERS, "predicate")
"""Reporters ``judge`` evaluates: the loop's LLM reporters and the predicate (a reference)."""


@dataclass(frozen=True)
class JudgeConfig:
    """What judges the cases: the reporter, its model and the client settings, per-case budgets."""

    reporter: str = "text"
    model: str | None = None
    api_base: str | None = None
    temperature: float = 0.0
    timeout_s: float = DEFAULT_TIMEOUT_S
    max_tokens: int = 2048
    cache_dir: str | None = None
    cache_only: bool = False
    case_max_tokens: int | None = None
    """LLM tokens per judged state (the bench's --episode-max-tokens): over it, the verdict is unknown."""
    case_max_cost_usd: float | None = None
    price: str | None = None
    prompts_dir: str | None = None
    reporter_prompt: str = "thesis"
    """The text reporter's prompt (:data:`capmj.agents.choices.REPORTER_PROMPTS`), as the bench's
    ``--reporter-prompt``."""

    def __post_init__(self) -> None:
        if self.reporter not in JUDGE_REPORTERS:
            raise ConfigError(f"unknown reporter {self.reporter!r}; valid reporters: {', '.join(JUDGE_REPORTERS)}")
        if self.reporter_prompt not in REPORTER_PROMPTS:
            raise ConfigError(f"unknown reporter prompt {self.reporter_prompt!r}; valid prompts: "
                              f"{', '.join(REPORTER_PROMPTS)}")
        if self.reporter_prompt != "thesis" and self.reporter != "text":
            raise ConfigError(f"--reporter-prompt {self.reporter_prompt} needs --reporter text")
        if self.reporter != "predicate" and not self.model:
            raise ConfigError(f"--reporter {self.reporter} needs --model (any litellm model string, e.g. "
                              "gpt-4o-mini or openai/<local alias> with --api-base)")

    @property
    def label(self) -> str:
        """``text openai/<model>``, ``text/checked openai/<model>``, ``predicate``: the name of
        this reporter in reports (the thesis prompt adds nothing, as before prompts were selectable)."""
        if self.reporter == "predicate":
            return self.reporter
        prompt = "" if self.reporter_prompt == "thesis" else f"/{self.reporter_prompt}"
        return f"{self.reporter}{prompt} {self.model}"


class Judge:
    """Judges cases one at a time; keeps the world of the last (task, seed) for the next case."""

    def __init__(self, config: JudgeConfig, log_dir: Path | None = None) -> None:
        self.config = config
        self.log_dir = log_dir
        """Write ``<log_dir>/<task>/<seed>-<case>.rrd`` per judged state (the state, the reporter's
        transcript, the label) when set."""
        self.client: LLMClient | None = None
        if config.reporter != "predicate":
            assert config.model is not None  # checked by JudgeConfig
            self.client = LLMClient(LLMConfig(
                model=config.model, api_base=config.api_base, temperature=float(config.temperature),
                max_tokens=int(config.max_tokens), timeout_s=float(config.timeout_s),
                cache_dir=Path(config.cache_dir) if config.cache_dir else None, cache_only=bool(config.cache_only)))
        self.price = parse_price(config.price)
        self._stage: Stage | None = None

    def _stage_for(self, case: JudgeCase) -> Stage:
        from capmj.tasks.registry import get_task

        st = self._stage
        if st is None or st.seed != case.seed or getattr(st.task, "name", None) != case.task:
            st = self._stage = Stage(get_task(case.task), case.seed)
        return st

    def judge(self, case: JudgeCase) -> tuple[dict[str, Any], list[dict[str, Any]]]:
        """``(record, transcript)`` of one case; the record's keys are :data:`capmj.judge.metrics.RECORD_FIELDS`."""
        t0 = time.perf_counter()
        stage = self._stage_for(case)
        stage.restart()
        rec = self._recorder(case, stage)
        ctx = stage.context(recorder=rec)
        reporter = make_reporter(self.config.reporter, self.config.prompts_dir, self.config.reporter_prompt) \
            if self.config.reporter != "predicate" else None
        out: dict[str, Any] = {
            "task": case.task, "seed": case.seed, "case": case.case, "kind": case.kind, "label": case.label,
            "reporter": self.config.label, "reporter_prompt": self.config.reporter_prompt, "verdict": None, "source": "unknown", "reason": "", "wrong": [],
            "errors": [], "confidence": None, "low_confidence": None, "predicate": None, "correct": False, "calls": 0, "cached_calls": 0,
            "prompt_tokens": 0, "completion_tokens": 0, "cost_usd": 0.0, "wall_s": 0.0, "error": None}
        transcript: list[Any] = []
        try:
            if reporter is not None:
                reporter.start(ctx)  # the "before" image: the initial scene
            state = stage.place(case.poses())
            _frame(rec, stage)
            out["predicate"] = bool(stage.evaluate(state).success)
            if reporter is None:
                out.update(verdict=out["predicate"], source="predicate", reason="the task predicate")
            else:
                self._ask(ctx, reporter, case, out, transcript)
        except Exception as exc:  # noqa: BLE001 - one broken case is recorded, the run goes on
            out["error"] = f"{type(exc).__name__}: {exc}"
        finally:
            if reporter is not None:
                reporter.close()
        out["correct"] = out["verdict"] is not None and out["verdict"] == case.label
        out["wall_s"] = round(time.perf_counter() - t0, 3)
        if not isinstance(rec, NullRecorder):
            _finish_log(rec, stage, case, out)
        return out, [c.to_dict() if hasattr(c, "to_dict") else c for c in transcript]

    def _recorder(self, case: JudgeCase, stage: Stage) -> Recorder:
        if self.log_dir is None:
            return NullRecorder()
        from capmj.log.recorder import RerunRecorder

        rec = RerunRecorder(self.log_dir / case.task / f"{case.seed}-{case.case}.rrd", task=case.task,
                            seed=case.seed, agent=f"judge {self.config.reporter}", model=self.config.model)
        rec.attach(stage.world)
        rec.text("goal", stage.scene.goal)
        _frame(rec, stage)
        return rec

    def _ask(self, ctx: EpisodeContext, reporter: Reporter, case: JudgeCase, rec: dict[str, Any],
             transcript: list[Any]) -> None:
        assert self.client is not None
        client = self.client
        meter = LLMMeter(client.config.model, price=self.price, max_tokens=self.config.case_max_tokens,
                         max_cost_usd=self.config.case_max_cost_usd)
        api = PlannerAPI(ctx)
        session = LMPSession(complete=meter.wrap(client.complete), api=api.functions(), objects_text=api.objects_text,
                             attempt=1, recorder=ctx.recorder, transcript=transcript,
                             directory=Path(self.config.prompts_dir) if self.config.prompts_dir else None,
                             lmp_budget=DEFAULT_LMP_BUDGET, rng=episode_rng(case.seed, "code1"))
        before = len(client.records)
        try:
            report = reporter.judge(session, ctx, ctx.scene.goal)
        except Exception as exc:  # noqa: BLE001 - provider failure or budget: the verdict stays unknown
            llm = find_llm_error(exc)
            rec["error"] = f"{type(llm or exc).__name__}: {llm or exc}"
        else:
            checked = assess(report, ctx.world.objects)
            rec.update(verdict=report.verdict, source=report.source, reason=report.reason, wrong=list(report.wrong),
                       errors=list(report.errors), confidence=checked.confidence, low_confidence=checked.why)
        new = client.records[before:]
        rec.update(calls=len(new), cached_calls=sum(r.cached for r in new),
                   prompt_tokens=meter.prompt_tokens, completion_tokens=meter.completion_tokens,
                   cost_usd=None if meter.source == "unknown" else round(meter.cost_usd, 10))


def _frame(rec: Recorder, stage: Stage) -> None:
    """One frame of every object's pose (the log shows the initial, then the judged state)."""
    w = stage.world
    rec.frame(w.time, {o.body: (w.pose(o.obj_id).pos, w.pose(o.obj_id).quat) for o in w.objects})


def _finish_log(rec: Recorder, stage: Stage, case: JudgeCase, out: dict[str, Any]) -> None:
    """The verdict text and the log's summary (the label as its success), then close the file."""
    word = {True: "ACHIEVED", False: "NOT ACHIEVED", None: "UNKNOWN"}[out["verdict"]]
    rec.text("verdict", f"label: {'achieved' if case.label else 'not achieved'} ({case.kind}: {case.detail})\n"
                        f"reporter: {word} (from {out['source']}): {out['reason']}\n" + case.condition)
    finish = getattr(rec, "finish", None)
    if finish is not None:
        finish({"task": case.task, "seed": case.seed, "agent": out["reporter"], "success": case.label,
                "progress": case.progress, "goal": stage.scene.goal, "diagnostics": [case.condition] if case.condition else [],
                "error": out["error"], "llm": {k: out[k] for k in ("verdict", "source", "reason", "wrong", "errors")}})
    rec.close()
