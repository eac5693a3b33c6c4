"""Parse mathematical expressions from untrusted text into SymPy, without evaluating Python.

A model file written by someone else gives positions, energies and forces as strings such as
``"l1*sin(theta1) + l2*sin(theta2)"``. :func:`parse_expression` turns such a string into a SymPy
expression without ``eval``, ``exec``, ``sympify`` or ``parse_expr``: the text is checked character
by character, :func:`ast.parse` builds its syntax tree (it runs nothing), and the tree is walked
against a whitelist, each allowed node becoming the SymPy node built from its already built
operands. The accepted grammar::

    expr     := number | name | family[index] | expr op expr | -expr | +expr | (expr)
              | function(expr, ...) | dot(coordinate)
    op       := +  -  *  /  **
    number   := an integer of at most 100 digits | a finite float such as 2.5e-3
    name     := a key of `names`, or one of the constants pi and E
    index    := name | name + integer | name - integer      (families given in `subscripts`)
    function := sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt abs sign

Anything else (attributes, lambdas, comprehensions, comparisons, strings, booleans, complex
numbers, keyword arguments, ``//``, ``%``, ``@``, bitwise operators, names starting with ``_``)
raises :class:`ExpressionError` naming the construct. Integers stay exact: ``1/2`` is
``Rational(1, 2)``.

The work is bounded too. Length, characters and bracket depth are checked by one linear scan
before parsing; the walk over the tree is iterative; whatever SymPy would evaluate with exact
arithmetic (a power of a number, the root of a number, a product of roots, ``exp(c*log(b))``) is
sized first, so that ``10**10**10`` or ``sqrt(7**1000 + 1)`` is refused at once instead of running
for minutes; and every numeric value built stays below 10**1000 in magnitude, since SymPy needs
precision in proportion to it (``sin(cosh(10**6))`` takes it 25 s). A failure inside SymPy becomes
an :class:`ExpressionError`.

What is not bounded: SymPy's assumption queries on symbols not declared real can be slow on
crafted input (``abs(cosh((x + a + b)**12))`` takes seconds, larger powers far longer); with real
symbols they are instant. Untrusted files are best parsed with real symbols, or under a time limit.
"""

from __future__ import annotations

import ast
import difflib
import keyword
import math
import re
import reprlib
import warnings
from collections.abc import Callable, Mapping
from types import MappingProxyType

import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelError
from pfaff.core.expansion import EXPANDING, MAX_FUNCTION_TERMS, expanded_terms

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "MAX_DIGITS",
    "MAX_EXPONENT",
    "MAX_INT_DIGITS",
    "MAX_NAME_LENGTH",
    "MAX_NODES",
    "MAX_ROOT_DIGITS",
    "MAX_WRITTEN_OUT",
    "RESERVED_NAMES",
    "ExpressionError",
    "check_name",
    "parse_expression",
    "parse_number",
]

MAX_INT_DIGITS = 100
"""Most digits of an integer literal."""
MAX_EXPONENT = 1000
"""Largest absolute value of a numeric exponent (after evaluation: ``(x**999)**999`` is refused)."""
MAX_DIGITS = 1000
"""Most decimal digits of an exact number SymPy may be made to compute (a power, product or sum)."""
MAX_ROOT_DIGITS = 100
"""Most digits of a number whose root SymPy may be made to extract (it factors it)."""
MAX_NODES = 20_000
# nodes of an expression with the values of the names it uses written out (a file's [[inputs]]:
# each may use the ones before it twice, doubling at each level)
MAX_WRITTEN_OUT = 10 * MAX_NODES
"""Most nodes of the syntax tree of one expression."""
MAX_NAME_LENGTH = 100
"""Longest name :func:`check_name` accepts."""

_T: sp.Symbol = sp.Symbol("t")  # the time symbol, equal to pfaff.core.symbols.t

FUNCTIONS: Mapping[str, tuple[Callable[..., sp.Expr], int]] = MappingProxyType(
    {
        "abs": (sp.Abs, 1),
        "acos": (sp.acos, 1),
        "asin": (sp.asin, 1),
        "atan": (sp.atan, 1),
        "atan2": (sp.atan2, 2),
        "cos": (sp.cos, 1),
        "cosh": (sp.cosh, 1),
        "exp": (sp.exp, 1),
        "log": (sp.log, 1),
        "sign": (sp.sign, 1),
        "sin": (sp.sin, 1),
        "sinh": (sp.sinh, 1),
        "sqrt": (sp.sqrt, 1),
        "tan": (sp.tan, 1),
        "tanh": (sp.tanh, 1),
    }
)
"""The default function table: name -> (SymPy callable, exact number of arguments)."""

CONSTANTS: Mapping[str, sp.Expr] = MappingProxyType({"pi": sp.pi, "E": sp.E})
"""Names every expression knows."""

RESERVED_NAMES: frozenset[str] = frozenset({*FUNCTIONS, *CONSTANTS, "dot", "t"})
"""Names a model file may not declare (:func:`check_name`)."""


class ExpressionError(ModelError):
    """An expression, number or name in a model file is invalid or not allowed.

    The message starts with the ``where`` label given by the caller (a file and key), then names
    the problem and its column.
    """


