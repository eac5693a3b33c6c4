"""``pfaff.root_locus``: eigenvalues of a linearization over a range of one parameter."""

from __future__ import annotations

from base64 import b64encode
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import sympy as sp

from pfaff.core.display import number, summary_html
from pfaff.core.errors import ModelError, ModelTypeError
from pfaff.core.keywords import checked_keywords
from pfaff.derive.linearize import linearize

MAX_VALUES = 100_000  # values of one varied parameter (an eigenvalue problem each)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from pfaff.derive.equations import Derivation


class RootLocus(NamedTuple):
    """What :func:`root_locus` returns (unpacks as ``values, eigenvalues, figure``).

    Attributes
    ----------
    values : ndarray, shape (k,)
        The parameter's values.
    eigenvalues : ndarray, shape (k, n_states)
        Per value, the eigenvalues of A (sorted by real part, then imaginary part).
    figure : matplotlib.figure.Figure
        Their real and imaginary parts against the parameter.
    """

    values: np.ndarray
    eigenvalues: np.ndarray
    figure: Figure

    def stable_ranges(self, tol: float = 1e-9) -> list[tuple[float, float]]:
        """The runs of consecutive values at which every nonzero eigenvalue has a negative
        real part (eigenvalues below ``tol`` times the largest |s| count as zero: ignorable
        coordinates), as (first, last) value pairs.

        Examples
        --------
        >>> eig = np.array([[0.0, 1.0], [0.0, -1.0], [0.0, -2.0], [0.0, 3.0]])
        >>> RootLocus(np.arange(4.0), eig, None).stable_ranges()
        [(1.0, 2.0)]
        """
        w = np.asarray(self.eigenvalues, dtype=complex).reshape(len(self.values), -1)
        scale = max(float(np.abs(w).max(initial=0.0)), 1.0)
        stable = [bool(np.all(row.real[np.abs(row) > tol * scale] < 0)) for row in w]
        out: list[tuple[float, float]] = []
        for i, ok in enumerate(stable):
            if ok and (i == 0 or not stable[i - 1]):
                out.append((float(self.values[i]), float(self.values[i])))
            elif ok:
                out[-1] = (out[-1][0], float(self.values[i]))
        return out

    def _repr_html_(self) -> str:
        """The parameter's range, where the motion is stable, and the figure."""
        values = np.asarray(self.values, dtype=float)
        name = self.figure.axes[-1].get_xlabel() if self.figure is not None else "parameter"
        ranges = ", ".join(f"{number(a)} … {number(b)}" for a, b in self.stable_ranges())
        rows = [
            (name, f"{len(values)} values, {number(values.min())} … {number(values.max())}"),
            ("states", str(np.shape(self.eigenvalues)[-1])),
            ("stable (nonzero eigenvalues with Re s < 0)", ranges or "nowhere"),
        ]
        png = getattr(self.figure, "_repr_png_", lambda: None)()
        img = "" if png is None else f'<img src="data:image/png;base64,{b64encode(png).decode()}"/>'
        return summary_html("pfaff.RootLocus", rows, after=img)


def _point(op_point: dict | Callable, name: str, value: float, params: set[str]) -> dict:
    """The operating point at one value: ``op_point(value)``, or the dict with the symbol of
    that name replaced by the value in every entry (and the parameter of that name set)."""
    if callable(op_point):
        point = op_point(value)
        if not isinstance(point, dict):
            raise ModelTypeError(f"`op_point({value})` must return a dict; got {point!r:.60}")
        return point
    sym = sp.Symbol(name)
    out = {}
    for key, v in op_point.items():
        if isinstance(v, sp.Basic) and name in {s.name for s in v.free_symbols}:
            v = v.xreplace({s: value for s in v.free_symbols if s.name == name})
        out[key] = v
    if name in params:
        out.pop(sym, None)
        out[name] = value
    return out


def _values(values: object, name: str) -> np.ndarray:
    """The varied values: real numbers (not strings, booleans or complex), finite, at least one."""
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raw = np.asarray([], dtype=object)
    if raw.dtype.kind not in "iuf":
        raise ModelTypeError(f"`vary['{name}']` must be real numbers; got {values!r:.60}")
    out = raw.astype(float).ravel()
    if not out.size or not np.all(np.isfinite(out)):
        raise ModelError("`vary`: give at least one value, every one finite")
    if out.size > MAX_VALUES:  # one eigenvalue problem each: a million takes hours
        raise ModelError(f"`vary['{name}']`: {out.size} values, more than {MAX_VALUES}")
    return out


def _appears(op_point: object, name: str) -> bool:
    """Whether a symbol named ``name`` appears in a value of the operating point."""
    if not isinstance(op_point, dict):
        return False
    return any(
        isinstance(v, sp.Basic) and any(s.name == name for s in v.free_symbols)
        for v in op_point.values()
    )


@checked_keywords
def root_locus(
    eom: Derivation,
    op_point: dict | Callable,
    independent: object,
    vary: dict,
    independent_speeds: object = None,
    inputs: object = (),
) -> RootLocus:
    """Eigenvalues of :meth:`pfaff.EquationsOfMotion.linearize` as one parameter varies.

    Parameters
    ----------
    eom : EquationsOfMotion
    op_point : dict or callable
        The operating point: a dict in which the varied symbol may appear in values (the
        bicycle's rates ``{x.diff(t): v, ...}``) and which it completes when it is a parameter of
        the model; or a function of the value returning the dict
        (:func:`pfaff.models.bicycle.bicycle_operating_point`).
    independent, independent_speeds, inputs
        As for :meth:`~pfaff.EquationsOfMotion.linearize`.
    vary : dict
        One entry: the parameter's name (or Symbol) and its values.

    Returns
    -------
    RootLocus
        ``(values, eigenvalues, figure)``, eigenvalues of shape (len(values), n_states).

    Examples
    --------
    The pendulum's eigenvalues ±i√(g/L) as g grows:

    >>> import pfaff
    >>> eom = pfaff.models.pendulum().equations()
    >>> th = eom.coordinates[0]
    >>> values, eig, fig = pfaff.root_locus(eom, {th: 0, "m": 1, "L": 1}, [th], vary={"g": [1, 4]})
    >>> eig.imag
    array([[-1.,  1.],
           [-2.,  2.]])
    """
    if not isinstance(vary, dict) or len(vary) != 1:
        raise ModelTypeError(
            f"`vary` must be a dict of one parameter and its values; got {vary!r:.60}"
        )
    ((key, values),) = vary.items()
    if not isinstance(key, str | sp.Symbol):
        raise ModelTypeError(f"`vary`: the parameter must be a name or Symbol; got {key!r:.60}")
    name = key if isinstance(key, str) else key.name
    values = _values(values, name)
    params = {p.name for p in eom.parameters}
    if not callable(op_point) and name not in params and not _appears(op_point, name):
        raise ModelError(
            f"`vary`: `{name}` is not a parameter of the model (its parameters: "
            f"{', '.join(sorted(params)) or 'none'}) nor a symbol of the operating point, so "
            "varying it would change nothing"
        )
    rows = []
    for value in values:
        point = _point(op_point, name, float(value), params)
        lin = linearize(eom, point, independent, independent_speeds, inputs)
        rows.append(lin.eigenvalues())
    eig = np.array(rows)
    from pfaff.results.locus import locus_figure

    return RootLocus(values, eig, locus_figure(values, eig, name))
