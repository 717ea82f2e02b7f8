"""capmj's own tasks by name, in the thesis's order: the one place the names are written out.

The ten benchmark tasks A–J (thesis Table 5.1, tag ``benchmark``) and the ten extended tasks 1–10
(Tables 5.3 and 5.4, tag ``extended``: the thesis's generator wrote them, capmj's versions are
written by hand; ``generated-by-llm`` marks what capmj's own generator writes).  The tasks themselves are plugins like any other
(``task_plugins/capmj_tasks``, declared in ``pyproject.toml``'s ``capmj.tasks`` entry points) and
are found through the registry; what the registry cannot say is their letters and numbers, which
reports print in front of the names and order rows by.  Names only: importing this module imports
no plugin, so a report over old results needs no task code.  ``tests/test_registry.py`` checks that
these lists and the registered tasks' tags agree.
"""

from __future__ import annotations

BENCHMARK_TAG = "benchmark"
"""Tag of the benchmark tasks A–J."""
EXTENDED_TAG = "extended"
"""Tag of the extended tasks 1–10: hand-written here, unseen by the planner's few-shot prompt."""
RENAMED_TAGS: dict[str, str] = {"generated": EXTENDED_TAG}
"""Old tag -> new tag.  ``generated`` marked the hand-written tasks 1–10 beside ``generated-by-llm``
on real generator output; a selection by the old name still works, with a warning."""

BENCHMARK_TASKS: tuple[str, ...] = (
    "stack-all-blocks-on-a-zone",                      # A
    "stack-blocks-of-same-size",                       # B
    "stack-blocks-of-same-color",                      # C
    "stack-blocks-by-color-and-size",                  # D
    "stack-blocks-by-relative-position-and-color",     # E
    "move-blocks-between-absolute-positions",          # F
    "move-blocks-between-absolute-positions-by-size",  # G
    "put-block-into-matching-bowl",                    # H
    "put-block-into-mismatching-bowl",                 # I
    "stack-blocks-with-alternate-color",               # J
)
"""The benchmark tasks A–J in the thesis's order."""

TASK_LETTERS: dict[str, str] = dict(zip(BENCHMARK_TASKS, "ABCDEFGHIJ"))
"""The thesis's letter of each benchmark task (Table 5.1), shown in front of its name."""

GENERATED_TASKS: tuple[str, ...] = (
    "build-rectangular-pyramid",                 # 1
    "build-cube",                                # 2
    "construct-circle-with-blocks",              # 3
    "construct-circle-ball-middle",              # 4
    "build-concentric-circles",                  # 5
    "divide-blocks",                             # 6
    "max-odd-number-blocks-in-same-color-zone",  # 7
    "stack-most-color-block",                    # 8
    "zone-bisector",                             # 9
    "insert-blocks-in-fixture",                  # 10
)
"""The extended tasks 1–10 in the thesis's order (Tables 5.3 and 5.4, where they are the generated tasks)."""

GENERATED_NUMBERS: dict[str, int] = {name: k for k, name in enumerate(GENERATED_TASKS, start=1)}
"""The thesis's number of each generated task: its row's order and label in reports."""

__all__ = ["BENCHMARK_TAG", "BENCHMARK_TASKS", "EXTENDED_TAG", "GENERATED_NUMBERS", "GENERATED_TASKS", "RENAMED_TAGS",
           "TASK_LETTERS"]