# Constructs refused by name (subject and verb); any other node type is refused by its class name.
_REFUSED: dict[type[ast.AST], str] = {
    ast.Attribute: "attribute access is",
    ast.Lambda: "lambda expressions are",
    ast.ListComp: "comprehensions are",
    ast.SetComp: "comprehensions are",
    ast.DictComp: "comprehensions are",
    ast.GeneratorExp: "generator expressions are",
    ast.Compare: "comparisons are",
    ast.BoolOp: "boolean operators (and, or) are",
    ast.IfExp: "conditional expressions (x if c else y) are",
    ast.Starred: "starred expressions are",
    ast.JoinedStr: "f-strings are",
    ast.FormattedValue: "f-strings are",
    ast.Dict: "dictionaries are",
    ast.List: "lists are",
    ast.Tuple: "tuples (a comma outside a call) are",
    ast.Set: "sets are",
    ast.NamedExpr: "assignment expressions (:=) are",
    ast.Await: "await is",
    ast.Yield: "yield is",
    ast.YieldFrom: "yield is",
    ast.Slice: "slices are",
    ast.Subscript: "indexing is",
}
_REFUSED_OPERATORS: dict[type[ast.AST], str] = {
    ast.FloorDiv: "floor division '//'",
    ast.Mod: "the remainder operator '%'",
    ast.MatMult: "matrix multiplication '@'",
    ast.LShift: "the shift '<<'",
    ast.RShift: "the shift '>>'",
    ast.BitOr: "the bitwise or '|'",
    ast.BitAnd: "the bitwise and '&'",
    ast.BitXor: "the bitwise xor '^' (a power is written x**2)",
    ast.Not: "'not'",
    ast.Invert: "the bitwise inversion '~'",
}
_REFUSED_CONSTANTS: dict[type, str] = {
    bool: "booleans (True, False) are",
    str: "strings are",
    bytes: "bytes are",
    complex: "complex numbers are",
    type(None): "None is",
    type(...): "the ellipsis '...' is",
}
_BAD_CHARACTER = re.compile(r"[^\t\n\r\x20-\x7e]")
_BRACKET = re.compile(r"[][(){}]")
_UNDEFINED = (sp.nan, sp.zoo, sp.oo, -sp.oo)
_LARGEST = sp.Integer(10) ** MAX_DIGITS
_shortrepr = reprlib.Repr()
_shortrepr.maxstring = _shortrepr.maxother = 40


def parse_expression(
    text: str,
    names: Mapping[str, sp.Expr],
    *,
    where: str = "expression",
    functions: Mapping[str, tuple[Callable[..., sp.Expr], int]] | None = None,
    max_length: int = 10_000,
    max_depth: int = 100,
    allow_dot: bool = True,
    subscripts: Mapping[str, Callable[[sp.Expr], sp.Expr]] | None = None,
) -> sp.Expr:
    """Parse the untrusted string ``text`` into a SymPy expression, evaluating no Python.

    Parameters
    ----------
    text : str
        The expression, in Python's syntax restricted to the grammar of this module.
    names : Mapping[str, Expr]
        What each allowed name stands for: coordinates (functions of ``t``), parameters
        (symbols), ``t``. The constants ``pi`` and ``E`` are always known and may not be keys.
    where : str
        Where the text comes from, the start of every error message (``"file m.toml, key
        particles[0].mass"``).
    functions : Mapping[str, tuple[Callable, int]], optional
        The callable functions: name -> (SymPy callable, exact number of arguments). Default
        :data:`FUNCTIONS`; pass ``{**FUNCTIONS, "cbrt": (sympy.cbrt, 1)}`` to extend it. Such
        callables are the caller's code: only ``sympy.sqrt`` and ``sympy.exp`` are sized first.
    max_length : int
        Longest accepted text, in characters.
    max_depth : int
        Deepest nesting of brackets, and of powers and function calls.
    allow_dot : bool
        Whether ``dot(q)``, the time derivative of the coordinate ``q``, is allowed.
    subscripts : Mapping[str, Callable[[Expr], Expr]], optional
        Indexed families: ``theta[k+1]`` calls ``subscripts["theta"](k + 1)``, with ``k`` taken
        from ``names``. An index is a name, or a name plus or minus an integer.

    Returns
    -------
    Expr
        The expression, built by SymPy's constructors with their usual evaluation.

    Raises
    ------
    ExpressionError
        The text is not a string, too long, contains a control or non-ASCII character, is not
        valid syntax, uses a construct or name that is not allowed, would make SymPy compute a
        huge number, or is infinite, undefined or complex.
    TypeError, ValueError
        ``names``, ``functions`` or ``subscripts`` are malformed (a bug of the caller).

    Examples
    --------
    >>> import sympy as sp
    >>> from pfaff.core.safe_expr import parse_expression
    >>> from sympy.physics.vector import dynamicsymbols
    >>> l, th = sp.Symbol("l"), dynamicsymbols("theta")
    >>> parse_expression("l*sin(theta) + l/2", {"l": l, "theta": th})
    l*sin(theta(t)) + l/2
    >>> parse_expression("dot(theta)**2", {"theta": th})
    Derivative(theta(t), t)**2
    >>> parse_expression("__import__('os')", {}, where="key x")
    Traceback (most recent call last):
    ...
    pfaff.core.safe_expr.ExpressionError: key x: names starting with '_' are not allowed: '__import__' (column 1)
    """
    table = FUNCTIONS if functions is None else functions
    _check_options(names, table, subscripts, allow_dot)
    _scan(text, where, max_length, max_depth)
    body = text.strip()
    lead = len(text) - len(text.lstrip())
    if not body:
        raise ExpressionError(f"{where}: the expression is empty")
    root = _parse(text, body, lead, where)
    builder = _Builder(text, body, lead, where, names, table, subscripts, allow_dot, max_depth)
    expr = builder.build(root)
    for number in expr.atoms(sp.Number):  # the model computes in floats: 10**400 overflows
        if number.is_finite and not math.isfinite(float(number)):
            raise ExpressionError(
                f"{where}: the constant {_shortrepr.repr(str(number))} is beyond the "
                "floating-point range (about 1.8e308) the equations are computed in"
            )
    return expr


