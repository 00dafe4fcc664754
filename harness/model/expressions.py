"""Equation text to sympy, through a whitelist of Python syntax and a closed namespace.

The text is first checked with Python's own ``ast`` (only numbers, known names, the
arithmetic operators and calls of known functions pass), then handed to
``sympy.parsing.sympy_parser.parse_expr`` with dictionaries that hold nothing but those
names, so no attribute, builtin or module of the process is reachable from a model file.
"""
from __future__ import annotations

import ast
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import sympy
from sympy.parsing.sympy_parser import auto_number, auto_symbol, parse_expr

#: Functions an equation may call, by the name it uses.
FUNCTIONS: dict[str, Callable[..., sympy.Expr]] = {
    "sin": sympy.sin, "cos": sympy.cos, "tan": sympy.tan, "atan": sympy.atan,
    "sinh": sympy.sinh, "cosh": sympy.cosh, "tanh": sympy.tanh,
    "exp": sympy.exp, "log": sympy.log, "sqrt": sympy.sqrt,
    "sign": sympy.sign, "abs": sympy.Abs,
}
#: Names with a fixed meaning, which no coordinate, input, parameter or constant may take.
RESERVED = frozenset(FUNCTIONS) | {"der", "pi", "t"}

_OPERATORS = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)


class ExpressionError(ValueError):
    """A problem with one side of one equation (the reader adds the file and equation)."""


@dataclass(frozen=True)
class Symbols:
    """The sympy symbols of a model's names: positions, velocities, accelerations, the rest."""

    position: dict[str, sympy.Symbol]
    velocity: dict[str, sympy.Symbol]
    acceleration: dict[str, sympy.Symbol]
    inputs: dict[str, sympy.Symbol]
    parameters: dict[str, sympy.Symbol]
    constants: dict[str, sympy.Symbol]

    @classmethod
    def of(cls, coordinates, inputs, parameters, constants) -> Symbols:
        """Real symbols; velocities and accelerations are named as written, der(x) and der(x,2)."""
        def real(name: str) -> sympy.Symbol:
            return sympy.Symbol(name, real=True)
        return cls({c: real(c) for c in coordinates},
                   {c: real(f"der({c})") for c in coordinates},
                   {c: real(f"der({c},2)") for c in coordinates},
                   {u: real(u) for u in inputs},
                   {p: real(p) for p in parameters},
                   {k: real(k) for k in constants})

    def names(self) -> dict[str, sympy.Symbol]:
        """Every name an equation may use, to its symbol."""
        return {**self.position, **self.inputs, **self.parameters, **self.constants}

    def measured(self) -> list[sympy.Symbol]:
        """Positions, velocities, accelerations and inputs, in the regressor's argument order."""
        return [*self.position.values(), *self.velocity.values(),
                *self.acceleration.values(), *self.inputs.values()]


def _check_syntax(text: str, symbols: Symbols) -> None:
    """Reject anything but numbers, known names, + - * / ** and calls of known functions."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"is not an expression ({exc.msg})") from None
    names = symbols.names()
    callees = {id(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    for node in ast.walk(tree):
        if id(node) in callees:
            continue  # a function's name, checked with its call
        if isinstance(node, (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Load) + _OPERATORS):
            continue
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ExpressionError(f"has a literal that is not a real number: {node.value!r}")
            continue
        if isinstance(node, ast.Name):
            if node.id in FUNCTIONS or node.id == "der":
                raise ExpressionError(f"uses the function '{node.id}' without calling it")
            if node.id not in names and node.id != "pi":
                raise ExpressionError(f"uses the unknown name '{node.id}' (declare it as a "
                                      "coordinate, input, parameter or constant)")
            continue
        if isinstance(node, ast.Call):
            _check_call(node, symbols)
            continue
        raise ExpressionError(f"uses {type(node).__name__} syntax, which equations do not allow "
                              "(only numbers, names, + - * / ^ and function calls)")


def _check_call(node: ast.Call, symbols: Symbols) -> None:
    if not isinstance(node.func, ast.Name):
        raise ExpressionError("calls something that is not a plain function name")
    name = node.func.id
    if node.keywords:
        raise ExpressionError(f"passes keyword arguments to {name}()")
    if name == "der":
        args = node.args
        if not 1 <= len(args) <= 2 or not isinstance(args[0], ast.Name) \
                or args[0].id not in symbols.position:
            raise ExpressionError("uses der() on something other than a coordinate: write "
                                  "der(c) or der(c,2) with c one of the coordinates")
        if len(args) == 2 and not (isinstance(args[1], ast.Constant)
                                   and type(args[1].value) is int and args[1].value in (1, 2)):
            raise ExpressionError(f"uses der({args[0].id}, ...) with an order other than 1 or 2")
        return
    if name not in FUNCTIONS:
        raise ExpressionError(f"calls the unknown function '{name}' (known: der, "
                              + ", ".join(sorted(FUNCTIONS)) + ")")
    if len(node.args) != 1:
        raise ExpressionError(f"calls {name}() with {len(node.args)} arguments instead of 1")


def parse_side(text: str, symbols: Symbols) -> sympy.Expr:
    """One side of an equation as a sympy expression over the model's symbols."""
    text = text.replace("^", "**")  # the power of the and Modelica's notation
    _check_syntax(text, symbols)

    def der(coordinate: sympy.Symbol, order: int = 1) -> sympy.Symbol:
        name = str(coordinate)
        return symbols.velocity[name] if int(order) == 1 else symbols.acceleration[name]

    local: dict[str, object] = {**symbols.names(), **FUNCTIONS, "der": der, "pi": sympy.pi}
    # Only what auto_number and auto_symbol emit; no builtins are reachable.
    global_dict: dict[str, object] = {"__builtins__": {}, "Integer": sympy.Integer,
                                      "Float": sympy.Float, "Rational": sympy.Rational,
                                      "Symbol": sympy.Symbol}
    try:
        expr = parse_expr(text, local_dict=local, global_dict=global_dict,
                          transformations=(auto_symbol, auto_number))
    except (SyntaxError, TypeError, ValueError) as exc:
        raise ExpressionError(f"cannot be read ({exc})") from None
    if not isinstance(expr, sympy.Expr):
        raise ExpressionError("is not an arithmetic expression")
    return expr


def parse_equation(text: str, symbols: Symbols) -> tuple[sympy.Expr, sympy.Expr]:
    """``lhs = rhs`` as two sympy expressions."""
    if not isinstance(text, str):
        raise ExpressionError("is not a string")
    sides = text.split("=")
    if len(sides) != 2 or not sides[0].strip() or not sides[1].strip():
        raise ExpressionError("must have the form 'left side = right side' with one '='")
    return parse_side(sides[0].strip(), symbols), parse_side(sides[1].strip(), symbols)


def free_names(expr: sympy.Expr, table: Mapping[str, sympy.Symbol]) -> set[str]:
    """The names of ``table`` whose symbols occur in ``expr``."""
    free = expr.free_symbols
    return {name for name, symbol in table.items() if symbol in free}
