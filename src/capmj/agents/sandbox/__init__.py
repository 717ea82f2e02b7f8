"""The only way capmj runs LLM-written code: a checked, rewritten, budgeted ``exec``.

Why this design (and not just ``exec`` with empty builtins): LLM code is untrusted in two ways.
It can reach the interpreter (``().__class__.__bases__``, ``np.load``, frames) and it can
accidentally never finish or allocate the machine to death (``while True``, ``[0] * 10**10``).
So each run goes through four layers:

1. **Static allow-list** (:func:`check_code`): only plain statements/expressions parse through;
   imports, classes, ``global``, ``with``, ``yield``/``async``, ``finally``, dunder names, any
   ``_private`` attribute and known dangerous names/attributes are rejected with their line.
2. **Rewrite**: ``*``, ``**``, ``<<`` and ``+`` (and their augmented forms) become calls of
   guards that refuse results above ``max_elements`` elements / 10**6 bits *before* computing
   them; every ``while`` iteration counts as an executed line; set displays become
   insertion-ordered sets (same iteration order in every process); a few growing methods (``arr.repeat``,
   ``s.ljust``, ``sep.join`` ...) are checked.  Guard names start with ``__`` which user code
   can never write, because the check runs first.
3. **Facades, not modules**: ``np``, ``math``, ``itertools``, ``shapely`` are read-only
   namespaces of vetted functions; allocating numpy constructors and infinite iterators are
   size-capped.  Builtins are a fresh curated dict each run, so nothing leaks between runs.
4. **Budgets at run time**, deterministic first: a ``sys.settrace`` tracer (only sandbox
   frames) counts executed lines, the guards sum allocated elements, env functions count API
   calls; wall time is a backstop that stops while env functions run.  Violations raise an
   internal ``BaseException`` that ``except Exception`` cannot swallow.

Everything surfaces as :class:`PlanError` / :class:`BudgetExceeded` ("ErrorClass: message",
1-based line in the submitted code).  Known gaps, on purpose: C-level work that is slow but
bounded (big numpy ops, ``shapely`` buffers with huge resolutions, format widths like
``f"{x:>1000000000}"``) is not interruptible; run plans in a subprocess for hard isolation.
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
