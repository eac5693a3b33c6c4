"""The safe expression parser: exact SymPy results, and hostile text refused quickly, running nothing."""

from __future__ import annotations

import builtins
import random

import pytest
import sympy as sp
import sympy.parsing.sympy_parser
from sympy.physics.vector import dynamicsymbols

import pfaff.core.symbols
from pfaff.core.errors import ModelError
from pfaff.core.safe_expr import (
    FUNCTIONS,
    MAX_DIGITS,
    ExpressionError,
    check_name,
    parse_expression,
    parse_number,
)

t = pfaff.core.symbols.t
theta1, theta2, x, y = dynamicsymbols("theta1 theta2 x y")
l1, l2, m, m1, m2, c, k, z = sp.symbols("l1 l2 m m1 m2 c k z")
NAMES = {
    "theta1": theta1,
    "theta2": theta2,
    "x": x,
    "y": y,
    "l1": l1,
    "l2": l2,
    "m": m,
    "m1": m1,
    "m2": m2,
    "c": c,
    "k": k,
    "z": z,
    "t": t,
}
WHERE = "file m.toml, key particles[0].mass"
theta = sp.Function("theta")
FAMILIES = {"theta": theta}


def parse(text: str, **kwargs) -> sp.Expr:
    return parse_expression(text, NAMES, where=WHERE, **kwargs)


def refused(text: str, match: str = "", **kwargs) -> ExpressionError:
    """Parse ``text``, expecting an ExpressionError (refused before any costly work: the
    parser's size bounds; speed is not asserted here, the machine may be busy)."""
    with pytest.raises(ExpressionError, match=match) as info:
        parse(text, **kwargs)
    assert str(info.value).startswith(WHERE + ": ")
    return info.value


# -- exact results ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("l1*sin(theta1) + l2*sin(theta2)", l1 * sp.sin(theta1) + l2 * sp.sin(theta2)),
        ("-c*(dot(theta2) - dot(theta1))", -c * (theta2.diff(t) - theta1.diff(t))),
        ("atan2(y, x)", sp.atan2(y, x)),
        ("x**2", x**2),
        ("2.5e-3*m", sp.Float(2.5e-3) * m),
        ("-x", -x),
        ("+x - -y", x + y),
        ("pi/2", sp.pi / 2),
        ("1/2", sp.Rational(1, 2)),
        ("E**x", sp.exp(x)),
        ("m1*m2/(m1 + m2)", m1 * m2 / (m1 + m2)),
        ("sqrt(l1**2 + l2**2)", sp.sqrt(l1**2 + l2**2)),
        ("exp(-c*t)*cos(k*t)", sp.exp(-c * t) * sp.cos(k * t)),
        ("abs(x)*sign(y) + log(m)", sp.Abs(x) * sp.sign(y) + sp.log(m)),
        ("tan(x) + asin(z) + acos(z) + atan(z)", sp.tan(x) + sp.asin(z) + sp.acos(z) + sp.atan(z)),
        ("sinh(x) + cosh(x) + tanh(x)", sp.sinh(x) + sp.cosh(x) + sp.tanh(x)),
        ("0.5*m*(dot(x)**2 + dot(y)**2)", sp.Float(0.5) * m * (x.diff(t) ** 2 + y.diff(t) ** 2)),
        ("2**10", sp.Integer(1024)),
        ("\n  l1 * x\n", l1 * x),
    ],
)
def test_parses_to_the_sympy_expression(text: str, expected: sp.Expr) -> None:
    assert parse(text) == expected


def test_floats_keep_their_python_value_and_integers_stay_exact() -> None:
    assert float(parse("0.1")) == 0.1
    assert parse("0.1") == sp.Float(0.1)
    assert isinstance(parse("3"), sp.Integer)
    assert parse("10**10") == sp.Integer(10**10)
    assert parse("2**1000") == sp.Integer(2**1000)


