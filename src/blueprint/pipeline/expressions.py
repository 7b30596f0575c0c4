"""Values of pipeline files: a plain value, or ``"= expression"`` over the declared variables
(numbers, variables, + - * / ( ), min and max), evaluated without ``eval``."""

from __future__ import annotations

import ast
import operator

from blueprint.pipeline.schema import fail

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_CALLS = {"min": min, "max": max}
# Longest expression parsed: Python's parser recurses on nesting, so a deeply nested expression
# must be refused before it is parsed.
_TEXT_LIMIT = 1000


def evaluate(value, variables: dict, source: str, key: str):
    """``value`` itself, or for a string ``"= expr"`` the expression's value over ``variables``."""
    if not (isinstance(value, str) and value.lstrip().startswith("=")):
        return value
    text = value.lstrip()[1:].strip()
    if len(text) > _TEXT_LIMIT:
        raise fail(source, key, f"an expression of {len(text)} characters (at most {_TEXT_LIMIT})")
    try:
        tree = ast.parse(text, mode="eval")
    except (SyntaxError, RecursionError, MemoryError):
        raise fail(source, key, f"cannot read the expression {text!r}") from None

    def numbers(*values):
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
            raise fail(source, key, f"arithmetic on a non-number in {text!r}")
        return values

    def walk(node):
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float | bool | str):
            return node.value
        if isinstance(node, ast.Name):
            if node.id not in variables:
                known = ", ".join(variables) or "none declared"
                raise fail(source, key, f"unknown variable {node.id!r} (choose {known})")
            return variables[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            a, b = numbers(walk(node.left), walk(node.right))
            try:
                return _BINARY[type(node.op)](a, b)
            except ZeroDivisionError:
                raise fail(source, key, f"division by zero in {text!r}") from None
            except OverflowError:
                raise fail(source, key, f"a number too large in {text!r}") from None
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            return _UNARY[type(node.op)](*numbers(walk(node.operand)))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _CALLS
            and not node.keywords
        ):
            if len(node.args) < 2:
                raise fail(source, key, f"{node.func.id} takes two or more numbers in {text!r}")
            return _CALLS[node.func.id](*numbers(*(walk(a) for a in node.args)))
        raise fail(source, key, f"{text!r}: expressions take numbers, variables, + - * / ( ), min and max")

    try:
        return walk(tree)
    except RecursionError:
        raise fail(source, key, "the expression nests too deeply") from None
