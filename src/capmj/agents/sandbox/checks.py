"""Layers 1 and 2 of the sandbox: the static allow-list check and the AST rewrite.

:func:`check_code` parses plan code and rejects, with the offending line, every construct that
could reach the interpreter (imports, classes, dunder names, ``_private`` attributes, known
dangerous names and attributes); :class:`Rewriter` then routes the operations that can grow
without bound (``*``, ``**``, ``<<``, ``+``, growing methods, ``while`` loops, ``except``
handlers) through ``__cap_*`` guards provided at run time, and makes set displays
insertion-ordered sets.  Both live together because the
rewrite is only sound on checked code: user code can never write a ``__`` name, so it cannot
shadow or call the guards itself.
"""

from __future__ import annotations

import ast
import copy
import re
import string
from collections.abc import Iterator

from capmj.confine.names import FORBIDDEN_ATTRIBUTES
from capmj.errors import PlanSyntaxError, SandboxViolation

FORBIDDEN_NAMES = frozenset({
    "exec", "eval", "compile", "open", "globals", "locals", "vars", "dir", "getattr", "setattr",
    "delattr", "hasattr", "input", "breakpoint", "help", "memoryview", "object",
    "super", "classmethod", "staticmethod", "property", "exit", "quit", "BaseException",
})
"""Rejected wherever the code reads them without binding them itself (none is a builtin here)."""


_ALLOWED_NODES: tuple[type[ast.AST], ...] = (
    ast.Module, ast.Expr, ast.Assign, ast.AugAssign, ast.AnnAssign, ast.For, ast.While, ast.If,
    ast.FunctionDef, ast.Return, ast.Pass, ast.Break, ast.Continue, ast.Try, ast.ExceptHandler,
    ast.Raise, ast.Assert, ast.Delete, ast.ListComp, ast.SetComp, ast.DictComp,
    ast.GeneratorExp, ast.comprehension, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare,
    ast.Call, ast.Attribute, ast.Subscript, ast.Slice, ast.Name, ast.Constant, ast.List,
    ast.Tuple, ast.Dict, ast.Set, ast.IfExp, ast.Lambda, ast.JoinedStr, ast.FormattedValue,
    ast.Starred, ast.NamedExpr, ast.keyword, ast.arguments, ast.arg, ast.Load, ast.Store,
    ast.Del, ast.operator, ast.unaryop, ast.boolop, ast.cmpop,
)

_WHY_NOT = {
    ast.Import: "import statements are not allowed; np, math, itertools and shapely are "
                "already available",
    ast.ImportFrom: "import statements are not allowed; np, math, itertools and shapely are "
                    "already available",
    ast.ClassDef: "class definitions are not allowed; use functions and dicts",
    ast.Global: "global statements are not allowed; return values instead",
    ast.Nonlocal: "nonlocal statements are not allowed; return values instead",
    ast.With: "with statements are not allowed",
    ast.Yield: "generators (yield) are not allowed",
    ast.YieldFrom: "generators (yield) are not allowed",
}

# Methods whose result can be far larger than their inputs, and a string's format methods; loads
# of these attributes are routed through a checker.
_GROWING_METHODS = frozenset({"repeat", "resize", "ljust", "rjust", "center", "zfill",
                              "expandtabs", "replace", "join", "dot", "clip", "format", "format_map"})

_FIELD_NAME = re.compile(r"\d*|[^\W\d]\w*")
"""A ``str.format`` field that names an argument only (``{}``, ``{0}``, ``{name}``), no attribute
(``{0.x}``) and no item (``{0[y]}``)."""


def format_fields(template: str) -> Iterator[str]:
    """Every replacement field name of a ``str.format`` template, those nested in format specs
    (``{0:{1}}``) included.  Raises ValueError for a malformed template, as ``str.format`` does."""
    for _, name, spec, _ in string.Formatter().parse(template):
        if name is not None:
            yield name
        if spec and "{" in spec:
            yield from format_fields(spec)


def reaching_field(template: str) -> str | None:
    """The first field of ``template`` that reaches an attribute or an item (None: none does, or
    the template is malformed and ``str.format`` will say so itself)."""
    try:
        return next((f for f in format_fields(template) if not _FIELD_NAME.fullmatch(f)), None)
    except ValueError:
        return None


FORMAT_FIELD_RULE = ("format fields may name arguments only ({}, {0}, {name}); use the value in the "
                     "arguments instead of reaching into it")
"""Why a field such as ``{0.x}`` or ``{0[y]}`` is refused, as plan code is told."""


