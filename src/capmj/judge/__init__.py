"""Reporters as a benchmark of their own (issue #26): a labelled set of final states and a judge.

Reporter accuracy measured inside closed-loop runs depends on which states the planner happened
to reach, so two reporters (or two prompts) cannot be compared there.  This package fixes the
states instead: per (task, seed) the oracle's final state (a positive), deterministic
perturbations of it that break one success condition (negatives), and hard cases just inside and
just outside a tolerance, each checked by the task's own predicate after settling in MuJoCo.

| module | what |
|---|---|
| :mod:`capmj.judge.cases` | the :class:`~capmj.judge.cases.JudgeCase` record, placing and settling a case |
| :mod:`capmj.judge.perturb` | the perturbations of a solved state (displaced, toppled, swapped, ...) |
| :mod:`capmj.judge.judgeset` | building the labelled set for tasks × seeds |
| :mod:`capmj.judge.fromrun` | ``--from RUN_DIR``: a real run's final states as cases |
| :mod:`capmj.judge.metrics` | accuracy, balanced accuracy, precision, recall, Wilson intervals |
| :mod:`capmj.judge.evaluate` | running a reporter (text, vlm, predicate) over the set |
| :mod:`capmj.judge.compare` | ``judge report A B``: two reporters on the same states (McNemar) |
| :mod:`capmj.judge.cli` | ``python -m capmj.bench judge`` |

It sits beside :mod:`capmj.bench` (it uses agents, tasks and sim, and bench only to share the
Wilson interval, the McNemar test and seed parsing); the bench's command line names it as a string
(:data:`capmj.bench.cli.COMMANDS`) and imports none of it.
"""