def parse_number(value: object, where: str) -> float:
    """Check a number given as a TOML value (a parameter or an initial value) and return it.

    Parameters
    ----------
    value : object
        The value read from the file: an int or a float, not a bool, a string or anything else.
    where : str
        Where the value comes from, the start of the error message.

    Returns
    -------
    float
        The value as a finite float.

    Raises
    ------
    ExpressionError
        ``value`` is not an int or float, or is infinite, NaN, or too large for a float.

    Examples
    --------
    >>> parse_number(3, "key m")
    3.0
    >>> parse_number("3", "key m")
    Traceback (most recent call last):
    ...
    pfaff.core.safe_expr.ExpressionError: key m: expected a number, got the string '3' (write numbers without quotes)
    """
    if isinstance(value, str):
        raise ExpressionError(
            f"{where}: expected a number, got the string {_shortrepr.repr(value)} "
            "(write numbers without quotes)"
        )
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ExpressionError(
            f"{where}: expected a number, got {type(value).__name__} {_shortrepr.repr(value)}"
        )
    try:
        number = float(value)
    except OverflowError:
        raise ExpressionError(f"{where}: the integer is too large for a float") from None
    if not math.isfinite(number):
        raise ExpressionError(f"{where}: expected a finite number, got {number}")
    return number


def check_name(name: object, where: str) -> None:
    """Check that ``name`` may be declared in a model file (a coordinate or a parameter).

    A name is an ASCII identifier of at most 100 characters, not a Python keyword, not starting
    with ``_`` and not one of :data:`RESERVED_NAMES` (the functions, ``dot``, ``t``, ``pi``,
    ``E``).

    Raises
    ------
    ExpressionError
        The name is not allowed; the message says why.

    Examples
    --------
    >>> check_name("theta1", "key coordinates[0]")
    >>> check_name("lambda", "key parameters")
    Traceback (most recent call last):
    ...
    pfaff.core.safe_expr.ExpressionError: key parameters: 'lambda' is a Python keyword, not allowed as a name
    """
    if not isinstance(name, str):
        raise ExpressionError(
            f"{where}: a name must be a string, got {type(name).__name__} {_shortrepr.repr(name)}"
        )
    shown = _shortrepr.repr(name)
    if len(name) > MAX_NAME_LENGTH:
        problem = f"is longer than {MAX_NAME_LENGTH} characters"
    elif not (name.isascii() and name.isidentifier()):
        problem = "is not a name (ASCII letters, digits and '_', not starting with a digit)"
    elif keyword.iskeyword(name):
        problem = "is a Python keyword, not allowed as a name"
    elif name.startswith("_"):
        problem = "starts with '_', which is reserved"
    elif name in RESERVED_NAMES:
        problem = "is reserved (a function, a constant, dot or the time t)"
    else:
        return
    raise ExpressionError(f"{where}: {shown} {problem}")


def _check_options(
    names: Mapping[str, sp.Expr],
    functions: Mapping[str, tuple[Callable[..., sp.Expr], int]],
    subscripts: Mapping[str, Callable[[sp.Expr], sp.Expr]] | None,
    allow_dot: bool,
) -> None:
    """Reject malformed arguments of :func:`parse_expression` (the caller's bugs)."""
    if not isinstance(names, Mapping):
        raise TypeError(f"`names` must be a mapping, got {type(names).__name__}")
    for key, value in names.items():
        if not isinstance(key, str) or not isinstance(value, sp.Expr):
            raise TypeError(
                f"`names` must map strings to SymPy expressions, got {key!r}: {value!r}"
            )
    for key, entry in functions.items():
        if not (isinstance(entry, tuple) and len(entry) == 2 and callable(entry[0])):
            raise TypeError(f"`functions`: {key!r} must map to (callable, arity), got {entry!r}")
    taken = set(CONSTANTS) | set(functions) | ({"dot"} if allow_dot else set())
    clash = sorted(taken.intersection(names))
    if clash:
        raise ValueError(f"`names` may not redefine functions or constants: {', '.join(clash)}")
    if subscripts is not None and not all(callable(f) for f in subscripts.values()):
        raise TypeError("`subscripts` must map family names to callables")


