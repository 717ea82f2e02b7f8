"""The LLM agent: closed loop plan -> execute -> report -> (reset + re-plan) over LMPs.

Per episode (``act``), under the default ``loop_policy="thesis"``::

    for attempt k = 1 .. attempts:
        if k > 1: ctx.reset()                      # back to the episode's initial state
        plan = planner LMP(objects, goal [, previous plan with line numbers + what happened])
               (k > 1: at replan_temperature; an answer identical to an earlier plan is asked again
                up to replan_retries times, hotter each time (planner.replan_sampling); a plan
                still identical is not run: the scene returns to where that plan ended)
        run plan in the sandbox (API + parse_obj_name / parse_position / parse_function)
        verdict = reporter (none | text | vlm): code -> repair -> direct structured verdict -> unknown
        predicate = the task's success predicate on the same state (recorded, never shown to the LLM)
        stop when the verdict is True, or there is no reporter and the plan finished,
             or the verdict is unknown and on_unknown == "stop"

``interaction="multi"`` runs turns of code with execution feedback instead of this loop
(:mod:`capmj.agents.llm_agent.multiturn`); the default ``single`` is this loop.  ``policy="tools"``
runs turns of function calls instead (:mod:`capmj.agents.llm_agent.tools`), with either interaction.

``loop_policy="careful"`` judges a plan that raised after acting, re-plans from the current state
when the verdict names only some objects wrong, and stops on a low-confidence verdict; the rules
and why are in :mod:`capmj.agents.llm_agent.loop_policy`, which decides after every attempt (the rule that
fired is the attempt record's ``rule``).

CapRavens re-ran the *old* plan before the new one after a failed verdict; capmj resets the scene
and runs only the new plan.  Every attempt is recorded as an :class:`~capmj.records.AttemptRecord`
(fields: :data:`~capmj.records.ATTEMPT_FIELDS`) in the episode's :class:`~capmj.records.LLMNotes`
(``ctx.notes["llm"]``, with LLM usage: calls, cached calls, tokens, cost), which the runner puts in
the episode result, and under ``llm/attempt{k}/`` in the episode log.  The full transcript (every prompt, completion and executed code)
is kept in ``ctx.notes["llm_transcript"]`` and :attr:`LLMAgent.transcript`.

Failures: bad code (no code, syntax error, sandbox violation, endless loop, huge allocation,
an exception) ends *that* attempt with a recorded error, and the next attempt re-plans with the
error as report.  A provider failure (``LLMError`` after the client's retries) ends the episode's
attempts.  The last attempt's error is re-raised so that the runner records it in the result.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from typing import Any, cast

from capmj.agents.attribution import api_error, failed_program
from capmj.agents.base import JUDGE_SETTLE_STEPS, Checkpoint, EpisodeContext
from capmj.agents.report.confidence import assess
from capmj.agents.lmp.meter import LLMMeter, check_limits
from capmj.agents.llm_agent.levels import LevelSession
from capmj.agents.llm_agent.options import LLMAgentOptions, llm_agent_configs
from capmj.agents.lmp.session import HelperCallCap, LMPCall, find_llm_error
from capmj.agents.llm_agent.loop_policy import Decision, Outcome, decide, judges_errors, wrong_share
from capmj.agents.api.perceived import make_api
from capmj.agents.llm_agent.multiturn import run_turns
from capmj.agents.llm_agent.tools import check_tool_calling, run_tool_turns
from capmj.agents.llm_agent.planner import Feedback, PlanOutcome, plan_and_run, replan_sampling
from capmj.agents.report.registry import Reporter, make_reporter
from capmj.agents.report.text import plan_check
from capmj.agents.report.verdict import Report
from capmj.errors import ConfigError, LLMError, PlanError, describe, error_facts
from capmj.llm import LLMClient, LLMConfig
from capmj.records import ATTEMPT_FIELDS, AttemptRecord, LLMNotes, Spend
from capmj.tasks.protocol import episode_rng

__all__ = ["ATTEMPT_FIELDS", "LLMAgent"]

STOPPED = {"achieved": "reporter: achieved", "finished": "plan finished", "unknown_stop": "reporter: unknown",
           "achieved_after_error": "reporter: achieved after an error", "low_confidence_stop": "reporter: low confidence"}
"""``LLMNotes.stopped`` of the rules that stop the loop (besides LLM errors, budgets, attempts used up)."""


class LLMAgent:
    """Plans with an LLM through the planner API; optional reporter and re-planning.

    ``config`` says what to ask (``config.model`` is any litellm model string: ``gpt-4o-mini``,
    ``ollama/<model>``, ``openai/<alias>`` with ``api_base`` for OpenAI-compatible local
    servers) and is used as given; ``options`` how the loop runs (:mod:`capmj.agents.llm_agent.options`).
    :meth:`from_options` builds both from flat keyword options, as the bench does.
    """

    name = "llm"

    def __init__(self, config: LLMConfig, options: LLMAgentOptions | None = None) -> None:
        if not isinstance(config, LLMConfig) or not isinstance(options, (LLMAgentOptions, type(None))):
            raise ConfigError("LLMAgent takes an LLMConfig and LLMAgentOptions (flat keyword options: "
                              "LLMAgent.from_options)")
        self.config = config
        self.options = options if options is not None else LLMAgentOptions()
        o = self.options
        # a cost cap needs the price of *this* model (declared or in litellm's list)
        check_limits(config.model, max_tokens=o.episode_max_tokens, max_cost_usd=o.episode_max_cost_usd,
                     price=o.price)
        if o.policy == "tools":  # a model without tool calling fails here, before any episode
            check_tool_calling(config.model)
        self.transcript: list[LMPCall] = []
        self.client: LLMClient | None = None

    @classmethod
    def from_options(cls, **options: Any) -> "LLMAgent":
        """The agent of flat keyword options (the bench's ``agent_options``; ``None`` = not given):
        :func:`~capmj.agents.llm_agent.options.llm_agent_configs` splits them into the two records."""
        return cls(*llm_agent_configs(options))

    @property
    def model(self) -> str:
        return self.config.model

    def _client(self) -> LLMClient:
        return LLMClient(self.config)

    def begin_episode(self, ctx: EpisodeContext) -> tuple[LLMClient, LLMMeter, list[LMPCall]]:
        """The episode's client, LLM meter (its per-episode limits, in ``ctx.notes["llm_calls"]``),
        helper-call cap and transcript, made anew and kept on the agent: the start of every loop form."""
        o = self.options
        client = self.client = self._client()
        meter = self.meter = LLMMeter(self.model, price=o.price, max_tokens=o.episode_max_tokens,
                                      max_cost_usd=o.episode_max_cost_usd)
        self.helper_cap = HelperCallCap(o.episode_max_helper_calls)  # all attempts of the episode together
        ctx.notes["llm_calls"] = meter.calls
        self.transcript = []
        return client, meter, self.transcript

    # ------------------------------------------------------------------ the loop
    def act(self, ctx: EpisodeContext) -> None:
        if self.options.policy == "tools":  # function calls in turns: its own module
            run_tool_turns(self, ctx)
            return
        if self.options.interaction == "multi":  # turns of code with feedback: its own module
            run_turns(self, ctx, check=plan_check)
            return
        o = self.options
        client, meter, transcript = self.begin_episode(ctx)
        attempts: list[AttemptRecord] = []
        stopped: str | None = None
        ctx.notes["llm"] = self._notes(client, attempts)
        ctx.notes["llm_transcript"] = transcript
        goal = ctx.scene.goal
        reporter = make_reporter(o.reporter, o.prompts_dir, o.reporter_prompt)
        feedback: Feedback | None = None  # of the last attempt whose plan ran
        feedbacks: list[Feedback] = []
        plans: list[str | None] = []  # plan_key of each attempt's plan (None: no answer)
        starts: list[bool] = []  # whether each attempt started from the initial scene
        ends: dict[int, tuple[Checkpoint, BaseException | None]] = {}  # state and error after attempt k
        last_error: BaseException | None = None
        reset = True  # whether the next attempt starts from the initial scene (careful: not after a partial verdict)
        movable = ctx.world.movable_ids
        try:
            if reporter is not None:
                reporter.start(ctx)
            for k in range(1, o.attempts + 1):
                if k > 1:
                    ctx.reset() if reset else ctx.next_attempt()
                from_initial = k == 1 or reset
                meter.attempt = k
                # a plan counts as a repeat only of plans run from the same (initial) scene: only then
                # is its outcome known (thesis: every attempt starts there, so every earlier plan counts)
                comparable = [key if from_initial and start else None for key, start in zip(plans, starts)]
                record, error, report, outcome = self._attempt(ctx, client, transcript, k, goal, reporter,
                                                               feedback, comparable, feedbacks, reset=k > 1 and reset)
                plans.append(outcome.key)
                starts.append(from_initial)
                if outcome.not_run is not None and outcome.identical_to in ends and from_initial:
                    # that plan, run again from the same initial state, would end where it ended
                    checkpoint, error = ends[outcome.identical_to]
                    ctx.restore(checkpoint)
                elif o.attempts > 1 and not isinstance(error, LLMError) and from_initial:
                    ends[k] = (ctx.checkpoint(), error)
                last_error = error
                record, decision, rule = self._decide(ctx, record, error, report, outcome, movable, from_initial)
                attempts.append(record)
                self._record_attempt(ctx, record)
                exceeded = meter.exceeded or self.helper_cap.exceeded
                if exceeded is not None:
                    stopped = "llm budget"
                    last_error = error or exceeded
                    break
                if isinstance(error, LLMError):
                    stopped = "llm error"
                    break
                if decision.stop:
                    stopped = STOPPED[rule]
                    if rule == "achieved_after_error":
                        last_error = None  # the loop ends on the reporter's "achieved"; the error is in the record
                    break
                if k == o.attempts:
                    stopped = "attempts used up"
                    break
                reset = decision.reset
                if outcome.not_run is None:
                    told = report if decision.shows_report else None
                    feedback = self._feedback(ctx, record, told, outcome, from_initial=from_initial, reset=reset)
                    feedbacks.append(feedback)
                elif feedback is not None and feedback.reset != reset:
                    feedback = replace(feedback, reset=reset)  # the next plan starts where this attempt left it
        finally:
            if reporter is not None:
                reporter.close()
            ctx.notes["llm"] = self._notes(client, attempts, stopped, meter.summary())
            ctx.notes["llm_transcript"] = [c.to_dict() for c in transcript]  # plain data for logs
        if last_error is not None:
            raise last_error

    def _decide(self, ctx: EpisodeContext, record: AttemptRecord, error: BaseException | None, report: Report | None,
                outcome: PlanOutcome, movable: tuple[int, ...], from_initial: bool) -> tuple[AttemptRecord, Decision, str]:
        """The loop policy's decision on an attempt, the rule that applies, and the attempt's record
        completed with that rule (an LLM budget or error overrides the policy's), the unknown-verdict policy and
        the reporter's confidence."""
        o = self.options
        checked = assess(report, ctx.world.objects) if report is not None else None
        decision = decide(o.loop_policy, Outcome(
            not_run=outcome.not_run is not None, error=error is not None,
            verdict=report.verdict if report is not None else None, judged=report is not None,
            assessment=checked, wrong_share=wrong_share(checked, movable)),
            on_unknown=o.on_unknown, reset=from_initial)
        rule = decision.rule
        unknown = rule in ("unknown_replan", "unknown_stop")  # recorded as before, whatever stops the loop
        over = self.meter.exceeded is not None or self.helper_cap.exceeded is not None
        if over or isinstance(error, LLMError):
            rule = "llm_budget" if over else "llm_error"
        record = replace(record, on_unknown=o.on_unknown if unknown else None, rule=rule,
                         confidence=checked.confidence if checked is not None else None,
                         low_confidence=checked.why if checked is not None else None)
        return record, decision, rule

    def _feedback(self, ctx: EpisodeContext, record: AttemptRecord, report: Report | None, outcome: PlanOutcome,
                  *, from_initial: bool, reset: bool) -> Feedback:
        """What the next plan is told of an attempt whose plan ran."""
        return Feedback(attempt=record.attempt, completion=outcome.completion or "", code=outcome.code,
                        error=record.error, error_line=record.error_line,
                        report=report.text() if report is not None else "",
                        scene=self._scene_summary(ctx), from_initial=from_initial, reset=reset)

    def _attempt(self, ctx: EpisodeContext, client: LLMClient, transcript: list[LMPCall], k: int, goal: str,
                 reporter: Reporter | None, feedback: Feedback | None, plans: list[str | None], feedbacks: list[Feedback],
                 *, reset: bool) -> tuple[AttemptRecord, BaseException | None, Report | None, PlanOutcome]:
        o = self.options
        api = make_api(ctx, o.perception)
        metered = self.meter.wrap(client.complete)  # logged, counted, stopped by the episode's LLM budget
        session = LevelSession(complete=metered, api=api.functions(o.api), objects_text=api.objects_text,
                               attempt=k, recorder=ctx.recorder, transcript=transcript, directory=o.prompts_dir,
                               lmp_budget=o.lmp_budget, max_fn_depth=o.max_fn_depth, helper_cap=self.helper_cap,
                               rng=episode_rng(ctx.seed, f"code{k}"),  # np.random of LLM code
                               api_level=o.api, examples=o.examples)
        session.check = plan_check(session, ctx)  # a plan's own parse_completion (CapRavens' plans check and retry)
        before = len(client.records)
        outcome = PlanOutcome()
        error: BaseException | None = None
        report: Report | None = None
        predicate: tuple[bool | None, float | None] = (None, None)
        # re-plans: planner requests sample at replan_sampling (attempt 1 and helpers at the client's temperature)
        sampling = partial(replan_sampling, o.replan_temperature, ctx.seed, k) if k > 1 else None
        try:
            plan_and_run(session, goal, feedback=feedback, previous=plans, budget=o.plan_budget, outcome=outcome,
                         retries=o.replan_retries, sampling=sampling, earlier=feedbacks)
        except Exception as exc:  # noqa: BLE001 - every failure ends this attempt, recorded
            llm_error = find_llm_error(exc)
            error = llm_error if llm_error is not None else exc
        if not isinstance(error, LLMError) and outcome.not_run is None:
            try:
                ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)
                # careful: a plan that raised after acting is judged on the state it reached (rule a)
                acted = error is not None and ctx.attempt_primitives > 0 and judges_errors(o.loop_policy)
                if reporter is not None and (error is None or acted):
                    report = reporter.judge(session, ctx, goal)
            except Exception as exc:  # noqa: BLE001
                llm_error = find_llm_error(exc)
                if llm_error is not None:
                    error = llm_error
                else:  # with no reporter only if settling raised: then an AttributeError, as ever
                    report = Report(cast(Reporter, reporter).mode, None, "", f"reporter failed: {describe(exc)}",
                                    "unknown", (), (f"reporter failed: {describe(exc)}",))
            predicate = self._predicate(ctx)  # the same state the reporter judged
        replanned = k > 1 and outcome.key is not None
        temperature = client.config.temperature  # of requests without their own
        error_text = describe(error) if error is not None else None
        error_type, error_status = error_facts(error) if error is not None else (None, None)
        told = f"plan not run: {outcome.not_run}" if outcome.not_run is not None else ""
        if error is not None:
            told = self._error_report(error, ctx)
        if report is not None:
            told = (f"the plan failed with {describe(error)}\n" if error is not None else "") + report.text() + \
                "\n" + self._scene_summary(ctx)
        new = client.records[before:]
        record = AttemptRecord(
            attempt=k, reset=reset,
            temperatures=tuple(temperature if t is None else t for t in outcome.temperatures),
            seeds=tuple(outcome.seeds), code=outcome.code,
            code_differs=outcome.identical_to is None if replanned else None,
            identical_to=outcome.identical_to if replanned else None,
            extra_requests=outcome.extra_requests, not_run=outcome.not_run,
            error=error_text,
            error_kind=None if error is None else "llm" if isinstance(error, LLMError) else "plan",
            error_line=error.line if isinstance(error, PlanError) else None,
            error_type=error_type, error_status=error_status,
            failed_program=failed_program(transcript, k, error_text) if error_text else None,
            api_error=api_error(error_text, api.call_log),
            verdict=report.verdict if report is not None else None,
            verdict_source=report.source if report is not None else None,
            reason=report.reason if report is not None else "",
            wrong=tuple(report.wrong) if report is not None else (),
            reporter_errors=tuple(report.errors) if report is not None else (),
            reporter_error=report.error if report is not None and report.error else None,
            predicate=predicate[0], predicate_progress=predicate[1], report=told,
            primitives=ctx.attempt_primitives, api_calls=len(api.call_log), llm_calls=len(new),
            prompt_tokens=sum(r.prompt_tokens for r in new), completion_tokens=sum(r.completion_tokens for r in new),
            said=tuple(api.messages))
        ctx.recorder.text(f"llm/attempt{k}/api_calls", api.log_text())
        return record, error, report, outcome

    @staticmethod
    def _predicate(ctx: EpisodeContext) -> tuple[bool | None, float | None]:
        """The task's predicate on the current state (success, progress), for the record only (the
        LLM never sees it); (None, None) when it fails."""
        try:
            verdict = ctx.task.evaluate(ctx.scene, ctx.world.state())
        except Exception:  # noqa: BLE001 - the runner's final evaluation reports a broken predicate
            return None, None
        return bool(verdict.success), float(verdict.progress)

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
        head = f"the plan failed with {describe(error)}"
        return head + "\n" + self._scene_summary(ctx)

    @staticmethod
    def _record_attempt(ctx: EpisodeContext, record: AttemptRecord) -> None:
        k = record.attempt
        rec = ctx.recorder
        if record.error:
            rec.text(f"llm/attempt{k}/error", record.error)
        word = {True: "achieved", False: "not achieved", None: "unknown"}[record.verdict]
        if record.not_run:
            word = f"not run: {record.not_run}"
        if record.verdict_source is not None:
            word += f" (reporter verdict from {record.verdict_source}; task predicate: {record.predicate})"
        rec.text(f"llm/attempt{k}/verdict", word + (f" (error: {record.error})" if record.error else ""))
        if record.report:
            rec.text(f"llm/attempt{k}/report", record.report)

    def _notes(self, client: LLMClient, attempts: list[AttemptRecord], stopped: str | None = None,
               spend: Spend | None = None) -> LLMNotes:
        """The episode's notes so far: options, the client's usage, the attempts, why it stopped."""
        u = client.usage()
        o = self.options
        return LLMNotes(model=self.model, reporter=o.reporter, max_attempts=o.attempts, on_unknown=o.on_unknown,
                        loop_policy=o.loop_policy, reporter_prompt=o.reporter_prompt,
                        temperature=self.config.temperature, replan_temperature=o.replan_temperature,
                        replan_retries=o.replan_retries, attempts=tuple(attempts), calls=u.calls,
                        cached_calls=u.cached_calls, failed_calls=u.failed_calls, prompt_tokens=u.prompt_tokens,
                        completion_tokens=u.completion_tokens, cost_usd=round(u.cost_usd, 8),
                        latency_s=round(u.latency_s, 3), stopped=stopped, spend=spend)
