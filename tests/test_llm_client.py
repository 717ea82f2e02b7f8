"""capmj.llm against a real OpenAI-compatible HTTP server on 127.0.0.1 (no internet needed)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from capmj.errors import ConfigError, LLMError
from capmj.llm import LLMClient, LLMConfig, cache_key, image_part, text_part
from llm_stub_server import Reply, StubLLMServer, prompt_text

HELLO = [{"role": "system", "content": "You write robot plans."},
         {"role": "user", "content": "Say hello."}]


@pytest.fixture
def server() -> Iterator[StubLLMServer]:
    with StubLLMServer() as stub:
        yield stub


class SleepRecorder:
    """Stands in for time.sleep: records the back-off schedule without waiting."""

    def __init__(self) -> None:
        self.calls: list[float] = []

    def __call__(self, seconds: float) -> None:
        self.calls.append(seconds)


def make_client(server: StubLLMServer, sleeps: SleepRecorder | None = None, **overrides: object
                ) -> LLMClient:
    fields: dict[str, object] = dict(model="openai/stub", api_base=server.base_url,
                                     api_key="sk-local", timeout_s=5.0, max_retries=2)
    fields.update(overrides)
    return LLMClient(LLMConfig(**fields), sleep=sleeps or SleepRecorder())  # type: ignore[arg-type]


def test_completion_through_real_server(server: StubLLMServer) -> None:
    server.script("hello robot")
    client = make_client(server, temperature=0.0, max_tokens=321)
    completion = client.complete(HELLO, purpose="plan")
    assert completion.text == "hello robot"
    assert (completion.cached, completion.attempts, completion.purpose) == (False, 1, "plan")
    assert completion.prompt_tokens > 0 and completion.completion_tokens > 0
    assert completion.cost_usd == 0.0  # unknown model: no price, and no exception
    (body,) = server.requests
    assert body["messages"] == HELLO
    assert body["max_tokens"] == 321 and body["temperature"] == 0.0
    assert server.request_log[0].headers["Authorization"] == "Bearer sk-local"
    usage = client.usage()
    assert (usage.calls, usage.cached_calls, usage.failed_calls) == (1, 0, 0)
    assert usage.prompt_tokens == completion.prompt_tokens
    assert client.records[0].purpose == "plan"


def test_per_call_temperature_and_seed_reach_the_server(server: StubLLMServer) -> None:
    server.script("a", "b")
    client = make_client(server, temperature=0.0)
    client.complete(HELLO)
    client.complete(HELLO, temperature=1.3, seed=123456)
    first, second = server.requests
    assert first["temperature"] == 0.0 and "seed" not in first  # no seed unless one is asked for
    assert second["temperature"] == 1.3 and second["seed"] == 123456
    with pytest.raises(ConfigError, match="temperature"):
        client.complete(HELLO, temperature=-0.5)
    with pytest.raises(ConfigError, match="seed"):
        client.complete(HELLO, seed="7")  # type: ignore[arg-type]
    assert len(server.requests) == 2


def test_seed_is_sent_only_to_providers_that_take_it() -> None:
    from capmj.llm.client import takes_seed

    assert takes_seed("openai/qwen2.5-coder-1.5b", "http://127.0.0.1:8080/v1")  # llama.cpp
    assert takes_seed("ollama/qwen2.5-coder") and takes_seed("gpt-4o-mini")
    assert not takes_seed("anthropic/claude-3-haiku-20240307")  # litellm would reject it


def test_dummy_key_for_local_api_base(server: StubLLMServer) -> None:
    server.script("ok")
    client = make_client(server, api_key=None)
    client.complete(HELLO)
    assert server.request_log[0].headers["Authorization"] == "Bearer sk-local"


def test_server_error_then_success_is_retried(server: StubLLMServer) -> None:
    server.script(500, "second time lucky")
    sleeps = SleepRecorder()
    completion = make_client(server, sleeps, backoff_s=0.25).complete(HELLO)
    assert completion.text == "second time lucky"
    assert completion.attempts == 2
    assert len(server.requests) == 2  # litellm/openai did not retry on their own
    assert sleeps.calls == [0.25]


def test_rate_limit_is_retried(server: StubLLMServer) -> None:
    server.script(429, 503, "ok")
    completion = make_client(server).complete(HELLO)
    assert (completion.text, completion.attempts, len(server.requests)) == ("ok", 3, 3)


def test_persistent_server_error_raises_after_all_attempts(server: StubLLMServer) -> None:
    server.script(500, 500, 500, 500, "never reached")
    sleeps = SleepRecorder()
    client = make_client(server, sleeps, max_retries=3, backoff_s=1.0)
    with pytest.raises(LLMError) as info:
        client.complete(HELLO, purpose="plan")
    message = str(info.value)
    assert message.startswith("openai/stub: InternalServerError:")
    assert message.endswith("after 4 attempts")
    assert len(server.requests) == 4
    assert sleeps.calls == [1.0, 2.0, 4.0]  # exponential and deterministic
    assert client.usage().failed_calls == 1
    assert client.records[0].attempts == 4 and client.records[0].error == message


def test_auth_error_is_not_retried(server: StubLLMServer) -> None:
    server.script(401, "not reached")
    with pytest.raises(LLMError, match=r"AuthenticationError: .* after 1 attempt$"):
        make_client(server).complete(HELLO)
    assert len(server.requests) == 1


def test_timeout_is_retried_then_raises(server: StubLLMServer) -> None:
    server.script(Reply.delayed(3.0, "late"), Reply.delayed(3.0, "late"), "not reached")
    client = make_client(server, timeout_s=0.5, max_retries=1)
    started = time.monotonic()
    with pytest.raises(LLMError, match=r"Timeout.*after 2 attempts"):
        client.complete(HELLO)
    assert time.monotonic() - started < 2.5
    assert len(server.requests) == 2


def test_answer_without_text_is_an_error(server: StubLLMServer) -> None:
    body = {"id": "x", "object": "chat.completion", "created": 0, "model": "stub",
            "choices": [{"index": 0, "message": {"role": "assistant", "content": None},
                         "finish_reason": "stop"}]}
    server.script(Reply.raw(body))
    with pytest.raises(LLMError, match="no text content"):
        make_client(server).complete(HELLO)


def test_second_identical_call_is_served_from_cache(server: StubLLMServer, tmp_path: Path) -> None:
    server.script("cached answer")
    client = make_client(server, cache_dir=tmp_path)
    first = client.complete(HELLO)
    second = make_client(server, cache_dir=tmp_path, api_key="sk-other").complete(HELLO)
    assert len(server.requests) == 1  # the api key is not part of the cache key
    assert (second.text, second.cached, second.attempts) == ("cached answer", True, 0)
    assert (first.prompt_tokens, first.completion_tokens) == (
        second.prompt_tokens, second.completion_tokens)
    files = list(tmp_path.rglob("*.json"))
    assert len(files) == 1 and len(files[0].relative_to(tmp_path).parts) == 3  # ab/cd/<key>.json
    assert "sk-local" not in files[0].read_text()
    client.complete(HELLO)
    usage = client.usage()
    assert (usage.calls, usage.cached_calls) == (2, 1)


@pytest.mark.parametrize("change", ["temperature", "call_temperature", "seed", "max_tokens", "message", "model",
                                    "api_base"])
def test_cache_misses_when_request_changes(server: StubLLMServer, tmp_path: Path,
                                           change: str) -> None:
    server.script("one", "two")
    make_client(server, cache_dir=tmp_path).complete(HELLO, seed=1)
    overrides: dict[str, object] = {"cache_dir": tmp_path}
    messages = HELLO
    sampling: dict[str, object] = {"seed": 1}
    if change == "call_temperature":
        sampling["temperature"] = 0.7
    elif change == "seed":
        sampling["seed"] = 2
    elif change == "temperature":
        overrides["temperature"] = 0.7
    elif change == "max_tokens":
        overrides["max_tokens"] = 100
    elif change == "model":
        overrides["model"] = "openai/stub-2"
    elif change == "api_base":
        overrides["api_base"] = server.base_url.replace("127.0.0.1", "localhost")
    else:
        messages = [HELLO[0], {"role": "user", "content": "Say goodbye."}]
    second = make_client(server, **overrides).complete(messages, **sampling)  # type: ignore[arg-type]
    assert (second.text, second.cached) == ("two", False)
    assert len(server.requests) == 2


def test_seeded_call_replays_from_the_cache_and_seedless_keys_are_unchanged(server: StubLLMServer,
                                                                           tmp_path: Path) -> None:
    server.script("seeded", "unseeded")
    make_client(server, cache_dir=tmp_path).complete(HELLO, temperature=0.9, seed=42)
    make_client(server, cache_dir=tmp_path).complete(HELLO, temperature=0.9)
    again = make_client(server, cache_dir=tmp_path).complete(HELLO, temperature=0.9, seed=42)
    assert (again.text, again.cached) == ("seeded", True) and len(server.requests) == 2
    base = dict(model="m", api_base=None, messages=HELLO, temperature=0.9, max_tokens=10)
    assert cache_key(**base, seed=None) == cache_key(**base)  # type: ignore[arg-type]
    assert cache_key(**base, seed=0) != cache_key(**base)  # type: ignore[arg-type]
    # a request without a seed keeps the key it had before seeds existed (old caches stay valid)
    old = {"format": 1, "model": "m", "api_base": None, "messages": HELLO, "temperature": 0.9, "max_tokens": 10}
    import hashlib

    digest = hashlib.sha256(json.dumps(old, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode())
    assert cache_key(**base) == digest.hexdigest()  # type: ignore[arg-type]


def test_corrupt_cache_file_is_a_miss_and_is_overwritten(server: StubLLMServer,
                                                         tmp_path: Path) -> None:
    server.script("first", "fresh")
    make_client(server, cache_dir=tmp_path).complete(HELLO)
    (entry,) = tmp_path.rglob("*.json")
    for garbage in ("{not json", json.dumps({"text": 5})):
        entry.write_text(garbage)
        completion = make_client(server, cache_dir=tmp_path).complete(HELLO)
        assert completion.cached is False
        assert json.loads(entry.read_text())["text"] == completion.text  # overwritten
        server.script("again")
    assert len(server.requests) == 3


def test_images_are_sent_and_keyed(server: StubLLMServer, tmp_path: Path) -> None:
    png_a, png_b = b"\x89PNG\r\n\x1a\nAAAA", b"\x89PNG\r\n\x1a\nBBBB"
    part = image_part(png_a)
    assert part["type"] == "image_url"
    assert part["image_url"]["url"].startswith("data:image/png;base64,")

    def ask(png: bytes) -> list[dict[str, object]]:
        return [{"role": "user", "content": [text_part("What is on the table?"), image_part(png)]}]

    server.script("a red block", "a blue block")
    client = make_client(server, cache_dir=tmp_path)
    assert client.complete(ask(png_a)).text == "a red block"
    assert client.complete(ask(png_b)).text == "a blue block"
    assert client.complete(ask(png_a)).cached
    assert server.requests[0]["messages"][0]["content"][1] == part
    assert prompt_text(server.requests[0]) == "What is on the table? "
    assert cache_key(model="m", api_base=None, messages=ask(png_a), temperature=0, max_tokens=1) \
        != cache_key(model="m", api_base=None, messages=ask(png_b), temperature=0, max_tokens=1)


def test_responder_hook_routes_by_prompt(server: StubLLMServer) -> None:
    server.respond_with(lambda body: "PLAN" if "plan" in prompt_text(body) else "DESCRIBE")
    client = make_client(server)
    assert client.complete([{"role": "user", "content": "write a plan"}]).text == "PLAN"
    assert client.complete([{"role": "user", "content": "look"}]).text == "DESCRIBE"


def test_exhausted_script_fails_loudly(server: StubLLMServer) -> None:
    with pytest.raises(LLMError, match="stub script exhausted"):
        make_client(server).complete(HELLO)
    assert len(server.requests) == 1


def test_mock_response_works_offline(tmp_path: Path) -> None:
    client = LLMClient(LLMConfig("gpt-4o-mini", mock_response="mocked plan", cache_dir=tmp_path))
    completion = client.complete(HELLO)
    assert completion.text == "mocked plan" and not completion.cached
    assert client.complete(HELLO, mock_response="other").text == "other"
    assert not list(tmp_path.rglob("*.json"))  # mock answers never enter the cache


def test_config_validation() -> None:
    with pytest.raises(ConfigError):
        LLMConfig("m", timeout_s=0)
    with pytest.raises(ConfigError):
        LLMConfig("m", max_retries=-1)
    with pytest.raises(ConfigError):
        LLMClient(LLMConfig("m", mock_response="x")).complete([])


def test_importing_capmj_llm_does_not_import_litellm() -> None:
    probe = "import sys, capmj.llm; print('litellm' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            timeout=60, check=True)
    assert result.stdout.strip() == "False"
