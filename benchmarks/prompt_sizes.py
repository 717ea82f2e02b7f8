"""Tokens per LMP prompt (gpt-4o-mini tokenizer via litellm, offline) as JSON.

Counts the messages one call of each LMP sends: the system prompt plus the rendered prompt file
with a typical question (a 7-object scene of task A, seed 10001, and its goal).  The VLM reporter
is counted for its text only (image tokens depend on the provider's image pricing; at OpenAI's
"low" detail each image is 85 tokens, at "auto"/"high" a 640x480 image is 765 tokens).

    LITELLM_LOCAL_MODEL_COST_MAP=True python benchmarks/prompt_sizes.py

The original CapRavens planner prompt was ~34 KB, ~10k tokens with 42 examples; its helper LMPs
~3k tokens each (per-call figures from the thesis's code, see docs/llm.md).
"""

from __future__ import annotations

import ast
import json
import os
import sys

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

from capmj.agents.prompt_files import load_prompt, load_system_prompt, prompts_dir  # noqa: E402

MODEL = "gpt-4o-mini"
ORIGINAL_PLANNER_TOKENS = 10_000
OBJECTS = ("objects = ['fixed orange zone with obj_id 1', 'fixed purple zone with obj_id 2', "
           "'movable small cyan block with obj_id 3', 'movable small yellow block with obj_id 4', "
           "'movable small pink block with obj_id 5', 'movable small red block with obj_id 6', "
           "'movable small blue block with obj_id 7']")
GOAL = "Stack all blocks in the orange zone."
QUESTIONS = {
    "planner": f"{OBJECTS}\n# {GOAL}",
    "parse_obj_name": f"{OBJECTS}\n# the blocks left of the purple zone.",
    "parse_position": f"{OBJECTS}\n# a point 0.1 m to the right of the orange zone.",
    "parse_question": f"{OBJECTS}\n# is the pink block in the orange zone?",
    "parse_function": "# define function: blocks = get_blocks_in_area(area).",
    "parse_completion": f"{OBJECTS}\n# goal: {GOAL}",
}


def main() -> dict:
    import litellm

    system = load_system_prompt()
    out: dict = {"model": MODEL, "tokenizer": "litellm.token_counter", "prompts": {}}
    for lmp, question in QUESTIONS.items():
        prompt = load_prompt(lmp)
        text = prompt.render(question)
        messages = [{"role": "system", "content": system}, {"role": "user", "content": text}]
        out["prompts"][lmp] = {
            "tokens": litellm.token_counter(model=MODEL, messages=messages),
            "chars": len(system) + len(text),
            "examples": len(prompt.examples),
        }
    vlm = (prompts_dir() / "vlm_reporter.txt").read_text(encoding="utf-8")
    vlm = vlm.replace("<<OBJECTS>>", "\n".join(f"- {n}" for n in ast.literal_eval(OBJECTS.split("=", 1)[1].strip())))
    vlm = vlm.replace("<<GOAL>>", GOAL)
    out["prompts"]["vlm_reporter_text_only"] = {
        "tokens": litellm.token_counter(model=MODEL, messages=[{"role": "system", "content": system},
                                                               {"role": "user", "content": vlm}]),
        "chars": len(system) + len(vlm), "images": 3,
    }
    planner = out["prompts"]["planner"]["tokens"]
    out["original_planner_tokens_approx"] = ORIGINAL_PLANNER_TOKENS
    out["planner_vs_original"] = round(planner / ORIGINAL_PLANNER_TOKENS, 3)
    out["planner_target_tokens"] = 8000
    out["planner_within_target"] = planner <= 8000
    return out


if __name__ == "__main__":
    json.dump(main(), sys.stdout, indent=2)
    sys.stdout.write("\n")
