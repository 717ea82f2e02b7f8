"""A scripted, OpenAI-compatible chat-completions server on 127.0.0.1, for tests.

Why a real HTTP server instead of mocking litellm: the LLM client's job is to survive what real
providers do (HTTP 5xx, 429, hung connections) through litellm's real HTTP stack, and only a real
socket exercises that.  Nothing here talks to the internet.

Usage (litellm/``capmj.llm`` settings: ``model="openai/stub"``, ``api_base=server.base_url``,
``api_key="sk-local"``)::

    with StubLLMServer() as server:
        server.script("first answer", 500, Reply.delayed(2.0, "too late"), "fourth answer")
        ...                                  # make calls against server.base_url
        assert len(server.requests) == 4     # JSON bodies the server received, in order

Behaviours are consumed one per request, in order.  A scripted item is a ``str`` (answer text),
an ``int`` (HTTP error status, e.g. 500 or 429) or a :class:`Reply`.  When the script is empty
the ``responder`` hook decides (``callable(request_json) -> str | Reply``, e.g. to route by prompt
content in end-to-end tests), else ``default_text``; with neither the server answers HTTP 400
"stub script exhausted" (not retried by clients, so a test fails loudly instead of looping).

A reply may also carry function calls (``Reply.calls``): streamed, each call arrives in OpenAI's
delta format (its ``id`` and ``name`` first, then its ``arguments`` text in pieces), else as the
message's ``tool_calls``.  The ``tools`` a request offered are in its body (:func:`offered_tools`),
so a responder can build its calls from the schemas it was sent.

Usage tokens in answers are approximate (characters / 4) but always present.
"""

from __future__ import annotations

import json
import re
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

__all__ = [
    "RecordedRequest",
    "Reply",
    "Responder",
    "StubLLMServer",
    "completion_body",
    "iter_prompts",
    "offered_tools",
    "prompt_text",
]


@dataclass(frozen=True)
class Reply:
    """One scripted behaviour of the server for one request.

    ``status`` != 200 answers an OpenAI-style error body with ``error_message``; ``headers`` are
    extra response headers (e.g. ``{"Retry-After": "2"}`` on a 429); ``delay_s`` waits
    before answering (to trigger client timeouts); ``body`` replaces the whole 200 JSON answer
    (e.g. to send a completion without text content).
    """

    text: str | None = None
    status: int = 200
    delay_s: float = 0.0
    error_message: str = "stub error"
    body: dict[str, Any] | None = None
    headers: dict[str, str] | None = None
    token_interval_s: float = 0.0
    """Streamed requests: seconds between two chunks (one per word of ``text``)."""
    stall_after: int | None = None
    """Streamed requests: after this many chunks, send nothing more (hold the connection)."""
    tool_calls: tuple[tuple[str, str], ...] = ()
    """Function calls answered, in order: (name, arguments as JSON text)."""

    @staticmethod
    def answer(text: str) -> Reply:
        return Reply(text=text)

    @staticmethod
    def error(status: int, message: str = "stub error") -> Reply:
        return Reply(status=status, error_message=message)

    @staticmethod
    def delayed(seconds: float, text: str = "(late answer)") -> Reply:
        return Reply(text=text, delay_s=seconds)

    @staticmethod
    def raw(body: dict[str, Any]) -> Reply:
        return Reply(body=body)

    @staticmethod
    def calls(*calls: tuple[str, Any], text: str | None = None) -> Reply:
        """An answer calling functions: ``(name, arguments)`` pairs, arguments a dict (sent as its
        JSON) or a JSON text sent as it is; ``text`` the content beside them (None: none)."""
        return Reply(text=text, tool_calls=tuple((name, args if isinstance(args, str) else json.dumps(args))
                                                 for name, args in calls))

    @staticmethod
    def trickle(text: str, interval_s: float, stall_after: int | None = None) -> Reply:
        """A streamed answer, one word every ``interval_s``; silent after ``stall_after`` words."""
        return Reply(text=text, token_interval_s=interval_s, stall_after=stall_after)


Responder = Callable[[dict[str, Any]], "str | Reply"]


@dataclass(frozen=True)
class RecordedRequest:
    """One request as the server saw it (recorded on arrival, before any delay)."""

    path: str
    headers: dict[str, str]
    body: dict[str, Any]
    received_at: float = field(default_factory=time.monotonic)


def _as_reply(item: str | int | Reply) -> Reply:
    if isinstance(item, Reply):
        return item
    if isinstance(item, bool) or not isinstance(item, (str, int)):
        raise TypeError(f"script items are str, int or Reply, not {type(item).__name__}")
    return Reply(text=item) if isinstance(item, str) else Reply.error(item)


def _text_of(content: object) -> str:
    """Plain text of a message ``content`` (string or list of OpenAI content parts)."""
    if isinstance(content, str):
        return content
    if isinstance(content, list):
        return " ".join(str(p.get("text", "")) for p in content if isinstance(p, dict))
    return ""