def test_dot_is_the_time_derivative_of_a_coordinate() -> None:
    assert parse("dot(theta1)") == theta1.diff(t)
    # SymPy's time symbol, made without importing sympy.physics: equal (and hashing alike)
    assert pfaff.core.symbols.t == dynamicsymbols._t
    assert hash(pfaff.core.symbols.t) == hash(dynamicsymbols._t)
    refused("dot(theta1)", "dot\\(\\) is not allowed", allow_dot=False)
    refused("dot(m1)", "'m1' is not a coordinate")
    refused("dot(1+2)", "dot\\(\\) takes the name of a coordinate, not '1\\+2'")
    refused("dot(dot(x))", "takes the name of a coordinate")
    refused("dot(x, y)", "dot\\(\\) takes 1 argument")
    refused("dot", "'dot' is a function")


def test_subscripts_call_the_family_with_the_index() -> None:
    assert parse("theta[k]", subscripts=FAMILIES) == theta(k)
    assert parse("theta[k+1] - theta[k-1]", subscripts=FAMILIES) == theta(k + 1) - theta(k - 1)
    assert parse("l1*sin(theta[k + 2])", subscripts=FAMILIES) == l1 * sp.sin(theta(k + 2))
    refused("theta[k]", "indexing is not allowed")
    refused("theta[2*k]", "an index must be a name", subscripts=FAMILIES)
    refused("theta[k+z*1]", "an index must be a name", subscripts=FAMILIES)
    refused("theta[k+True]", "an index must be a name", subscripts=FAMILIES)
    refused("theta[1:2]", "an index must be a name", subscripts=FAMILIES)
    refused("theta[j]", "unknown name 'j'", subscripts=FAMILIES)
    refused("x[k]", "'x' is not an indexed family", subscripts=FAMILIES)
    refused("theta", "'theta' is an indexed family", subscripts=FAMILIES)
    refused("sin(x)[k]", "only a family name can be indexed", subscripts=FAMILIES)
    with pytest.raises(TypeError, match="`subscripts`: 'theta' gave 1, not a SymPy expression"):
        parse("theta[k]", subscripts={"theta": lambda index: 1})


def test_custom_function_table() -> None:
    table = {"cbrt": (sp.cbrt, 1)}
    assert parse("cbrt(m)", functions=table) == sp.cbrt(m)
    refused("sin(m)", "unknown function 'sin'", functions=table)
    assert parse("sin(m)", functions={**FUNCTIONS, **table}) == sp.sin(m)


def test_a_failure_inside_sympy_is_an_expression_error() -> None:
    def overflow(arg: sp.Expr) -> sp.Expr:
        raise OverflowError("too many digits in integer")  # as SymPy raises on some inputs

    e = refused(
        "1 + boom(x)",
        "SymPy could not evaluate 'boom\\(x\\)' \\(OverflowError\\)",
        functions={"boom": (overflow, 1)},
    )
    assert isinstance(e.__cause__, OverflowError)


def test_a_long_sum_is_walked_without_recursion() -> None:
    names = {f"a{i}": sp.Symbol(f"a{i}") for i in range(800)}
    text = " + ".join(f"{i}*a{i}" for i in range(800))
    expr = parse_expression(text, names)  # (a recursive walk would exceed Python's limit)
    assert expr == sp.Add(*(i * names[f"a{i}"] for i in range(800)))


# -- error messages -------------------------------------------------------------------------------


def test_errors_name_the_place_the_problem_and_the_declared_names() -> None:
    e = refused("m1 + foo", "unknown name 'foo'")
    assert isinstance(e, ModelError)
    assert isinstance(e, ValueError)
    assert "column 6" in str(e)
    assert "declared: c, k, l1, l2, m, m1, m2, t, theta1, theta2, x, y" in str(e)
    refused("theta11", "did you mean 'theta1'")
    refused("(x +\n  foo)", "line 2, column 3")
    refused("sin", "'sin' is a function")
    refused("m1(x)", "'m1' is not a function")
    refused("pi(x)", "'pi' is not a function")


