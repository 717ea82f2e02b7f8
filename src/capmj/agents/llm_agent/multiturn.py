"""Multi-turn code with execution feedback (``--interaction multi``): the model drives the robot in turns.

Per episode, over one conversation::

    system: prompts/multiturn_system.txt (its <<QUESTION>>: the number of turns)
    user:   the planner prompt (prompts/planner.py: API, examples) with objects and the goal
    for turn k = 1 .. max_turns:
        answer = the model's next message: a fenced python block, FINISH alone on a line, or both
        run the block in the sandbox, in the namespace the earlier turns left (no scene reset)
        stop at FINISH (after running the block of an answer that has both)
        user: the turn's feedback (prompts/multiturn_feedback.txt), by --feedback:
              text     what the block printed, its error and the line it came from, each API call
                       of the turn with its result, the objects after the turn as the API sees them
                       (the perceived scene under --perception rgbd, never the truth)
              image    text + the cameras' RGB views after the turn as image parts
              describe text + what a second call (--describe-model; prompts/multiturn_describe.txt)
                       wrote about the views before and after the turn

The namespace: names a turn binds (variables, functions) are defined in every later turn; a turn
that raises keeps none of its own bindings (the sandbox returns a namespace only from code that
finished), the earlier turns' stay.  Functions defined in a turn run later under their own turn's
sandbox budget.  Every turn is a new attempt of the episode context without a reset
(:meth:`~capmj.agents.base.EpisodeContext.next_attempt`): the per-attempt budgets (primitives,
simulation steps, sandbox) count per turn; the episode's LLM budget counts over all turns.

Records: each turn is an :class:`~capmj.records.AttemptRecord` (``attempt`` = the turn) with the
turn keys ``finish``, ``feedback``, ``images`` and ``described``; its rule is ``finish``,
``next_turn`` or ``max_turns`` (or ``llm_error`` / ``llm_budget``).  The episode's
:class:`~capmj.records.LLMNotes` say ``interaction``, ``feedback``, ``max_turns``, why it stopped
(``model: FINISH``, :data:`~capmj.records.notes.TURNS_USED_UP`, ``llm error``, ``llm budget``) and
``finish_agreed``: whether the task predicate held when the model said FINISH.  Success is the
task's predicate, as for every agent.  A plan error in a turn is feedback, not the episode's error;
a provider failure or the LLM budget ends the episode and is raised, as in the single-plan loop.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from capmj.agents.api.perceived import make_api
from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.attribution import api_error, failed_program
from capmj.agents.base import JUDGE_SETTLE_STEPS, EpisodeContext
from capmj.agents.llm_agent.levels import LevelSession
from capmj.agents.llm_agent.planner import question
from capmj.agents.lmp.session import LMPCall, LMPSession, find_llm_error
from capmj.agents.prompt_files import load_prompt, object_names, prompts_dir
from capmj.agents.sandbox import extract_code, run_code
from capmj.errors import ConfigError, LLMError, NoCodeError, PlanError, describe, error_facts
from capmj.llm import LLMClient, image_part, text_part
from capmj.records import AttemptRecord, LLMNotes
from capmj.records.notes import TURNS_USED_UP
from capmj.tasks.protocol import episode_rng

if TYPE_CHECKING:
    from capmj.agents.llm_agent.agent import LLMAgent

__all__ = ["FINISH", "FINISHED", "Answer", "CameraViews", "ViewsFeedback", "counting_describer", "describe_change", "describing_client",
           "feedback_text",
           "parse_answer", "run_turns", "scene_text", "system_prompt", "text_template", "views_feedback"]

FINISH = "FINISH"
"""The word, alone on a line outside code, with which the model claims the goal holds."""

FINISHED = "model: FINISH"
"""``LLMNotes.stopped`` of an episode the model ended with FINISH."""

_FENCED = re.compile(r"```.*?(?:```|\Z)", re.DOTALL)


@dataclass(frozen=True)
class Answer:
    """One turn's answer: its code (None: none) and whether it said FINISH; ``error`` is why an
    answer with neither is not a turn (``NoCodeError``)."""

    code: str | None
    finish: bool
    error: NoCodeError | None = None


def parse_answer(text: str) -> Answer:
    """The code and the FINISH of an answer: FINISH counts alone on a line outside fenced blocks;
    the code is :func:`~capmj.agents.sandbox.extract_code` of the answer without its FINISH lines."""
    outside = _FENCED.sub("", text)
    finish = any(line.strip() == FINISH for line in outside.splitlines())
    rest = "\n".join(line for line in text.splitlines() if line.strip() != FINISH)
    try:
        return Answer(extract_code(rest), finish)
    except NoCodeError as exc:
        return Answer(None, finish, None if finish else exc)


def text_template(name: str, directory: Path | None) -> str:
    """A text prompt without its ``#@`` metadata lines."""
    folder = Path(directory) if directory is not None else prompts_dir()
    try:
        raw = (folder / name).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"prompt {folder / name} not found") from None
    return "\n".join(line for line in raw.splitlines() if not line.startswith("#@")).strip() + "\n"