def prompt_text(request_json: dict[str, Any]) -> str:
    """All message text of a request joined by newlines; handy inside responders."""
    messages = request_json.get("messages") or []
    return "\n".join(_text_of(m.get("content")) for m in messages if isinstance(m, dict))


def offered_tools(request_json: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The functions a request offered as ``tools``, by name: {name: its JSON Schema ``parameters``}."""
    return {t["function"]["name"]: t["function"].get("parameters", {}) for t in request_json.get("tools") or ()
            if isinstance(t, dict) and t.get("type") == "function"}


def _call_id(serial: int, index: int) -> str:
    return f"call_stub_{serial}_{index}"


def completion_body(request_json: dict[str, Any], text: str, serial: int,
                    tool_calls: tuple[tuple[str, str], ...] = ()) -> dict[str, Any]:
    """An OpenAI ``chat.completion`` JSON object answering ``text`` (and ``tool_calls``)."""
    prompt_tokens = len(prompt_text(request_json)) // 4 + 1
    completion_tokens = (len(text) + sum(len(n) + len(a) for n, a in tool_calls)) // 4 + 1
    message: dict[str, Any] = {"role": "assistant", "content": text if text or not tool_calls else None}
    if tool_calls:
        message["tool_calls"] = [{"id": _call_id(serial, i), "type": "function",
                                  "function": {"name": name, "arguments": args}}
                                 for i, (name, args) in enumerate(tool_calls)]
    return {
        "id": f"chatcmpl-stub-{serial}",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": str(request_json.get("model", "stub")),
        "choices": [
            {
                "index": 0,
                "message": message,
                "finish_reason": "tool_calls" if tool_calls else "stop",
            }
        ],
        "usage": {
            "prompt_tokens": prompt_tokens,
            "completion_tokens": completion_tokens,
            "total_tokens": prompt_tokens + completion_tokens,
        },
    }


class StubLLMServer:
    """Context manager running the stub server in a daemon thread on an ephemeral port."""

    def __init__(self, *, responder: Responder | None = None,
                 default_text: str | None = None) -> None:
        self._lock = threading.Lock()
        self._queue: deque[Reply] = deque()
        self._log: list[RecordedRequest] = []
        self._responder = responder
        self._default_text = default_text
        self._stopping = threading.Event()
        self._httpd: ThreadingHTTPServer | None = None
        self._thread: threading.Thread | None = None

    # -- scripting -------------------------------------------------------------------------
    def script(self, *items: str | int | Reply) -> StubLLMServer:
        """Append behaviours, consumed one per request in order.  Returns ``self``."""
        replies = [_as_reply(i) for i in items]
        with self._lock:
            self._queue.extend(replies)
        return self

    def respond_with(self, responder: Responder | None) -> None:
        """Set (or clear) the hook used when the script is empty."""
        with self._lock:
            self._responder = responder

    def reset(self) -> None:
        """Forget the script and the recorded requests."""
        with self._lock:
            self._queue.clear()
            self._log.clear()

    @property
    def pending(self) -> int:
        """Scripted behaviours not consumed yet."""
        with self._lock:
            return len(self._queue)

    # -- inspection ------------------------------------------------------------------------
    @property
    def requests(self) -> list[dict[str, Any]]:
        """JSON bodies of every chat request received so far, oldest first (a copy)."""
        with self._lock:
            return [r.body for r in self._log]

    @property
    def request_log(self) -> list[RecordedRequest]:
        """Every request with path and headers (a copy)."""
        with self._lock:
            return list(self._log)

    @property
    def base_url(self) -> str:
        """``http://127.0.0.1:<port>/v1``, the ``api_base`` to give clients."""
        if self._httpd is None:
            raise RuntimeError("StubLLMServer is not running; use it as a context manager")
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/v1"

    # -- lifecycle -------------------------------------------------------------------------
    def start(self) -> StubLLMServer:
        if self._httpd is not None:
            return self
        self._stopping.clear()
        httpd = ThreadingHTTPServer(("127.0.0.1", 0), _make_handler(self))
        httpd.daemon_threads = True
        self._httpd = httpd
        self._thread = threading.Thread(target=httpd.serve_forever, args=(0.02,),
                                        name="stub-llm", daemon=True)  # fast shutdown()
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop serving; requests still sleeping in a delay are abandoned at once."""
        if self._httpd is None:
            return
        self._stopping.set()
        self._httpd.shutdown()
        self._httpd.server_close()
        if self._thread is not None:
            self._thread.join(timeout=5)
        self._httpd = None
        self._thread = None

    def __enter__(self) -> StubLLMServer:
        return self.start()

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # -- used by the handler ---------------------------------------------------------------
    def _next_reply(self, record: RecordedRequest) -> tuple[Reply, int]:
        with self._lock:
            self._log.append(record)
            serial = len(self._log)
            if self._queue:
                return self._queue.popleft(), serial
            responder, default = self._responder, self._default_text
        if responder is not None:
            return _as_reply(responder(record.body)), serial
        if default is not None:
            return Reply(text=default), serial
        return Reply.error(400, "stub script exhausted"), serial


def _make_handler(server: StubLLMServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: object) -> None:  # noqa: A002 - silence stderr
            return

        def _send_json(self, status: int, payload: dict[str, Any],
                       headers: dict[str, str] | None = None) -> None:
            data = json.dumps(payload).encode()
            try:
                self.send_response(status)
                for key, value in (headers or {}).items():
                    self.send_header(key, value)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)
            except (BrokenPipeError, ConnectionResetError):  # client gave up (timeout)
                pass

        def _error(self, status: int, message: str, headers: dict[str, str] | None = None) -> None:
            error = {"message": message, "type": "stub_error", "code": status}
            self._send_json(status, {"error": error}, headers)

        def _stream(self, body: dict[str, Any], reply: Reply, serial: int) -> None:
            """Server-sent events as OpenAI streams them: one chunk per word, usage, [DONE]."""
            full = completion_body(body, reply.text or "", serial, reply.tool_calls)
            self.send_response(200)
            self.send_header("Content-Type", "text/event-stream")
            self.send_header("Cache-Control", "no-cache")
            self.end_headers()
            base = {"id": full["id"], "object": "chat.completion.chunk", "created": full["created"],
                    "model": full["model"]}

            def send(payload: dict[str, Any] | str) -> None:
                data = payload if isinstance(payload, str) else json.dumps(payload)
                self.wfile.write(f"data: {data}\n\n".encode())
                self.wfile.flush()

            words = re.findall(r"\S+\s*|\s+", reply.text or "")
            try:
                for i, word in enumerate(words):
                    if reply.stall_after is not None and i >= reply.stall_after:
                        server._stopping.wait(3600)  # silent until the client gives up or we stop
                        return
                    delta = {"role": "assistant", "content": word} if i == 0 else {"content": word}
                    send({**base, "choices": [{"index": 0, "delta": delta, "finish_reason": None}]})
                    if reply.token_interval_s and server._stopping.wait(reply.token_interval_s):
                        return
                for index, (name, args) in enumerate(reply.tool_calls):  # OpenAI's pieces of a call
                    first = {"index": index, "id": _call_id(serial, index), "type": "function",
                             "function": {"name": name, "arguments": ""}}
                    pieces = [{"index": index, "function": {"arguments": args[i:i + 7]}} for i in range(0, len(args), 7)]
                    for piece in [first, *pieces]:
                        delta = {"tool_calls": [piece]}
                        if not words and index == 0 and piece is first:
                            delta["role"] = "assistant"
                        send({**base, "choices": [{"index": 0, "delta": delta, "finish_reason": None}]})
                finish = "tool_calls" if reply.tool_calls else "stop"
                send({**base, "choices": [{"index": 0, "delta": {}, "finish_reason": finish}]})
                if (body.get("stream_options") or {}).get("include_usage"):
                    send({**base, "choices": [], "usage": full["usage"]})
                send("[DONE]")
            except (BrokenPipeError, ConnectionResetError):
                return  # the client gave up

        def do_GET(self) -> None:  # noqa: N802 - http.server API
            if self.path.rstrip("/").endswith("/models"):
                models = [{"id": "stub", "object": "model"}]
                self._send_json(200, {"object": "list", "data": models})
            else:
                self._error(404, f"no route {self.path}")

        def do_POST(self) -> None:  # noqa: N802 - http.server API
            if not self.path.rstrip("/").endswith("/chat/completions"):
                self._error(404, f"no route {self.path}")
                return
            raw = self.rfile.read(int(self.headers.get("Content-Length") or 0))
            try:
                body = json.loads(raw or b"{}")
            except json.JSONDecodeError:
                self._error(400, "request body is not JSON")
                return
            record = RecordedRequest(self.path, dict(self.headers.items()), body)
            try:
                reply, serial = server._next_reply(record)
            except Exception as exc:  # a broken responder must not hang the client
                self._error(500, f"stub responder failed: {type(exc).__name__}: {exc}")
                return
            if reply.delay_s > 0 and server._stopping.wait(reply.delay_s):
                return  # server is shutting down
            if reply.status != 200:
                self._error(reply.status, reply.error_message, reply.headers)
            elif reply.body is not None:
                self._send_json(200, reply.body)
            elif body.get("stream"):
                self._stream(body, reply, serial)
            else:
                self._send_json(200, completion_body(body, reply.text or "", serial, reply.tool_calls))

    return Handler


def iter_prompts(server: StubLLMServer) -> Iterator[str]:
    """Prompt text of every received request, oldest first."""
    for body in server.requests:
        yield prompt_text(body)
