"""Streamed answers and stop sequences: what lets a slow local model finish (issue #27).

Why streaming: a small model on a few CPU cores writes about ten tokens a second, so a long answer
takes minutes.  Without streaming, the request timeout bounds the *whole* answer and a
long one is thrown away at the timeout and started again from nothing.  Streamed, the timeout is
the HTTP read timeout between two chunks: a request fails only when the server sends nothing
for that long (a stall), and then the text that did arrive is kept on the error.

Why stop sequences are also cut here: a provider that ignores ``stop`` (or a scripted server)
must not let a run-on answer through; the cut is the same either way, so the cached text is too.

Why a repetition guard: a small model at temperature 0 sometimes falls into a loop, writing one
comment line (or a short block) again and again until the token limit: minutes of a CPU server
for nothing (``docs/llm.md``).  No stop
sequence can end it, because the repeated text is not the next example.  :func:`repetition_cut`
finds such a loop at the end of the text; the stream is then closed (the server stops writing)
and the answer keeps one copy of the repeated block.

Why tool calls are assembled here: a streamed answer to a request with ``tools`` sends each call
in pieces (OpenAI's delta format: the first piece of call ``index`` carries its ``id`` and
``name``, the next ones chunks of its ``arguments`` text); :class:`ToolCallParts` joins them by
index, so the calls do not depend on how a provider or litellm rebuilds a stream.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from capmj.llm.records import ToolCall


class StreamCut(Exception):
    """A stream that ended in an exception after ``partial`` had arrived (``error`` is the cause)."""

    def __init__(self, error: Exception, partial: str, chunks: int) -> None:
        super().__init__(f"{type(error).__name__}: {error}")
        self.error = error
        self.partial = partial
        self.chunks = chunks


def _delta(chunk: Any) -> str:
    try:
        content = chunk.choices[0].delta.content
    except (AttributeError, IndexError, KeyError, TypeError):
        return ""
    return content if isinstance(content, str) else ""


def _get(obj: Any, name: str) -> Any:
    """``obj.name`` or ``obj[name]`` (litellm's chunks are objects, a raw delta a dict), else None."""
    if isinstance(obj, dict):
        return obj.get(name)
    return getattr(obj, name, None)


@dataclass
class ToolCallParts:
    """The tool calls of a stream, joined from their pieces (by ``index``, in order of first
    appearance): :meth:`add` each chunk, :meth:`calls` at the end."""

    _parts: dict[int, list[str]] = field(default_factory=dict)
    """index -> [id, name, arguments so far]."""

    def add(self, chunk: Any) -> None:
        try:
            deltas = chunk.choices[0].delta.tool_calls
        except (AttributeError, IndexError, KeyError, TypeError):
            return
        for i, delta in enumerate(deltas or ()):
            index = _get(delta, "index")
            index = index if isinstance(index, int) and not isinstance(index, bool) else i
            part = self._parts.setdefault(index, ["", "", ""])
            function = _get(delta, "function")
            for slot, value in ((0, _get(delta, "id")), (1, _get(function, "name"))):
                if isinstance(value, str) and value and not part[slot]:
                    part[slot] = value
            arguments = _get(function, "arguments")
            if isinstance(arguments, str):
                part[2] += arguments

    def calls(self) -> tuple[ToolCall, ...]:
        """The calls received (a call without an id gets ``call_<index>``)."""
        return tuple(ToolCall(i or f"call_{index}", name, arguments)
                     for index, (i, name, arguments) in sorted(self._parts.items()))


def tool_calls_of(response: Any) -> tuple[ToolCall, ...]:
    """The calls in a whole (not streamed) response's message, in order; () when it has none."""
    try:
        raw = response.choices[0].message.tool_calls
    except (AttributeError, IndexError, KeyError, TypeError):
        return ()
    out = []
    for index, call in enumerate(raw or ()):
        function = _get(call, "function")
        name, arguments, id_ = _get(function, "name"), _get(function, "arguments"), _get(call, "id")
        if isinstance(name, str) and name:
            out.append(ToolCall(id_ if isinstance(id_, str) and id_ else f"call_{index}", name,
                                arguments if isinstance(arguments, str) else ""))
    return tuple(out)


REPEATS = {1: 8, 2: 4, 3: 3, 4: 3}
"""Block length (non-blank lines) -> consecutive copies at the end of an answer that make a loop.

Eight identical lines in a row, or four copies of a two-line block, do not occur in a plan or a
task module a person would write (distinct objects make distinct lines), so a cut there loses
nothing an answer needed."""


def repetition_cut(text: str) -> int | None:
    """Where to cut ``text`` when it ends in a repetition loop (after the first copy), else None.

    Only complete lines count (the last line may still be arriving); lines compare without
    trailing white space; blank lines are skipped.
    """
    lines: list[tuple[int, int, str]] = []  # (start, end, text) of each complete non-blank line
    pos = 0
    for raw in text.split("\n")[:-1]:
        if raw.strip():
            lines.append((pos, pos + len(raw), raw.rstrip()))
        pos += len(raw) + 1
    for period, copies in REPEATS.items():
        if len(lines) < period * copies:
            continue
        block = [t for _, _, t in lines[-period:]]
        first = len(lines) - period  # start index of the earliest copy in the run
        while first - period >= 0 and [t for _, _, t in lines[first - period:first]] == block:
            first -= period
        if (len(lines) - first) // period >= copies:
            return lines[first + period - 1][1]
    return None


def _close(stream: Any) -> None:
    """Close the HTTP response under a litellm stream so the server stops generating."""
    for obj in (stream, getattr(stream, "completion_stream", None)):
        close = getattr(obj, "close", None)
        if callable(close):
            try:
                close()
            except Exception:  # noqa: BLE001,S110 - best effort: the text is already cut
                pass


def drain(stream: Iterable[Any], litellm: Any, messages: Sequence[Any],
          tools: ToolCallParts | None = None) -> Any:
    """Read ``stream`` to its end and rebuild one response (text and usage) from its chunks; the
    pieces of tool calls go to ``tools`` when given.

    Stops early, closing the stream, when the text falls into a repetition loop
    (:func:`repetition_cut`; the caller cuts the text).  Raises :class:`StreamCut` with the text
    received so far when reading fails midway.
    """
    chunks: list[Any] = []
    parts: list[str] = []
    try:
        for chunk in stream:
            chunks.append(chunk)
            if tools is not None:
                tools.add(chunk)
            delta = _delta(chunk)
            parts.append(delta)
            if "\n" in delta and repetition_cut("".join(parts)) is not None:
                _close(stream)
                break
    except Exception as exc:  # noqa: BLE001 - re-raised with what arrived
        raise StreamCut(exc, "".join(parts), len(chunks)) from exc
    if not chunks:
        raise StreamCut(ConnectionError("the stream ended without a chunk"), "", 0)
    return litellm.stream_chunk_builder(chunks, messages=list(messages))


def cut_answer(text: str, stop: Sequence[str]) -> tuple[str, str | None]:
    """The answer as used and cached: cut at the first stop sequence, then at a repetition loop.

    Returns ``(text, cut)`` where ``cut`` is ``"repetition"`` when a loop was cut, else None.
    """
    text = cut_at_stop(text, stop)
    end = repetition_cut(text)
    return (text, None) if end is None else (text[:end], "repetition")


def cut_at_stop(text: str, stop: Sequence[str]) -> str:
    """``text`` up to the first occurrence of any stop sequence (the sequence itself excluded)."""
    ends = [i for i in (text.find(s) for s in stop if s) if i >= 0]
    return text[: min(ends)] if ends else text


__all__ = ["REPEATS", "StreamCut", "ToolCallParts", "cut_answer", "cut_at_stop", "drain", "repetition_cut",
           "tool_calls_of"]