def system_prompt(max_turns: int, directory: Path | None = None) -> str:
    """The multi-turn system message: ``prompts/multiturn_system.txt`` with the number of turns."""
    return load_prompt("multiturn_system.txt", directory).render(str(max_turns)).strip()


def scene_text(api: PlannerAPI) -> str:
    """The objects as the planner API sees them: the planner prompt's ``objects = [...]`` line and
    each object's centre (the perceived scene under ``--perception rgbd``); never raises."""
    try:
        lines = [api.objects_text()]
        for o in api.objects():
            lines.append(f"# {o.name}: {[round(float(v), 3) for v in api.position(o.obj_id)]}")
    except Exception as exc:  # noqa: BLE001 - the feedback says so instead
        return f"# (the scene could not be read: {describe(exc)})"
    return "\n".join(lines)


def feedback_text(template: str, *, turn: int, left: int, output: Sequence[str], error: str | None,
                  error_line: int | None, code: str | None, calls: str, scene: str, described: str | None) -> str:
    """The feedback after a turn: ``template`` (``prompts/multiturn_feedback.txt``) with its placeholders
    filled (``<<TURN>>``, ``<<LEFT>>``, ``<<OUTPUT>>``, ``<<ERROR>>``, ``<<CALLS>>``, ``<<OBJECTS>>``,
    ``<<DESCRIBED>>``, whose whole line is left out when ``described`` is None)."""
    printed = "\n".join(output).strip() or "(nothing)"
    if error is None:
        failure = "none: the block ran to its end"
    else:
        failure = error
        lines = code.rstrip("\n").splitlines() if code else []
        if error_line is not None and 1 <= error_line <= len(lines):
            failure = f"line {error_line}: {lines[error_line - 1].strip()}\n{error}"
    text = (template.replace("<<TURN>>", str(turn)).replace("<<LEFT>>", str(left))
            .replace("<<OUTPUT>>", printed).replace("<<ERROR>>", failure)
            .replace("<<CALLS>>", calls.strip() or "(none)").replace("<<OBJECTS>>", scene.strip()))
    if described is None:  # the line that names it goes
        return "\n".join(line for line in text.splitlines() if "<<DESCRIBED>>" not in line).strip() + "\n"
    return text.replace("<<DESCRIBED>>", described.strip()).strip() + "\n"


@dataclass
class CameraViews:
    """The cameras' RGB views of the current state as PNG bytes (by camera), rendered on demand."""

    ctx: EpisodeContext
    rig: Any = None
    last: dict[str, bytes] = field(default_factory=dict)

    def render(self, turn: int, label: str) -> dict[str, bytes]:
        from capmj.sim.cameras import CameraRig
        from capmj.sim.image_colour import to_png

        if self.rig is None:
            self.rig = CameraRig(self.ctx.world)
        self.ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)
        views = self.rig.render_all(seg=False, heightmap=False).views
        out = {}
        for name, frame in views.items():
            self.ctx.recorder.image(f"llm/attempt{turn}/feedback/{label}_{name}_rgb", frame.rgb)
            out[name] = to_png(frame.rgb)
        self.last = out
        return out

    def close(self) -> None:
        if self.rig is not None:
            self.rig.close()


