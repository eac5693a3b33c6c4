"""The compiled stepping loop: Python runs once per reported point, not once per stage.

For a small model (the fused kernel with its generated solve, as machine code), ``"projection"``
with DOP853 spends most of a step in Python: twelve calls of a right-hand side that itself costs
a few tens of nanoseconds. Here the whole step (DOP853's stages, error norm and step-size
controller, the projection onto the constraints, the work integral, the dense output at
``t_eval``) runs in one function compiled by numba (:mod:`pfaff.integrate.loopkernel`), which
calls the model's machine code through its C entry points (:mod:`pfaff.numeric.machineloop`);
the driver (:mod:`pfaff.integrate.simulation`) records what it reports.

Why numba: it is built on llvmlite (LLVM, as SymEngine's machine code is), calls a function
pointer natively, keeps what it compiles in an on-disk cache (``cache=True``: beside the module,
or numba's user-wide folder when that is read-only, or ``NUMBA_CACHE_DIR``), and needs no C
compiler on the user's machine. SymEngine's ``Lambdify`` compiles straight-line code only;
generated C would need a compiler. Without numba, or with ``PFAFF_LOOP=0``, or where the loop
does not apply, runs take the Python path (:class:`pfaff.integrate.integrators.ProjectedRK` on
:class:`pfaff.integrate.fastrk.FloatDOP853`), whose results the loop reproduces to rounding:
the same method, step-size rule, projection and quadratures.

Where it applies: ``method="projection"`` (the class itself, not a subclass) with DOP853 on
floats, a model whose run can use its machine code (:func:`pfaff.numeric.machineloop.machine_loop`),
and no events of any kind (user events, attitude sets with switches or singularities,
unilateral contacts), which stay on the Python path. Any step the loop cannot take exactly as the
Python path would (a non-finite value, M not positive definite, a projection that fails) is
taken by the Python stepper, from the same state, and the loop goes on after it.
``Trajectory.stats["stepping"]`` says which path ran; ``model.timings["compiled_loop"]`` the
CPU seconds the loop's code took to load or compile in this process.
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from pfaff.integrate.integrators import ProjectedRK
from pfaff.integrate.reach import UNREACHED
from pfaff.integrate.stepper import _RunFailure
from pfaff.numeric.jit import loaded

if TYPE_CHECKING:
    from pfaff.numeric.machineloop import LoopCode


def _kernel() -> tuple[Any, str, float]:
    """The kernel module (numba code, compiled or loaded now, once per process), or None and
    the reason; and the CPU seconds its load took (:func:`pfaff.numeric.jit.loaded`)."""
    if os.environ.get("PFAFF_LOOP", "1").strip().lower() in ("0", "false", "no", "off"):
        return None, "PFAFF_LOOP=0", 0.0
    return loaded("loopkernel", _load_kernel)


def _load_kernel() -> Any:
    from pfaff.integrate import loopkernel

    _warm(loopkernel)
    return loopkernel


CHUNK = 4096  # steps per call at most: between calls the driver sees Ctrl-C and max_seconds


def _warm(kernel: Any) -> None:
    """Compile (or load from numba's cache) the kernel for the argument types of every run."""
    buffers = _Buffers(kernel, 1, 1, np.zeros(0), 4, 1, 0, 0)
    buffers.c[kernel.BUDGET] = 0  # no step: only the types matter
    pattern = np.zeros((1, 2), np.int64)
    buffers.call(np.zeros(6, dtype=np.int64), pattern, pattern, np.zeros((0, 2), np.int64))


class _Buffers:
    """The arrays one run's calls of ``advance`` share."""

    def __init__(
        self, kernel: Any, n: int, m: int, te: np.ndarray, rhs_in: int, rhs_size: int,
        con_in: int, con_size: int, eulers: int = 0,
    ) -> None:  # fmt: skip
        self.kernel, self.n = kernel, n
        self.rin, self.rout = np.zeros(rhs_in), np.zeros(rhs_size)
        self.cin, self.cout, self.pout = np.zeros(max(con_in, 1)), np.zeros(con_size), np.zeros(1)
        self.hol = np.zeros(m)
        self.s, self.c = np.zeros(11), np.zeros(14, dtype=np.int64)
        self.atol, self.y, self.f = np.zeros(2 * n), np.zeros(2 * n), np.zeros(2 * n)
        self.te = np.ascontiguousarray(te, dtype=float)
        cap = te.size if te.size else CHUNK  # (every step is reported only without t_eval)
        self.out_t, self.out_y, self.out_w = np.zeros(cap), np.zeros((cap, 2 * n)), np.zeros(cap)
        self.work = kernel.workspace(n, m, eulers)

    def call(self, fns: np.ndarray, mass: np.ndarray, acon: np.ndarray, euler: np.ndarray) -> int:
        k = self.kernel
        return k.advance(
            fns, self.rin, self.rout, self.cin, self.cout, self.pout, mass, acon, self.hol,
            k.TABLEAU, self.s, self.c, self.atol, self.y, self.f, self.te, self.out_t,
            self.out_y, self.out_w, euler, self.work,
        )  # fmt: skip


class CompiledLoop:
    """The compiled loop of one run (see the module docstring); :meth:`advance` is what the
    driver calls instead of a Python step."""

    name = "compiled loop"

    def __init__(self, kernel: Any, code: LoopCode, run: Any, te: np.ndarray | None) -> None:
        st: ProjectedRK = run.stepper
        solver = st.solver
        n, m = st.n, len(code.holonomic)
        self.stepper, self.code = st, code
        eulers = [(i, symmetric) for _, i, _, symmetric in run.events.eulers]
        self.euler = np.array(eulers, dtype=np.int64).reshape(-1, 2)
        self.eulers = [(int(i), bool(sym)) for i, sym in eulers]
        b = _Buffers(kernel, n, m, np.zeros(0) if te is None else te, code.rhs_in.size,
                     code.rhs_size, code.con_in.size, code.con_size, len(eulers))  # fmt: skip
        b.rin[:], b.cin[: code.con_in.size], b.hol[:] = code.rhs_in, code.con_in, code.holonomic
        b.atol[:] = solver.atol
        s, K = b.s, kernel
        s[K.T_BOUND], s[K.RTOL] = solver.t_bound, solver.rtol
        s[K.MAX_STEP], s[K.TOL], s[K.UNREACHED] = solver.max_step, st.projector.tol, UNREACHED
        b.c[K.MAX_ITER] = st.projector.max_iter
        b.c[K.FLAGS] = (
            (K.HAS_TE if te is not None else 0)
            | (K.PROJECT_OUT if run.projector is not None else 0)
            | (K.HAS_POWER if run.power is not None else 0)
        )
        self.b, self.kernel = b, kernel
        self.bailed = False
        st.stats["stepping"] = self.name
        st.stats["python_steps"] = 0

    def advance(self, run: Any, k: int, work: float) -> tuple[int, float] | None:
        """Steps from the stepper's state until a budget (:data:`CHUNK`, ``max_steps``), a full
        window of the run's pace, the span's end, or a step the Python path must take; their
        reported states recorded. Returns the next ``t_eval`` index and the work so far, or
        None: the driver takes the next step in Python."""
        if self.bailed:  # the step the loop left: Python's, then the loop again
            self.bailed = False
            self.stepper.stats["python_steps"] += 1
            return None
        K, b, st, pace = self.kernel, self.b, self.stepper, run.pace
        solver, s, c = st.solver, b.s, b.c
        s[K.T], s[K.H], s[K.WORK] = solver.t, solver.h_abs, work
        b.y[:], b.f[:] = solver._y, solver._f
        c[K.NFEV : K.BUDGET] = 0
        c[K.K_EVAL] = k
        c[K.BUDGET] = CHUNK if pace.max_steps is None else min(CHUNK, pace.max_steps - pace.steps)
        c[K.PACE_STEPS], c[K.PACE_COUNT], s[K.START], s[K.LARGEST] = pace.history()
        c[K.FLAGS] = c[K.FLAGS] & ~(K.QUIET | K.HAS_BEFORE) | (K.QUIET if pace.quiet else 0)
        if self.euler.size and run._last_q is not None:  # the Euler angles' last check
            c[K.FLAGS] |= K.HAS_BEFORE
            q = run._last_q
            b.work.angles[:] = [math.sin(q[i]) if sym else math.cos(q[i]) for i, sym in self.eulers]
        code = b.call(self.code.functions, self.code.mass, self.code.acon, self.euler)
        steps = int(c[K.N_STEP])
        self._sync(steps)
        if steps and self.euler.size:
            run._last_q = b.y[: b.n].copy()
        if code == K.BAIL:
            self.bailed = True
            if not steps:
                return self.advance(run, k, work)
        try:
            pace.resume(int(c[K.PACE_STEPS]), int(c[K.PACE_COUNT]), float(s[K.START]),
                        float(s[K.LARGEST]), float(s[K.T]))  # fmt: skip
        except _RunFailure:  # (STALL): its last step is not recorded, as on the Python path
            self._record(run, float(s[K.LAST_T]))
            raise
        self._record(run, np.inf)
        return int(c[K.K_EVAL]), float(s[K.WORK])

    def _record(self, run: Any, until: float) -> None:
        b, n = self.b, self.b.n
        for i in range(int(b.c[self.kernel.N_OUT])):
            t = float(b.out_t[i])
            if t > until:
                break
            y = b.out_y[i]
            run._record(t, y[:n], y[n:], False, float(b.out_w[i]))

    def _sync(self, steps: int) -> None:
        """The Python stepper's solver at the loop's state; the loop's counts added to its
        statistics and to the projector's."""
        K, b, st = self.kernel, self.b, self.stepper
        c, solver = b.c, st.solver
        if steps:
            solver.t, solver.h_abs = float(b.s[K.T]), float(b.s[K.H])
            solver.y, solver.f = b.y, b.f
        st.stats["steps"] += int(c[K.STEPS])
        st.stats["rejected"] += int(c[K.REJECTED])
        solver.nfev += int(c[K.NFEV])
        st._restarts += int(c[K.RESTARTS])
        ps = st.projector.stats
        ps["projections"] += int(c[K.PROJECTIONS])
        ps["projection_iterations"] += int(c[K.ITERATIONS])


def compiled_loop(run: Any, model: Any) -> tuple[CompiledLoop | None, str]:
    """The compiled loop of a run set up by :func:`pfaff.simulate` (its ``_Run``), or None and
    the reason it does not apply (module docstring)."""
    from pfaff.integrate.fastrk import FloatDOP853

    st = run.stepper
    if type(st) is not ProjectedRK or not isinstance(st.solver, FloatDOP853):
        return None, ""  # another method (or a subclass): not a candidate
    if run.user or run.events.mrps or getattr(model, "contacts", None):
        return None, "events"
    make = getattr(model, "machine_loop", None)
    if make is None:
        return None, "the model has no machine code for the loop"
    kernel, reason, seconds = _kernel()
    if kernel is None:
        return None, reason
    timings = getattr(model, "timings", None)
    if isinstance(timings, dict) and "compiled_loop" not in timings:
        timings["compiled_loop"] = seconds
    code, reason = make(st.fun)
    if code is None:
        return None, reason
    return CompiledLoop(kernel, code, run, run.te), ""
