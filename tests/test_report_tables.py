"""The summary's success tables: Table 5.2 shape for the benchmark tasks, and a second table shaped
like Table 5.4 (generated tasks 1–10 in the spec's order) when generated tasks are in the run."""

from __future__ import annotations

from capmj.bench.report import GENERATED_NUMBERS, markdown
from capmj.bench.results import summarize
from capmj.tasks.builtin import GENERATED_TASKS

SPEC_ORDER = list(GENERATED_TASKS)


def records(task: str, wins: int, n: int = 4, agent: str = "oracle") -> list[dict]:
    return [{"task": task, "seed": 10001 + 2 * k, "agent": agent, "model": None, "success": k < wins,
             "progress": 1.0 if k < wins else 0.5, "primitives": 3, "sim_s": 10.0, "wall_s": 2.0, "error": None}
            for k in range(n)]


def table(md: str, first: str) -> list[list[str]]:
    """The rows (cells) of the table whose header starts with ``| {first} |``."""
    lines = md.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"| {first} |"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_generated_numbers_follow_the_spec():
    assert sorted(GENERATED_NUMBERS, key=GENERATED_NUMBERS.get) == SPEC_ORDER


def test_benchmark_only_run_keeps_the_single_table():
    recs = records("stack-all-blocks-on-a-zone", 4) + records("put-block-into-matching-bowl", 2)
    md = markdown(summarize(recs))
    assert "Table 5.4" not in md and "Generated task" not in md
    rows = table(md, "Task")
    assert [r[0] for r in rows] == ["A stack-all-blocks-on-a-zone", "H put-block-into-matching-bowl", "**Overall**"]
    assert rows[-1][1].startswith("**75 % [")


def test_generated_tasks_get_a_second_table_in_spec_order():
    gen = ["zone-bisector", "build-cube", "build-rectangular-pyramid", "insert-blocks-in-fixture"]
    recs = records("stack-all-blocks-on-a-zone", 4) + records("stack-blocks-of-same-size", 4)
    recs += records("my-plugin-task", 0)
    for k, t in enumerate(gen):
        recs += records(t, k) + records(t, 4, agent="reference")
    md = markdown(summarize(recs))
    bench = table(md, "Task")
    assert [r[0] for r in bench] == ["A stack-all-blocks-on-a-zone", "B stack-blocks-of-same-size", "my-plugin-task",
                                     "**All benchmark tasks**"]
    # pooled over the benchmark rows only: 8 of 12 for the oracle, and no reference episode there
    assert bench[-1][1].startswith("**67 % [") and bench[-1][2] == "**—**"
    gen_rows = table(md, "Generated task")
    assert [r[0] for r in gen_rows] == ["1 build-rectangular-pyramid", "2 build-cube", "9 zone-bisector",
                                        "10 insert-blocks-in-fixture", "**All generated tasks**"]
    header = next(line for line in md.splitlines() if line.startswith("| Generated task |"))
    assert "oracle (n=4)" in header and "reference (n=4)" in header
    assert gen_rows[0][1].startswith("50 % [") and gen_rows[1][1].startswith("25 % [")  # pyramid 2/4, cube 1/4
    assert gen_rows[-1][1].startswith("**38 % [") and gen_rows[-1][2].startswith("**100 % [")  # 6/16, 16/16
    assert md.index("Table 5.2") < md.index("Table 5.4") < md.index("## Details")
    assert "Overall, all 7 tasks: oracle 50 % [" in md  # 14 of 28 oracle episodes


def test_only_generated_tasks():
    md = markdown(summarize(records("build-cube", 3) + records("divide-blocks", 1)))
    assert "Table 5.2" not in md and "Overall, all" not in md
    assert [r[0] for r in table(md, "Generated task")] == ["2 build-cube", "6 divide-blocks", "**All generated tasks**"]