def describe_change(session: LMPSession, directory: Path | None, goal: str, scene: str,
                    before: Mapping[str, bytes], after: Mapping[str, bytes]) -> str:
    """The describing call: the views before and after the turn -> what changed (recorded as the
    LMP ``describe`` of the turn)."""
    prompt = text_template("multiturn_describe.txt", directory)
    content: list[dict[str, Any]] = [text_part(prompt.replace("<<GOAL>>", " ".join(goal.split()))
                                               .replace("<<OBJECTS>>", scene))]
    for name in after:
        if name in before:
            content += [text_part(f"Before, camera {name}:"), image_part(before[name])]
        content += [text_part(f"After, camera {name}:"), image_part(after[name])]
    call = session.next_call("describe", goal)
    return session.ask(call, [{"role": "user", "content": content}]).strip()


@dataclass(frozen=True)
class ViewsFeedback:
    """What ``--feedback image|describe`` adds after a turn (:func:`views_feedback`)."""

    parts: list[dict[str, Any]]
    """The image parts of the message (``image``), each camera's view after its caption."""
    images: int
    """Images sent: the views (``image``) or the before and after views described (``describe``)."""
    described: str | None
    """The describing call's account (``describe``), or why there are no views."""
    llm_error: LLMError | None
    """The describing call's LLM error, which ends the episode as any LLM error does."""


def views_feedback(feedback: str | None, views: CameraViews, turn: int, goal: str, scene: str, directory: Path | None,
                   describer: LMPSession) -> ViewsFeedback:
    """The views after ``turn`` as image parts (``image``) or as the change the ``describer`` session
    describes (``describe``); nothing for ``text``.  A renderer that fails is said in the text."""
    parts: list[dict[str, Any]] = []
    images, described = 0, None
    try:
        if feedback == "image":
            for name, png in views.render(turn, "after").items():
                parts += [text_part(f"Camera {name} after turn {turn}:"), image_part(png)]
            images = len(parts) // 2
        elif feedback == "describe":
            earlier = dict(views.last)
            after = views.render(turn, "after")
            images = len(earlier) + len(after)
            described = describe_change(describer, directory, goal, scene, earlier, after)
    except Exception as exc:  # noqa: BLE001 - no renderer: the feedback says so
        llm_error = find_llm_error(exc)
        if llm_error is not None:
            return ViewsFeedback(parts, images, described, llm_error)
        described = f"(no camera views: {describe(exc)})"
    return ViewsFeedback(parts, images, described, None)


def describing_client(agent: LLMAgent, client: LLMClient) -> LLMClient:
    """The client of ``--feedback describe``'s second call: one of ``--describe-model`` when it names
    another model than the agent's, else the agent's own ``client``."""
    o = agent.options
    if o.feedback == "describe" and o.describe_model not in (None, agent.config.model):
        return LLMClient(replace(agent.config, model=str(o.describe_model)))
    return client


def counting_describer(notes: LLMNotes, client: LLMClient, describer: LLMClient) -> LLMNotes:
    """``notes`` with a separate describing client's calls counted as the episode's."""
    if describer is client:
        return notes
    d = describer.usage()
    return replace(notes, calls=notes.calls + d.calls, cached_calls=notes.cached_calls + d.cached_calls,
                   failed_calls=notes.failed_calls + d.failed_calls,
                   prompt_tokens=notes.prompt_tokens + d.prompt_tokens,
                   completion_tokens=notes.completion_tokens + d.completion_tokens,
                   cost_usd=round(notes.cost_usd + d.cost_usd, 8), latency_s=round(notes.latency_s + d.latency_s, 3))


