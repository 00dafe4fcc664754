"""Equation text to sympy, through a whitelist of Python syntax and a closed namespace.

The text is first checked with Python's own ``ast`` (only numbers, known names, the
arithmetic operators and calls of known functions pass), then the checked tree is turned
into sympy node by node, with nothing but the model's symbols and the known functions:
no text is evaluated as code, so no attribute, builtin or module of the process is
reachable from a model file.

The work any text can ask for is bounded before sympy sees it (sympy computes with
exact integers and multiplies powers of sums out, so unbounded text would be unbounded
time and memory): the text's length and characters, the size and nesting of its syntax
tree, every number and every power of numbers (worked out in float64 first: a number
beyond it, or without a real value, is refused by name), the exponents of powers of
names, and the number of terms the equation has once multiplied out (the linearity and
dimension checks multiply it out).  The limits are the constants below.
"""
from __future__ import annotations

import ast
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import sympy

#: Functions an equation may call, by the name it uses.
FUNCTIONS: dict[str, Callable[..., sympy.Expr]] = {
    "sin": sympy.sin, "cos": sympy.cos, "tan": sympy.tan, "atan": sympy.atan,
    "sinh": sympy.sinh, "cosh": sympy.cosh, "tanh": sympy.tanh,
    "exp": sympy.exp, "log": sympy.log, "sqrt": sympy.sqrt,
    "sign": sympy.sign, "abs": sympy.Abs,
}
#: Names with a fixed meaning, which no coordinate, input, parameter or constant may take
#: ("time": the FMI 3 FMU's independent variable, fmpy's time column beside the FMU's).
RESERVED = frozenset(FUNCTIONS) | {"der", "pi", "t", "time"}

_OPERATORS = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)

# ---- limits on the work an equation may ask for (why each is what it is) ----------------
#: Characters in one equation: a 7-coordinate robot's equation written out is a few
#: thousand; the bound keeps the messages and the parser's work small.
MAX_EQUATION_CHARS = 20_000
#: Syntax-tree nodes of one equation: the model FMU's term program holds 4096 tokens
#: (program.MAX_TOKENS), so a longer equation could not become an FMU anyway.
MAX_NODES = 4096
#: Nesting of the syntax tree, every level counted (a sum of n terms is n deep): Python's
#: own parser and compiler, and sympy's parser that runs them, give up near 3000.
MAX_DEPTH = 1000
#: Nesting that sympy keeps (calls, powers, a product inside a sum ...; a chain of one
#: operator is one level): sympy walks expressions recursively, several Python frames a
#: level, under Python's limit of 1000 frames.
MAX_NESTING = 100
#: |exponent| of a power of something that is not a number: x^64 is far beyond any
#: equation of motion, and (a+b)^n multiplies out into n+1 terms.
MAX_EXPONENT = 64
#: Terms of one equation once multiplied out: (a+b)^n (c+d)^m has (n+1)(m+1).
MAX_EXPANDED_TERMS = 20_000

#: Functions of numbers worked out in float64 to check the number is real and finite.
_FLOAT_FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "atan": math.atan,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "exp": math.exp,
    "log": math.log, "sqrt": math.sqrt, "abs": abs,
    "sign": lambda x: float((x > 0) - (x < 0)),
}


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


def _check_text(text: str) -> None:
    """The text's length and characters, before any parser sees it."""
    if len(text) > MAX_EQUATION_CHARS:
        raise ExpressionError(f"is {len(text)} characters long; an equation has at most "
                              f"{MAX_EQUATION_CHARS}")
    for position, char in enumerate(text):
        if not (char.isascii() and (char.isprintable() or char in " \t")):
            # Python reads fullwidth letters as ASCII ones (NFKC) but sympy does not, and
            # a Cyrillic letter looks like a Latin one: names are ASCII.
            raise ExpressionError(f"has the character {char!r} (U+{ord(char):04X}) at "
                                  f"position {position + 1}: equations are ASCII text")


