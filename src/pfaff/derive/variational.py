"""The variational equations of a compiled model: exact derivatives of its equations by the state
and by parameters, generated once through the model's linearizer factory.

Along a solution of E = M q̈ − (Q − h) − Aᵀλ = 0, G = A q̈ + Ȧq̇ + ḃ = 0, the sensitivities
S_q = ∂q/∂p, S_v = ∂q̇/∂p obey (differentiating both equations by p)

    [[M, Aᵀ], [A, 0]] [S_a; −S_λ] = −[E_q S_q + E_qd S_v + E_p; G_q S_q + G_qd S_v + G_p]

with S_a = ∂q̈/∂p and S_λ = ∂λ/∂p. On the constraint manifold they keep
f_q S_q + f_p = 0 (holonomic rows, f_q = A there) and V_q S_q + A S_v + V_p = 0 (V = A q̇ + b).
:class:`VariationalKernel` evaluates what these need, as functions of x = (t, q, q̇, q̈, λ, p)
(:class:`pfaff.numeric.linearizer.LinearizationKernel`'s argument) generated once per set of
parameters by :meth:`pfaff.derive.linearize.CompiledLinearizer.generated`: nothing is derived
when a model is compiled, and models of other parameter values share the code.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from pfaff.derive.linearize import CompiledLinearizer, LinearForms


def _kkt_exprs(forms: LinearForms) -> list:
    """[[M, Aᵀ], [A, 0]] and [E; G], flattened row by row."""
    n, m = forms.n, forms.m
    K = [[*forms.M[i], *(forms.A[k][i] for k in range(m))] for i in range(n)]
    K += [[*forms.A[k], *([0] * m)] for k in range(m)]
    return [e for row in K for e in row] + [*forms.E, *forms.G]


def _rate_exprs(forms: LinearForms, params: tuple[int, ...]) -> list:
    """[E_q, E_qd, E_p; G_q, G_qd, G_p], flattened row by row."""
    jac = forms.jacobians
    ps = [forms.params[i] for i in params]
    out: list = []
    for name, exprs in (("E", forms.E), ("G", forms.G)):
        blocks = (jac[f"{name}_q"], jac[f"{name}_qd"], forms._jac(exprs, ps))
        for rows in zip(*blocks, strict=True):
            out += [e for row in rows for e in row]
    return out


def _tangent_exprs(forms: LinearForms, params: tuple[int, ...]) -> list:
    """A, V_q, V_p and f_p (holonomic rows), flattened row by row."""
    ps = [forms.params[i] for i in params]
    lists = [forms.A, forms.jacobians["V_q"], forms._jac(forms.V, ps), forms._jac(forms.f, ps)]
    return [e for rows in lists for row in rows for e in row]


def _split(flat: np.ndarray, shapes: list[tuple[int, int]]) -> list[np.ndarray]:
    out, k = [], 0
    for r, c in shapes:
        out.append(flat[k : k + r * c].reshape(r, c))
        k += r * c
    return out


class VariationalKernel:
    """The matrices of the variational equations of a model at x = (t, q, q̇, q̈, λ, p).

    Parameters
    ----------
    factory : CompiledLinearizer
        The compiled model's ``linearizer``.
    params : tuple of int
        Indices (in the model's parameter order) of the parameters p differentiated by.

    Attributes
    ----------
    n, m, n_p : int
        Coordinates, constraint rows, parameters.
    holonomic_rows : list of int
        The rows with a holonomic f (the rows of ``f_p``).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> eom = pfaff.models.pendulum().equations()
    >>> kernel = variational_kernel(eom.compile({"L": 2.0, "g": 9.81, "m": 1.0}).linearizer, (0,))
    >>> x = np.array([0.0, 0.5, 0.0, 0.0, 2.0, 9.81, 1.0])  # t, θ, θ̇, θ̈, L, g, m
    >>> E_p = kernel.rates(x)[0, 2]  # ∂(m L² θ̈ + m g L sin θ)/∂L = m g sin θ at θ̈ = 0
    >>> bool(np.isclose(E_p, 9.81 * np.sin(0.5)))
    True
    """

    def __init__(self, factory: CompiledLinearizer, params: tuple[int, ...]) -> None:
        forms = factory.forms
        n, m, r, h = forms.n, forms.m, len(params), len(forms.hol)
        self.n, self.m, self.n_p = n, m, r
        self.holonomic_rows = list(forms.hol)
        self._kkt = factory.generated("kkt", _kkt_exprs)
        self._rates = factory.generated(("rates", params), lambda f: _rate_exprs(f, params))
        self._tangent = factory.generated(("tangent", params), lambda f: _tangent_exprs(f, params))
        self._tangent_shapes = [(m, n), (m, n), (m, r), (h, r)]

    def kkt(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """K = [[M, Aᵀ], [A, 0]] (n + m, n + m) and [E; G] (n + m,) at x."""
        flat = np.asarray(self._kkt(x), dtype=float).ravel()
        s = self.n + self.m
        return flat[: s * s].reshape(s, s), flat[s * s :]

    def rates(self, x: np.ndarray) -> np.ndarray:
        """[[E_q, E_qd, E_p], [G_q, G_qd, G_p]] at x, shape (n + m, 2n + n_p)."""
        flat = np.asarray(self._rates(x), dtype=float).ravel()
        return flat.reshape(self.n + self.m, 2 * self.n + self.n_p)

    def tangent(self, x: np.ndarray) -> list[np.ndarray]:
        """[A (m, n), V_q (m, n), V_p (m, n_p), f_p (h, n_p)] at x (q̈, λ not used)."""
        flat = np.asarray(self._tangent(x), dtype=float).ravel()
        return _split(flat, self._tangent_shapes)


def variational_kernel(factory: CompiledLinearizer, params: tuple[int, ...]) -> VariationalKernel:
    """The :class:`VariationalKernel` of a model's linearizer factory for these parameters (its
    code generated on the first evaluation's request, then shared through the factory).

    Examples
    --------
    >>> import pfaff
    >>> eom = pfaff.models.cartesian_pendulum().equations()
    >>> variational_kernel(eom.compile({"L": 1.0, "g": 9.81, "m": 1.0}).linearizer, ()).m
    1
    """
    return VariationalKernel(factory, params)
