"""The only way capmj runs LLM-written code: a checked, rewritten, budgeted ``exec``.

Why this design (and not just ``exec`` with empty builtins): LLM code is untrusted in two ways.
It can reach the interpreter (``().__class__.__bases__``, ``np.load``, frames) and it can
accidentally never finish or allocate the machine to death (``while True``, ``[0] * 10**10``).
So each run goes through four layers:

1. **Static allow-list** (:func:`check_code`): only plain statements/expressions parse through;
   imports, classes, ``global``, ``with``, ``yield``/``async``, ``finally``, dunder names, any
   ``_private`` attribute and known dangerous names/attributes are rejected with their line.
2. **Rewrite**: every binary operator and comparison (and the augmented forms) becomes a call
   of a guard that refuses results above ``max_elements`` elements / 10**6 bits *before*
   computing them (arrays broadcast: ``np.ones((n, 1)) + np.ones((1, n))`` is n² elements);
   ``str(x)``, ``repr(x)``, f-string fields, ``%`` and ``str.format`` count the text they would
   make first (``max_text_chars``; a list that holds one inner list a thousand times is a
   thousand times its text), and ``format`` fields that reach attributes or items (``{0.x}``,
   ``{0[y]}``) are refused, when the template is a literal already by the static check;
   every ``while`` iteration counts as an executed line; set displays become
   insertion-ordered sets (same iteration order in every process); a few growing methods (``arr.repeat``,
   ``s.ljust``, ``sep.join`` ...) are checked.  Guard names start with ``__`` which user code
   can never write, because the check runs first.
3. **Facades, not modules**: ``np``, ``math``, ``itertools``, ``shapely`` are read-only
   namespaces of vetted functions; every numpy function counts the arrays it would make (of
   nested lists it is given, and its broadcast or product result) and infinite iterators are
   size-capped; sizes are found without making anything (:mod:`~capmj.agents.sandbox.sizes`).
   Builtins are a fresh curated dict each run, so nothing leaks between runs.
4. **Budgets at run time**, deterministic first: a ``sys.settrace`` tracer (only sandbox
   frames) counts executed lines, the guards sum allocated elements, env functions count API
   calls; wall time is a backstop that stops while env functions run.  Violations raise an
   internal ``BaseException`` that ``except Exception`` cannot swallow.

Everything surfaces as :class:`PlanError` / :class:`BudgetExceeded` ("ErrorClass: message",
1-based line in the submitted code).  Known gaps, on purpose: C-level work that is slow but
bounded (big numpy ops, ``shapely`` buffers with huge resolutions, format widths like
``f"{x:>1000000000}"``) is not interruptible; text made by ``str`` called through an alias
(``s = str; s(x)``, ``map(str, xs)``, ``sorted(xs, key=str)``) is not counted; run plans in a subprocess with a memory
limit for hard isolation.
"""

from __future__ import annotations

from capmj.agents.sandbox.checks import FORBIDDEN_ATTRIBUTES, FORBIDDEN_NAMES, check_code
from capmj.agents.sandbox.extract import extract_code
from capmj.agents.sandbox.facades import PROVIDED_NAMES
from capmj.agents.sandbox.runtime import run_code

# Public and importable from here, but (as before the split into a package) not in __all__.
from capmj.agents.sandbox.session import MAX_INT_BITS as MAX_INT_BITS
from capmj.agents.sandbox.session import SandboxBudget

__all__ = ["FORBIDDEN_ATTRIBUTES", "FORBIDDEN_NAMES", "PROVIDED_NAMES", "SandboxBudget", "check_code",
           "extract_code", "run_code"]