# ------------------------------------------------------------------------------------------------
# 1. static check
# ------------------------------------------------------------------------------------------------
def bound_names(tree: ast.AST) -> set[str]:
    """Every name ``tree`` binds anywhere (assignments, arguments, defs, except/import names).

    Shared with the code preparation of the LLM agent (``capmj.agents.lmp.codeprep``), which needs the
    same notion of "defined by this code" to find functions the code calls but never defines.
    """
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            names.add(node.id)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                names.add((alias.asname or alias.name).split(".")[0])
    return names


def _check_node(node: ast.AST, line: int | None, bound: set[str], code: str) -> None:
    line = getattr(node, "lineno", None) or line

    def reject(message: str) -> None:
        raise SandboxViolation(f"SandboxViolation: {message}", line=line, code=code)

    if not isinstance(node, _ALLOWED_NODES):
        kind = type(node)
        reject(_WHY_NOT.get(kind, f"{kind.__name__} is not allowed in plan code"))
    identifiers: list[str] = []
    if isinstance(node, ast.Name):
        identifiers.append(node.id)
        if node.id in FORBIDDEN_NAMES and node.id not in bound:
            reject(f"the name '{node.id}' is not available")
    elif isinstance(node, ast.Attribute):
        if node.attr.startswith("_"):
            reject(f"private attribute '.{node.attr}' is not allowed")
        if node.attr in FORBIDDEN_ATTRIBUTES:
            reject(f"attribute '.{node.attr}' is not allowed")
        if node.attr in ("format", "format_map") and isinstance(node.value, ast.Constant) \
                and isinstance(node.value.value, str):
            field = reaching_field(node.value.value)
            if field is not None:
                reject(f"format field {{{field}}} reaches an attribute or an item of an argument; "
                       f"{FORMAT_FIELD_RULE}")
    elif isinstance(node, ast.keyword) and node.arg is not None:
        identifiers.append(node.arg)
    elif isinstance(node, ast.arg):
        identifiers.append(node.arg)
    elif isinstance(node, (ast.FunctionDef, ast.ExceptHandler)) and node.name:
        identifiers.append(node.name)
    elif isinstance(node, ast.Try) and node.finalbody:
        reject("try/finally is not allowed; use try/except")
    for name in identifiers:
        if name.startswith("__"):
            reject(f"the name '{name}' is not allowed (names may not start with '__')")
    for child in ast.iter_child_nodes(node):
        _check_node(child, line, bound, code)


def check_code(code: str) -> ast.Module:
    """Parse and allow-list-check ``code``; the AST, or PlanError naming the offending line."""
    if not isinstance(code, str):  # a caller's mistake, not the LLM's
        raise TypeError(f"plan code must be str, not {type(code).__name__}")
    try:
        tree = ast.parse(code, mode="exec")
    except SyntaxError as exc:
        raise PlanSyntaxError(f"SyntaxError: {exc.msg}", line=exc.lineno, code=code) from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise PlanSyntaxError(f"SyntaxError: {exc}", code=code) from None
    try:
        _check_node(tree, None, bound_names(tree), code)
    except RecursionError:
        raise SandboxViolation("SandboxViolation: code is nested too deeply", code=code) from None
    return tree


# ------------------------------------------------------------------------------------------------
# 2. rewrite
# ------------------------------------------------------------------------------------------------
_BINOP_GUARDS: dict[type[ast.operator], str] = {
    ast.Add: "__cap_add", ast.Sub: "__cap_sub", ast.Mult: "__cap_mul", ast.Div: "__cap_truediv",
    ast.FloorDiv: "__cap_floordiv", ast.Mod: "__cap_mod", ast.Pow: "__cap_pow", ast.LShift: "__cap_lshift",
    ast.RShift: "__cap_rshift", ast.BitAnd: "__cap_and", ast.BitOr: "__cap_or", ast.BitXor: "__cap_xor",
    ast.MatMult: "__cap_matmul",
}
"""Every binary operator, by the guard that checks its result's size first (arrays broadcast)."""

_COMPARE_GUARDS: dict[type[ast.cmpop], str] = {
    ast.Lt: "lt", ast.LtE: "le", ast.Gt: "gt", ast.GtE: "ge", ast.Eq: "eq", ast.NotEq: "ne", ast.In: "in",
    ast.NotIn: "not_in", ast.Is: "is", ast.IsNot: "is_not",
}
"""Comparisons by guard name (``__cap_cmp_<name>``; identity tests are never rewritten alone)."""

THUNK_ARG = "__cap_thunk"
"""The one parameter of the lambdas that wrap the operands of a chained comparison; the tracer
does not count their frames as executed lines (they are not lines of the submitted code)."""

_TEXT_BUILTINS = frozenset({"str", "repr"})
"""Builtins whose calls ``str(x)`` / ``repr(x)`` are routed through ``__cap_text_call``."""


