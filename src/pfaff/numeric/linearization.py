"""Linearization of the equations with multipliers about an operating point, and its result.

The equations M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 with the constraints A q̇ + b = 0 (holonomic
rows also f(q, t) = 0) are perturbed about an operating point (q₀, q̇₀, u₀) with accelerations q̈₀
and multipliers λ₀ (an equilibrium or a steady motion). With E = M q̈ − (Q − h) − Aᵀλ,
G = A q̈ + Ȧq̇ + ḃ and V = A q̇ + b, and the coordinates split into kept ones x_q (``independent``)
and dependent ones, the rates into kept ones x_u (``independent_speeds``) and dependent ones:

    δq  = T_q x_q                         (f_q δq = 0: the holonomic rows)
    δq̇  = T_uq x_q + T_us x_u + T_uu δu   (A δq̇ + V_q δq + V_u δu = 0: every row)
    [[M, −Aᵀ], [A, 0]] [δq̈; δλ] = −[E_q δq + E_q̇ δq̇ + E_u δu;  G_q δq + G_q̇ δq̇ + G_u δu]

so that ẋ = A x + B δu with x = (x_q, x_u), and δλ = C x + D δu. :func:`reduce_linear` does this
algebra on the matrices at the operating point, as NumPy arrays (:data:`NUMPY`) or, from the
derivation stage, as SymPy matrices (the same code with other operations: this stage imports no
symbolic algebra). :class:`Linearization` is the result both paths return.

A compiled model linearizes through a :class:`LinearizerFactory` that the derivation stage hands
it (:func:`pfaff.derive.linearize.linearizer_for`): its :class:`LinearizationKernel` is generated
code of (t, q, q̇, q̈, λ, parameters), made on the first call, so :func:`linearize_model` does only
numeric work afterwards, for any parameter values and input values.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg

from pfaff.core.display import complex_number, number, summary_html, table_html
from pfaff.core.errors import (
    ConstraintError,
    PfaffError,
)
from pfaff.numeric.redundant import independent_rows

TOL = 1e-8  # residuals (constraints, accelerations) above this times their scale are refused
SINGULAR = 1e-10  # a block whose smallest singular value is below this times its largest: singular
ZERO_COLUMN = 1e-12  # an entry below this times max |A| counts as zero (ignorable coordinates)


def _ix(rows: Sequence[int], cols: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """``np.ix_(rows, cols)`` for short index lists, without its checks."""
    return np.array(rows, dtype=np.intp).reshape(-1, 1), np.array(cols, dtype=np.intp)


class NumpyOps:
    """The matrix operations :func:`reduce_linear` needs, on NumPy arrays."""

    @staticmethod
    def zeros(rows: int, cols: int) -> np.ndarray:
        return np.zeros((rows, cols))

    @staticmethod
    def take(a: np.ndarray, rows: Sequence[int], cols: Sequence[int]) -> np.ndarray:
        return np.asarray(a)[_ix(rows, cols)]

    @staticmethod
    def put(a: np.ndarray, rows: Sequence[int], cols: Sequence[int], value: Any) -> None:
        if len(rows) and len(cols):
            a[_ix(rows, cols)] = value

    @staticmethod
    def hstack(*blocks: np.ndarray) -> np.ndarray:
        return np.hstack(blocks)

    @staticmethod
    def vstack(*blocks: np.ndarray) -> np.ndarray:
        return np.vstack(blocks)

    @staticmethod
    def eye(k: int) -> np.ndarray:
        return np.eye(k)

    @staticmethod
    def solve(a: np.ndarray, b: np.ndarray, what: str) -> np.ndarray:
        """a⁻¹ b; a ``ConstraintError`` naming ``what`` when ``a`` is (nearly) singular."""
        if a.shape[0] == 0:
            return np.zeros((0, b.shape[1]))
        s = np.linalg.svd(a, compute_uv=False)
        if not np.all(np.isfinite(s)) or s[-1] <= SINGULAR * max(s[0], 1e-300):
            raise ConstraintError(f"{what} is singular at the operating point")
        return np.linalg.solve(a, b)

    @staticmethod
    def finish(a: np.ndarray) -> np.ndarray:
        return np.asarray(a, dtype=float) + 0.0  # no -0.0 entries

    @staticmethod
    def independent(a: np.ndarray) -> list[int] | None:
        """A maximal set of independent rows of ``a``, None when all are (pivoted QR)."""
        rows = independent_rows(np.asarray(a, dtype=float))
        return None if rows is None else rows.tolist()

    @staticmethod
    def spread(a: np.ndarray, keep: Sequence[int], lam: np.ndarray) -> np.ndarray:
        """δλ of the kept rows to the minimum-norm δλ of all rows (same Aᵀδλ)."""
        A = np.asarray(a, dtype=float)
        return scipy.linalg.lstsq(A.T, A[list(keep)].T @ lam, cond=1e-9)[0]


NUMPY = NumpyOps()


def complement(n: int, kept: Sequence[int]) -> list[int]:
    """The indices of ``range(n)`` not in ``kept``, in order."""
    s = set(kept)
    return [i for i in range(n) if i not in s]


def _names(names: Sequence[str], idx: Sequence[int]) -> str:
    return ", ".join(f"`{names[i]}`" for i in idx)


@dataclass
class OperatingMatrices:
    """The equations and their derivatives at an operating point (NumPy arrays or SymPy matrices).

    ``M`` (n, n), ``A`` (m, n), ``hol`` the indices of the holonomic rows; ``E_q``, ``E_qd``
    (n, n), ``E_u`` (n, r); ``G_q``, ``G_qd`` (m, n), ``G_u`` (m, r); ``V_q`` (m, n), ``V_u``
    (m, r): the derivatives of E, G and V (module docstring) by q, q̇ and the inputs.
    """

    M: Any
    A: Any
    hol: list[int]
    E_q: Any
    E_qd: Any
    E_u: Any
    G_q: Any
    G_qd: Any
    G_u: Any
    V_q: Any
    V_u: Any


def reduce_linear(
    mats: OperatingMatrices,
    independent: Sequence[int],
    speeds: Sequence[int],
    names: Sequence[str],
    ops: Any = NUMPY,
) -> tuple[Any, Any, Any, Any]:
    """(A, B, C, D) of ẋ = A x + B δu, δλ = C x + D δu, x = (δq[independent], δq̇[speeds]).

    Raises a :class:`pfaff.ConstraintError` when the kept coordinates or rates leave the others
    undetermined: a count that does not match the constraints, or a singular block of the
    constraint Jacobian (named by ``names``, the coordinate names).
    """
    n, full = len(names), mats.A
    keep = ops.independent(full) if full.shape[0] else None
    if keep is not None:  # redundant rows: the independent ones (pivoted QR) decide the motion
        mats = _rows_kept(mats, keep, n, ops)
    m = mats.A.shape[0]
    r = mats.E_u.shape[1]
    dep = complement(n, independent)
    dspd = complement(n, speeds)
    ni, ns = len(independent), len(speeds)
    if len(dep) != len(mats.hol):
        raise ConstraintError(
            f"`independent` keeps {ni} of {n} coordinates, so {len(dep)} ({_names(names, dep)}) "
            f"must be fixed by the holonomic constraints, but there are {len(mats.hol)}"
        )
    if len(dspd) != m:
        raise ConstraintError(
            f"`independent_speeds` keeps {ns} of {n} rates, so {len(dspd)} "
            f"({_names(names, dspd)}) must be fixed by the constraints, but there are {m}"
        )
    Ah = ops.take(mats.A, mats.hol, range(n))
    Tq = ops.zeros(n, ni)
    ops.put(Tq, independent, range(ni), ops.eye(ni))
    what = (
        f"the holonomic constraints' Jacobian by the dependent coordinates ({_names(names, dep)})"
    )
    ops.put(Tq, dep, range(ni), -ops.solve(ops.take(Ah, range(len(dep)), dep), Ah @ Tq, what))
    Ad = ops.take(mats.A, range(m), dspd)
    what = f"the constraint matrix's block of the dependent rates ({_names(names, dspd)})"
    cols = ops.hstack(
        mats.V_q @ Tq, ops.take(mats.A, range(m), speeds), mats.V_u
    )  # A_D δq̇_D = -(V_q T_q x_q + A_S x_u + V_u δu)
    dq = ops.solve(Ad, cols, what) if m else ops.zeros(0, ni + ns + r)
    Tu = ops.zeros(n, ni + ns + r)  # δq̇ = Tu (x_q, x_u, δu)
    ops.put(Tu, speeds, range(ni, ni + ns), ops.eye(ns))
    ops.put(Tu, dspd, range(ni + ns + r), -dq)
    Tx = ops.hstack(Tq, ops.zeros(n, ns + r))  # δq = Tx (x_q, x_u, δu)
    Ux = ops.hstack(ops.zeros(r, ni + ns), ops.eye(r))  # δu = Ux (x_q, x_u, δu)
    rhs = ops.vstack(
        mats.E_q @ Tx + mats.E_qd @ Tu + mats.E_u @ Ux,
        mats.G_q @ Tx + mats.G_qd @ Tu + mats.G_u @ Ux,
    )
    K = ops.vstack(
        ops.hstack(mats.M, -mats.A.T), ops.hstack(mats.A, ops.zeros(m, m))
    )  # [[M, -Aᵀ], [A, 0]]
    sol = ops.solve(K, -rhs, "the augmented matrix [[M, -Aᵀ], [A, 0]]")
    rows = ops.vstack(
        ops.take(Tu, independent, range(ni + ns + r)), ops.take(sol, speeds, range(ni + ns + r))
    )
    x = range(ni + ns)
    u = range(ni + ns, ni + ns + r)
    lam = range(n, n + m)
    C, D = ops.take(sol, lam, x), ops.take(sol, lam, u)
    if keep is not None:  # δλ over all rows: minimum-norm (only Aᵀδλ is determined)
        C, D = ops.spread(full, keep, C), ops.spread(full, keep, D)
    return (
        ops.finish(ops.take(rows, range(ni + ns), x)),
        ops.finish(ops.take(rows, range(ni + ns), u)),
        ops.finish(C),
        ops.finish(D),
    )


def operating_solve(ops: Any, M: Any, A: Any, E: Any, G: Any) -> Any:
    """[q̈; λ] at the operating point, shape (n + m, 1): K [q̈; λ] = [−E; −G] with K =
    [[M, −Aᵀ], [A, 0]]; where rows of A depend on the others, from the independent ones (pivoted
    QR), λ then minimum-norm over all rows."""
    n, m = M.shape[0], A.shape[0]
    keep = ops.independent(A) if m else None
    Ak, Gk = (A, G) if keep is None else (ops.take(A, keep, range(n)), ops.take(G, keep, [0]))
    mk = Ak.shape[0]
    K = ops.vstack(ops.hstack(M, -Ak.T), ops.hstack(Ak, ops.zeros(mk, mk)))
    sol = ops.solve(K, ops.vstack(-E, -Gk), "the augmented matrix [[M, -Aᵀ], [A, 0]]")
    if keep is None:
        return sol
    lam = ops.spread(A, keep, ops.take(sol, range(n, n + mk), [0]))
    return ops.vstack(ops.take(sol, range(n), [0]), lam)


def _rows_kept(mats: OperatingMatrices, keep: list[int], n: int, ops: Any) -> OperatingMatrices:
    """The operating matrices of the rows ``keep`` only."""
    where = {row: k for k, row in enumerate(keep)}

    def rows(a: Any) -> Any:
        return ops.take(a, keep, range(a.shape[1]))

    return OperatingMatrices(
        M=mats.M, A=rows(mats.A), hol=[where[i] for i in mats.hol if i in where],
        E_q=mats.E_q, E_qd=mats.E_qd, E_u=mats.E_u, G_q=rows(mats.G_q), G_qd=rows(mats.G_qd),
        G_u=rows(mats.G_u), V_q=rows(mats.V_q), V_u=rows(mats.V_u),
    )  # fmt: skip


def ignorable(A: np.ndarray, tol: float = ZERO_COLUMN) -> list[int]:
    """States whose columns vanish once the other such states are left out (repeatedly).

    A zero column j makes e_j an eigenvector of eigenvalue 0 and leaves the other eigenvalues
    those of A without row and column j; a column that is zero only in the rows of states so
    left out (the bicycle's yaw: only ẏ depends on it) is left out next.
    """
    small = np.abs(np.asarray(A, dtype=float))
    small = small <= tol * max(float(small.max(initial=0.0)), 1.0)
    keep = np.ones(small.shape[0], dtype=bool)
    while True:
        zero = keep & small[keep].all(axis=0)  # zero in the rows of the states still kept
        if not zero.any():
            return np.flatnonzero(~keep).tolist()
        keep &= ~zero


class Modes(NamedTuple):
    """Modes of a :class:`Linearization`, in the order of its ``eigenvalues()``.

    Attributes
    ----------
    frequencies : ndarray, shape (k,)
        Natural frequencies |s| (rad/s) of the eigenvalues s.
    damping_ratios : ndarray, shape (k,)
        −Re s / |s| (NaN for s = 0).
    shapes : ndarray, shape (n_states, k)
        Eigenvectors over the states, each scaled to its largest entry 1.
    """

    frequencies: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray


def _numeric(a: Any, what: str) -> np.ndarray:
    try:
        return np.asarray(a, dtype=float)
    except (TypeError, ValueError) as e:
        raise PfaffError(
            f"{what} is symbolic: give every parameter a value in `op_point` for numbers"
        ) from e


def state_name(state: object) -> str:
    """A state as its CSV column is named: ``theta`` for θ(t), ``theta_dot`` for its rate.

    Examples
    --------
    >>> state_name("Derivative(theta(t), t)"), state_name("x(t)"), state_name("u")
    ('theta_dot', 'x', 'u')
    """
    text = re.sub(r"Derivative\((\w+)\(t\), t\)", r"\1_dot", str(state))
    return re.sub(r"(\w+)\(t\)", r"\1", text)


def _sorted(w: np.ndarray, v: np.ndarray | None = None):
    order = np.lexsort((w.imag, w.real))
    return w[order] if v is None else (w[order], v[:, order])


class Linearization:
    """Linearized equations of motion ẋ = A x + B u about an operating point.

    x = (δq of the kept coordinates, δq̇ of the kept rates); u the inputs' deviations from their
    operating values; the multipliers' deviations are δλ = C x + D u.

    Attributes
    ----------
    A : ndarray or Matrix, shape (n_states, n_states)
        State matrix (a NumPy array when every value is numeric, else a SymPy matrix).
    B : ndarray or Matrix, shape (n_states, n_inputs)
        Input matrix.
    states : list
        The kept coordinates, then the kept rates (``q.diff(pfaff.t)``), in the order given.
    inputs : list
        The inputs, in the order given.
    multipliers : tuple (C, D)
        C, shape (m, n_states), and D, shape (m, n_inputs): δλ = C x + D u.
    lambda0 : ndarray or Matrix, shape (m,)
        The multipliers at the operating point.

    Examples
    --------
    >>> import numpy as np
    >>> lin = Linearization(np.array([[0.0, 1.0], [-4.0, -0.4]]), np.zeros((2, 0)), ["x", "v"])
    >>> lin.eigenvalues()
    array([-0.2-1.98997487j, -0.2+1.98997487j])
    >>> lin.is_stable()
    True
    >>> [round(float(z), 2) for z in lin.modes().damping_ratios]
    [0.1, 0.1]
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        states: Sequence,
        inputs: Sequence = (),
        multipliers: tuple = (None, None),
        lambda0: Any = None,
    ) -> None:
        self.A, self.B = A, B
        self.states, self.inputs = list(states), list(inputs)
        self.multipliers = multipliers
        self.lambda0 = lambda0

    @property
    def numeric(self) -> bool:
        """True when A and B are NumPy arrays."""
        return isinstance(self.A, np.ndarray)

    def ignorable(self) -> list[int]:
        """Indices of the states that bring only zero eigenvalues: coordinates that no kept
        equation depends on (zero columns of A), repeatedly (:func:`ignorable`)."""
        return ignorable(_numeric(self.A, "A"))

    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of A, shape (n_states,), sorted by real part, then imaginary part."""
        return _sorted(np.linalg.eigvals(_numeric(self.A, "A")).astype(complex))

    def modes(self) -> Modes:
        """Natural frequencies, damping ratios and mode shapes, in the order of
        :meth:`eigenvalues`."""
        w, v = np.linalg.eig(_numeric(self.A, "A"))
        w, v = _sorted(w.astype(complex), v.astype(complex))
        mag = np.abs(w)
        with np.errstate(invalid="ignore", divide="ignore"):
            zeta = np.where(mag > 0, -w.real / np.where(mag > 0, mag, 1.0), np.nan)
        if v.size:
            big = v[np.abs(v).argmax(axis=0), np.arange(v.shape[1])]
            v = v / np.where(big == 0, 1.0, big)
        return Modes(mag, zeta, v)

    def is_stable(self) -> bool:
        """Every eigenvalue has a negative real part, the zero eigenvalues of the ignorable
        states (:meth:`ignorable`: the bicycle's position, yaw and wheel angles) left out."""
        A = _numeric(self.A, "A")
        keep = complement(A.shape[0], self.ignorable())
        w = np.linalg.eigvals(A[np.ix_(keep, keep)])
        return bool(np.all(w.real < 0))

    MAX_SHOWN = 24  # eigenvalues listed in a notebook

    def _repr_html_(self) -> str:
        """States, inputs, stability and the eigenvalues with their frequencies and damping
        ratios (a symbolic linearization lists its states only)."""
        rows = [
            ("states", ", ".join(map(state_name, self.states)) or "none"),
            ("inputs", ", ".join(map(state_name, self.inputs)) or "none"),
        ]
        title = f"pfaff.Linearization: {len(self.states)} states, {len(self.inputs)} inputs"
        if not self.numeric:
            rows.append(("eigenvalues", "symbolic: give every parameter a value for numbers"))
            return summary_html(title, rows)
        try:
            w, (freq, zeta, _) = self.eigenvalues(), self.modes()
            rows.append(("stable", "yes" if self.is_stable() else "no"))
        except (np.linalg.LinAlgError, PfaffError) as e:  # a non-finite A
            rows.append(("eigenvalues", f"not computed ({e})"))
            return summary_html(title, rows)
        shown = range(min(len(w), self.MAX_SHOWN))
        table = table_html(
            ["eigenvalue s (1/s)", "|s| (rad/s)", "damping ratio"],
            [[complex_number(w[i]), number(freq[i]), number(zeta[i])] for i in shown],
        )
        if len(w) > self.MAX_SHOWN:
            table += f"<p>(first {self.MAX_SHOWN} of {len(w)})</p>"
        return summary_html(title, rows, after=table)

    def __repr__(self) -> str:
        kind = "numeric" if self.numeric else "symbolic"
        return (
            f"<pfaff.Linearization: {len(self.states)} states, {len(self.inputs)} inputs, {kind}>"
        )
