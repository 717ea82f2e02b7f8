"""``python -m capmj.bench judge``: build the labelled state set and score a reporter on it.

Files in ``--out DIR``: ``cases.jsonl`` (the set: one case per line, with its layout),
``skipped.jsonl`` (cases a (task, seed) does not have, and why), ``judged.jsonl`` (one verdict per
state, keys :data:`capmj.judge.metrics.RECORD_FIELDS`), ``transcripts.jsonl`` (every LMP call per
state), ``summary.json`` (``overall``, ``tasks.<task>``, ``kinds.<kind>``: ``n``, ``positives``,
``negatives``, ``accuracy``, ``balanced_accuracy``, ``precision``, ``recall``, ``verdict_rate``, ...;
see :mod:`capmj.judge.metrics`), ``summary.md`` and ``config.json``.  Exit codes as the bench's:
0 done, 2 bad input, 3 stopped by --max-tokens / --max-cost-usd.  ``judge report A B`` compares two
runs (:mod:`capmj.judge.compare`); ``judge summarize DIR`` writes the summary of a killed run from
the states it judged.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Sequence

from capmj.atomic import atomic_write
from capmj.errors import ConfigError
from capmj.llm.options import add_llm_options, llm_values

__all__ = ["build_parser", "main", "markdown"]

DEFAULT_TASKS = "benchmark,extended"
DEFAULT_SEEDS = "10001:10011:2"
"""The first five test seeds (the issue's measurement: 20 tasks × 5 test seeds)."""
EXIT_BUDGET = 3


def build_parser() -> argparse.ArgumentParser:
    from capmj.agents.choices import REPORTER_PROMPTS, reporter_prompt_help
    from capmj.judge.cases import KINDS
    from capmj.judge.evaluate import JUDGE_REPORTERS, LLM_REPORTERS

    p = argparse.ArgumentParser(
        prog="python -m capmj.bench judge",
        description="Score a completion reporter on a fixed labelled set of final states: the oracle's state "
                    "(achieved) and perturbations of it that break one success condition (not achieved), plus "
                    "states just inside / outside a tolerance.  Same --tasks and --seeds give the same states.",
        epilog="examples:\n"
               "  python -m capmj.bench judge --reporter predicate --out runs/judge-ref      # the ceiling\n"
               "  python -m capmj.bench judge --reporter text --model openai/qwen2.5-coder-1.5b \\\n"
               "      --api-base http://127.0.0.1:8080/v1 --llm-cache /tmp/llm/cache --out runs/judge-qwen\n"
               "  python -m capmj.bench judge report runs/judge-a runs/judge-b   # paired McNemar test\n"
               "  python -m capmj.bench judge summarize runs/judge-a   # the summary of a killed run",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tasks", default=DEFAULT_TASKS, metavar="SEL",
                   help=f"task names or tags, comma-separated (default: {DEFAULT_TASKS})")
    p.add_argument("--seeds", default=DEFAULT_SEEDS, metavar="SEEDS",
                   help=f"seeds '1,3,5' and/or 'start:stop[:step]' (default: {DEFAULT_SEEDS})")
    p.add_argument("--kinds", default=",".join(KINDS), metavar="K,...",
                   help=f"case kinds to build (default: all: {', '.join(KINDS)}); with --from, 'run' alone "
                        "judges only the run's final states")
    p.add_argument("--reporter", default="text", choices=JUDGE_REPORTERS,
                   help=f"{' / '.join(LLM_REPORTERS)}: the closed loop's reporters; predicate: the task predicate "
                        "(a reference)")
    p.add_argument("--reporter-prompt", dest="reporter_prompt", default="thesis", choices=REPORTER_PROMPTS,
                   help=reporter_prompt_help())
    p.add_argument("--per-task", dest="per_task", type=int, default=None, metavar="N",
                   help="judge a deterministic stratified subset: N cases per task, drawn in turn from oracle, "
                        "negatives, near_inside, near_outside (capmj.judge.subset); default: every case")
    g = p.add_argument_group("LLM options (as for the bench; see docs/llm.md)")
    add_llm_options(g)
    g.add_argument("--cache-only", dest="cache_only", action="store_true",
                   help="answer only from the cache: a missing entry leaves that verdict unknown, no live call")
    g.add_argument("--episode-max-tokens", dest="case_max_tokens", type=int, default=None, metavar="N",
                   help="LLM tokens per judged state; over it the verdict is unknown")
    g.add_argument("--episode-max-cost-usd", dest="case_max_cost_usd", type=float, default=None, metavar="USD",
                   help="LLM cost per judged state (needs a known or declared price)")
    g.add_argument("--price", default=None, metavar="IN,OUT", help="USD per million input,output tokens")
    b = p.add_argument_group("run budget")
    b.add_argument("--max-tokens", dest="max_tokens", type=int, default=None, metavar="N",
                   help=f"stop judging once the run's LLM tokens reach N (exit {EXIT_BUDGET})")
    b.add_argument("--max-cost-usd", dest="max_cost_usd", type=float, default=None, metavar="USD",
                   help=f"stop judging once the run's LLM cost reaches USD (exit {EXIT_BUDGET})")
    p.add_argument("--from", dest="from_run", type=Path, default=None, metavar="RUN_DIR",
                   help="also judge the final states of every episode of a bench result folder (kind 'run', "
                        "labelled by the task predicate); --kinds run: those states only")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="result folder")
    p.add_argument("--log", action="store_true",
                   help="write DIR/rrd/<task>/<seed>-<case>.rrd per judged state: the state, the reporter's "
                        "transcript and the label (open with python -m capmj.replay FILE --open)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def _pct(v: float | None) -> str:
    return "–" if v is None else f"{100 * v:.0f} %"


def markdown(summary: dict[str, Any]) -> str:
    """The short human report: one table per grouping (overall, tasks, kinds)."""
    head = ("| group | n | pos | neg | accuracy | balanced acc. | precision | recall | specificity | verdicts | "
            "sources (code/repair/direct/unknown) | contrasts told apart / blind |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")

    def row(name: str, m: dict[str, Any]) -> str:
        s = m["verdict_sources"]
        src = "/".join(str(s.get(k, 0)) for k in ("code", "repair", "direct", "unknown"))
        if s.get("predicate"):
            src += f" (+{s['predicate']} predicate)"
        contrasts = (f"{m['contrasts_told_apart']} / {m['contrasts_state_blind']} of {m['contrasts']}"
                     if m["contrasts"] else "–")
        return (f"| {name} | {m['n']} | {m['positives']} | {m['negatives']} | {_pct(m['accuracy'])} | "
                f"{_pct(m['balanced_accuracy'])} | {_pct(m['precision'])} | {_pct(m['recall'])} | "
                f"{_pct(m['specificity'])} | {_pct(m['verdict_rate'])} | {src} | {contrasts} |\n")

    o = summary["overall"]
    out = [f"# Reporter judgement: {summary['reporter']}\n\n",
           f"{o['n']} states ({o['positives']} achieved, {o['negatives']} not) from {summary['pairs']} (task, seed) "
           f"pairs; {summary['skipped']} cases skipped (see skipped.jsonl). Tokens: {o['prompt_tokens']} prompt + "
           f"{o['completion_tokens']} completion in {o['calls']} calls ({o['cached_calls']} cached). "
           f"Label mismatches: {o['label_mismatches']}. Errors: {o['errors']}.\n"]
    if summary.get("stopped"):
        out.append(f"\n**Stopped early:** {summary['stopped']}\n")
    out.append("\n## Overall\n\n" + head + row("**overall**", o))
    out.append("\n## Per task\n\n" + head + "".join(row(t, m) for t, m in summary["tasks"].items()))
    out.append("\n## Per kind\n\n" + head + "".join(row(k, m) for k, m in summary["kinds"].items()))
    return "".join(out)


def _write_text(path: Path, text: str) -> None:
    with atomic_write(path, "w", encoding="utf-8") as f:
        f.write(text)


def _write_jsonl(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    _write_text(path, "".join(json.dumps(r, sort_keys=True) + "\n" for r in rows))


def write_summary(out: Path, records: Sequence[dict[str, Any]], cases: Sequence[Any], skipped: int, *,
                  reporter: str, reporter_prompt: str | None, per_task: int | None, stopped: str | None
                  ) -> dict[str, Any]:
    """Write ``summary.json`` and ``summary.md`` of the judged ``records`` of ``cases``; the summary."""
    from capmj.judge.cases import set_digest
    from capmj.judge.metrics import group_metrics, metrics

    summary: dict[str, Any] = {
        "reporter": reporter, "reporter_prompt": reporter_prompt, "per_task": per_task,
        "set_digest": set_digest(list(cases)), "pairs": len({(c.task, c.seed) for c in cases}),
        "cases": len(cases), "judged": len(records), "skipped": skipped, "stopped": stopped,
        "overall": metrics(records), "tasks": group_metrics(records, lambda r: str(r["task"])),
        "kinds": group_metrics(records, lambda r: str(r["kind"]))}
    _write_text(out / "summary.json", json.dumps(summary, indent=2, sort_keys=True) + "\n")
    _write_text(out / "summary.md", markdown(summary))
    return summary


def _read_jsonl(path: Path) -> list[dict[str, Any]]:
    try:
        return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    except FileNotFoundError:
        raise ConfigError(f"{path} not found; give the --out folder of a judge run") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(f"{path}: not JSON lines ({exc})") from None


def summarize(argv: Sequence[str]) -> int:
    """``judge summarize DIR``: rewrite the summary of a judge run from its ``judged.jsonl``.

    A killed run (a slow model, a session that ended) has every verdict it reached in
    ``judged.jsonl`` and the set in ``cases.jsonl``, but no summary; this writes it, with
    ``stopped`` saying how many states were judged.  It also refreshes the summary of a finished
    run after the figures gained a key."""
    from capmj.judge.cases import JudgeCase

    p = argparse.ArgumentParser(prog="python -m capmj.bench judge summarize", description=summarize.__doc__)
    p.add_argument("dir", type=Path, help="the --out folder of a judge run")
    out = p.parse_args(list(argv)).dir
    cases = [JudgeCase.from_dict(c) for c in _read_jsonl(out / "cases.jsonl")]
    records = _read_jsonl(out / "judged.jsonl")
    if not records:
        raise ConfigError(f"{out / 'judged.jsonl'} has no judged state")
    config = json.loads((out / "config.json").read_text()) if (out / "config.json").is_file() else {}
    skipped = len(_read_jsonl(out / "skipped.jsonl")) if (out / "skipped.jsonl").is_file() else 0
    before = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else {}
    stopped = before.get("stopped") or (None if len(records) >= len(cases) else (  # a budget stop keeps its reason
        f"interrupted: {len(records)} of {len(cases)} states judged (summarized from judged.jsonl)"))
    summary = write_summary(out, records, cases, skipped, reporter=str(records[0].get("reporter")),
                            reporter_prompt=records[0].get("reporter_prompt"),
                            per_task=config.get("per_task"), stopped=stopped)
    print(f"summarized {len(records)}/{len(cases)} judged states: balanced accuracy "
          f"{_pct(summary['overall']['balanced_accuracy'])}; wrote {out / 'summary.md'}", file=sys.stderr)
    return 0


def run(args: argparse.Namespace, argv: Sequence[str]) -> int:
    from capmj.bench.seeds import parse_seeds
    from capmj.judge.evaluate import Judge, JudgeConfig
    from capmj.judge.judgeset import build_set
    from capmj.tasks import registry

    seeds = parse_seeds(args.seeds)
    tasks = registry.resolve(args.tasks)
    if not tasks:
        raise ConfigError(f"task selection {args.tasks!r} matches no task; see python -m capmj.bench --list")
    kinds = tuple(k.strip() for k in args.kinds.split(",") if k.strip())
    llm = llm_values(args)
    config = JudgeConfig(reporter=args.reporter, model=llm["model"], api_base=llm["api_base"],
                         temperature=llm["temperature"] or 0.0,
                         **{k: llm[k] for k in ("timeout_s", "max_tokens") if llm[k] is not None},
                         cache_dir=llm["cache_dir"], cache_only=bool(args.cache_only),
                         case_max_tokens=args.case_max_tokens, case_max_cost_usd=args.case_max_cost_usd,
                         price=args.price, reporter_prompt=args.reporter_prompt)
    if args.per_task is not None and args.per_task < 1:
        raise ConfigError(f"--per-task must be >= 1, got {args.per_task}")
    from capmj.judge.fromrun import RUN_KIND, run_cases

    if RUN_KIND in kinds and args.from_run is None:
        raise ConfigError(f"--kinds {RUN_KIND} needs --from RUN_DIR (the run whose final states to judge)")
    synthetic = tuple(k for k in kinds if k != RUN_KIND)
    out: Path = args.out
    judge = Judge(config, log_dir=out / "rrd" if args.log else None)
    out.mkdir(parents=True, exist_ok=True)
    cases: list[Any] = []
    skipped: list[dict[str, Any]] = []
    if synthetic:  # `--from R --kinds run`: only the run's states, no set to build
        try:
            the_set = build_set(tasks, seeds, kinds=synthetic, progress=not args.no_progress)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None
        cases = list(the_set.cases)
        if args.per_task is not None:
            from capmj.judge.subset import stratified

            cases = stratified(cases, args.per_task)
        skipped = [s.__dict__ for s in the_set.skipped]
    if args.from_run is not None:
        extra, problems = run_cases(args.from_run)
        cases += extra
        skipped += [{"kind": RUN_KIND, "reason": p} for p in problems]
    _write_jsonl(out / "cases.jsonl", [c.to_dict() for c in cases])
    _write_jsonl(out / "skipped.jsonl", skipped)
    records, transcripts, stopped = _judge_all(judge, cases, args, out)
    _write_jsonl(out / "judged.jsonl", records)
    _write_jsonl(out / "transcripts.jsonl", transcripts)
    summary = write_summary(out, records, cases, len(skipped), reporter=config.label,
                            reporter_prompt=config.reporter_prompt, per_task=args.per_task, stopped=stopped)
    _write_text(out / "config.json", json.dumps({"argv": list(argv), "tasks": tasks, "seeds": seeds,
                                                       "kinds": kinds, "per_task": args.per_task,
                                                       "config": config.__dict__},
                                                      indent=2, sort_keys=True) + "\n")
    o = summary["overall"]
    print(f"judged {len(records)}/{len(cases)} states: balanced accuracy {_pct(o['balanced_accuracy'])}, "
          f"accuracy {_pct(o['accuracy'])}, verdicts {_pct(o['verdict_rate'])}; wrote {out / 'summary.md'}",
          file=sys.stderr)
    return EXIT_BUDGET if stopped else 0


def _judge_all(judge: Any, cases: list[Any], args: argparse.Namespace, out: Path
               ) -> tuple[list[dict[str, Any]], list[dict[str, Any]], str | None]:
    """Judge the cases in order.  Each verdict and transcript is appended to ``judged.jsonl`` /
    ``transcripts.jsonl`` as it arrives (a small local model takes minutes per state, so a killed
    run keeps every state judged so far); the caller rewrites both files whole at the end."""
    journals = [out / "judged.jsonl", out / "transcripts.jsonl"]
    for path in journals:
        path.write_text("", encoding="utf-8")
    bar: Any = None
    if not args.no_progress and cases:
        from tqdm import tqdm

        bar = tqdm(total=len(cases), file=sys.stderr, unit="state", dynamic_ncols=True, desc="judging")
    records: list[dict[str, Any]] = []
    transcripts: list[dict[str, Any]] = []
    tokens, cost, stopped = 0, 0.0, None
    try:
        for case in cases:
            if args.max_tokens is not None and tokens >= args.max_tokens:
                stopped = f"--max-tokens {args.max_tokens} reached ({tokens} tokens) after {len(records)} states"
                break
            if args.max_cost_usd is not None and cost >= args.max_cost_usd:
                stopped = f"--max-cost-usd {args.max_cost_usd:g} reached ({cost:.4f} USD) after {len(records)} states"
                break
            rec, calls = judge.judge(case)
            records.append(rec)
            transcripts.append({"task": case.task, "seed": case.seed, "case": case.case, "calls": calls})
            for path, row in zip(journals, (rec, transcripts[-1])):
                with open(path, "a", encoding="utf-8") as f:
                    f.write(json.dumps(row, sort_keys=True) + "\n")
            tokens += rec["prompt_tokens"] + rec["completion_tokens"]
            cost += rec["cost_usd"] or 0.0
            if bar is not None:
                right = sum(r["correct"] for r in records)
                bar.set_postfix_str(f"correct {100 * right / len(records):.0f}%", refresh=False)
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return records, transcripts, stopped


def main(argv: Sequence[str] | None = None) -> int:
    from capmj.llm.keys import take_secrets

    take_secrets()  # reporters' checking code runs in this process: no key in its environment
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "report":
        from capmj.judge.compare import main as compare_main

        return compare_main(argv[1:])
    try:
        if argv and argv[0] == "summarize":
            return summarize(argv[1:])
        return run(build_parser().parse_args(argv), argv)
    except ConfigError as exc:
        print(f"capmj-bench judge: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
