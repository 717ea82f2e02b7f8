"""``--policy tools``: the model calls the planner API's functions as OpenAI tools, turn by turn.

Per episode, over one conversation::

    system: prompts/tools_system.txt (its <<QUESTION>>: the number of turns)
    user:   the planner's question: the objects = [...] line and the goal
    for turn k = 1 .. max_turns:
        answer = the model's next message, offered the tools (capmj.agents.api.tool_schemas)
        calls  = its tool_calls, else the {"name", "arguments"} objects written in its text
                 (capmj.agents.llm_agent.tools_calls: form content_json)
        each call in order, through the planner API's logged functions (as plan code calls them):
            a tool message (tool_call_id) with its value as JSON or its error's text
        --interaction multi: then a user message with the --feedback of the turn
              (prompts/tools_feedback.txt: the objects now; image: + the cameras' views;
              describe: + a second call's account of what changed, as in multi-turn code)
        stop after an answer without a call or with FINISH alone on a line (its calls run first)

Every answer is a turn and every turn an attempt of the episode context without a reset
(:meth:`~capmj.agents.base.EpisodeContext.next_attempt`): the per-attempt budgets (primitives,
simulation steps, and the plan budget's ``max_api_calls`` for the calls of a turn) count per turn,
the episode's LLM budget over all turns.  A call's error goes back to the model, as a plan error
goes back in the multi-turn feedback; a provider failure or the LLM budget ends the episode and is
raised.

Records: each turn is an :class:`~capmj.records.AttemptRecord` with ``tool_calls`` (each call's
arguments, form, result or error), ``finish`` and its rule (``answered``, ``finish``,
``next_turn``, ``max_turns``, ``llm_error``, ``llm_budget``); the episode's
:class:`~capmj.records.LLMNotes` say ``policy="tools"``, ``max_turns``, why it stopped (``model:
FINISH``, :data:`~capmj.records.notes.ANSWERED`, :data:`~capmj.records.notes.TURNS_USED_UP`, whose
failure label is ``no_finish``) and ``finish_agreed``: whether the task predicate held when the model
ended the episode.  The transcript holds each turn's planner call: the conversation sent, the
answer, the calls (``code``) and what they returned (``result``).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from capmj.agents.api.perceived import make_api
from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.api.tool_schemas import TOOL_FUNCTIONS, tool_schemas
from capmj.agents.attribution import api_error
from capmj.agents.base import JUDGE_SETTLE_STEPS, EpisodeContext
from capmj.agents.llm_agent.multiturn import (FINISHED, CameraViews, counting_describer, describing_client, scene_text,
                                              text_template, views_feedback)
from capmj.agents.llm_agent.planner import question
from capmj.agents.llm_agent.tools_calls import Call, answer_calls, run_call, says_finish
from capmj.agents.lmp.session import LMPCall, LMPSession, find_llm_error
from capmj.agents.prompt_files import load_prompt
from capmj.errors import (BudgetExceeded, LLMBudgetExceeded, LLMError, ToolCallingUnsupported, ToolsRejected, describe,
                          error_facts)
from capmj.llm import ToolCall, text_part
from capmj.llm.provider import import_litellm, short
from capmj.llm.records import Completion
from capmj.records import AttemptRecord, LLMNotes, ToolCallRecord
from capmj.records.notes import ANSWERED, TURNS_USED_UP
from capmj.tasks.protocol import episode_rng

if TYPE_CHECKING:
    from capmj.agents.llm_agent.agent import LLMAgent

__all__ = ["check_tool_calling", "conversation_text", "run_tool_turns", "system_prompt"]


@functools.lru_cache(maxsize=32)
def check_tool_calling(model: str) -> None:
    """Raise :class:`~capmj.errors.ToolCallingUnsupported` naming ``model`` when litellm's model list
    says it has no tool calling: ``supports_function_calling`` false, or not a chat model (a
    completion or embedding model).  A chat model the list does not say it of, or does not know
    (a self-hosted server's alias), is asked; a server that refuses the tools fails the request
    with :class:`~capmj.errors.ToolsRejected`."""
    litellm = import_litellm()
    try:
        info = litellm.get_model_info(model)
    except Exception:  # noqa: BLE001 - litellm raises for models it does not list
        return
    mode = info.get("mode")
    if info.get("supports_function_calling") is False or mode not in (None, "chat", "responses"):
        why = "no tool calling" if mode in (None, "chat", "responses") else f"a {mode} model, no chat"
        raise ToolCallingUnsupported(f"--policy tools needs a model with tool calling, and {model!r} has none "
                                     f"(litellm's model list: {why}; provider {info.get('litellm_provider')}); "
                                     "use --policy code, or a model that calls functions")


def system_prompt(max_turns: int, directory: Path | None = None, examples: str = "full") -> str:
    """The tool-calling system message: ``prompts/tools_system.txt`` with the number of turns; its
    example conversation left out with ``examples="none"`` (``--examples none``)."""
    prompt = load_prompt("tools_system.txt", directory)
    return (prompt if examples == "full" else prompt.without_examples()).render(str(max_turns)).strip()


def conversation_text(messages: Sequence[dict[str, Any]]) -> str:
    """A conversation as readable text for the logs: each message's role and text, an assistant's
    calls as ``name(arguments)``, a tool message with the id it answers; images summarised."""
    out: list[str] = []
    for m in messages:
        content = m.get("content")
        if isinstance(content, list):
            content = "\n".join(str(p.get("text", "")) if p.get("type") == "text" else
                                f"<image {len(str(p.get('image_url', {}).get('url', '')))} chars>" for p in content)
        head = f"[{m.get('role')}]" + (f" {m['tool_call_id']}" if m.get("tool_call_id") else "")
        lines = [head] + ([str(content)] if content else [])
        for c in m.get("tool_calls") or ():
            lines.append(f"call {c['id']}: {c['function']['name']}({c['function']['arguments']})")
        out.append("\n".join(lines))
    return "\n\n".join(out) + "\n"


@dataclass(frozen=True)
class _Turn:
    """What one turn did: the answer (None: the request failed), its calls and what they returned."""

    error: LLMError | LLMBudgetExceeded | None
    """Why the request failed (a provider failure, the LLM budget)."""
    text: str
    calls: tuple[ToolCallRecord, ...]
    finish: bool
    api_calls: int
    said: tuple[str, ...]
    last_error: BaseException | None
    """The last call's error when it failed (the turn's error, as a plan's last error is)."""


def _ask(session: LMPSession, call: LMPCall, messages: list[dict[str, Any]], tools: list[dict[str, Any]],
         model: str) -> Completion:
    """The planner request of a turn, offered ``tools``; recorded on ``call`` like an LMP's."""
    session.record(call, "prompt", conversation_text(messages))
    try:
        completion: Completion = session.complete(messages, purpose=f"{call.lmp}#{call.n}", tools=tools)
    except LLMBudgetExceeded as exc:  # the episode's LLM budget: the answer came, over the limit
        session.record(call, "error", describe(exc))
        raise
    except LLMError as exc:
        cause = exc.__cause__
        if cause is not None and getattr(cause, "status_code", None) == 400 and "tool" in str(cause).lower():
            rejected = ToolsRejected(f"{model}: the server refused the request's tools ({short(cause, 300)}); "
                                     "--policy tools needs a model with tool calling")
            rejected.__cause__ = exc
            exc = rejected
        session.record(call, "error", describe(exc))
        if exc.partial:
            session.record(call, "partial", exc.partial)
        raise exc from exc.__cause__
    call.cached = bool(completion.cached)
    shown = completion.text + "".join(f"\n[call {t.id}] {t.name}({t.arguments})" for t in completion.tool_calls)
    session.record(call, "completion", shown)
    if completion.cut:
        session.record(call, "cut", completion.cut)
    return completion


def _turn(session: LMPSession, api: PlannerAPI, messages: list[dict[str, Any]], tools: list[dict[str, Any]],
          goal: str, k: int, max_calls: int, model: str) -> _Turn:
    """Ask for turn ``k``'s answer and run its calls; the conversation gets the answer and the tool
    messages."""
    call = session.next_call("planner", goal)
    before, said_before = len(api.call_log), len(api.messages)
    try:
        completion = _ask(session, call, messages, tools, model)
    except Exception as exc:
        if isinstance(exc, LLMBudgetExceeded):  # the episode's LLM budget ends the turn
            return _Turn(exc, "", (), False, 0, (), None)
        found = find_llm_error(exc)
        if found is None:
            raise
        return _Turn(found, "", (), False, 0, (), None)  # a provider failure ends the turn
    calls: list[Call] = answer_calls(completion.text, completion.tool_calls, TOOL_FUNCTIONS, k)
    finish = says_finish(completion.text)
    records: list[ToolCallRecord] = []
    last: BaseException | None = None
    if calls:
        messages.append({"role": "assistant", "content": completion.text or None,
                         "tool_calls": [c.to_message() for c in calls]})
    functions = session.api
    for n, c in enumerate(calls, start=1):
        error: BaseException | None
        if n > max_calls:
            result, error = None, BudgetExceeded(f"API call budget of {max_calls} calls per turn used up "
                                                 "(max_api_calls of the plan budget)")
        else:
            result, error = run_call(c, functions, TOOL_FUNCTIONS)
        text = result if error is None else f"error: {describe(error)}"
        messages.append({"role": "tool", "tool_call_id": c.id, "content": text})
        records.append(ToolCallRecord(c.id, c.name, c.arguments, c.form, result=result,
                                      error=describe(error) if error is not None else None))
        last = error
    session.record(call, "code", "\n".join(f"{r.name}({r.arguments})" for r in records))
    session.record(call, "result", "\n".join(f"{r.name} -> {r.result if r.error is None else 'error: ' + r.error}"
                                             for r in records) or ("FINISH" if finish else "no call"))
    return _Turn(None, completion.text, tuple(records), finish or not calls, len(api.call_log) - before,
                 tuple(api.messages[said_before:]), last)


def run_tool_turns(agent: LLMAgent, ctx: EpisodeContext) -> None:
    """Run one episode of ``agent`` (``options.policy == "tools"``) in turns of function calls; fills
    ``ctx.notes`` as :meth:`LLMAgent.act` does and raises a provider failure or an exceeded LLM budget
    (a call's error is the model's to read, recorded in its turn)."""
    o = agent.options
    assert o.max_turns is not None  # normalised by LLMAgentOptions for tools
    max_turns: int = o.max_turns
    multi = o.interaction == "multi"
    client, meter, transcript = agent.begin_episode(ctx)
    describer = describing_client(agent, client)
    clients = (client,) if describer is client else (client, describer)
    turns: list[AttemptRecord] = []
    stopped: str | None = None
    agreed: bool | None = None

    def notes() -> LLMNotes:
        out = agent._notes(client, turns, stopped, meter.summary() if stopped is not None else None)
        out = counting_describer(out, client, describer)
        return replace(out, max_attempts=max_turns, interaction="multi" if multi else None,
                       feedback=o.feedback if multi else None, max_turns=max_turns, finish_agreed=agreed,
                       policy="tools")

    ctx.notes["llm"] = notes()
    ctx.notes["llm_transcript"] = transcript
    goal = ctx.scene.goal
    api = make_api(ctx, o.perception)
    functions = api.functions()
    tools = tool_schemas()
    template = text_template("tools_feedback.txt", o.prompts_dir) if multi else ""
    views = CameraViews(ctx)
    messages: list[dict[str, Any]] = []
    raised: BaseException | None = None
    try:
        if o.feedback == "describe":
            views.render(1, "before")
        for k in range(1, max_turns + 1):
            if k > 1:
                ctx.next_attempt()
            meter.attempt = k
            session = LMPSession(complete=meter.wrap(client.complete), api=functions, objects_text=api.objects_text,
                                 attempt=k, recorder=ctx.recorder, transcript=transcript, directory=o.prompts_dir,
                                 lmp_budget=o.lmp_budget, max_fn_depth=o.max_fn_depth, helper_cap=agent.helper_cap,
                                 rng=episode_rng(ctx.seed, f"code{k}"))
            if not messages:
                messages = [{"role": "system", "content": system_prompt(max_turns, o.prompts_dir, o.examples)},
                            {"role": "user", "content": question(session.objects_text(), goal)}]
            before = [len(c.records) for c in clients]
            made = len(meter.calls)
            ran = _turn(session, api, messages, tools, goal, k, o.plan_budget.max_api_calls, agent.model)
            native = [ToolCall(c.id, c.name, c.arguments).to_message() for c in ran.calls if c.form == "tool_calls"]
            if native and len(meter.calls) > made:  # the call log (transcripts, export) keeps the answer's calls
                meter.calls[made]["tool_calls"] = native
            llm_error = ran.error if isinstance(ran.error, LLMError) else None
            predicate: tuple[bool | None, float | None] = (None, None)
            if llm_error is None:
                try:
                    ctx.world.settle(max_steps=JUDGE_SETTLE_STEPS)  # the state judged, shown and built on
                except Exception:  # noqa: BLE001 - the runner's final evaluation reports a broken world
                    pass
                predicate = agent._predicate(ctx)
            over = meter.exceeded or agent.helper_cap.exceeded
            if ran.finish and llm_error is None and over is None:
                agreed = predicate[0] is True
            feedback: str | None = None
            described: str | None = None
            images = 0
            if multi and not (ran.finish or k == max_turns or over is not None or llm_error is not None):
                scene = scene_text(api)
                seen = views_feedback(o.feedback, views, k, goal, scene, o.prompts_dir,
                                      replace(session, complete=meter.wrap(describer.complete), check=None))
                parts, images, described, llm_error = seen.parts, seen.images, seen.described, seen.llm_error
                over = meter.exceeded or agent.helper_cap.exceeded
                if llm_error is None and over is None:
                    feedback = _feedback(template, k, max_turns - k, scene, described)
                    messages.append({"role": "user", "content": [text_part(feedback)] + parts if parts else feedback})
                    ctx.recorder.text(f"llm/attempt{k}/feedback", feedback)
            error = llm_error if llm_error is not None else ran.error if ran.error is not None else ran.last_error
            new = [r for c, n in zip(clients, before) for r in c.records[n:]]
            error_text = describe(error) if error is not None else None
            error_type, error_status = error_facts(error) if error is not None else (None, None)
            rule = ("llm_budget" if over is not None else "llm_error" if llm_error is not None
                    else ("finish" if says_finish(ran.text) else "answered") if ran.finish
                    else "max_turns" if k == max_turns else "next_turn")
            calls_log = api.call_log[len(api.call_log) - ran.api_calls:] if ran.api_calls else []
            record = AttemptRecord(
                attempt=k, reset=False, error=error_text,
                error_kind=None if error is None else "llm" if isinstance(error, LLMError) else "plan",
                error_type=error_type, error_status=error_status,
                failed_program="planner" if error is not None else None,
                api_error=api_error(error_text, calls_log) if error_text and llm_error is None else None,
                predicate=predicate[0], predicate_progress=predicate[1], rule=rule, primitives=ctx.attempt_primitives,
                api_calls=ran.api_calls, llm_calls=len(new), prompt_tokens=sum(r.prompt_tokens for r in new),
                completion_tokens=sum(r.completion_tokens for r in new), said=ran.said, finish=ran.finish,
                feedback=feedback, images=images if multi else None, described=described, tool_calls=ran.calls)
            turns.append(record)
            agent._record_attempt(ctx, record)
            ctx.recorder.text(f"llm/attempt{k}/api_calls", "\n".join(api.log_text().splitlines()[-ran.api_calls:])
                              if ran.api_calls else "")
            if over is not None:
                stopped, raised = "llm budget", llm_error or over
                break
            if llm_error is not None:
                stopped, raised = "llm error", llm_error
                break
            if ran.finish:
                stopped = FINISHED if says_finish(ran.text) else ANSWERED
                break
            if k == max_turns:
                stopped = TURNS_USED_UP
    finally:
        views.close()
        ctx.notes["llm"] = notes()
        ctx.notes["llm_transcript"] = [c.to_dict() for c in transcript]
    if raised is not None:
        raise raised


def _feedback(template: str, turn: int, left: int, scene: str, described: str | None) -> str:
    """The ``--interaction multi`` message after a turn's calls (``prompts/tools_feedback.txt``;
    the line of ``<<DESCRIBED>>`` left out when ``described`` is None)."""
    text = template.replace("<<TURN>>", str(turn)).replace("<<LEFT>>", str(left)).replace("<<OBJECTS>>", scene.strip())
    if described is None:
        return "\n".join(line for line in text.splitlines() if "<<DESCRIBED>>" not in line).strip() + "\n"
    return text.replace("<<DESCRIBED>>", described.strip()).strip() + "\n"
