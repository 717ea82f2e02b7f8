"""What the ``relations`` reporter prompt can express at best: a human's check of every goal.

``python benchmarks/relations_ceiling.py [--seeds 10001:10011:2] [--out DIR]`` runs ``capmj.bench judge
--reporter-prompt relations`` over the 20 built-in tasks with a scripted local HTTP server that
answers each goal with the check below: written from the goal *text* with the calls the prompt
documents, as a person reading the goal would write it, not from the task predicates.  The figures
are the ceiling of the prompt with a model that maps every goal to its relations perfectly; where
they fall short of 100 % the calls cannot express the goal (a fixture's slots, evenly spaced rows).
A scripted answer is a fixture: these are not a model's figures.  Prints ``summary.json``'s
``overall`` and per-task balanced accuracy as JSON.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from llm_stub_server import StubLLMServer, prompt_text  # noqa: E402

from capmj.bench.cli import main  # noqa: E402

CHECKS: dict[str, str] = {
    "Move all the bigger blocks in the": """
moved = blocks(size="big", start_area="{a1}")
require_inside(moved, "{a2}")
require_unmoved(other_blocks(moved))""",
    "Move all the smaller blocks in the": """
moved = blocks(size="small", start_area="{a1}")
require_inside(moved, "{a2}")
require_unmoved(other_blocks(moved))""",
    "Move all the blocks in the": """
moved = blocks(start_area="{a1}")
require_inside(moved, "{a2}")
require_unmoved(other_blocks(moved))""",
    "Put the blocks in the bowls with matching": """
for b in bowls():
    require_inside(blocks(color=b["color"]), b)
colors = [b["color"] for b in bowls()]
for b in bowls():
    require_outside([x for x in blocks() if x["color"] not in colors], b)""",
    "Put the blocks in the bowls with mismatching": """
for b in bowls():
    require_outside(blocks(color=b["color"]), b)
require_inside(blocks(), bowls())""",
    "Stack all blocks in the": """
require_inside(blocks(), zone("{c}"))
require_stack(blocks())""",
    "Stack only the": """
chosen = blocks(color="{warmth}", size="{size}")
require_inside(chosen, zone("{c}"))
require_stack(chosen)
require_outside(other_blocks(chosen), zone("{c}"))""",
    "Stack all the blocks, which are": """
ref = blocks(color="{ref}")[0]
chosen = blocks_beside(ref, "{side}", 0.05)
require_inside(chosen, zone("{c}"))
require_stack(chosen)
require_outside(other_blocks(chosen), zone("{c}"))""",
    "Stack all the blocks of the same color together": """
for z in zones():
    same = blocks(color=z["color"])
    require_inside(same, z)
    require_stack(same)
    require_outside(other_blocks(same), z)""",
    "Stack blocks of the same size": """
big, small = blocks(size="big"), blocks(size="small")
require_stack(big)
require_stack(small)
if big and big[0]["inside"] == zone("{c1}")["name"]:
    require_inside(big, zone("{c1}"))
    require_inside(small, zone("{c2}"))
else:
    require_inside(big, zone("{c2}"))
    require_inside(small, zone("{c1}"))""",
    "Stack blocks with alternate colors": """
require_inside(blocks(), zone("{c}"))
require_stack(blocks())
require_alternating(blocks(), first_color="{first}")""",
    "Construct two concentric circles": """
require_inside(blocks(), zone())
require_on_table(blocks())
require_circle(blocks(color="{c1}"))
require_circle(blocks(color="{c2}"))""",
    "Construct a 2*2*2 cube": """
require_inside(blocks(), zone())
require_layers(blocks(), [4, 4])""",
    "Construct a 9-4-1": """
require_inside(blocks(), zone())
require_layers(blocks(), [9, 4, 1])""",
    "Construct a circle with suitable radius with alternating {c1} and {c2} blocks around the ball": """
require_on_table(blocks())
require_circle(blocks(), around=ball())
require_alternating(blocks())""",
    "Construct a circle with suitable radius with alternating": """
require_inside(blocks(), zone())
require_on_table(blocks())
require_circle(blocks())
require_alternating(blocks())""",
    "Divide the blocks into groups of": """
for z in zones():
    group = [b for b in blocks() if b["inside"] == z["name"]]
    require_stack(group)
require_inside(blocks(), zones())""",
    "Each L-shaped fixture": """
require_on_table(blocks())""",
    "Place the maximal odd number": """
for z in zones():
    same = blocks(color=z["color"])
    n = len(same) if len(same) % 2 else len(same) - 1
    require_count(same, z, n)
    require_outside(other_blocks(same), z)""",
    "Stack blocks of the same color that has the largest": """
colors = [b["color"] for b in blocks()]
top = max(colors, key=colors.count)
require_inside(blocks(color=top), zone())
require_stack(blocks(color=top))
require_outside(other_blocks(blocks(color=top)), zone())""",
    "Arrange all blocks on the zone bisector": """
require_on_table(blocks())
require_row(blocks())
require_outside(blocks(), zones()[0])
require_outside(blocks(), zones()[1])""",
}
"""Goal prefix -> the check; ``{...}`` are filled from the goal's words by :func:`fill`."""


def fill(goal: str) -> str:
    """The check of ``goal``: the first matching entry of :data:`CHECKS`, its blanks filled from the goal's words."""
    words = goal.rstrip(".").replace(",", "").split()
    for prefix, body in CHECKS.items():
        if re.match(re.sub(r"\\\{\w+\\\}", r"\\S+", re.escape(prefix)), goal):  # a {blank} is one word
            return body.format(**_blanks(goal, words)).strip()
    raise KeyError(goal)


def _blanks(goal: str, words: list[str]) -> dict[str, Any]:
    b: dict[str, Any] = {}
    if " area to the " in goal:
        i = words.index("area")
        b["a1"], b["a2"] = " ".join(words[i - 2:i]), " ".join(words[-3:-1])
    if "zone" in words:
        zi = words.index("zone")
        b["c"] = words[zi - 1]
    if goal.startswith("Stack only the"):
        b["size"], b["warmth"] = words[3], words[6]
    if goal.startswith("Stack all the blocks, which are"):
        b["side"], b["ref"] = words[8], words[11]
    if goal.startswith("Stack blocks of the same size"):
        b["c1"], b["c2"] = words[8], words[11]
    if goal.startswith("Stack blocks with alternate"):
        b["first"] = words[-2]
    if goal.startswith("Construct two concentric"):
        b["c1"], b["c2"] = words[-5], words[-2]
    return b


def run(seeds: str, out: Path) -> dict[str, Any]:
    def answer(request: dict[str, Any]) -> str:
        text = prompt_text(request)
        goal = text[text.rindex("# goal: ") + 8:].splitlines()[0]
        return f"```python\n{fill(goal)}\n```"

    with StubLLMServer(responder=answer) as server:
        rc = main(["judge", "--seeds", seeds, "--out", str(out), "--no-progress", "--reporter", "text",
                   "--reporter-prompt", "relations", "--model", "openai/scripted-human-checks",
                   "--api-base", server.base_url, "--llm-timeout", "30"])
    summary = json.loads((out / "summary.json").read_text())
    return {"exit": rc, "seeds": seeds, "overall": summary["overall"],
            "balanced_accuracy_per_task": {t: v["balanced_accuracy"] for t, v in summary["tasks"].items()}}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="10001:10011:2")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print(json.dumps(run(args.seeds, args.out or Path(tmp) / "judge"), indent=2))
