"""Harness failures apart (#49 item 3): every failure label is the agent's or an anomaly, anomalies
never enter the agent's denominator, a provider that fails every call is reported as anomalies,
and a server that is not there stops the run before it starts."""

from __future__ import annotations

import json
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Iterator

import pytest
from llm_stub_server import Reply, StubLLMServer

from capmj.bench.anomalies import ANOMALY, ANOMALY_LABELS, SIDE, headline, is_anomaly, section
from capmj.bench.cli import main
from capmj.bench.failures import LABELS, classify
from capmj.bench.results import stats, summarize
from capmj.records import AttemptRecord, EpisodeRecord, LLMNotes

TASK = "stack-all-blocks-on-a-zone"


def _rec(seed: int, *, success: bool = False, error: str | None = None, error_type: str | None = None,
         attempts: int = 1, llm: LLMNotes | None = None, config: str | None = None) -> EpisodeRecord:
    base = EpisodeRecord(TASK, seed, "llm", "m", success, 1.0 if success else 0.0, 0.0, 0, attempts, 1.0, 2.0, error,
                         llm=llm, error_type=error_type, config=config)
    return EpisodeRecord.of(base, failure=classify(base), config=config)


def test_every_failure_label_is_on_one_side_and_only_harness_failures_are_anomalies() -> None:
    assert set(SIDE) == set(LABELS)  # the audit table classifies every label classify() can return
    assert ANOMALY_LABELS == ("llm_error", "infrastructure")
    assert all(SIDE[lab] != ANOMALY for lab in ("budget", "no_finish", "reporter_false_negative", "physics",
                                                "perception", "sandbox_violation", "wrong_plan"))


@pytest.mark.parametrize(("kwargs", "label", "anomaly"), [
    ({"error": "WorkerCrash: the worker process died", "error_type": "WorkerCrash", "attempts": 0},
     "infrastructure", True),
    ({"error": "EvaluationFailed: the predicate raised", "error_type": "EvaluationFailed"}, "infrastructure", True),
    ({"error": "TaskError: scene could not be built", "error_type": "TaskError", "attempts": 0}, "infrastructure", True),
    ({"error": "LLMError: openai/m: InternalServerError after 4 attempts", "error_type": "LLMError"}, "llm_error", True),
    ({"llm": LLMNotes("m", attempts=(AttemptRecord(attempt=1, error="LLMError: RateLimitError after 4 attempts",
                                              error_kind="llm"),))}, "llm_error", True),
    ({"error": "PlanError: line 2: NameError", "error_type": "NameError"}, "plan_exception", False),
    # the LLM agent re-raises its last attempt's error; anything else escaped its loop: a crash inside capmj
    ({"error": "PlanError: line 2: NameError: name 'x' is not defined", "error_type": "NameError",
      "llm": LLMNotes("m", attempts=(AttemptRecord(attempt=1, error="PlanError: line 2: NameError: name 'x' is not "
                                                   "defined", error_kind="plan", error_type="NameError"),))},
     "plan_exception", False),
    ({"error": "KeyError: 'verdict'", "error_type": "KeyError",
      "llm": LLMNotes("m", attempts=(AttemptRecord(attempt=1),))}, "infrastructure", True),
    ({"error": "RuntimeError: unreachable", "error_type": "MotionFailed"}, "motion", False),
    ({}, "wrong_plan", False),
    ({"success": True}, None, False),
])
def test_records_are_labelled_and_split(kwargs: dict[str, Any], label: str | None, anomaly: bool) -> None:
    rec = _rec(10001, **kwargs)
    assert rec.failure == label and is_anomaly(rec) is anomaly


def test_anomalies_leave_the_denominator_and_are_listed() -> None:
    recs = [_rec(1, success=True), _rec(3, success=True), _rec(5), _rec(7, error="LLMError: x", error_type="LLMError"),
            _rec(9, error="WorkerCrash: died", error_type="WorkerCrash", attempts=0)]
    st = stats(recs)
    assert (st["n"], st["successes"], st["episodes"], st["anomalies"]) == (3, 2, 5, 2)
    assert st["success_rate"] == pytest.approx(2 / 3) and st["denominator"] == "2/3 episodes, 2 anomalies excluded"
    assert st["failures"] == {"wrong_plan": 1} and st["anomaly_labels"] == {"llm_error": 1, "infrastructure": 1}
    found = section(recs, 0.1)
    assert found["count"] == 2 and found["exceeded"] and [a["seed"] for a in found["list"]] == [7, 9]
    assert (headline(found) or "").startswith("WARNING: 2 of 5 episodes (40 %) are anomalies")
    assert not section(recs, 0.5)["exceeded"] and headline(section(recs, 0.5)) is None
    summary = summarize(recs)
    assert summary["profile"]["overall"]["llm m"]["denominator"] == "2/3 episodes, 2 anomalies excluded"


