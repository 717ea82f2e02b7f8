"""``python -m capmj.bench judge report A B``: two reporters on the same states, exact McNemar test.

Both runs judged the same cases (same ``--tasks``, ``--seeds``, ``--kinds`` give the same set; the
``set_digest`` of the two summaries says whether they did), so their right/wrong outcomes are
paired per case, and only the discordant cases (one reporter right, the other wrong) carry evidence
about which is better: :func:`capmj.bench.stats.mcnemar_exact` on those counts, per task and overall.
Cases only one run judged are counted in ``unpaired``, never compared.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Mapping, Sequence

from capmj.bench.stats import ALPHA, mcnemar_exact
from capmj.errors import ConfigError

__all__ = ["compare", "compare_markdown", "main", "read_run"]

Key = tuple[str, int, str]


def read_run(folder: Path) -> tuple[dict[str, Any], dict[Key, bool]]:
    """A judge run's summary and whether each case ``(task, seed, case)`` was judged right."""
    try:
        summary = json.loads((folder / "summary.json").read_text())
        lines = (folder / "judged.jsonl").read_text().splitlines()
    except FileNotFoundError as exc:
        raise ConfigError(f"{folder} is not a judge result folder (no {Path(exc.filename).name}); "
                          "make one with python -m capmj.bench judge --out DIR") from None
    right = {}
    for line in lines:
        r = json.loads(line)
        right[(str(r["task"]), int(r["seed"]), str(r["case"]))] = bool(r["correct"])
    return summary, right


def _cell(pairs: Sequence[tuple[bool, bool]]) -> dict[str, Any]:
    n = len(pairs)
    only_a = sum(1 for a, b in pairs if a and not b)
    only_b = sum(1 for a, b in pairs if b and not a)
    p = mcnemar_exact(only_a, only_b)
    return {"n": n, "correct_a": sum(a for a, _ in pairs), "correct_b": sum(b for _, b in pairs),
            "only_a": only_a, "only_b": only_b, "p_value": p, "significant": p < ALPHA}


def compare(a: Mapping[Key, bool], b: Mapping[Key, bool]) -> dict[str, Any]:
    """Paired statistics of run ``a`` against run ``b``, per task and overall."""
    common = sorted(set(a) & set(b))
    by_task: dict[str, list[tuple[bool, bool]]] = {}
    for key in common:
        by_task.setdefault(key[0], []).append((a[key], b[key]))
    return {"alpha": ALPHA, "unpaired": len(set(a) ^ set(b)),
            "tasks": {t: _cell(p) for t, p in by_task.items()}, "overall": _cell([(a[k], b[k]) for k in common])}


def compare_markdown(result: Mapping[str, Any]) -> str:
    head = (f"# Reporters compared: A = {result['a']}, B = {result['b']}\n\n"
            f"Exact McNemar test on the cases both judged ({result['unpaired']} unpaired"
            f"{'; the two sets differ' if not result['same_set'] else ''}).\n\n"
            "| group | n | A right | B right | only A | only B | p |\n|---|---|---|---|---|---|---|\n")

    def row(name: str, c: Mapping[str, Any]) -> str:
        star = "" if c["significant"] else " (n.s.)"
        return (f"| {name} | {c['n']} | {c['correct_a']} | {c['correct_b']} | {c['only_a']} | {c['only_b']} | "
                f"{c['p_value']:.3g}{star} |\n")

    return head + row("**overall**", result["overall"]) + "".join(row(t, c) for t, c in result["tasks"].items())


def main(argv: Sequence[str]) -> int:
    p = argparse.ArgumentParser(prog="python -m capmj.bench judge report",
                                description="Compare two judge runs on the same states (exact McNemar test).")
    p.add_argument("a", type=Path, metavar="A")
    p.add_argument("b", type=Path, metavar="B")
    p.add_argument("--out", type=Path, default=None, metavar="DIR", help="also write comparison.json/.md here")
    args = p.parse_args(list(argv))
    try:
        (sa, ra), (sb, rb) = read_run(args.a), read_run(args.b)
    except ConfigError as exc:
        print(f"capmj-bench judge report: error: {exc}", file=sys.stderr)
        return 2
    result = {"a": sa.get("reporter"), "b": sb.get("reporter"),
              "same_set": sa.get("set_digest") == sb.get("set_digest"), **compare(ra, rb)}
    md = compare_markdown(result)
    print(md, end="")
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "comparison.json").write_text(json.dumps(result, indent=2, sort_keys=True) + "\n")
        (args.out / "comparison.md").write_text(md)
    return 0
