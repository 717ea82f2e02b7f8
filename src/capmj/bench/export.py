"""``python -m capmj.bench export DIR --format chat-jsonl``: LLM calls of a run as fine-tuning data;
``export DIR --bundle OUT.zip``: the run's evidence bundle (:mod:`capmj.bench.bundle`).

One JSON line per planner / helper LMP / reporter call that returned a completion, in the OpenAI
chat fine-tuning format: ``messages`` = the messages sent plus the completion as the final
``assistant`` message (with its ``tool_calls`` under ``--policy tools``, whose planner calls also
carry the ``tools`` they offered).  ``metadata`` says where the call came from and how its episode ended
(task, seed, attempt, LMP, success, failure label, reporter verdict of that attempt); with
``--messages-only`` the lines carry ``messages`` alone, as strict uploaders demand.  See
docs/export.md.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Iterator, Sequence

from capmj.agents.api.tool_schemas import tool_schemas
from capmj.bench.results import EPISODES, read_records
from capmj.bench.transcripts import read_calls
from capmj.errors import ConfigError

__all__ = ["FORMATS", "chat_examples", "main"]

FORMATS = ("chat-jsonl",)


def chat_examples(run_dir: str | Path, *, only_success: bool = False,
                  messages_only: bool = False) -> Iterator[dict[str, Any]]:
    """The fine-tuning examples of a result folder, episode by episode, call by call."""
    run_dir = Path(run_dir)
    if not (run_dir / EPISODES).is_file():
        raise ConfigError(f"{run_dir} is not a result folder (no {EPISODES})")
    records, _ = read_records(run_dir / EPISODES)
    records.sort(key=lambda r: (r.task, r.seed))
    for rec in records:
        if only_success and not rec.success:
            continue
        verdicts = {a.attempt: a.verdict for a in rec.llm_attempts}
        try:
            calls = read_calls(run_dir, rec)
        except (OSError, ValueError) as exc:
            raise ConfigError(f"transcript of {rec.task} seed {rec.seed} is unreadable: {exc}") from None
        tools = tool_schemas() if rec.llm is not None and rec.llm.policy == "tools" else None
        for call in calls:
            answer: dict[str, Any] = {"role": "assistant", "content": call["completion"]}
            if call.get("tool_calls"):  # --policy tools: the calls the answer made
                answer["tool_calls"] = call["tool_calls"]
            messages = [dict(m) for m in call["messages"]] + [answer]
            example: dict[str, Any] = {"messages": messages}
            if tools is not None and not messages_only and str(call.get("purpose", "")).startswith("planner#"):
                example["tools"] = tools  # what the planner requests offered (the format's key)
            if not messages_only:
                lmp, _, n = str(call.get("purpose", "")).partition("#")
                example["metadata"] = {
                    "task": rec.task, "seed": rec.seed, "model": rec.model,
                    "attempt": call.get("attempt"), "lmp": lmp, "call": int(n) if n.isdigit() else None,
                    "episode_success": rec.success, "failure": rec.failure,
                    "attempt_verdict": verdicts.get(call.get("attempt")), "cached": call.get("cached"),
                }
            yield example


def _bundle(run_dir: Path, out: Path, with_rrd: bool) -> int:
    from capmj.bench.bundle import write_bundle

    try:
        path = write_bundle(run_dir, out, with_rrd=with_rrd)
    except (ConfigError, OSError) as exc:
        print(f"capmj-bench export: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB)", file=sys.stderr)
    return 0


def main(argv: Sequence[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m capmj.bench export",
                                description="Write every LLM call of a run as a chat transcript (OpenAI fine-tuning "
                                            "JSONL) with its episode's verdict and failure label; or, with --bundle, "
                                            "the run's evidence as one zip file.")
    p.add_argument("dir", type=Path, metavar="DIR")
    p.add_argument("--bundle", type=Path, default=None, metavar="OUT.zip",
                   help="write the run's evidence bundle instead: summary, manifest, episodes, transcripts, the "
                        "report page, versions, evidence.json and the command that reproduces it (docs/bench.md)")
    p.add_argument("--with-rrd", action="store_true", help="with --bundle: also the episodes' .rrd logs")
    p.add_argument("--format", default="chat-jsonl", choices=FORMATS)
    p.add_argument("--only-success", action="store_true", help="only calls of successful episodes")
    p.add_argument("--messages-only", action="store_true", help="lines carry 'messages' only (no metadata)")
    p.add_argument("--out", type=Path, default=None, metavar="FILE", help="output file (default: stdout)")
    args = p.parse_args(list(argv))
    if args.bundle is not None:
        return _bundle(args.dir, args.bundle, args.with_rrd)
    n = 0
    try:
        examples = chat_examples(args.dir, only_success=args.only_success, messages_only=args.messages_only)
        sink = open(args.out, "w", encoding="utf-8") if args.out else sys.stdout
        try:
            for ex in examples:
                sink.write(json.dumps(ex, ensure_ascii=False) + "\n")
                n += 1
        finally:
            if args.out:
                sink.close()
    except (ConfigError, OSError) as exc:
        print(f"capmj-bench export: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    print(f"exported {n} call(s)" + (f" to {args.out}" if args.out else ""), file=sys.stderr)
    return 0
