"""Streamed answers and stop sequences: what lets a slow local model finish (issue #27).

Why streaming: a 1.5B model on two CPU cores writes 8-10 tokens/s, so a 1 500-token answer takes
two and a half minutes.  Without streaming, the request timeout bounds the *whole* answer and a
long one is thrown away at the timeout and started again from nothing.  Streamed, the timeout is
the HTTP read timeout between two chunks: a request fails only when the server sends nothing
for that long (a stall), and then the text that did arrive is kept on the error.

Why stop sequences are also cut here: a provider that ignores ``stop`` (or a scripted server)
must not let a run-on answer through; the cut is the same either way, so the cached text is too.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any


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


def drain(stream: Iterable[Any], litellm: Any, messages: Sequence[Any]) -> Any:
    """Read ``stream`` to its end and rebuild one response (text and usage) from its chunks.

    Raises :class:`StreamCut` with the text received so far when reading fails midway.
    """
    chunks: list[Any] = []
    parts: list[str] = []
    try:
        for chunk in stream:
            chunks.append(chunk)
            parts.append(_delta(chunk))
    except Exception as exc:  # noqa: BLE001 - re-raised with what arrived
        raise StreamCut(exc, "".join(parts), len(chunks)) from exc
    if not chunks:
        raise StreamCut(ConnectionError("the stream ended without a chunk"), "", 0)
    return litellm.stream_chunk_builder(chunks, messages=list(messages))


def cut_at_stop(text: str, stop: Sequence[str]) -> str:
    """``text`` up to the first occurrence of any stop sequence (the sequence itself excluded)."""
    ends = [i for i in (text.find(s) for s in stop if s) if i >= 0]
    return text[: min(ends)] if ends else text


__all__ = ["StreamCut", "cut_at_stop", "drain"]
