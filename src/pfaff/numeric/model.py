"""The numeric model: compiled M, Q - h, A, b, bias, energy and residuals, and the KKT solve.

No SymPy here: the compile stage hands over :class:`pfaff.numeric.kernel.Kernel` objects and index arrays.
The augmented system is solved in its symmetric form

    [[M, Aᵀ], [A, 0]] [q̈; -λ] = [Q - h; -(Ȧq̇ + ḃ)],

densely for small systems and with SciPy's sparse LU (SuperLU) otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from pfaff.core.errors import ConstraintError, StateError
from pfaff.numeric.kernel import Kernel
from pfaff.numeric.kkt import FLOOR, STATE_FLOOR, row_scales, solve_floored

if TYPE_CHECKING:
    from pfaff.numeric.fused import FusedKernel

_gesv = scipy.linalg.lapack.dgesv
DENSE_LIMIT = 400  # n + m up to which the KKT system is assembled and solved densely


@dataclass
class DynamicsPart:
    """A dynamics kernel with the global (row, col) of each mass entry and row of each forcing entry."""

    kernel: Kernel
    mass_rows: np.ndarray  # shape (n_mass, n_inst)
    mass_cols: np.ndarray
    forcing_rows: np.ndarray  # shape (n_forcing, n_inst)
    energy: Kernel


@dataclass
class ConstraintPart:
    """A constraint kernel: A entries (row, col), then b, bias and f per instance row."""

    kernel: Kernel
    rows: np.ndarray  # shape (n_inst,)
    cols: np.ndarray  # shape (n_A, n_inst)


def _slots(lin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique sorted linear indices and, per entry, its slot (duplicates are summed)."""
    uniq, slot = np.unique(lin, return_inverse=True)
    return uniq, slot.ravel()


def check_state(
    t: object, q: object, qd: object, n: int, names: Sequence[str] | None = None
) -> tuple[float, np.ndarray, np.ndarray]:
    """Validate a numeric state: real t, finite q and q̇ of shape (n,); names go in the message."""
    try:
        tt = float(t)  # type: ignore[arg-type]
        qa = np.asarray(q, dtype=float)
        qda = np.asarray(qd, dtype=float)
    except (TypeError, ValueError) as e:
        raise StateError(f"`t`, `q` and `qd` must be real numbers and arrays: {e}") from e
    for name, arr in (("q", qa), ("qd", qda)):
        if arr.shape != (n,):
            which = ","
            if names is not None:
                which = f" for coordinates {', '.join(names[:6])}{'...' if n > 6 else ''};"
            raise StateError(f"`{name}` must have shape ({n},){which} got shape {arr.shape}")
        # one pass and no temporary: a finite sum means finite entries (NaN and ±inf propagate);
        # only a sum that overflowed needs the elementwise test
        if not (math.isfinite(float(np.sum(arr))) or np.isfinite(arr).all()):
            raise StateError(f"`{name}` contains NaN or infinity")
    if not np.isfinite(tt):
        raise StateError("`t` is not finite")
    return tt, qa, qda