def _parse_tree(text: str) -> ast.Expression:
    """Python's syntax tree of ``text``, its size and nesting bounded."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"is not an expression ({exc.msg})") from None
    except (RecursionError, MemoryError):  # the parser's own stack bound
        raise ExpressionError(f"is nested more than {MAX_DEPTH} deep (each term of a sum "
                              "and each factor of a product, each sign, counts a level)") from None
    except ValueError:  # an integer literal of more than 4300 digits
        raise ExpressionError("has a number of thousands of digits, beyond the range of "
                              "float64 (about 1.8e308)") from None
    count = 0
    stack: list[tuple[ast.AST, int, int]] = [(tree.body, 1, 1)]
    while stack:  # without recursion: the tree is what is being bounded
        node, depth, nesting = stack.pop()
        count += isinstance(node, ast.expr)  # numbers, names, operations, calls
        if count > MAX_NODES:
            raise ExpressionError(f"has more than {MAX_NODES} operations, names and numbers "
                                  "(the most an equation may have)")
        if depth > MAX_DEPTH:
            raise ExpressionError(f"is nested more than {MAX_DEPTH} deep (each term of a sum "
                                  "and each factor of a product, each sign, counts a level)")
        if nesting > MAX_NESTING:
            raise ExpressionError(f"nests functions, powers, products and sums more than "
                                  f"{MAX_NESTING} deep")
        for child in ast.iter_child_nodes(node):
            stack.append((child, depth + 1, nesting + _nests(node, child)))
    return tree


def _family(node: ast.AST) -> str:
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
        return "sum"
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
        return "product"
    if isinstance(node, ast.UnaryOp):
        return "sign"
    return type(node).__name__


def _nests(parent: ast.AST, child: ast.AST) -> int:
    """1 when sympy keeps ``child`` as a level below ``parent`` (a chain of + and -, of
    * and /, or of signs is flattened into one)."""
    if isinstance(child, (ast.Name, ast.Constant, ast.expr_context, ast.operator,
                          ast.unaryop)):
        return 0
    family = _family(child)
    return 0 if family in ("sum", "product", "sign") and family == _family(parent) else 1


def _numbers(tree: ast.Expression, text: str) -> dict[int, float | None]:
    """The float64 value of every node of ``tree`` that holds no name (None for those that
    do), by id; ExpressionError when such a value is not a finite real number (an
    overflow, a division by zero, a negative number to a fractional power, log(-1))."""
    values: dict[int, float | None] = {}
    order: list[ast.AST] = []
    stack: list[ast.AST] = [tree.body]
    while stack:  # post-order without recursion
        current = stack.pop()
        order.append(current)
        stack.extend(ast.iter_child_nodes(current))
    for current in reversed(order):
        values[id(current)] = _fold(current, values, text)
    return values


def _fold(node: ast.AST, values: Mapping[int, float | None], text: str) -> float | None:
    """One node's float64 value from its children's (see :func:`_numbers`)."""
    try:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                return None  # refused with its message by the syntax check
            value = float(node.value)
        elif isinstance(node, ast.Name):
            return math.pi if node.id == "pi" else None
        elif isinstance(node, ast.UnaryOp):
            operand = values.get(id(node.operand))
            if operand is None:
                return None
            value = -operand if isinstance(node.op, ast.USub) else operand
        elif isinstance(node, ast.BinOp):
            left, right = values.get(id(node.left)), values.get(id(node.right))
            if isinstance(node.op, ast.Div) and right == 0.0:
                raise ZeroDivisionError
            if left is None or right is None:
                return None
            if isinstance(node.op, ast.Add):
                value = left + right
            elif isinstance(node.op, ast.Sub):
                value = left - right
            elif isinstance(node.op, ast.Mult):
                value = left * right
            elif isinstance(node.op, ast.Div):
                value = left / right
            elif isinstance(node.op, ast.Pow):
                power = left ** right
                if isinstance(power, complex):
                    raise ExpressionError(f"raises the negative number {left:g} to the "
                                          f"fractional power {right:g} in "
                                          f"'{_excerpt(node, text)}', which has no real value")
                value = power
            else:
                return None
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                and node.func.id in _FLOAT_FUNCTIONS and len(node.args) == 1:
            argument = values.get(id(node.args[0]))
            if argument is None:
                return None
            value = _FLOAT_FUNCTIONS[node.func.id](argument)
        else:
            return None
    except OverflowError:
        raise ExpressionError(f"has the number '{_excerpt(node, text)}', beyond the range of "
                              "float64 (about 1.8e308)") from None
    except ZeroDivisionError:
        raise ExpressionError(f"divides by zero in '{_excerpt(node, text)}'") from None
    except ValueError:  # math domain error: log(-1), sqrt(-1)
        raise ExpressionError(f"has '{_excerpt(node, text)}', which has no real "
                              "value") from None
    if not math.isfinite(value):
        raise ExpressionError(f"has the number '{_excerpt(node, text)}', beyond the range of "
                              "float64 (about 1.8e308)")
    return value


def _excerpt(node: ast.AST, text: str, limit: int = 60) -> str:
    """The source text of ``node``, shortened for a message (only made for one)."""
    segment = ast.get_source_segment(text, node) or "..."
    return segment if len(segment) <= limit else segment[:limit - 3] + "..."


def _check_powers(tree: ast.Expression, text: str) -> None:
    """Every number worked out in float64 is finite and real, no division is by zero; an
    exponent of a power of names is a bounded number or holds names itself (x^y is never
    multiplied out)."""
    values = _numbers(tree, text)
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            base, exponent = values[id(node.left)], values[id(node.right)]
            if base is None and exponent is not None and abs(exponent) > MAX_EXPONENT:
                raise ExpressionError(f"raises '{_excerpt(node.left, text)}' to the power "
                                      f"{exponent:g} (at most {MAX_EXPONENT} in size)")


def _check_exponents(expr: sympy.Expr) -> None:
    """Powers of names that sympy merged ((x^60)^60 is x^3600) stay within MAX_EXPONENT."""
    for node in sympy.preorder_traversal(expr):
        if isinstance(node, sympy.Pow) and node.exp.is_Number and not node.base.is_Number \
                and abs(float(node.exp)) > MAX_EXPONENT:
            raise ExpressionError(f"raises '{node.base}' to the power {node.exp} (at most "
                                  f"{MAX_EXPONENT} in size)")


def expanded_terms(expr: sympy.Expr, limit: int = MAX_EXPANDED_TERMS) -> int:
    """An upper bound on the terms of ``sympy.expand(expr)``, counted without expanding
    (capped a little above ``limit``): sums add, products multiply, an integer power n
    of k terms has C(k+n-1, n); the arguments of functions and non-integer powers are
    multiplied out where they stand, and count too."""
    cap = limit + 1
    inner = 0

    def count(e: sympy.Basic) -> int:
        nonlocal inner
        if e.is_Add:
            return min(cap, sum(count(a) for a in e.args))
        if e.is_Mul:
            total = 1
            for a in e.args:
                total = min(cap, total * count(a))
            return total
        if e.is_Pow:
            base = count(e.base)
            if e.exp.is_Integer and e.exp != 0:
                n = min(abs(int(e.exp)), cap)
                return min(cap, math.comb(base + n - 1, n)) if base > 1 else 1
            inner = min(cap, inner + base + count(e.exp))
            return 1
        if e.args:  # a function
            inner = min(cap, inner + sum(count(a) for a in e.args))
        return 1

    return min(cap, count(expr) + inner)


#: A number as equations write it: decimal digits, a point, an exponent.
_DECIMAL = re.compile(r"(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def _check_syntax(text: str, symbols: Symbols) -> ast.Expression:
    """Reject anything but numbers, known names, + - * / ** and calls of known functions,
    and text whose work is beyond the limits above; the checked syntax tree."""
    _check_text(text)
    tree = _parse_tree(text)
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
            written = ast.get_source_segment(text, node) or ""
            if not _DECIMAL.fullmatch(written):  # Python also reads 0x10, 0o7, 1_000
                raise ExpressionError(f"has the number {written!r}: numbers are written in "
                                      "decimal, such as 16, 0.5 or 1.5e-3")
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
    _check_powers(tree, text)
    return tree


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
    tree = _check_syntax(text, symbols)
    try:
        expr = _Translator(text, symbols).expression(tree.body)
    except (RecursionError, MemoryError):  # beyond what the bounds above let through
        raise ExpressionError("is too large or too deeply nested to be read") from None
    if not isinstance(expr, sympy.Expr):
        raise ExpressionError("is not an arithmetic expression")
    return expr


@dataclass
class _Translator:
    """The checked syntax tree as sympy, built directly (nothing is evaluated as Python
    code): a chain of + and - becomes one sympy.Add, of * and / one sympy.Mul, so a sum
    of n terms takes time in n, not n^2, and Python recursion only at real nesting."""

    text: str
    symbols: Symbols

    def expression(self, node: ast.expr) -> sympy.Expr:
        if isinstance(node, ast.Constant):
            return self.number(node)
        if isinstance(node, ast.Name):
            return sympy.pi if node.id == "pi" else self.symbols.names()[node.id]
        if isinstance(node, ast.UnaryOp):
            signs, inner = 0, node  # type: tuple[int, ast.expr]
            while isinstance(inner, ast.UnaryOp):  # a run of signs, without recursion
                signs += isinstance(inner.op, ast.USub)
                inner = inner.operand
            value = self.expression(inner)
            return -value if signs % 2 else value
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            return sympy.Add(*self.chain(node, (ast.Add, ast.Sub), ast.Sub, -1))
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
            return sympy.Mul(*self.chain(node, (ast.Mult, ast.Div), ast.Div, 0))
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            return sympy.Pow(self.expression(node.left), self.expression(node.right))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            if node.func.id == "der":
                # checked by _check_call: der(c) or der(c, 1 or 2), c a coordinate
                coordinate = ast.get_source_segment(self.text, node.args[0]) or ""
                second = len(node.args) == 2 and getattr(node.args[1], "value", 1) == 2
                table = self.symbols.acceleration if second else self.symbols.velocity
                return table[coordinate.strip()]
            return FUNCTIONS[node.func.id](self.expression(node.args[0]))
        raise ExpressionError(f"uses {type(node).__name__} syntax, which equations do not allow")

    def chain(self, node: ast.BinOp, kinds: tuple[type, ...], inverse: type,
              power: int) -> list[sympy.Expr]:
        """The operands of a left-deep chain of one family of operators, in order; those
        after an ``inverse`` operator negated (power -1: a sum's) or inverted (a product's)."""
        operands: list[tuple[ast.expr, bool]] = []
        current: ast.expr = node
        while isinstance(current, ast.BinOp) and isinstance(current.op, kinds):
            operands.append((current.right, isinstance(current.op, inverse)))
            current = current.left
        operands.append((current, False))
        out = []
        for operand, inverted in reversed(operands):
            value = self.expression(operand)
            if inverted:
                value = -value if power == -1 else sympy.Pow(value, -1)
            out.append(value)
        return out

    def number(self, node: ast.Constant) -> sympy.Expr:
        """A literal as sympy writes it: an Integer, or a Float of the digits as written."""
        if isinstance(node.value, int):
            return sympy.Integer(node.value)
        literal = ast.get_source_segment(self.text, node) or repr(node.value)
        try:
            return sympy.Float(literal.replace("_", ""))
        except ValueError:
            return sympy.Float(node.value)


def parse_equation(text: str, symbols: Symbols) -> tuple[sympy.Expr, sympy.Expr]:
    """``lhs = rhs`` as two sympy expressions."""
    if not isinstance(text, str):
        raise ExpressionError("is not a string")
    _check_text(text)
    sides = text.split("=")
    if len(sides) != 2 or not sides[0].strip() or not sides[1].strip():
        raise ExpressionError("must have the form 'left side = right side' with one '='")
    lhs, rhs = parse_side(sides[0].strip(), symbols), parse_side(sides[1].strip(), symbols)
    _check_exponents(lhs - rhs)
    terms = expanded_terms(lhs - rhs)
    if terms > MAX_EXPANDED_TERMS:  # before the checks that multiply it out
        raise ExpressionError(f"has more than {MAX_EXPANDED_TERMS} terms once multiplied "
                              "out (powers and products of sums); write it in a shorter form")
    return lhs, rhs


def free_names(expr: sympy.Expr, table: Mapping[str, sympy.Symbol]) -> set[str]:
    """The names of ``table`` whose symbols occur in ``expr``."""
    free = expr.free_symbols
    return {name for name, symbol in table.items() if symbol in free}
