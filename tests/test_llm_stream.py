"""Streamed answers and stop sequences through a real HTTP server on 127.0.0.1 (issue #27).

The server's answers are scripted fixtures; the client, litellm, HTTP and the cache are real.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from capmj.errors import LLMError
from capmj.llm import LLMClient, LLMConfig
from capmj.llm.stream import cut_at_stop
from llm_stub_server import Reply, StubLLMServer

HELLO = [{"role": "user", "content": "Write the plan."}]


@pytest.fixture
def server() -> Iterator[StubLLMServer]:
    with StubLLMServer() as stub:
        yield stub


def client(server: StubLLMServer, **kw: object) -> LLMClient:
    fields: dict[str, object] = dict(model="openai/stub", api_base=server.base_url, timeout_s=10.0, max_retries=0)
    fields.update(kw)
    return LLMClient(LLMConfig(**fields))  # type: ignore[arg-type]


def test_a_slow_stream_is_read_to_the_end_with_a_short_stall_timeout(server: StubLLMServer) -> None:
    """300 words at one every 0.2 s: a 60 s answer, each gap far below the 10 s timeout."""
    text = " ".join(f"w{i}" for i in range(300))
    server.script(Reply.trickle(text, 0.2))
    t0 = time.monotonic()
    done = client(server).complete(HELLO, purpose="plan")
    assert done.text == text and time.monotonic() - t0 > 55
    assert done.completion_tokens > 0 and server.requests[0]["stream"] is True


def test_a_stall_mid_answer_fails_after_the_stall_timeout_keeping_what_arrived(server: StubLLMServer) -> None:
    server.script(Reply.trickle("x = 1\ny = 2\nz = 3", 0.05, stall_after=6))
    c = client(server, timeout_s=2.0)
    t0 = time.monotonic()
    with pytest.raises(LLMError) as err:
        c.complete(HELLO, purpose="plan")
    waited = time.monotonic() - t0
    assert 1.5 < waited < 30, waited
    assert err.value.partial == "x = 1\ny = 2\n" and "characters had arrived" in str(err.value)
    (record,) = c.records
    assert record.error is not None and record.partial == "x = 1\ny = 2\n"


def test_a_streamed_answer_replays_from_the_cache_without_http(server: StubLLMServer, tmp_path: Path) -> None:
    server.script(Reply.trickle("put_first_on_second(a, b)\n", 0.01))
    first = client(server, cache_dir=tmp_path).complete(HELLO, purpose="plan", stop=("\n\nobjects = [",))
    server.reset()
    again = client(server, cache_dir=tmp_path).complete(HELLO, purpose="plan", stop=("\n\nobjects = [",))
    assert server.requests == [] and again.cached and again.text == first.text
    assert again.prompt_tokens == first.prompt_tokens and again.completion_tokens == first.completion_tokens


def test_stop_sequences_are_sent_and_cut_here_too(server: StubLLMServer) -> None:
    """The stub ignores ``stop`` (as some providers do): the client cuts the run-on itself."""
    answer = "put_first_on_second(a, b)\n\nobjects = ['movable small red block with obj_id 9']\n# next goal\n"
    server.script(answer, answer)
    stop = ("\n\nobjects = [",)
    streamed = client(server).complete(HELLO, stop=stop)
    plain = client(server, stream=False).complete(HELLO, stop=stop)
    assert streamed.text == plain.text == "put_first_on_second(a, b)"
    assert server.requests[0]["stop"] == list(stop) and "stream" not in server.requests[1]


def test_cut_at_stop_takes_the_earliest_sequence() -> None:
    assert cut_at_stop("a\n# define x\nb\n# example\n", ("# example", "# define")) == "a\n"
    assert cut_at_stop("no stop here", ("# define",)) == "no stop here"
    assert cut_at_stop("objects = [1]", ()) == "objects = [1]"


def test_the_bench_and_the_generator_share_the_llm_flags(tmp_path: Path) -> None:
    from capmj.bench.cli import build_parser as bench_parser
    from capmj.bench.options import AGENT_OPTIONS as BENCH_AGENT_OPTIONS
    from capmj.generate.cli import parser as generate_parser
    from capmj.llm.options import LLM_OPTIONS, llm_values

    flags = ["--model", "openai/x", "--api-base", "http://127.0.0.1:1/v1", "--llm-timeout", "42",
             "--llm-max-tokens", "99", "--llm-cache", str(tmp_path)]
    gen = llm_values(generate_parser().parse_args(["--mode", "bottom-up", "--out", str(tmp_path / "o"), *flags]))
    bench = llm_values(bench_parser().parse_args(["--agent", "llm", *flags]))
    expected = {"model": "openai/x", "api_base": "http://127.0.0.1:1/v1", "timeout_s": 42.0, "max_tokens": 99,
                "cache_dir": str(tmp_path)}
    assert {k: gen[k] for k in expected} == {k: bench[k] for k in expected} == expected
    assert gen["temperature"] == 0.0 and bench["temperature"] is None  # the bench resolves its defaults later
    assert {o.field for o in LLM_OPTIONS} <= set(BENCH_AGENT_OPTIONS)  # every shared flag reaches the agent


def test_a_repetition_loop_is_cut_and_the_stream_closed_early(server: StubLLMServer, tmp_path: Path) -> None:
    """A model looping on one comment line until its token limit (seen with the 1.5B model):
    the client stops reading after eight copies and keeps one; the cut answer is what is cached."""
    loop = "# put the red block on the blue block\n" * 150  # 8 words per line: 1 200 chunks, 24 s
    server.script(Reply.trickle("put_first_on_second(a, b)\n\n" + loop, 0.02))
    c = client(server, cache_dir=tmp_path)
    t0 = time.monotonic()
    done = c.complete(HELLO, purpose="plan")
    assert time.monotonic() - t0 < 12
    assert done.text == "put_first_on_second(a, b)\n\n# put the red block on the blue block" and done.cut == "repetition"
    assert c.records[-1].cut == "repetition"
    server.reset()
    again = client(server, cache_dir=tmp_path).complete(HELLO, purpose="plan")
    assert again.cached and again.text == done.text and server.requests == []


def test_repetition_cut_needs_a_real_loop() -> None:
    from capmj.llm.stream import repetition_cut

    plan = "".join(f"put_first_on_second(blocks[{i}], zone)\n" for i in range(12))
    assert repetition_cut(plan) is None  # distinct lines
    assert repetition_cut("x = 1\n" * 7) is None  # seven copies: below the line limit
    block = "pick(a)\nplace(a)\n"
    assert repetition_cut("go()\n" + block * 3) is None
    text = "go()\n" + block * 4 + "pick("
    assert text[: repetition_cut(text)] == "go()\npick(a)\nplace(a)"