def test_syntax_errors_are_expression_errors() -> None:
    refused("", "empty")
    refused("   \n ", "empty")
    refused("1 +", "invalid syntax")
    refused("x +\n 1", "invalid syntax")
    refused("(x", "invalid syntax")
    refused("x = 1", "invalid syntax")
    refused("import os", "invalid syntax")


def test_bad_arguments_of_the_caller() -> None:
    with pytest.raises(TypeError, match="`names` must map strings to SymPy expressions"):
        parse_expression("a", {"a": 1})  # type: ignore[dict-item]
    with pytest.raises(ValueError, match="may not redefine functions or constants: pi, sin"):
        parse_expression("a", {"pi": sp.Symbol("p"), "sin": z})


# -- hostile input --------------------------------------------------------------------------------


def test_import_and_system_call_do_not_run(tmp_path) -> None:
    target = tmp_path / "pwned"
    refused(f"__import__('os').system('touch {target}')", "attribute access is not allowed")
    refused("__import__('os')", "names starting with '_' are not allowed: '__import__'")
    assert not target.exists()


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("().__class__.__bases__[0].__subclasses__()", "attribute access is not allowed"),
        ("(lambda: 1)()", "lambda expressions are not allowed"),
        ("[x for x in ()]", "comprehensions are not allowed"),
        ("sum(x for x in y)", "unknown function 'sum'"),
        ("(x for x in y)", "generator expressions are not allowed"),
        ("sin.__globals__", "attribute access is not allowed"),
        ("x.diff", "attribute access is not allowed"),
        ("open('x')", "unknown function 'open'"),
        ("eval('1')", "unknown function 'eval'"),
        ("exec('1')", "unknown function 'exec'"),
        ("getattr(x, 'y')", "unknown function 'getattr'"),
        ("globals()", "unknown function 'globals'"),
        ("_x", "names starting with '_' are not allowed"),
        ("sin(x)(y)", "only named functions can be called"),
        ("foo", "unknown name 'foo'"),
        ("True", "booleans \\(True, False\\) are not allowed"),
        ("None", "None is not allowed"),
        ("'abc'", "strings are not allowed"),
        ("b'abc'", "bytes are not allowed"),
        ("1j", "complex numbers are not allowed"),
        ("...", "ellipsis"),
        ("sin(x=1)", "keyword arguments are not allowed"),
        ("sin(**x)", "keyword arguments are not allowed"),
        ("sin(*x)", "starred arguments are not allowed"),
        ("atan2(1)", "atan2\\(\\) takes 2 arguments, got 1"),
        ("sin(x, y)", "sin\\(\\) takes 1 argument, got 2"),
        ("f'{x}'", "f-strings are not allowed"),
        ("(z:=1)", "assignment expressions \\(:=\\) are not allowed"),
        ("x if y else z", "conditional expressions .* are not allowed"),
        ("x < y", "comparisons are not allowed"),
        ("x and y", "boolean operators \\(and, or\\) are not allowed"),
        ("not x", "'not' is not allowed"),
        ("x @ y", "matrix multiplication '@' is not allowed"),
        ("x // y", "floor division '//' is not allowed"),
        ("x % y", "the remainder operator '%' is not allowed"),
        ("~x", "the bitwise inversion '~' is not allowed"),
        ("x ^ 2", "a power is written x\\*\\*2"),
        ("x | y", "bitwise or"),
        ("x << 2", "shift"),
        ("[x]", "lists are not allowed"),
        ("{x: 1}", "dictionaries are not allowed"),
        ("{x}", "sets are not allowed"),
        ("x, y", "tuples .* are not allowed"),
        ("x[0]", "indexing is not allowed"),
    ],
)
def test_constructs_outside_the_grammar_are_refused(text: str, match: str) -> None:
    refused(text, match)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("10**10**10", "the exponent '10000000000' is larger than 1000"),
        ("9**9**9", "the exponent '387420489' is larger than 1000"),
        ("x**1001", "larger than 1000"),
        ("(x**999)**999", "has the exponent '998001'"),
        ("3**(1/1001)", "the root of index 1001 is larger than 1000"),
        ("2**(x + 10**10)", "the exponent '10000000000' is larger than 1000"),
        ("tan(atan2(k, 7**300**(k + 7**300)))", "larger than 1000"),
        ("3**(1/(7**99 + 1))", "the root of index"),
        ("11**999", f"about \\d+ digits \\(at most {MAX_DIGITS}\\)"),
        ("(7**500*x)**3", "the power would be a number"),
        ("sqrt(7**1000 + 1)", "the root of a number of more than 100 digits"),
        ("(7**200 + 1)**(1/3)", "the root of a number of more than 100 digits"),
        ("exp(999*log(11))", "the power would be a number"),
        ("E**(999*log(11))", "the power would be a number"),
        ("exp(log(7**200 + 1)/2)", "the root of a number"),
        ("*".join(["(7**300 + 1)"] * 4), "the product would be a number"),
        ("*".join(f"sqrt(7**31 + {i})" for i in range(8)), "the product would take the root"),
        ("+".join(f"1/(7**300 + {i})" for i in range(5)), "the sum would have a number"),
        ("sin(cosh(10**6))", "'cosh\\(10\\*\\*6\\)' is a number of magnitude beyond 10\\*\\*1000"),
        ("atan2(sin(exp(exp(10))), 1)", "'exp\\(exp\\(10\\)\\)' is a number of magnitude beyond"),
        ("exp(7**99 + 1)**log(2)", "magnitude beyond"),
        ("1e300**4", "magnitude beyond"),
        ("x*1e300*1e300*1e300*1e300", "magnitude beyond"),
        ("1" * 101, "an integer has more than 100 digits"),
        ("1e999", "the number '1e999' is too large for a float"),
        ("1/0", "'1/0' is infinite or undefined"),
        ("x/0", "infinite or undefined"),
        ("log(0)", "infinite or undefined"),
        ("sqrt(-1)", "'sqrt\\(-1\\)' is not a real number"),
        ("(-8)**(1/3)", "is not a real number"),
        ("(-2.0)**0.5", "is not a real number"),
        ("asin(2) + x", "'asin\\(2\\)' is not a real number"),
    ],
)
def test_huge_or_undefined_numbers_are_refused_before_computing(text: str, match: str) -> None:
    refused(text, match)