def test_a_provider_failing_every_call_is_reported_as_anomalies_not_agent_failures(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Tried as a new user would: a local endpoint answering HTTP 500 to every chat request. The
    start-up probe passes (the server lists its models), every episode ends with the provider's
    error after the client's retries: anomalies, none in the agent's denominator."""
    out = tmp_path / "run"
    with StubLLMServer(responder=lambda request: Reply.error(500, "internal error")) as server:
        rc = main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "none",
                   "--tasks", TASK, "--seeds", "10001:10005:2", "--out", str(out), "--no-progress", "--no-log",
                   "--workers", "0", "--concurrency", "2", "--llm-cache", str(tmp_path / "cache")])
        assert len(server.requests) == 8  # two episodes, each its planner request tried 1 + 3 times
    printed = capsys.readouterr().out.splitlines()
    assert rc == 0
    assert printed[0].startswith("WARNING: 2 of 2 episodes (100 %) are anomalies (llm_error 2)")
    assert "(0/0 episodes, 2 anomalies excluded" in printed[1]
    summary = json.loads((out / "summary.json").read_text())
    cell = summary["overall"]["llm openai/stub"]
    assert (cell["n"], cell["successes"], cell["anomalies"], cell["success_rate"]) == (0, 0, 2, None)
    assert cell["failures"] == {} and cell["anomaly_labels"] == {"llm_error": 2}
    assert summary["anomalies"]["count"] == 2 and summary["anomalies"]["exceeded"] is True
    assert {a["label"] for a in summary["anomalies"]["list"]} == {"llm_error"}
    md = (out / "summary.md").read_text()
    assert md.startswith("WARNING: 2 of 2 episodes") and "— (n=0, 2 anomalies excluded)" in md
    table = md.split("| Task |")[1].split("## Details")[0]
    assert " 0 % [" not in table  # no 0 % success blamed on the model


class _KeyRefusingServer(ThreadingHTTPServer):
    """An OpenAI-compatible endpoint that refuses every key (HTTP 401), counting chat requests."""

    chats = 0


@pytest.fixture
def refusing() -> Iterator[_KeyRefusingServer]:
    class Handler(BaseHTTPRequestHandler):
        def _refuse(self) -> None:
            body = json.dumps({"error": {"message": "invalid api key", "type": "invalid_request_error"}}).encode()
            self.send_response(401)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def do_GET(self) -> None:  # noqa: N802 - http.server API
            self._refuse()

        def do_POST(self) -> None:  # noqa: N802 - http.server API
            server.chats += 1
            self._refuse()

        def log_message(self, *args: Any) -> None:
            pass

    server = _KeyRefusingServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server
    server.shutdown()
    server.server_close()


def _grid(api_base: str, out: Path, *extra: str) -> int:
    return main(["--agent", "llm", "--model", "openai/stub", "--api-base", api_base, "--tasks", TASK,
                 "--seeds", "10001", "--out", str(out), "--no-progress", "--no-log", "--workers", "0", *extra])


def test_a_refused_key_stops_the_run_at_start_up(refusing: _KeyRefusingServer, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    host, port = refusing.server_address[:2]
    rc = _grid(f"http://{host}:{port}/v1", tmp_path / "run")
    err = capsys.readouterr().err
    assert rc == 2 and refusing.chats == 0
    assert "capmj-bench: error: model openai/stub at http://" in err and "refused the key (HTTP 401" in err
    assert not (tmp_path / "run" / "episodes.jsonl").exists() and not (tmp_path / "run" / "config.json").exists()


def test_an_unreachable_server_stops_the_run_at_start_up_unless_told_not_to_probe(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with StubLLMServer() as gone:
        base = gone.base_url  # a port that was just freed: nothing listens there now
    assert _grid(base, tmp_path / "a") == 2
    err = capsys.readouterr().err
    assert "the server did not answer" in err and "--no-probe" in err
    assert not (tmp_path / "a" / "episodes.jsonl").exists()


def test_the_probe_of_a_cloud_model_is_one_uncached_completion(tmp_path: Path) -> None:
    """Without --api-base the probe asks the model itself (here through the stub's URL, as litellm
    would a provider): a refused key stops the run, an answer lets it start and is never cached."""
    from capmj.bench.probe import probe_completion
    from capmj.errors import ModelUnreachable
    from capmj.llm.config import LLMConfig

    with StubLLMServer() as server:
        cfg = LLMConfig("openai/stub", api_base=server.base_url, api_key="sk-wrong", cache_dir=tmp_path / "cache",
                        backoff_s=0.0)
        server.script(Reply.error(401, "invalid api key"))
        with pytest.raises(ModelUnreachable, match="a probe request failed.*AuthenticationError"):
            probe_completion(cfg)
        server.script("OK")
        probe_completion(cfg)
        assert [r["max_tokens"] for r in server.requests] == [8, 8]
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").rglob("*.json"))