def _scan(text: object, where: str, max_length: int, max_depth: int) -> None:
    """The checks before parsing: type, length, characters, bracket depth (one linear pass each)."""
    if not isinstance(text, str):
        raise ExpressionError(
            f"{where}: expected an expression string, got {type(text).__name__} "
            f"{_shortrepr.repr(text)}"
        )
    if len(text) > max_length:
        raise ExpressionError(
            f"{where}: the expression is {len(text)} characters long, more than {max_length}"
        )
    bad = _BAD_CHARACTER.search(text)
    if bad:
        char = bad.group()
        if char == "\0":
            what = "a NUL character"
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            what = f"the control character U+{ord(char):04X}"
        else:
            what = f"the non-ASCII character {char!r} (U+{ord(char):04X})"
        raise ExpressionError(
            f"{where}: {what} at position {bad.start() + 1}: expressions are printable ASCII"
        )
    depth = 0
    for match in _BRACKET.finditer(text):
        depth += 1 if match.group() in "([{" else -1
        if depth > max_depth:
            raise ExpressionError(
                f"{where}: brackets nested more than {max_depth} deep "
                f"(position {match.start() + 1})"
            )


_LONG_DIGITS = re.compile(rf"(?<![0-9.eE_])[0-9]{{{MAX_INT_DIGITS + 1},}}(?![0-9.eEjJ_])")  # ints


def _parse(text: str, body: str, lead: int, where: str) -> ast.expr:
    """``ast.parse`` of the stripped text, its failures as :class:`ExpressionError`."""
    digits = _LONG_DIGITS.search(body)  # Python refuses > 4300 digits in words of its own
    if digits is not None:
        raise ExpressionError(
            f"{where}: an integer has more than {MAX_INT_DIGITS} digits "
            f"({_location(text, lead, 1, digits.start())})"
        )
    try:
        with warnings.catch_warnings():  # SyntaxWarning, DeprecationWarning of odd literals
            warnings.simplefilter("ignore")
            return ast.parse(body, mode="eval").body
    except SyntaxError as e:
        where_in = ""
        if e.lineno and e.offset:
            where_in = f" ({_location(text, lead, e.lineno, e.offset - 1)})"
        raise ExpressionError(f"{where}: invalid syntax: {e.msg}{where_in}") from None
    except (RecursionError, MemoryError):
        raise ExpressionError(
            f"{where}: the expression is nested too deeply for Python's parser "
            "(a chain of about a thousand operators or more)"
        ) from None
    except ValueError as e:
        raise ExpressionError(f"{where}: invalid expression: {e}") from None


def _location(text: str, lead: int, lineno: int, col: int) -> str:
    """'column C' (or 'line L, column C' for text of several lines), 1-based, in ``text``."""
    skipped = text[:lead]
    line = lineno + skipped.count("\n")
    if lineno == 1:
        col += lead - (skipped.rfind("\n") + 1)
    return f"line {line}, column {col + 1}" if "\n" in text else f"column {col + 1}"


def tree_size(expr: sp.Basic) -> int:
    """The nodes of ``expr`` as a tree: a subexpression shared n times counts n times (what a
    traversal, a derivative or printed code costs), found in one pass over the distinct ones.

    Examples
    --------
    >>> x = sp.Symbol("x")
    >>> u = x + 1
    >>> for _ in range(40):
    ...     u = sp.Mul(u, u + x, evaluate=False)
    >>> tree_size(x), tree_size(x + 1), tree_size(u) > 2**40
    (1, 3, True)
    """
    sizes: dict[int, int] = {}
    stack: list[tuple[sp.Basic, bool]] = [(expr, False)]
    while stack:
        node, ready = stack.pop()
        if id(node) in sizes:
            continue
        if ready:
            sizes[id(node)] = 1 + sum(sizes[id(a)] for a in node.args)
            continue
        stack.append((node, True))
        stack.extend((a, False) for a in node.args if id(a) not in sizes)
    return sizes[id(expr)]


def _digits(r: sp.Rational) -> float:
    """Decimal digits of the numerator plus those of the denominator."""
    p, q = int(r.p), int(r.q)
    return (math.log10(abs(p)) if p else 0.0) + math.log10(q)


def _content(expr: sp.Expr) -> tuple[float, float]:
    """Digits of the exact numbers SymPy multiplies when ``expr`` is a factor or a base.

    Returns the digits of its rational factors, and those of the rational bases of its powers
    (roots such as ``sqrt(6)``, which SymPy combines and factors).
    """
    if expr.is_Rational:
        return _digits(expr), 0.0
    if expr.is_Pow and expr.base.is_Rational:
        return 0.0, _digits(expr.base)
    if expr.is_Mul:
        parts = [_content(a) for a in expr.args]  # the args of a Mul are not Muls
        return sum(p[0] for p in parts), sum(p[1] for p in parts)
    return 0.0, 0.0