def test_exponent_towers_are_refused_before_computing() -> None:
    refused("10**10**10", "the exponent '10000000000' is larger than 1000")
    refused("9**9**9", "the exponent '387420489' is larger than 1000")


def test_deep_nesting_is_refused_without_recursion_error() -> None:
    deep = "(" * 100_000 + "1" + ")" * 100_000
    refused(deep, "characters long, more than 10000")
    refused(deep, "brackets nested more than 100 deep", max_length=1_000_000)
    refused("(" * 101 + "x" + ")" * 101, "brackets nested more than 100 deep")
    refused("-" * 5000 + "x", "nested too deeply for Python's parser")
    refused("+".join(["x"] * 3000), "nested too deeply for Python's parser")
    refused("**".join(["x"] * 102), "powers and function calls are nested more than 100 deep")
    refused("sin(" * 30 + "x" + ")" * 30, "nested more than 20 deep", max_depth=20)
    assert parse("-" * 500 + "x") == x


def test_long_text_and_characters_are_checked_before_parsing() -> None:
    refused("x+" * 500_000 + "x", "characters long")
    refused("x + \0", "a NUL character at position 5")
    refused("x\x07", "the control character U\\+0007")
    refused("x\x1b[2J", "the control character U\\+001B")
    refused("x + \u03b8", "the non-ASCII character 'θ'")
    refused("ｓｉｎ(x)", "non-ASCII")  # NFKC would turn it into sin: refused before parsing
    garbage = random.Random(0).randbytes(4096).decode("latin-1")
    refused(garbage, "character")
    refused(bytes(range(256)).decode("latin-1"), "NUL")
    with pytest.raises(ExpressionError, match="expected an expression string, got bytes"):
        parse_expression(b"x", NAMES)  # type: ignore[arg-type]
    with pytest.raises(ExpressionError, match="expected an expression string, got float"):
        parse_expression(1.5, NAMES)  # type: ignore[arg-type]