def run_turns(agent: LLMAgent, ctx: EpisodeContext,
              check: Callable[[LMPSession, EpisodeContext], Callable[..., Any]] | None = None) -> None:
    """Run one episode of ``agent`` (``options.interaction == "multi"``) in turns; fills
    ``ctx.notes`` as :meth:`LLMAgent.act` does and raises a provider failure or an exceeded LLM
    budget (a turn's plan error is feedback, recorded in its turn).  ``check(session, ctx)`` gives
    the code's ``parse_completion`` (the agent passes the reporters' plan check; None: code cannot
    call it)."""
    o = agent.options
    assert o.max_turns is not None and o.feedback is not None  # normalised by LLMAgentOptions for multi
    max_turns: int = o.max_turns
    client, meter, transcript = agent.begin_episode(ctx)
    describer = describing_client(agent, client)
    turns: list[AttemptRecord] = []
    stopped: str | None = None
    agreed: bool | None = None
    clients = (client,) if describer is client else (client, describer)

    def notes() -> LLMNotes:
        out = agent._notes(client, turns, stopped, meter.summary() if stopped is not None else None)
        out = counting_describer(out, client, describer)
        return replace(out, max_attempts=max_turns, interaction="multi", feedback=o.feedback,
                       max_turns=max_turns, finish_agreed=agreed)

    ctx.notes["llm"] = notes()
    ctx.notes["llm_transcript"] = transcript
    goal = ctx.scene.goal
    api = make_api(ctx, o.perception)  # one API for the episode: functions defined earlier log here too
    functions = api.functions(o.api)
    template = text_template("multiturn_feedback.txt", o.prompts_dir)
    views = CameraViews(ctx)
    namespace: dict[str, object] = {}
    messages: list[dict[str, Any]] = []
    raised: BaseException | None = None
    try:
        if o.feedback == "describe":
            views.render(1, "before")
        for k in range(1, o.max_turns + 1):
            if k > 1:
                ctx.next_attempt()
            meter.attempt = k
            session = LevelSession(complete=meter.wrap(client.complete), api=functions, objects_text=api.objects_text,
                                   attempt=k, recorder=ctx.recorder, transcript=transcript, directory=o.prompts_dir,
                                   lmp_budget=o.lmp_budget, max_fn_depth=o.max_fn_depth, helper_cap=agent.helper_cap,
                                   rng=episode_rng(ctx.seed, f"code{k}"), api_level=o.api, examples=o.examples)
            session.check = check(session, ctx) if check is not None else None
            if not messages:
                q = question(session.objects_text(), goal)
                messages = [{"role": "system", "content": system_prompt(o.max_turns, o.prompts_dir)},
                            {"role": "user", "content": session.prompt("planner").render(q)}]
            before = [len(c.records) for c in clients]
            ran = _turn(session, ctx, api, messages, namespace, goal, k, o.plan_budget)
            error, answer = ran.error, ran.answer
            predicate: tuple[bool | None, float | None] = (None, None)
            if not isinstance(error, LLMError):
                try:
                    ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)  # the state judged, shown and built on
                except Exception:  # noqa: BLE001 - the runner's final evaluation reports a broken world
                    pass
                predicate = agent._predicate(ctx)
            over = meter.exceeded or agent.helper_cap.exceeded
            llm_error = error if isinstance(error, LLMError) else None
            described: str | None = None
            images = 0
            feedback: str | None = None
            if answer.finish and llm_error is None and over is None:
                agreed = predicate[0] is True
            if not (answer.finish or k == o.max_turns or over is not None or llm_error is not None):
                scene = scene_text(api)
                seen = views_feedback(o.feedback, views, k, goal, scene, o.prompts_dir,
                                      replace(session, complete=meter.wrap(describer.complete), check=None))
                parts, images, described, llm_error = seen.parts, seen.images, seen.described, seen.llm_error
                over = meter.exceeded or agent.helper_cap.exceeded
                if llm_error is None and over is None:
                    error_line = error.line if isinstance(error, PlanError) else None
                    feedback = feedback_text(template, turn=k, left=o.max_turns - k, output=ran.output,
                                             error=describe(error) if error is not None else None,
                                             error_line=error_line, code=ran.code, calls=ran.calls_text, scene=scene,
                                             described=described)
                    content: Any = [text_part(feedback)] + parts if parts else feedback
                    messages += [{"role": "assistant", "content": transcript_completion(transcript, k)},
                                 {"role": "user", "content": content}]
                    ctx.recorder.text(f"llm/attempt{k}/feedback", feedback)
            if llm_error is not None and error is None:
                error = llm_error
            new = [r for c, n in zip(clients, before) for r in c.records[n:]]
            error_text = describe(error) if error is not None else None
            error_type, error_status = error_facts(error) if error is not None else (None, None)
            rule = ("llm_budget" if over is not None else "llm_error" if llm_error is not None
                    else "finish" if answer.finish else "max_turns" if k == o.max_turns else "next_turn")
            record = AttemptRecord(
                attempt=k, reset=False, code=ran.code, error=error_text,
                error_kind=None if error is None else "llm" if isinstance(error, LLMError) else "plan",
                error_line=error.line if isinstance(error, PlanError) else None, error_type=error_type,
                error_status=error_status,
                failed_program=failed_program(transcript, k, error_text) if error_text else None,
                api_error=api_error(error_text, list(ran.calls)), predicate=predicate[0],
                predicate_progress=predicate[1], rule=rule, primitives=ctx.attempt_primitives,
                api_calls=len(ran.calls), llm_calls=len(new), prompt_tokens=sum(r.prompt_tokens for r in new),
                completion_tokens=sum(r.completion_tokens for r in new), said=ran.said, finish=answer.finish,
                feedback=feedback, images=images, described=described)
            turns.append(record)
            agent._record_attempt(ctx, record)
            if over is not None:
                stopped, raised = "llm budget", error if isinstance(error, LLMError) else over
                break
            if llm_error is not None:
                stopped, raised = "llm error", llm_error
                break
            if answer.finish:
                stopped = FINISHED
                break
            if k == o.max_turns:
                stopped = TURNS_USED_UP
    finally:
        views.close()
        ctx.notes["llm"] = notes()
        ctx.notes["llm_transcript"] = [c.to_dict() for c in transcript]
    if raised is not None:
        raise raised