def _sum_digits(terms: list[sp.Expr]) -> float:
    """A bound on the digits of the rational coefficients SymPy adds up in ``Add(*terms)``.

    Terms with the same non-numeric part are collected: the sum of n rationals p/q has at most
    log10(n) + max digits(p) + 2 * (digits of the distinct q) digits.
    """
    groups: dict[sp.Expr, tuple[int, float, set[int]]] = {}
    for part in (p for e in terms for p in (e.args if e.is_Add else (e,))):
        coeff, rest = part.as_coeff_Mul()
        if coeff.is_Rational:
            count, top, dens = groups.get(rest, (0, 0.0, set()))
            top = max(top, math.log10(abs(int(coeff.p))) if coeff.p else 0.0)
            dens.add(int(coeff.q))
            groups[rest] = (count + 1, top, dens)
    return max(
        (
            math.log10(n) + top + 2 * sum(math.log10(q) for q in dens)
            for n, top, dens in groups.values()
        ),
        default=0.0,
    )


def _chain(
    node: ast.BinOp, ops: tuple[type[ast.operator], ...]
) -> tuple[list[ast.expr], list[bool]]:
    """The operands of a left-leaning chain ``a + b - c`` and whether each is subtracted/divided."""
    operands: list[ast.expr] = []
    inverted: list[bool] = []
    current: ast.expr = node
    while isinstance(current, ast.BinOp) and isinstance(current.op, ops):
        operands.append(current.right)
        inverted.append(isinstance(current.op, ast.Sub | ast.Div))
        current = current.left
    operands.append(current)
    inverted.append(False)
    return operands[::-1], inverted[::-1]


_Value = tuple[sp.Expr, int]  # an expression and its depth in powers and calls
_Task = tuple[Callable[[ast.expr, object, list[_Value]], None] | None, ast.expr, object]