def _helper_call(name: str, args: list[ast.expr], like: ast.AST) -> ast.Call:
    call = ast.Call(func=ast.Name(id=name, ctx=ast.Load()), args=args, keywords=[])
    return ast.copy_location(call, like)


def _helper_statement(name: str, like: ast.AST) -> ast.Expr:
    return ast.copy_location(ast.Expr(_helper_call(name, [], like)), like)


class Rewriter(ast.NodeTransformer):
    """Routes resource-hungry operations of checked code through the session's guards."""

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        self.generic_visit(node)
        guard = _BINOP_GUARDS.get(type(node.op))
        return _helper_call(guard, [node.left, node.right], node) if guard else node

    def visit_Compare(self, node: ast.Compare) -> ast.AST:
        """``a < b`` -> ``__cap_cmp_lt(a, b)``; a chain ``a < b < c`` -> ``__cap_chain(("lt", "lt"),
        lambda: a, lambda: b, lambda: c)`` (each operand once, in order, short-circuiting).  A
        chain whose operands bind names (``:=``) stays as written: a lambda would scope them."""
        self.generic_visit(node)
        names = [_COMPARE_GUARDS[type(op)] for op in node.ops]
        if len(names) == 1:
            if names[0] in ("is", "is_not"):
                return node
            return _helper_call(f"__cap_cmp_{names[0]}", [node.left, *node.comparators], node)
        operands = [node.left, *node.comparators]
        if any(isinstance(n, ast.NamedExpr) for o in operands for n in ast.walk(o)):
            return node
        thunks: list[ast.expr] = []
        for operand in operands:
            params = ast.arguments(posonlyargs=[], args=[ast.arg(THUNK_ARG)], vararg=None, kwonlyargs=[],
                                   kw_defaults=[], kwarg=None, defaults=[ast.Constant(None)])
            thunks.append(ast.copy_location(ast.Lambda(params, operand), operand))
        ops = ast.copy_location(ast.Tuple([ast.Constant(n) for n in names], ast.Load()), node)
        return _helper_call("__cap_chain", [ops, *thunks], node)

    def visit_FormattedValue(self, node: ast.FormattedValue) -> ast.AST:
        self.generic_visit(node)  # f"{x}": the size of x's text is checked before it is made
        node.value = _helper_call("__cap_field", [node.value, ast.Constant(node.conversion)], node.value)
        return node

    def visit_Call(self, node: ast.Call) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.func, ast.Name) and node.func.id in _TEXT_BUILTINS:
            call = ast.Call(func=ast.Name(id="__cap_text_call", ctx=ast.Load()), args=[node.func, *node.args],
                            keywords=node.keywords)
            return ast.copy_location(call, node)
        return node

    def visit_AugAssign(self, node: ast.AugAssign) -> ast.AST:
        # Re-reading the target is only safe when that has no side effects (no calls in it).
        pure = not any(isinstance(n, ast.Call) for n in ast.walk(node.target))
        self.generic_visit(node)
        guard = _BINOP_GUARDS.get(type(node.op))
        if guard and pure:
            current = copy.deepcopy(node.target)
            current.ctx = ast.Load()  # type: ignore[attr-defined]
            # In place (keeps list/ndarray identity): x op= check(x, y) returns y unchanged.
            node.value = _helper_call(guard + "_check", [current, node.value], node)
        return node

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.ctx, ast.Load) and node.attr in _GROWING_METHODS:
            return _helper_call("__cap_attr", [node.value, ast.Constant(node.attr)], node)
        return node

    def visit_Set(self, node: ast.Set) -> ast.AST:
        self.generic_visit(node)  # {a, b}: an insertion-ordered set (see sandbox.ordered)
        return _helper_call("__cap_set", [ast.copy_location(ast.List(node.elts, ast.Load()), node)], node)

    def visit_SetComp(self, node: ast.SetComp) -> ast.AST:
        self.generic_visit(node)
        gen = ast.copy_location(ast.GeneratorExp(node.elt, node.generators), node)
        return _helper_call("__cap_set", [gen], node)

    def visit_While(self, node: ast.While) -> ast.AST:
        self.generic_visit(node)
        # ``while True: pass`` emits no per-iteration line events: tick explicitly.
        node.body.insert(0, _helper_statement("__cap_tick", node))
        return node

    def visit_ExceptHandler(self, node: ast.ExceptHandler) -> ast.AST:
        self.generic_visit(node)
        if node.type is None:  # bare except: would catch our aborts
            node.type = ast.copy_location(ast.Name(id="__cap_Exception", ctx=ast.Load()), node)
        # A tracer that raised (e.g. RecursionError at the recursion limit) is switched off by
        # CPython; re-arm it whenever the code swallows an exception.
        node.body.insert(0, _helper_statement("__cap_rearm", node))
        return node