def transcript_completion(transcript: Sequence[LMPCall], turn: int) -> str:
    """The model's answer in ``turn`` as it was received (the planner call of that turn)."""
    for call in reversed(transcript):
        if call.attempt == turn and call.lmp == "planner":
            return call.completion or ""
    return ""


@dataclass(frozen=True)
class _Ran:
    """What one turn did, for its record and its feedback."""

    error: BaseException | None
    answer: Answer
    code: str | None
    output: tuple[str, ...]
    calls: tuple[dict[str, Any], ...]
    """The API calls of the turn (entries of the API's call log)."""
    calls_text: str
    said: tuple[str, ...]


def _turn(session: LMPSession, ctx: EpisodeContext, api: PlannerAPI, messages: list[dict[str, Any]],
          namespace: dict[str, object], goal: str, k: int, budget: Any) -> _Ran:
    """Ask for turn ``k``'s answer and run its code in ``namespace`` (updated with what it binds)."""
    call = session.next_call("planner", goal)
    calls_before, said_before = len(api.call_log), len(api.messages)
    error: BaseException | None = None
    answer = Answer(None, False)
    output: list[str] = []
    code: str | None = None
    try:
        answer = parse_answer(session.ask(call, list(messages)))
        if answer.error is not None:
            session.record(call, "error", describe(answer.error))
            raise answer.error
        code = answer.code
        if code is not None:
            env = session.plan_env()
            env["objects"] = object_names(session.objects_text()) or []
            env["goal"] = goal
            env.update(namespace)
            code = session.prepare(code, env, parent=call, program="the plan")
            session.record(call, "code", code)
            bound = run_code(code, env, budget=budget, filename=f"<turn {k}>", output=output, rng=session.rng,
                             program="the plan")
            namespace.update(bound)
            session.record(call, "result", "finished" + (" (then FINISH)" if answer.finish else ""))
        else:
            session.record(call, "result", FINISH)
    except Exception as exc:  # noqa: BLE001 - every failure ends this turn, recorded
        found = find_llm_error(exc)
        error = found if found is not None else exc
        if found is None and call.error is None:
            session.record(call, "error", describe(exc))
    if output:
        ctx.recorder.text(f"llm/attempt{k}/output", "\n".join(output))
    calls = tuple(api.call_log[calls_before:])
    every = api.log_text().splitlines()
    calls_text = "\n".join(every[calls_before:])
    ctx.recorder.text(f"llm/attempt{k}/api_calls", calls_text)
    return _Ran(error, answer, code, tuple(output), calls, calls_text, tuple(api.messages[said_before:]))