class NumericModel:
    """Compiled equations of motion for one set of parameter values.

    Attributes
    ----------
    n, m : int
        Number of coordinates and of constraints (multipliers).
    coordinate_names, multiplier_names : list of str
    parameters : dict
        Parameter name -> value used.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    >>> qdd, lam = model.accelerations(0.0, np.array([0.0, -2.0]), np.zeros(2))
    >>> float(-2 * 2 * lam[0])  # rod tension -2Lλ of a pendulum hanging at rest: mg
    9.81
    """

    def __init__(
        self,
        n: int,
        dyn: list[DynamicsPart],
        con: list[ConstraintPart],
        m: int,
        param_values: Sequence[float],
        names: dict,
        fused: FusedKernel | None = None,
    ) -> None:
        self.n, self.m = n, m
        self._dyn, self._con, self._p = dyn, con, list(param_values)
        self.coordinate_names: list[str] = names["coordinates"]
        self.multiplier_names: list[str] = names["multipliers"]
        self.constraint_names: list[str] = names["constraints"]
        self.parameters: dict = names["parameters"]
        self.holonomic = np.zeros(m, dtype=bool)
        for part in con:
            self.holonomic[part.rows] = names["holonomic_rows"][part.rows]
        N = n + m
        mr = [np.ravel(p.mass_rows) for p in dyn]
        mc = [np.ravel(p.mass_cols) for p in dyn]
        ar = [np.ravel(np.broadcast_to(p.rows, p.cols.shape)) for p in con]
        ac = [np.ravel(p.cols) for p in con]
        cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0, dtype=np.int64)  # noqa: E731
        self._mr, self._mc, self._ar, self._ac = cat(mr), cat(mc), cat(ar), cat(ac)
        rows = np.concatenate([self._mr, n + self._ar, self._ac])
        cols = np.concatenate([self._mc, self._ac, n + self._ar])
        self.dense = N <= DENSE_LIMIT
        self._kkt_lin = cols * N + rows  # column-major: sorted order is CSC order
        self._kkt_uniq, self._kkt_slot = _slots(self._kkt_lin)
        self._frows = cat([np.ravel(p.forcing_rows) for p in dyn])
        self.stats = {"kkt_solves": 0}
        self._fused = fused

    # ------------------------------------------------------------------ validation
    def _state(self, t: float, q: object, qd: object) -> tuple[float, np.ndarray, np.ndarray]:
        return check_state(t, q, qd, self.n, self.coordinate_names)

    # ------------------------------------------------------------------ raw evaluation
    def _dynamics(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mdata, fdata = [], []
        for part in self._dyn:
            outs = part.kernel(t, q, qd, self._p)
            nm = part.mass_rows.shape[0]
            mdata.extend(outs[:nm])
            fdata.extend(outs[nm:])
        mvals = np.concatenate(mdata) if mdata else np.zeros(0)
        fvals = np.concatenate(fdata) if fdata else np.zeros(0)
        forcing = np.bincount(self._frows, weights=fvals, minlength=self.n)
        return mvals, forcing

    def _constraints(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, ...]:
        adata = []
        b, bias, f = np.zeros(self.m), np.zeros(self.m), np.zeros(self.m)
        for part in self._con:
            outs = part.kernel(t, q, qd, self._p)
            na = part.cols.shape[0]
            adata.extend(outs[:na])
            b[part.rows], bias[part.rows], f[part.rows] = outs[na], outs[na + 1], outs[na + 2]
        avals = np.concatenate(adata) if adata else np.zeros(0)
        return avals, b, bias, f

    # ------------------------------------------------------------------ public evaluation
    def mass_matrix(
        self, t: float, q: object, qd: object | None = None
    ) -> np.ndarray | sps.csr_matrix:
        """M(q, t), shape (n, n): a dense array when small, else a SciPy CSR matrix."""
        t, q, qd = self._state(t, q, np.zeros(self.n) if qd is None else qd)
        M = sps.coo_matrix((self._dynamics(t, q, qd)[0], (self._mr, self._mc)), shape=(self.n,) * 2)
        return M.toarray() if self.dense else M.tocsr()

    def forcing(self, t: float, q: object, qd: object) -> np.ndarray:
        """Q - h, shape (n,)."""
        return self._dynamics(*self._state(t, q, qd))[1]

    def constraint_matrix(self, t: float, q: object) -> np.ndarray | sps.csr_matrix:
        """A(q, t), shape (m, n): dense when small, else CSR."""
        t, q, qd = self._state(t, q, np.zeros(self.n))
        A = sps.coo_matrix(
            (self._constraints(t, q, qd)[0], (self._ar, self._ac)), shape=(self.m, self.n)
        )
        return A.toarray() if self.dense else A.tocsr()

    def constraint_residual(self, t: float, q: object, qd: object) -> tuple[np.ndarray, np.ndarray]:
        """Position residuals f(q,t) (0 for velocity constraints) and velocity residuals A q̇ + b."""
        return self._residual(*self._state(t, q, qd))

    def _residual(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self._fused is not None:
            _, _, _, _, f, g = self._kkt(t, q, qd)
            return f, g
        avals, b, _, f = self._constraints(t, q, qd)
        g = b + np.bincount(self._ar, weights=avals * qd[self._ac], minlength=self.m)
        return f, g

    def energy(self, t: float, q: object, qd: object) -> tuple[float, float]:
        """Kinetic and potential energy (T, V)."""
        return self._energies(*self._state(t, q, qd))

    def kkt_matrix(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """The symmetric augmented matrix [[M, Aᵀ], [A, 0]] and right-hand side [Q - h; -bias]."""
        K, forcing, _, bias, _, _ = self._kkt(t, q, qd)
        return K, np.concatenate([forcing, -bias])

    def _kkt(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple:
        """K, Q - h, b, Ȧq̇ + ḃ, f and g = A q̇ + b at an (unchecked) state."""
        n, m = self.n, self.m
        N = n + m
        if self._fused is not None:
            fk = self._fused
            v = self._fused_values(t, q, qd)
            K = np.zeros((N, N))
            K.flat[fk.kkt_index] = v[fk.kkt_source]
            o = fk.offsets
            forcing, bias, b, f = v[o[0] : o[1]], -v[o[1] : o[2]], v[o[2] : o[3]], v[o[3] :]
            return K, forcing, b, bias, f, K[n:, :n] @ qd + b
        mvals, forcing = self._dynamics(t, q, qd)
        avals, b, bias, f = self._constraints(t, q, qd)
        g = b + np.bincount(self._ar, weights=avals * qd[self._ac], minlength=m)
        data = np.concatenate([mvals, avals, avals])
        if self.dense:
            K = np.bincount(self._kkt_lin, weights=data, minlength=N * N).reshape(N, N).T
        else:
            vals = np.bincount(self._kkt_slot, weights=data, minlength=len(self._kkt_uniq))
            K = sps.csc_matrix(
                (vals, self._kkt_uniq % N, _indptr(self._kkt_uniq // N, N)), shape=(N, N)
            )
        return K, forcing, b, bias, f, g

    def _solve_kkt(
        self,
        K: np.ndarray | sps.csc_matrix,
        forcing: np.ndarray,
        c: np.ndarray,
        t: float,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """q̈ and λ of K [q̈; −λ] = [Q − h; c].

        Dense systems take the range-space solve of :mod:`pfaff.kkt`, which passes configurations
        where A loses rank (a linkage folded flat); a singular M (a coordinate without inertia)
        goes to LAPACK gesv on K, then to least squares. Sparse systems go to SuperLU. ``floor``:
        and ``scales``: see :mod:`pfaff.kkt` (``FLOOR`` with row scales in integrators,
        ``STATE_FLOOR`` for single states).
        """
        self.stats["kkt_solves"] += 1
        n = self.n
        try:
            if self.dense:
                try:
                    qdd, lam = solve_floored(K[:n, :n], K[n:, :n], forcing, c, floor, scales)
                except np.linalg.LinAlgError:
                    qdd, lam = self._solve_full(K, np.concatenate([forcing, c]), t)
            else:
                sol = spla.splu(K).solve(np.concatenate([forcing, c]))
                qdd, lam = sol[:n], -sol[n:]
        except (np.linalg.LinAlgError, RuntimeError, ValueError) as e:
            raise ConstraintError(self._singular_message(t)) from e
        if not math.isfinite(qdd.sum() + lam.sum()):
            raise ConstraintError(self._singular_message(t))
        if floor == STATE_FLOOR and self.dense and self.m:
            self._check_consistent(K[n:, :n], qdd, c, t)
        return qdd, lam

    def _check_consistent(self, A: np.ndarray, qdd: np.ndarray, c: np.ndarray, t: float) -> None:
        """A single state's q̈ must satisfy A q̈ = c: else the constraints are inconsistent here."""
        r = np.abs(A @ qdd - c)
        scale = 1.0 + np.abs(c).max() + np.abs(A).max() * np.abs(qdd).max()
        if r.max() > 1e-8 * scale:
            i = int(np.argmax(r))
            raise ConstraintError(
                f"{self._singular_message(t)} (inconsistent equations: no acceleration satisfies "
                f"constraint `{self.constraint_names[i]}` together with the others)"
            )

    def _solve_full(self, K: np.ndarray, rhs: np.ndarray, t: float) -> tuple:
        """q̈, λ from the whole dense augmented matrix (LAPACK gesv, then least squares)."""
        # LAPACK gesv straight: np.linalg.solve's checks cost 4x the solve of a 3x3 system
        sol, info = _gesv(K, rhs)[2:]
        if info != 0:
            sol = self._least_squares(K, rhs, t)
        return sol[: self.n], -sol[self.n :]

    def _least_squares(self, K: np.ndarray, rhs: np.ndarray, t: float) -> np.ndarray:
        """Rank-deficient K: redundant constraints at this configuration (a linkage folded flat).

        If the equations are consistent, the minimum-norm least-squares solution keeps the unique
        q̈ and the minimum-norm λ. A constraint with no gradient at all, or inconsistent equations,
        is an error.
        """
        n = self.n
        A = K[n:, :n]
        dead = np.flatnonzero(np.abs(A).max(axis=1, initial=0.0) == 0.0)
        if dead.size:
            names = ", ".join(f"`{self.constraint_names[i]}`" for i in dead[:5])
            raise ConstraintError(
                f"{self._singular_message(t)}; constraint {names} has a zero gradient here"
            )
        self.stats["kkt_lstsq"] = self.stats.get("kkt_lstsq", 0) + 1
        sol = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]
        if np.linalg.norm(K @ sol - rhs) > 1e-8 * (1.0 + np.linalg.norm(rhs)):
            raise ConstraintError(self._singular_message(t) + " (inconsistent equations)")
        return sol

    def _solve_accelerations(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        alpha: float = 0.0,
        beta: float = 0.0,
        floor: float = STATE_FLOOR,
        scales: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Unchecked q̈, λ with the constraint rows' right-hand side −(Ȧq̇+ḃ) − 2αg − β²f."""
        if self._fused is not None and not (alpha or beta) and floor == STATE_FLOOR:
            return self._fused_accelerations(t, q, qd)
        K, forcing, _, bias, f, g = self._kkt(t, q, qd)
        c = -bias
        if alpha:
            c = c - 2.0 * alpha * g
        if beta:
            c = c - beta * beta * f
        return self._solve_kkt(K, forcing, c, t, floor, scales)

    def _row_scales(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray | None:
        """Reference constraint row sizes for the integrators' floor (:func:`pfaff.kkt.row_scales`)."""
        if not self.dense or not self.m:
            return None
        K = self._kkt(t, q, qd)[0]
        try:
            return row_scales(K[: self.n, : self.n], K[self.n :, : self.n])
        except np.linalg.LinAlgError:  # M singular: the full augmented matrix is used anyway
            return None

    def _ode_function(
        self, alpha: float = 0.0, beta: float = 0.0, scales: np.ndarray | None = None
    ):
        """y' = [q̇, q̈] of y = [q, q̇] (Baumgarte-stabilized when α, β > 0), for integrators.

        Small systems get a closure around the fused kernel: a few microseconds per call; its
        attribute ``on_lists`` is the same function on lists of floats (:mod:`pfaff.fastrk`).
        A non-finite q̈ raises :class:`StateError` naming the time. ``scales``: reference row
        sizes for the floor of :mod:`pfaff.kkt` (None: no floor); the function's ``rescale(new)``
        replaces them during a run.
        """
        n = self.n
        fk = self._fused
        ref = [None if scales is None else np.asarray(scales, dtype=float)]  # see ``rescale``
        if fk is None:
            solve = self._solve_accelerations

            def fun(t: float, y: np.ndarray) -> np.ndarray:
                out = np.empty(2 * n)
                out[:n] = y[n:]
                out[n:] = solve(t, y[:n], y[n:], alpha, beta, FLOOR, ref[0])[0]
                if not math.isfinite(out.sum()):
                    raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
                return out

            fun.rescale = lambda new: ref.__setitem__(0, new)  # type: ignore[attr-defined]
            return fun
        rhs = [self._fused_rhs(alpha, beta, ref[0])]
        isfinite = math.isfinite

        def list_fun(t: float, yl: list) -> list:
            out = rhs[0](t, yl)
            try:
                finite = isfinite(sum(out))
            except TypeError:  # a complex number: a fractional power of a negative value
                raise StateError(_not_real(t)) from None
            if not finite:
                raise StateError(f"the accelerations are NaN or infinite at t = {t:.17g}")
            return out

        def fused_fun(t: float, y: np.ndarray) -> np.ndarray:
            return np.array(list_fun(t, y.tolist()))

        def rescale(new: np.ndarray) -> None:
            rhs[0] = self._fused_rhs(alpha, beta, new)

        fused_fun.on_lists = list_fun  # type: ignore[attr-defined]
        fused_fun.rescale = rescale  # type: ignore[attr-defined]
        return fused_fun

    def _fused_rhs(self, alpha: float, beta: float, scales: np.ndarray | None):
        """``rhs(t, y: list) -> list`` of a fused model for given reference row sizes."""
        fk, n = self._fused, self.n
        kfn, ofn, sfn, p, gesv = fk.kfn, fk.ofn, fk.sfn, (*self._p, alpha, beta), _gesv
        # no reference sizes: no floor (a singular S then goes to LAPACK and least squares)
        taus = [0.0] * self.m if scales is None else (FLOOR * np.asarray(scales)).tolist()
        taus.append(FLOOR if scales is not None else 0.0)  # the cap factor

        def slow(t: float, yl: list) -> list:
            try:
                qdd = sfn(*ofn(t, *yl, *p), *taus)
            except (ValueError, ZeroDivisionError):  # M not definite: LAPACK on the whole K
                K, r = kfn(t, *yl, *p)
                x, info = gesv(K, r)[2:]
                if info != 0:  # singular: the careful path
                    x = self._solve_full(np.array(K), np.array(r), t)[0]
                qdd = x[:n].tolist()
            return yl[n:] + qdd

        return fk.rfn(*p, *taus, slow) if fk.rfn is not None else slow

    def _fused_values(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The fused kernel's flat outputs at a state; non-real values are an error naming t."""
        try:
            v = np.array(self._fused.fn(t, *q.tolist(), *qd.tolist(), *self._p))
        except ValueError as e:  # math domain error: sqrt or log of a negative value
            raise StateError(f"the equations are not defined at t = {t:.17g} ({e})") from None
        if v.dtype.kind == "c":
            raise StateError(_not_real(t))
        return v

    def _fused_accelerations(
        self, t: float, q: np.ndarray, qd: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        # the hot path of small systems: every NumPy call here costs about a microsecond
        fk, N = self._fused, self.n + self.m
        v = self._fused_values(t, q, qd)
        K = np.zeros((N, N))
        K.flat[fk.kkt_index] = v[fk.kkt_source]
        o = fk.offsets
        return self._solve_kkt(K, v[o[0] : o[1]], v[o[1] : o[2]], t)

    def accelerations(self, t: float, q: object, qd: object) -> tuple[np.ndarray, np.ndarray]:
        """Solve M q̈ + h = Q + Aᵀλ, A q̈ + Ȧq̇ + ḃ = 0 for q̈ (shape (n,)) and λ (shape (m,)).

        Examples
        --------
        >>> import numpy as np, pfaff
        >>> sys = pfaff.models.rolling_ring(8, force=True)
        >>> model = sys.equations().compile({"M": 1, "r": 0.5, "F": 2})
        >>> q, qd = pfaff.models.ring_state(8, radius=0.5, theta=0.3)
        >>> qdd, lam = model.accelerations(0.0, q, qd)
        >>> round(float(qdd[1]), 12), round(float(lam[0]), 12)
        (2.0, -1.0)
        """
        return self._solve_accelerations(*self._state(t, q, qd))

    def _energies(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
        T = V = 0.0
        for part in self._dyn:
            Tk, Vk = part.energy(t, q, qd, self._p)
            T += float(np.sum(Tk))
            V += float(np.sum(Vk))
        return T, V

    def evaluate_states(
        self, t: np.ndarray, q: np.ndarray, qd: np.ndarray
    ) -> dict[str, np.ndarray]:
        """What a trajectory reports at k states: q̈, λ, f, g, T, V and T(q, 0, t).

        Parameters
        ----------
        t : ndarray, shape (k,)
        q, qd : ndarray, shape (k, n)

        Returns
        -------
        dict
            ``qdd`` (k, n), ``multipliers`` (k, m), ``f`` and ``g`` (k, m), and (k,) arrays ``T``,
            ``V``, ``T0`` = T(q, 0, t) and ``T2`` (the part of T quadratic in q̇).
        """
        t = np.asarray(t, dtype=float)
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if self._fused is not None:
            try:
                return self._fused_states(t, q, qd)
            except (np.linalg.LinAlgError, ConstraintError):
                pass  # a redundant configuration somewhere: state by state below
        k, n, m = len(t), self.n, self.m
        out = {"qdd": np.zeros((k, n)), "multipliers": np.zeros((k, m))}
        out.update({key: np.zeros((k, m)) for key in ("f", "g")})
        out.update({key: np.zeros(k) for key in ("T", "V", "T0", "T2")})
        zero = np.zeros(n)
        for i in range(k):
            out["qdd"][i], out["multipliers"][i] = self._solve_accelerations(t[i], q[i], qd[i])
            out["f"][i], out["g"][i] = self._residual(t[i], q[i], qd[i])
            out["T"][i], out["V"][i] = self._energies(t[i], q[i], qd[i])
            out["T0"][i] = self._energies(t[i], q[i], zero)[0]
            out["T2"][i] = 0.5 * (out["T"][i] + self._energies(t[i], q[i], -qd[i])[0])
        out["T2"] -= out["T0"]
        return out

    def _fused_states(self, t: np.ndarray, q: np.ndarray, qd: np.ndarray) -> dict[str, np.ndarray]:
        fk, k, n, N = self._fused, len(t), self.n, self.n + self.m
        args = [t, *q.T, *qd.T, *self._p]
        vals = np.empty((k, fk.offsets[3] + self.m))
        for i, o in enumerate(fk.vfn(*args)):
            vals[:, i] = o
        K = np.zeros((k, N * N))
        K[:, fk.kkt_index] = vals[:, fk.kkt_source]
        K = K.reshape(k, N, N)
        o = fk.offsets
        qdd, lam = solve_floored(
            K[:, :n, :n], K[:, n:, :n], vals[:, o[0] : o[1]], vals[:, o[1] : o[2]], STATE_FLOOR
        )
        if not (np.isfinite(qdd).all() and np.isfinite(lam).all()):
            raise ConstraintError(self._singular_message(float(t[0])))
        g = np.einsum("kij,kj->ki", K[:, n:, :n], qd) + vals[:, o[2] : o[3]]
        T, V, T0 = (np.broadcast_to(e, (k,)).astype(float) for e in fk.efn(*args))
        Tneg = np.broadcast_to(fk.efn(t, *q.T, *(-qd).T, *self._p)[0], (k,))
        T2 = 0.5 * (T + Tneg) - T0
        self.stats["kkt_solves"] += k
        return {
            "qdd": qdd,
            "multipliers": lam,
            "f": vals[:, o[3] :],
            "g": g,
            "T": T,
            "V": V,
            "T0": T0,
            "T2": T2,
        }

    def _singular_message(self, t: float) -> str:
        return (
            f"the augmented matrix [[M, Aᵀ], [A, 0]] is singular at t = {t:g}: the constraints are "
            "redundant or inconsistent in this configuration, or M is singular on the admissible "
            "motions (a coordinate without inertia)"
        )


def _not_real(t: float) -> str:
    return (
        f"the equations are not real at t = {t:.17g}: a fractional power of a negative value "
        "(write it with sqrt, cbrt or Abs where the model allows)"
    )


def _indptr(col_of_entry: np.ndarray, N: int) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(np.bincount(col_of_entry, minlength=N))])