def test_no_python_evaluation_is_used(monkeypatch: pytest.MonkeyPatch) -> None:
    def forbidden(*args, **kwargs):
        raise AssertionError("evaluation of a string was attempted")

    monkeypatch.setattr(builtins, "eval", forbidden)
    monkeypatch.setattr(builtins, "exec", forbidden)
    monkeypatch.setattr(sp, "sympify", forbidden)
    monkeypatch.setattr(sp, "parse_expr", forbidden, raising=False)
    monkeypatch.setattr(sympy.parsing.sympy_parser, "parse_expr", forbidden)  # sympify(str), S(str)
    expr = parse("l1*sin(theta1) + 0.5*m*dot(x)**2 - atan2(y, x)/2 + pi**2 + E")
    expected = l1 * sp.sin(theta1) + sp.Float(0.5) * m * x.diff(t) ** 2
    assert expr == expected - sp.atan2(y, x) / 2 + sp.pi**2 + sp.E
    refused("eval('1')", "unknown function 'eval'")


# -- numbers and names of model files -------------------------------------------------------------


def test_parse_number() -> None:
    assert parse_number(3, "key m") == 3.0
    assert isinstance(parse_number(3, "key m"), float)
    assert parse_number(-2.5e-3, "key m") == -2.5e-3
    for bad, match in [
        (True, "got bool"),
        ("1.0", "got the string '1.0' \\(write numbers without quotes\\)"),
        (None, "got NoneType"),
        ([1.0], "got list"),
        (float("nan"), "finite"),
        (float("inf"), "finite"),
        (-float("inf"), "finite"),
        (10**400, "too large for a float"),
    ]:
        with pytest.raises(ExpressionError, match=f"^key m: .*{match}"):
            parse_number(bad, "key m")


@pytest.mark.parametrize("name", ["x", "theta1", "m_1", "Theta", "l", "k2"])
def test_check_name_accepts_plain_names(name: str) -> None:
    check_name(name, "key coordinates")


@pytest.mark.parametrize(
    ("name", "match"),
    [
        ("", "is not a name"),
        ("1a", "is not a name"),
        ("a-b", "is not a name"),
        ("a b", "is not a name"),
        ("θ", "is not a name"),
        ("class", "Python keyword"),
        ("None", "Python keyword"),
        ("_x", "starts with '_'"),
        ("__import__", "starts with '_'"),
        ("sin", "is reserved"),
        ("atan2", "is reserved"),
        ("dot", "is reserved"),
        ("t", "is reserved"),
        ("pi", "is reserved"),
        ("E", "is reserved"),
        ("a" * 101, "longer than 100 characters"),
        (3, "must be a string"),
    ],
)
def test_check_name_refuses(name: object, match: str) -> None:
    with pytest.raises(ExpressionError, match=f"^key coordinates: .*{match}"):
        check_name(name, "key coordinates")


def test_dot_of_a_family_member() -> None:
    s = pfaff.System()
    th = s.add_family("theta", 4)
    k = sp.Symbol("k")
    got = parse_expression(
        "dot(theta[k+1]) - dot(theta[k])", {"k": k}, subscripts={"theta": lambda i: th[i]}
    )
    assert got == th[k + 1].diff(pfaff.t) - th[k].diff(pfaff.t)
