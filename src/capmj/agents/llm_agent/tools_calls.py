"""The function calls of a ``--policy tools`` answer, and running one through the planner API.

A model calls a function in one of two forms (:data:`~capmj.records.CALL_FORMS`):

* ``tool_calls``: the answer's OpenAI ``tool_calls`` (each with the provider's id);
* ``content_json``: no ``tool_calls``, but JSON objects ``{"name": ..., "arguments": {...}}`` (or
  ``"parameters"``) in the answer's text, naming an offered function; small models answer so, in
  bare text, in a fenced block or in ``<tool_call>`` tags.  capmj reads them as calls, in the order
  written, and labels them; each gets the id ``json_<turn>_<n>``.

:func:`run_call` runs one call with the logged planner API functions
(:meth:`~capmj.agents.api.planner_api.PlannerAPI.functions`, the plan code's), so it is logged and
budgeted like a call in code and fails with the same errors; its value goes back as JSON (numpy
values as lists and numbers), its error as the error's text.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from capmj.errors import describe
from capmj.llm import ToolCall

__all__ = ["Call", "FINISH", "answer_calls", "content_calls", "plain", "run_call", "says_finish"]

FINISH = "FINISH"
"""The word, alone on a line, with which the model claims the goal holds."""

_FENCED = re.compile(r"```.*?(?:```|\Z)", re.DOTALL)


@dataclass(frozen=True)
class Call:
    """One call to run: the model's id for it, the function's name, its arguments as written
    (JSON text) and the form it came in."""

    id: str
    name: str
    arguments: str
    form: str

    def to_message(self) -> dict[str, Any]:
        """The call as an assistant message's ``tool_calls`` entry."""
        return ToolCall(self.id, self.name, self.arguments).to_message()


def says_finish(text: str) -> bool:
    """Whether FINISH stands alone on a line of ``text`` outside fenced blocks."""
    return any(line.strip() == FINISH for line in _FENCED.sub("", text).splitlines())


def content_calls(text: str, names: Collection[str], turn: int) -> list[Call]:
    """The calls written as JSON objects in ``text`` (``{"name": one of names, "arguments": {...}}``,
    ``"parameters"`` also read, also inside ``{"function": {...}}``; arguments given as a JSON text
    kept as that text), in order."""
    decoder = json.JSONDecoder()
    calls: list[Call] = []
    i = text.find("{")
    while i >= 0:
        try:
            value, end = decoder.raw_decode(text, i)
        except json.JSONDecodeError:
            i = text.find("{", i + 1)
            continue
        if isinstance(value, dict) and isinstance(value.get("function"), dict) and "name" not in value:
            value = value["function"]  # the OpenAI form of a call: {"type": "function", "function": {...}}
        if isinstance(value, dict) and value.get("name") in names:
            args = value.get("arguments", value.get("parameters", {}))
            arguments = args if isinstance(args, str) else json.dumps(args)
            calls.append(Call(f"json_{turn}_{len(calls) + 1}", str(value["name"]), arguments, "content_json"))
        i = text.find("{", end)
    return calls


def answer_calls(text: str, tool_calls: tuple[ToolCall, ...], names: Collection[str], turn: int) -> list[Call]:
    """The calls of an answer: its ``tool_calls`` when it has any, else those written in its text."""
    if tool_calls:
        return [Call(t.id, t.name, t.arguments, "tool_calls") for t in tool_calls]
    return content_calls(text, names, turn)


def plain(value: Any) -> Any:
    """``value`` as JSON data: numpy arrays and numbers as lists and numbers, tuples as lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, float):
        return float(value)
    return value


def run_call(call: Call, functions: Mapping[str, Callable[..., Any]], offered: Collection[str]) -> tuple[
        str | None, BaseException | None]:
    """Run ``call`` with ``functions`` (the logged planner API) when it names an ``offered`` one:
    ``(its value as JSON text, None)`` or ``(None, what it raised)``.  Arguments that are not a JSON
    object, or an unknown name, are a ValueError saying so (the function is not called)."""
    if call.name not in offered or call.name not in functions:
        return None, ValueError(f"there is no function {call.name!r}; the functions: {', '.join(offered)}")
    try:
        args = json.loads(call.arguments) if call.arguments.strip() else {}
    except json.JSONDecodeError as exc:
        return None, ValueError(f"the arguments of {call.name} are not JSON: {exc}")
    if not isinstance(args, dict):
        return None, ValueError(f"the arguments of {call.name} must be a JSON object of named arguments, "
                                f"got {call.arguments[:200]}")
    try:
        value = functions[call.name](**args)
    except Exception as exc:  # noqa: BLE001 - the model is told, as plan code would be
        return None, exc
    try:
        return json.dumps(plain(value), allow_nan=False), None
    except (TypeError, ValueError) as exc:
        return None, ValueError(f"{call.name} returned a value that is not JSON: {describe(exc)}")
