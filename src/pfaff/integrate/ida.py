"""The DAE method: SUNDIALS IDA (through scikit-sundae) on the stabilized index-2 GGL form.

Unknowns y = [q, v, λ, μ] (μ one per position constraint), residuals (Gear–Gupta–Leimkuhler):

    q' − v − A_hᵀ μ          = 0      (μ = 0 on the exact solution; it keeps q on f = 0)
    M(q) v' − (Q − h) − Aᵀ λ = 0
    A(q) v + b               = 0      (every constraint at velocity level)
    f_h(q, t)                = 0      (position constraints)

λ and μ are algebraic: they are marked so for IDA and left out of its error test (a huge absolute
tolerance), as the index-2 theory asks. Consistent initial values are computed: q and v projected,
λ from the KKT solve, μ = 0, y' = [v, q̈, 0, 0]. The Newton matrix is our own (``_jacobian``):
exact blocks for λ, μ and y', forward differences for the q and v columns of small systems (on the
pendulum 5x fewer steps than leaving the curvature terms ∂(Aᵀλ)/∂q and ∂(A v)/∂q out, which larger
systems do to keep each iteration cheap), and a small regularization of the algebraic diagonal so
that it stays invertible where a linkage folds flat and A loses rank.

A family model (``model.sparse_dae``) takes the same residual and Newton matrix over its template
streams instead, in CSC (:class:`pfaff.numeric.ggl.GGLNewton`: exact blocks, and the state
derivatives of each template's outputs by differences in its local coordinates), factored
exactly (a band with a dense border, :mod:`pfaff.numeric.bordered`, or SciPy's SuperLU) as the
preconditioner of IDA's GMRES, which then converges in one iteration until c_j drifts; the
factors are kept over several steps, and over IDA's own requests while c_j stays within a factor
16 of theirs (``KEEP_RATIO``: GMRES iterates a little more, 3 factorizations instead of 14 on the
ring of 2^16); its first step comes from the local error of IDA's
first-order start (:func:`first_step`). scikit-sundae's ``linsolver="sparse"`` (SuperLU_MT with
this matrix as ``jacfn``) did as well as SuperLU in time (ring of 2^16, 1 s: 44 steps, 12.4 s
against 43 steps, 11.5 s; CPU, the machine busy) but chooses its
own pivots by magnitude with no ordering option: where they fill in, SuperLU_MT runs out of its
preallocated storage and aborts the process (the ring of 1024 before the x row was weighted),
where SciPy raises an error a run can report. ``ida_jacobian`` given: the dense path, for any
model (refused by size as before). The sparse path's unknowns are λ/s and μ/s
(:func:`algebraic_scale`) under one scalar absolute tolerance: weights within a factor √2 of
those of the tolerance vector with 1e12 on λ and μ, which scikit-sundae checks entry by entry in Python
(0.12 s at 2^16 members); the Newton matrix's pattern and band plan are the model's, made at its
first IDA run (:class:`pfaff.numeric.gglshape.NewtonShape`, 0.25 s at 2^16).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sps

from pfaff.core.errors import PfaffError
from pfaff.integrate.feasible import refuse_dense_ida, refuse_sparse_ida
from pfaff.integrate.stepper import Power, Stepper, StepperOptions
from pfaff.integrate.work import hermite_work
from pfaff.numeric.kkt import augmentation_weight
from pfaff.numeric.projection import Projector, diagonal_weights
from pfaff.numeric.protocol import DynamicsModel

SQRT_EPS = float(np.sqrt(np.finfo(float).eps))
REGULARIZATION = 1e-8  # ε / (max diag A M⁻¹Aᵀ / cj) on the algebraic diagonal
STALL_STEPS = 200  # consecutive steps of at most STALL_ULPS ulps of t: a stall
STALL_ULPS = 4096.0
STALL_FRACTION = 1e-6  # near t = 0, the ulps are those of this fraction of the span
EPS = float(np.finfo(float).eps)
FIRST_ERROR = 0.25  # the first step's estimated local error, in units of the tolerance
FD_LIMIT = 80  # unknowns up to which IDA builds its Newton matrix by finite differences
ALGEBRAIC_ATOL = 1e12  # λ's and μ's absolute tolerance: out of IDA's error test


def algebraic_scale(atol: float) -> float | None:
    """s of the sparse path's unknowns λ/s and μ/s (:class:`pfaff.numeric.ggl.GGLNewton`): the
    power of 2 nearest ``ALGEBRAIC_ATOL / atol``, so that the scalar tolerance ``atol`` gives
    them a weight within a factor √2 of the one ``ALGEBRAIC_ATOL`` gives λ and μ; None where
    ``atol`` is not positive or so small that s is not a float (the tolerance vector then).

    Examples
    --------
    >>> s = algebraic_scale(1e-11)
    >>> s == 2.0**76, 0.7 < s * 1e-11 / ALGEBRAIC_ATOL < 1.42, algebraic_scale(1e-300)
    (True, True, None)
    """
    if not atol > 0:
        return None
    exponent = round(np.log2(ALGEBRAIC_ATOL) - np.log2(atol))
    return float(2.0**exponent) if exponent < 1000 else None


def first_step(
    model: DynamicsModel,
    t0: float,
    state: tuple[np.ndarray, np.ndarray, np.ndarray],
    t_end: float,
    opts: StepperOptions,
) -> dict[str, float]:
    """IDA's first step from the local error of its first-order start, as ``first_step``
    (empty where the estimate fails: IDA's own choice then).

    Backward Euler's local error is h²/2 ‖y''‖, y'' = [q̈, q⃛] in IDA's error weights
    (atol + rtol |y|, RMS over q and q̇), q⃛ by a difference of q̈ along an explicit Euler step
    sized as in Hairer, Nørsett & Wanner, Solving ODE I, II.4: h₀ makes it ``FIRST_ERROR`` of
    the tolerance, at most a hundredth of the span; IDA's error test still accepts or shrinks
    it. IDA's own estimate keeps ‖h y'₀‖ ≤ 1/2 in those weights, where a velocity at rest
    weighs 1/atol: h₀ ≈ 5e-12 on the pushed ring at rest, then 35 steps (and Newton matrices)
    doubling it (43 steps for 1 s; 19 from this estimate). Used for families (the sparse path),
    where every step costs a factorization of an N-long matrix; small systems keep IDA's own
    (a contact test looks at the last digits there: a particle leaving a sphere stays outside
    it in IDA's tiny first steps).

    Parameters
    ----------
    model : DynamicsModel
        Its ``solve`` gives q̈ at the trial Euler step.
    t0, t_end : float
    state : tuple of ndarray, each shape (n,)
        q, q̇ and q̈ at t0.
    opts : StepperOptions
        rtol, atol and max_step.

    Returns
    -------
    dict
        ``{"first_step": h0}``, or empty.

    Examples
    --------
    >>> import numpy as np
    >>> from pfaff.integrate.stepper import StepperOptions
    >>> class Fall:  # q̈ = -g everywhere: q⃛ = 0, y'' = [-g, 0]
    ...     def solve(self, t, q, qd):
    ...         return np.full(1, -9.81), np.zeros(0)
    >>> start = (np.ones(1), np.zeros(1), np.full(1, -9.81))
    >>> h = first_step(Fall(), 0.0, start, 1.0, StepperOptions(rtol=1e-9, atol=1e-11))
    >>> weight = np.sqrt(((9.81 / (1e-11 + 1e-9)) ** 2 + 0.0) / 2)  # RMS of y'' / (atol + rtol|y|)
    >>> bool(np.isclose(h["first_step"], np.sqrt(2 * FIRST_ERROR / weight)))
    True
    """
    q0, qd0, qdd0 = state
    span = abs(t_end - t0)
    y0 = np.concatenate([q0, qd0])
    scale = float(opts.atol) + float(opts.rtol) * np.abs(y0)
    d0 = _rms(y0 / scale)
    d1 = _rms(np.concatenate([qd0, qdd0]) / scale)
    delta = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, span)
    try:
        qdd1, _ = model.solve(t0 + delta, q0 + delta * qd0, qd0 + delta * qdd0)
    except (PfaffError, ArithmeticError, np.linalg.LinAlgError):
        return {}
    d2 = _rms(np.concatenate([qdd0, (qdd1 - qdd0) / delta]) / scale)
    h = min(0.01 * span, float(opts.max_step or np.inf))
    if d2 > 0:
        h = min(h, float(np.sqrt(2.0 * FIRST_ERROR / d2)))
    return {"first_step": h} if np.isfinite(h) and h > 0 else {}


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else 0.0


class IDAStepper(Stepper):
    """IDA driven one internal step at a time (a :class:`~pfaff.integrate.stepper.Stepper`)."""

    name = "ida"

    def __init__(
        self,
        model: DynamicsModel,
        t0: float,
        q0: np.ndarray,
        qd0: np.ndarray,
        t_end: float,
        opts: StepperOptions,
        projector: Projector,
    ) -> None:
        try:
            from sksundae.ida import IDA, IDAPrecond
        except ImportError as e:  # pragma: no cover - a declared dependency
            raise PfaffError("method 'ida' needs scikit-sundae (pip install scikit-sundae)") from e
        if not opts.ida_jacobian and not model.mass_singular:
            model = model.dae_model  # (a family's dependent closing row left out: sparse again)
        self.model = model
        n, m = model.n, model.m
        self.hrows = np.flatnonzero(model.holonomic)
        mh = len(self.hrows)
        self.n, self.m, self.mh = n, m, mh
        self.size = 2 * n + m + mh
        qdd0, lam0 = model.solve(t0, q0, qd0)
        y0 = np.concatenate([q0, qd0, lam0, np.zeros(mh)])
        yp0 = np.concatenate([qd0, qdd0, np.zeros(m + mh)])
        self._ref, self._ref_h = np.zeros(m), np.zeros(mh)  # rows' largest sizes so far
        alg = np.arange(2 * n, self.size)  # (an array: scikit-sundae checks each entry)
        atol: np.ndarray | float = np.full(self.size, float(opts.atol))
        atol[alg] = ALGEBRAIC_ATOL  # algebraic variables: out of the error test
        kw = opts.step_sizes()
        # a family: the sparse Newton matrix (numeric.ggl), factored by SuperLU as the exact
        # preconditioner of IDA's GMRES; else (or when ida_jacobian asks) the dense one
        sparse = not opts.ida_jacobian and not model.mass_singular and model.sparse_dae
        if sparse:
            refuse_sparse_ida(self.size, n)  # before anything N-long is made (integrate.feasible)
            scale = algebraic_scale(float(opts.atol))  # λ/s and μ/s, one scalar tolerance
            if scale is None:
                scale = 1.0
            else:
                atol = float(opts.atol)
                y0[2 * n :] /= scale
            newton = model.dae_newton(self.hrows, t0, y0, yp0, algebraic_scale=scale)
            precond = IDAPrecond(newton.factor, newton.precondition)
            resfn, jacfn = newton.residual, None
            kw |= {"linsolver": "gmres", "precond": precond}
            if opts.first_step is None:  # (each step costs a factorization of an N-long matrix)
                kw |= first_step(model, t0, (q0, qd0, qdd0), t_end, opts)
            self.fd = False
        else:
            refuse_dense_ida(self.size, n)  # before IDA allocates anything (integrate.feasible)
            resfn, jacfn = self._residual, self._jacobian
            self.fd = self._finite_differences(opts)
        self.solver = IDA(
            resfn,
            rtol=float(opts.rtol),
            atol=atol,
            # (IDA reads these only for IDACalcIC and suppressalg, neither used: a family leaves
            # out scikit-sundae's Python loops over them, the same steps to the last bit)
            algebraic_idx=alg if alg.size and not sparse else None,
            jacfn=jacfn,
            max_num_steps=1_000_000,
            **kw,
        )
        self.newton = newton if sparse else None
        # M singular (quaternion coordinates): the augmented Lagrangian M + ρAᵀA (see _residual)
        self.rho = self._augmentation(t0, q0, qd0) if model.mass_singular else 0.0
        self.t_end = t_end
        self._span = abs(t_end - t0)
        self._tiny_count = 0
        res = self._call(self.solver.init_step, t0, y0, yp0)
        self._check(res)
        self._last = res
        self.stats = {"steps": 0, "rejected": None, "nfev": 0, "njev": 0}

    def _finite_differences(self, opts: StepperOptions) -> bool:
        """Difference columns for small systems: exact, and 2n residuals per Newton matrix."""
        choice = opts.ida_jacobian or ("fd" if self.size <= FD_LIMIT else "approximate")
        return choice == "fd"

    # ------------------------------------------------------------------ residual and Newton matrix
    def _blocks(self, t: float, y: np.ndarray) -> tuple:
        n = self.n
        q, v = y[:n], y[n : 2 * n]
        M, A, forcing, f, g = self.model.dae_blocks(t, q, v)
        if sps.issparse(M):
            M, A = M.toarray(), A.toarray()
        return M, A, forcing, f, g

    def _augmentation(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """ρ of M + ρAᵀA (:func:`pfaff.numeric.kkt.augmentation_weight`) at the first state."""
        M, A, *_ = self.model.dae_blocks(t, q, qd)
        M, A = (x.toarray() if sps.issparse(x) else x for x in (M, A))
        return augmentation_weight(M, A)

    def _residual(self, t: float, y: np.ndarray, yp: np.ndarray, res: np.ndarray) -> None:
        """The GGL residuals. With a singular M the dynamic rows are those of the augmented
        Lagrangian, (M + ρAᵀA) v' − (Q − h) − Aᵀλ + ρAᵀ(Ȧv + ḃ): the added ρAᵀ(A v' + Ȧv + ḃ)
        vanishes on every motion (its acceleration constraint), so the solution is the same,
        but v' is determined by these rows alone (index 2 again, not 3 along M's null space)."""
        n, m = self.n, self.m
        M, A, forcing, f, g = self._blocks(t, y)
        lam, mu = y[2 * n : 2 * n + m], y[2 * n + m :]
        Ah = A[self.hrows]
        res[:n] = yp[:n] - y[n : 2 * n] - Ah.T @ mu
        vp = yp[n : 2 * n]
        res[n : 2 * n] = M @ vp - forcing - A.T @ lam
        if self.rho:
            bias = self.model.constraint_bias(t, y[:n], y[n : 2 * n])
            res[n : 2 * n] += self.rho * (A.T @ (A @ vp + bias))
        res[2 * n : 2 * n + m] = g
        res[2 * n + m :] = f[self.hrows]

    def _jacobian(self, t, y, yp, res, cj, JJ) -> None:
        """Newton matrix ∂F/∂y + cj ∂F/∂y', regularized where A loses rank.

        The λ and μ columns and the y' part are exact (−Aᵀ, −A_hᵀ, cj·I, cj·M). The q and v
        columns come from forward differences of the residual ("fd") or from M and A alone
        ("approximate", no curvature terms). The diagonal blocks (g, λ) and (f, μ) get
        ε_i = 1e-8 · s_i / cj, s_i the largest A_i D⁻¹A_iᵀ seen so far, D = diag M (and the same
        with A_h A_hᵀ): it leaves a
        well-conditioned Newton matrix practically unchanged and keeps it invertible where a
        linkage folds flat, so that Newton still converges in every other direction (λ and μ
        are outside the error test, so the collapsing multiplier's slow convergence is harmless).
        """
        n, m, mh = self.n, self.m, self.mh
        M, A, *_ = self._blocks(t, y)
        if self.rho:  # the augmented Lagrangian's mass matrix (see _residual)
            M = M + self.rho * (A.T @ A)
        Ah = A[self.hrows]
        JJ[:, :] = 0.0
        idx = np.arange(n)
        if self.fd:
            tmp = np.empty(self.size)
            for j in range(2 * n):  # ∂F/∂q and ∂F/∂v by forward differences
                h = SQRT_EPS * max(abs(y[j]), 1.0)
                yj = y.copy()
                yj[j] += h
                self._residual(t, yj, yp, tmp)
                JJ[:, j] = (tmp - res) / h
        else:
            JJ[idx, n + idx] = -1.0
            JJ[2 * n : 2 * n + m, n : 2 * n] = A
            JJ[2 * n + m :, :n] = Ah
        JJ[idx, idx] += cj
        JJ[n : 2 * n, n : 2 * n] += cj * M
        JJ[:n, 2 * n + m :] = -Ah.T
        JJ[n : 2 * n, 2 * n : 2 * n + m] = -A.T
        if m:  # per row, relative to the row's largest size so far (a small row stays exact)
            d = diagonal_weights(M)
            self._ref = np.maximum(self._ref, (A * A / d).sum(axis=1))
            JJ[2 * n + np.arange(m), 2 * n + np.arange(m)] = REGULARIZATION * self._ref / cj
        if mh:
            self._ref_h = np.maximum(self._ref_h, (Ah * Ah).sum(axis=1))
            idx_h = 2 * n + m + np.arange(mh)
            JJ[idx_h, idx_h] = REGULARIZATION * self._ref_h / cj

    # ------------------------------------------------------------------ stepping contract
    def _check(self, res: Any) -> None:
        if res.status < 0:
            self.fail(f"IDA failed at t = {float(res.t):.17g}: {res.message}")

    @property
    def t(self) -> float:
        return float(self._last.t)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        y = self._last.y
        return y[: self.n].copy(), y[self.n : 2 * self.n].copy()

    def endpoints(self) -> tuple[tuple[float, np.ndarray, np.ndarray], ...]:
        """(t, y, ẏ) of q and v at both ends of the last internal step (IDA's own y and y′)."""
        return tuple((t, y.copy(), yp.copy()) for t, y, yp in self._ends())

    def _ends(self) -> tuple[tuple[float, np.ndarray, np.ndarray], ...]:
        """:meth:`endpoints` as views, for reading only (the work integral)."""
        n2 = 2 * self.n
        a, b = self._previous, self._last
        return ((float(a.t), a.y[:n2], a.yp[:n2]), (float(b.t), b.y[:n2], b.yp[:n2]))

    @staticmethod
    def _call(fn: Callable, *args: object, **kw: object) -> Any:
        """A call into scikit-sundae; its unmapped SUNDIALS return codes (a KeyError such as -60
        at times where the step size underflows) become a failure of the run."""
        try:
            return fn(*args, **kw)
        except KeyError as e:
            Stepper.fail(
                f"IDA stopped with SUNDIALS return code {e.args[0] if e.args else '?'} (the "
                "time span may be too far from 0 for its step sizes, or the tolerances too tight)"
            )

    def step_work(self, power: Power) -> float:
        """∫ P dt over the last internal step (see :func:`pfaff.integrate.work.hermite_work`)."""
        ends = self._ends()
        return hermite_work(ends, power, ends[0][0], ends[1][0])

    def work_until(self, power: Power, b: float) -> float:
        """∫ P dt from the start of the last internal step to ``b`` inside it (Hermite)."""
        ends = self._ends()
        return hermite_work(ends, power, ends[0][0], b)

    def step(self) -> None:
        t_before = self.t
        res = self._call(self.solver.step, self.t_end, method="onestep", tstop=self.t_end)
        self._check(res)
        self._previous, self._last = self._last, res
        # a step that hardly moves t against its own size (a few thousand ulps) counts as stalled
        tiny = STALL_ULPS * EPS * max(abs(self.t), STALL_FRACTION * self._span)
        self._tiny_count = self._tiny_count + 1 if self.t - t_before < tiny else 0
        if self._tiny_count >= STALL_STEPS:
            self.fail(
                f"IDA stalled at t = {self.t:.17g}: {STALL_STEPS} steps in a row shorter than "
                f"{tiny:.3g}. Its corrector cannot meet the tolerances here: they may "
                "be too tight for IDA (rtol below about 1e-10), or the constraint Jacobian loses "
                "rank (a linkage folding flat, which method='projection' passes)"
            )
        self.stats["steps"] += 1
        self.stats["nfev"] = int(res.nfev)
        self.stats["njev"] = int(res.njev) if self.newton is None else self.newton.factorizations

    def dense(self, ts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """IDA's own interpolation inside the last internal step."""
        out = []
        for ti in ts:
            r = self._call(self.solver.step, float(ti), method="normal", tstop=self.t_end)
            self._check(r)
            out.append((r.y[: self.n].copy(), r.y[self.n : 2 * self.n].copy()))
        return out

    def finish(self) -> dict[str, int | float | None]:
        return self.stats
