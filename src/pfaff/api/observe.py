"""What a fit compares with measurements: coordinates, their rates, or expressions of q and q̇.

:class:`Observation` maps a run with sensitivities to the observed values y(t_i) and their
derivatives dy/dθ = y_q S_q + y_q̇ S_v + y_p (θ the fitted parameters and initial values).
A string is a name: a coordinate, or ``"<coordinate>_dot"`` for its rate (the columns of
:meth:`pfaff.Trajectory.to_csv`); it is never parsed. A SymPy expression of the coordinates,
their rates and the model's parameters (a point's position, say) is differentiated exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelError, OptionError
from pfaff.core.symbols import speed


def _named(name: str, coords: list[str]) -> tuple[int, bool]:
    """(coordinate index, is a rate) of an observed name."""
    if name in coords:
        return coords.index(name), False
    if name.endswith("_dot") and name[:-4] in coords:
        return coords.index(name[:-4]), True
    raise OptionError(
        f"`observe`: {name!r:.60} is neither a coordinate nor a coordinate's rate "
        f"(`<name>_dot`); coordinates: {', '.join(coords)}"
    )


class Observation:
    """The observed quantities of a fit, in the order of ``observe``.

    Parameters
    ----------
    observe : sequence of str or sympy.Expr
    coordinates : sequence of sympy functions of t
        The model's coordinates q(t) (``EquationsOfMotion.coordinates``); needed for expressions.
    names : list of str
        The coordinates' names.
    parameters : list of str
        The model's parameter names, in its order.

    Examples
    --------
    >>> import pfaff
    >>> obs = Observation(["theta", "theta_dot"], [], ["theta"], ["m", "l", "g", "c"])
    >>> obs.labels
    ['theta', 'theta_dot']
    """

    def __init__(
        self,
        observe: object,
        coordinates: Sequence[Any],
        names: list[str],
        parameters: list[str],
    ) -> None:
        if isinstance(observe, str) or not isinstance(observe, Sequence) or not len(observe):
            raise OptionError(
                "`observe` must be a non-empty list of coordinate names or expressions of "
                f"them; got {observe!r:.60}"
            )
        self.names, self.parameters = names, parameters
        self.items: list[tuple[int, bool] | tuple[Any, ...]] = []
        self.labels: list[str] = []
        for item in observe:
            if isinstance(item, str):
                self.items.append(_named(item, names))
                self.labels.append(item)
            elif isinstance(item, sp.Expr):
                self.items.append(self._expression(item, list(coordinates)))
                self.labels.append(str(item))
            else:
                raise OptionError(
                    f"`observe` entries must be names (str) or SymPy expressions; got {item!r:.60}"
                )

    def _expression(self, e: sp.Expr, coords: list) -> tuple[Any, ...]:
        if not coords:
            raise OptionError("`observe`: expressions need the model's coordinates")
        n = len(coords)
        q = sp.symbols(f"_oq0:{n}")
        v = sp.symbols(f"_ov0:{n}")
        ps = [sp.Symbol(p) for p in self.parameters]
        rule = {speed(c): v[i] for i, c in enumerate(coords)}
        rule.update({c: q[i] for i, c in enumerate(coords)})
        x = e.xreplace(rule)
        by_name = {p.name: p for p in ps}  # a parameter by its name, whatever its assumptions
        x = x.xreplace({s: by_name[s.name] for s in x.free_symbols if s.name in by_name})
        known = set(q) | set(v) | set(ps)
        unknown = {s for s in x.free_symbols if s not in known}
        if unknown or x.atoms(AppliedUndef, sp.Derivative):
            raise ModelError(
                f"`observe`: {e} uses {', '.join(sorted(map(str, unknown))) or 'a function'} "
                "that is neither a coordinate, a rate nor a parameter of the model"
            )
        args = [*q, *v, *ps]
        grads = [x.diff(a) for a in args]
        fn = sp.lambdify(args, [x, *grads], modules="numpy")
        return (fn, n, len(ps))

    def values(self, run: Any, cols: list[int], fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(y (k, n_obs), dy/dθ (k, n_obs, n_θ)) of a run with sensitivities: ``cols`` are the
        run's sensitivity columns of θ, ``fixed[j]`` the model parameter index of θ_j (-1 for
        an initial value)."""
        k, n = len(run.t), len(self.names)
        S = run.sensitivity[:, :, cols]
        y = np.empty((k, len(self.items)))
        dy = np.zeros((k, len(self.items), len(cols)))
        for o, item in enumerate(self.items):
            if len(item) == 2:
                j, rate = item
                y[:, o] = (run.qd if rate else run.q)[:, j]
                dy[:, o] = S[:, n * rate + j]
                continue
            fn = item[0]
            p = np.array(list(run.parameters.values()), dtype=float)
            for i in range(k):
                vals = fn(*run.q[i], *run.qd[i], *p)
                g = np.array([float(z) for z in vals[1:]])
                y[i, o] = float(vals[0])
                dy[i, o] = g[: 2 * n] @ S[i]
                for c, pi in enumerate(fixed):
                    if pi >= 0:
                        dy[i, o, c] += g[2 * n + pi]
        return y, dy
