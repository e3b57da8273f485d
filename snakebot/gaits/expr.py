"""Safe arithmetic for parameter values ("pi/4", "0.5*pi", "radians(30)") without eval()."""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable

MAX_EXPRESSION_CHARS = 200

_CONSTANTS = {"pi": math.pi, "tau": math.tau, "e": math.e}
_FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "radians": math.radians,
    "degrees": math.degrees,
}
_BINARY: dict[type[ast.operator], Callable[[float, float], float]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_UNARY: dict[type[ast.unaryop], Callable[[float], float]] = {
    ast.UAdd: operator.pos,
    ast.USub: operator.neg,
}


def parse_number(text: str) -> float:
    """Evaluate a numeric literal or arithmetic expression to a finite float; ValueError if not."""
    source = text.strip()
    if not source:
        raise ValueError("empty value")
    if len(source) > MAX_EXPRESSION_CHARS:
        raise ValueError(f"expression longer than {MAX_EXPRESSION_CHARS} characters")
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"not a number or arithmetic expression: {source!r}") from exc
    try:
        value = _evaluate(tree.body)
    except OverflowError as exc:
        raise ValueError(f"{source!r} is too large") from exc
    except (ArithmeticError, ValueError) as exc:
        raise ValueError(f"cannot evaluate {source!r}: {exc}") from exc
    if not math.isfinite(value):
        raise ValueError(f"{source!r} is not finite")
    return value


def _evaluate(node: ast.expr) -> float:
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            raise ValueError(f"unsupported literal {node.value!r}")
        return float(node.value)
    if isinstance(node, ast.Name) and node.id in _CONSTANTS:
        return _CONSTANTS[node.id]
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        result: object = _BINARY[type(node.op)](_evaluate(node.left), _evaluate(node.right))
        if not isinstance(result, float):
            raise ValueError("the result is not a real number")
        return result
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        return _UNARY[type(node.op)](_evaluate(node.operand))
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in _FUNCTIONS
        and len(node.args) == 1
        and not node.keywords
    ):
        return _FUNCTIONS[node.func.id](_evaluate(node.args[0]))
    allowed = ", ".join([*_CONSTANTS, *(f"{name}()" for name in _FUNCTIONS)])
    raise ValueError(f"only numbers, + - * / ** and {allowed} are allowed")