class _Builder:
    """Walks a syntax tree iteratively, building the SymPy expression of each allowed node."""

    def __init__(
        self,
        text: str,
        body: str,
        lead: int,
        where: str,
        names: Mapping[str, sp.Expr],
        functions: Mapping[str, tuple[Callable[..., sp.Expr], int]],
        subscripts: Mapping[str, Callable[[sp.Expr], sp.Expr]] | None,
        allow_dot: bool,
        max_depth: int,
    ) -> None:
        self.text, self.body, self.lead, self.where = text, body, lead, where
        self.names, self.functions, self.subscripts = names, functions, subscripts or {}
        self.allow_dot, self.max_depth = allow_dot, max_depth
        self.written_out = 0  # the nodes the names' values add, written out as trees
        self.sizes: dict[str, int] = {}  # each name's value's tree_size

    # -- errors -------------------------------------------------------------------------------

    def error(self, node: ast.AST, problem: str, detail: str = "") -> ExpressionError:
        """The error for ``problem`` at ``node``, located by column."""
        where = _location(self.text, self.lead, node.lineno, node.col_offset)  # type: ignore[attr-defined]
        return ExpressionError(
            f"{self.where}: {problem} ({where}{'; ' + detail if detail else ''})"
        )

    def segment(self, node: ast.AST) -> str:
        """The source text of ``node``, shortened, quoted."""
        return _shortrepr.repr(ast.get_source_segment(self.body, node) or "")

    def refuse(self, node: ast.AST) -> ExpressionError:
        """The error for a construct outside the whitelist, named."""
        what = _REFUSED.get(type(node), f"the construct {type(node).__name__} is")
        return self.error(node, f"{what} not allowed: {self.segment(node)}")

    def unknown(self, node: ast.AST, name: str, kind: str = "name") -> ExpressionError:
        """The error for an undeclared name, with the close matches and the declared names."""
        known = sorted(self.names)
        pool = known + sorted(CONSTANTS) if kind == "name" else sorted(self.functions)
        close = difflib.get_close_matches(name, pool, n=1) if len(name) <= 100 else []
        hint = f"did you mean {close[0]!r}? " if close else ""
        if kind == "function":
            listing = "functions: " + ", ".join(sorted(self.functions))
        else:
            listing = "declared: " + (", ".join(known[:12]) + (", ..." if len(known) > 12 else ""))
        return self.error(node, f"unknown {kind} {_shortrepr.repr(name)}", hint + listing)

    # -- the walk -----------------------------------------------------------------------------

    def build(self, root: ast.expr) -> sp.Expr:
        """The expression of ``root``: a post-order walk with an explicit stack."""
        count = 0
        for node in ast.walk(root):
            count += isinstance(node, ast.expr)
            if count > MAX_NODES:
                raise self.error(root, f"the expression has more than {MAX_NODES} terms")
        tasks: list[_Task] = [(None, root, None)]
        values: list[_Value] = []
        while tasks:
            combine, node, extra = tasks.pop()
            if combine is None:
                self.visit(node, tasks, values)
                continue
            try:
                combine(node, extra, values)
            except ExpressionError:
                raise
            except Exception as e:  # SymPy's own evaluation failed (an overflow, a bug)
                raise self.error(
                    node, f"SymPy could not evaluate {self.segment(node)} ({type(e).__name__})"
                ) from e
        ((expr, _),) = values
        if expr.has(*_UNDEFINED):
            raise self.error(root, "the expression is infinite or undefined (a division by zero?)")
        if expr.has(sp.I) or any(
            p.base.is_Number and p.base.is_negative and not p.exp.is_Integer
            for p in expr.atoms(sp.Pow)
        ):  # I, or a root of a negative number such as (-8)**(1/3)
            raise self.error(root, f"the expression is complex: {_shortrepr.repr(str(expr))}")
        return expr

    def visit(self, node: ast.expr, tasks: list[_Task], values: list[_Value]) -> None:
        """Check ``node``; push its value if a leaf, else its combination and its operands."""
        operands: list[ast.expr] = []
        if isinstance(node, ast.Constant):
            values.append((self.constant(node), 0))
        elif isinstance(node, ast.Name):
            values.append((self.name(node), 0))
        elif isinstance(node, ast.Subscript) and self.subscripts:
            values.append((self.subscript(node), 0))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add | ast.Sub):
            operands, inverted = _chain(node, (ast.Add, ast.Sub))
            tasks.append((self.combine_sum, node, inverted))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult | ast.Div):
            operands, inverted = _chain(node, (ast.Mult, ast.Div))
            tasks.append((self.combine_product, node, inverted))
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            operands = [node.left, node.right]
            tasks.append((self.combine_power, node, None))
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.UAdd | ast.USub):
            operands = [node.operand]
            if isinstance(node.op, ast.USub):
                tasks.append((self.combine_negative, node, None))
        elif isinstance(node, ast.BinOp | ast.UnaryOp):
            raise self.error(node, f"{_REFUSED_OPERATORS[type(node.op)]} is not allowed")
        elif isinstance(node, ast.Call):
            entry = self.callee(node)
            if entry is None:
                values.append((self.dot(node), 0))
            else:
                operands = list(node.args)
                tasks.append((self.combine_call, node, entry))
        else:
            raise self.refuse(node)
        tasks.extend((None, operand, None) for operand in reversed(operands))

    def push(self, node: ast.expr, expr: sp.Expr, depth: int, values: list[_Value]) -> None:
        """Check a built expression and push it."""
        if depth > self.max_depth:
            raise self.error(
                node, f"powers and function calls are nested more than {self.max_depth} deep"
            )
        if not isinstance(expr, sp.Expr):
            raise self.error(node, f"{self.segment(node)} is not a scalar expression")
        if any(expr is u for u in _UNDEFINED):
            raise self.error(
                node, f"{self.segment(node)} is infinite or undefined (a division by zero?)"
            )
        if expr.is_Rational and _digits(expr) > MAX_DIGITS:
            raise self.error(
                node, f"{self.segment(node)} is a number of more than {MAX_DIGITS} digits"
            )
        if expr.is_number and not expr.is_Rational:
            self.check_magnitude(node, expr)
        elif (expr.is_Mul or expr.is_Add) and expr.args[0].is_Float:  # 1e300**9 * x
            self.check_magnitude(node, expr.args[0])
        if expr.is_Pow and expr.exp.is_Number and abs(expr.exp) > MAX_EXPONENT:
            raise self.error(
                node,
                f"{self.segment(node)} has the exponent {_shortrepr.repr(str(expr.exp))}, "
                f"larger than {MAX_EXPONENT}",
            )
        values.append((expr, depth))

    # -- leaves -------------------------------------------------------------------------------

    def constant(self, node: ast.Constant) -> sp.Expr:
        """An int or finite float literal (``type(True)`` is bool, refused)."""
        value = node.value
        if type(value) is int:
            if abs(value) >= 10**MAX_INT_DIGITS:
                raise self.error(node, f"an integer has more than {MAX_INT_DIGITS} digits")
            return sp.Integer(value)
        if type(value) is float:
            if not math.isfinite(value):
                raise self.error(node, f"the number {self.segment(node)} is too large for a float")
            return sp.Float(value)
        what = _REFUSED_CONSTANTS.get(type(value), f"constants of type {type(value).__name__} are")
        raise self.error(node, f"{what} not allowed: {self.segment(node)}")

    def plain(self, node: ast.AST, name: str) -> None:
        """Refuse a name starting with '_' (dunder names are the usual escape route)."""
        if name.startswith("_"):
            raise self.error(
                node, f"names starting with '_' are not allowed: {_shortrepr.repr(name)}"
            )

    def declared(self, node: ast.Name) -> sp.Expr:
        """The value of a name of ``names``."""
        self.plain(node, node.id)
        if node.id not in self.names:
            raise self.unknown(node, node.id)
        return self.names[node.id]

    def name(self, node: ast.Name) -> sp.Expr:
        """A declared name or a constant."""
        name = node.id
        self.plain(node, name)
        if name in self.names:
            value = self.names[name]
            if name not in self.sizes:
                self.sizes[name] = tree_size(value)
            self.written_out += self.sizes[name] - 1
            if self.written_out > MAX_WRITTEN_OUT:
                raise self.error(
                    node,
                    f"the expression, with the values of the names it uses written out, has more "
                    f"than {MAX_WRITTEN_OUT} terms (inputs built from inputs double at each level)",
                )
            return value
        if name in CONSTANTS:
            return CONSTANTS[name]
        if name in self.functions or (name == "dot" and self.allow_dot):
            raise self.error(node, f"{name!r} is a function: call it, as in {name}(x)")
        if name in self.subscripts:
            raise self.error(node, f"{name!r} is an indexed family: index it, as in {name}[k]")
        raise self.unknown(node, name)

    def subscript(self, node: ast.Subscript) -> sp.Expr:
        """``family[k]``, ``family[k + 1]``, ``family[k - 1]``: the family's member at the index."""
        family = node.value
        if not isinstance(family, ast.Name):
            raise self.error(node, f"only a family name can be indexed, not {self.segment(family)}")
        self.plain(family, family.id)
        if family.id not in self.subscripts:
            listing = ", ".join(sorted(self.subscripts))
            raise self.error(
                family, f"{family.id!r} is not an indexed family", f"families: {listing}"
            )
        index = node.slice
        if isinstance(index, ast.Name):
            value = self.declared(index)
        elif (
            isinstance(index, ast.BinOp)
            and isinstance(index.op, ast.Add | ast.Sub)
            and isinstance(index.left, ast.Name)
            and isinstance(index.right, ast.Constant)
            and type(index.right.value) is int
        ):
            offset = self.constant(index.right)
            value = self.declared(index.left) + (
                offset if isinstance(index.op, ast.Add) else -offset
            )
        else:
            raise self.error(
                index,
                f"an index must be a name, or a name plus or minus an integer, as in "
                f"{family.id}[k+1], not {self.segment(index)}",
            )
        member = self.subscripts[family.id](value)
        if not isinstance(member, sp.Expr):
            raise TypeError(f"`subscripts`: {family.id!r} gave {member!r}, not a SymPy expression")
        return member

    def callee(self, node: ast.Call) -> tuple[Callable[..., sp.Expr], int] | None:
        """The function table entry of a call (None for ``dot``), its form checked."""
        func = node.func
        if not isinstance(func, ast.Name):
            if type(func) in _REFUSED:
                raise self.refuse(func)
            raise self.error(node, f"only named functions can be called, not {self.segment(func)}")
        name = func.id
        self.plain(func, name)
        if node.keywords:
            raise self.error(node, f"keyword arguments are not allowed: {self.segment(node)}")
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise self.error(node, f"starred arguments are not allowed: {self.segment(node)}")
        if name == "dot" and self.allow_dot:
            return None
        if name in self.functions:
            entry = self.functions[name]
            if len(node.args) != entry[1]:
                s = "" if entry[1] == 1 else "s"
                raise self.error(
                    node, f"{name}() takes {entry[1]} argument{s}, got {len(node.args)}"
                )
            return entry
        if name == "dot":
            raise self.error(node, "dot() is not allowed here")
        if name in self.names or name in CONSTANTS:
            raise self.error(node, f"{name!r} is not a function")
        raise self.unknown(func, name, "function")

    def dot(self, node: ast.Call) -> sp.Expr:
        """``dot(q)``: the time derivative of the coordinate ``q`` (or of a family member
        ``theta[k+1]``)."""
        if len(node.args) != 1:
            raise self.error(node, f"dot() takes 1 argument (a coordinate), got {len(node.args)}")
        arg = node.args[0]
        if isinstance(arg, ast.Subscript) and self.subscripts:  # dot(theta[k+1]): a member
            member = self.subscript(arg)
            return sp.Derivative(member, _T)
        if not isinstance(arg, ast.Name):
            raise self.error(arg, f"dot() takes the name of a coordinate, not {self.segment(arg)}")
        q = self.declared(arg)
        if not (isinstance(q, AppliedUndef) and q.args == (_T,)):
            raise self.error(
                arg, f"dot({arg.id}): {arg.id!r} is not a coordinate (a function of t)"
            )
        return sp.Derivative(q, _T)

    # -- combinations -------------------------------------------------------------------------

    @staticmethod
    def pop(values: list[_Value], n: int) -> tuple[list[sp.Expr], int]:
        """The last ``n`` values and their greatest depth."""
        taken = values[-n:]
        del values[-n:]
        return [e for e, _ in taken], max(d for _, d in taken)

    def combine_sum(self, node: ast.expr, inverted: object, values: list[_Value]) -> None:
        """``a + b - c ...`` as one ``Add``."""
        assert isinstance(inverted, list)
        terms, depth = self.pop(values, len(inverted))
        terms = [
            sp.Mul(sp.S.NegativeOne, e) if neg else e
            for e, neg in zip(terms, inverted, strict=True)
        ]
        if _sum_digits(terms) > MAX_DIGITS:
            raise self.error(node, f"the sum would have a number of more than {MAX_DIGITS} digits")
        self.push(node, sp.Add(*terms), depth, values)

    def combine_product(self, node: ast.expr, inverted: object, values: list[_Value]) -> None:
        """``a * b / c ...`` as one ``Mul``."""
        assert isinstance(inverted, list)
        factors, depth = self.pop(values, len(inverted))
        factors = [
            self.power(node, e, sp.S.NegativeOne) if inv else e
            for e, inv in zip(factors, inverted, strict=True)
        ]
        parts = [_content(f) for f in factors]
        exact, roots = sum(p[0] for p in parts), sum(p[1] for p in parts)
        if exact > MAX_DIGITS:
            raise self.error(
                node, f"the product would be a number of more than {MAX_DIGITS} digits"
            )
        if roots > MAX_ROOT_DIGITS:
            raise self.error(
                node,
                f"the product would take the root of a number of more than {MAX_ROOT_DIGITS} digits",
            )
        self.push(node, sp.Mul(*factors), depth, values)

    def combine_power(self, node: ast.expr, _: object, values: list[_Value]) -> None:
        """``a ** b``."""
        (base, exponent), depth = self.pop(values, 2)
        self.push(node, self.power(node, base, exponent), depth + 1, values)

    def combine_negative(self, node: ast.expr, _: object, values: list[_Value]) -> None:
        """``-a``."""
        (operand,), depth = self.pop(values, 1)
        self.push(node, sp.Mul(sp.S.NegativeOne, operand), depth, values)

    def combine_call(self, node: ast.expr, entry: object, values: list[_Value]) -> None:
        """``f(a, ...)`` for a function of the table."""
        assert isinstance(entry, tuple)
        func, arity = entry
        args, depth = self.pop(values, arity) if arity else ([], 0)
        for a in args if func in EXPANDING else ():
            if (size := expanded_terms(a)) > MAX_FUNCTION_TERMS:
                shown = f"{size}" if size < 1 << 40 else "more than 2**40"
                raise self.error(
                    node,
                    f"the argument of {self.segment(node)} would expand to {shown} terms "
                    f"(at most {MAX_FUNCTION_TERMS}): SymPy expands it to decide its sign or "
                    "reality, which can take minutes; write a shorter argument",
                )
        if func is sp.sqrt:
            self.check_power(node, args[0], sp.S.Half)
        elif func is sp.exp:
            self.check_exp(node, args[0])
        self.push(node, func(*args), depth + 1, values)

    # -- sizing what SymPy would compute exactly ----------------------------------------------

    def power(self, node: ast.expr, base: sp.Expr, exponent: sp.Expr) -> sp.Expr:
        """``Pow(base, exponent)``, sized first."""
        self.check_power(node, base, exponent)
        return sp.Pow(base, exponent)

    def check_power(self, node: ast.expr, base: sp.Expr, exponent: sp.Expr) -> None:
        """Refuse a power whose evaluation would make a huge number or factor a large one.

        The numeric part of the exponent is sized: the exponent itself, or its constant term
        (SymPy splits ``2**(x + n)`` into ``2**n * 2**x`` when it extracts contents).
        """
        number = exponent if exponent.is_Number else exponent.as_coeff_Add()[0]
        if number.is_Number and number != 0:
            self.check_exponent(node, base, number)
        if base is sp.E:
            self.check_exp(node, exponent)

    def check_exponent(self, node: ast.expr, base: sp.Expr, number: sp.Number) -> None:
        """Refuse ``base**number`` if the number is large, or the power or root costly."""
        if abs(number) > MAX_EXPONENT:
            shown = _shortrepr.repr(str(number))
            raise self.error(node, f"the exponent {shown} is larger than {MAX_EXPONENT}")
        exact, roots = _content(base)
        size = (exact + roots) * abs(float(number))
        if size > MAX_DIGITS:
            raise self.error(
                node,
                f"the power would be a number of about {size:.0f} digits (at most {MAX_DIGITS})",
            )
        if number.is_Rational and number.q > MAX_EXPONENT:
            raise self.error(node, f"the root of index {number.q} is larger than {MAX_EXPONENT}")
        if number.is_Rational and not number.is_Integer and exact + roots > MAX_ROOT_DIGITS:
            raise self.error(
                node, f"the root of a number of more than {MAX_ROOT_DIGITS} digits is not taken"
            )

    def check_magnitude(self, node: ast.expr, expr: sp.Expr) -> None:
        """Refuse a numeric value that is not real, or beyond 10**MAX_DIGITS in magnitude.

        A function of a huge number costs SymPy precision in proportion to its size (it takes
        sin(cosh(10**6)) 25 s to find the sign), and functions of complex numbers grow into
        logarithms of square roots; bounding every numeric value as it is built keeps the next
        one cheap. The result would be refused as complex anyway.
        """
        value = expr.evalf(15)
        if value.has(sp.I):
            raise self.error(node, f"{self.segment(node)} is not a real number ({value})")
        if not (value.is_Number and value.is_finite and abs(value) <= _LARGEST):
            raise self.error(
                node,
                f"{self.segment(node)} is a number of magnitude beyond 10**{MAX_DIGITS} "
                "(or one that cannot be evaluated)",
            )

    def check_exp(self, node: ast.expr, arg: sp.Expr) -> None:
        """Refuse ``exp(c*log(b) + ...)``, which SymPy turns into ``b**c * ...``, if too large."""
        exact = roots = 0.0
        for term in sp.Add.make_args(arg):
            factors = sp.Mul.make_args(term)
            logs = [f for f in factors if isinstance(f, sp.log)]
            if len(logs) != 1:
                continue
            coeff = sp.Mul(*(f for f in factors if f is not logs[0]))
            if coeff.is_Number:  # SymPy evaluates only a numeric coefficient
                base = logs[0].args[0]
                self.check_power(node, base, coeff)
                size = sum(_content(base))
                if coeff.is_Integer:
                    exact += size * abs(float(coeff))
                else:
                    roots += size
        if exact > MAX_DIGITS:
            raise self.error(
                node, f"the exponential would be a number of more than {MAX_DIGITS} digits"
            )
        if roots > MAX_ROOT_DIGITS:
            raise self.error(
                node, f"the root of a number of more than {MAX_ROOT_DIGITS} digits is not taken"
            )
