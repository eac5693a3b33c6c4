"""One generated kernel per template, run over all its instances: :class:`StreamKernel`.

:class:`StreamCode` is what the compile stage generates (:func:`pfaff.derive.codegen.stream_code`);
the index arithmetic the kernels run on is in :mod:`pfaff.numeric.streams`.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pfaff.core.errors import raised_in_generated_code, undefined_at
from pfaff.numeric import streams
from pfaff.numeric.generated import loaded, portable
from pfaff.numeric.streams import Index, in_spans, take
from pfaff.numeric.trig import sincos, workspace
from pfaff.numeric.trigjit import compiled
from pfaff.numeric.trigjit import sincos as jit_sincos


@dataclass(frozen=True)
class StreamCode:
    """Generated code of one template's outputs, made by :func:`pfaff.derive.codegen.stream_code`.

    Attributes
    ----------
    const : list of float or None
        Per output: its value when it does not depend on the state, else None (a summed output:
        the constant times the number of instances).
    varying : list of int
        The outputs that depend on the state, in the order ``fn`` returns them.
    summed : list of bool
        Per output: reduce it to its total over the instances.
    fn : callable or None
        ``fn(q_0.., q_{k-1}, qd_0.., qd_{k-1}, t, s_0, c_0, s_1, c_1, ...)``: the varying outputs,
        given sin and cos of every angle of ``angles``; None when nothing varies.
    angle_fn : callable or None
        ``angle_fn(q.., qd.., t)``: the angles whose sin and cos ``fn`` takes; None for none.
    angles : tuple
        The angle expressions (for reports and tests).
    params : tuple of float
        Parameter values ``fn`` takes last, at run time; empty when they are folded in (always,
        unless a folded number would leave the double range).
    """

    const: list
    varying: list
    summed: list
    fn: Callable | None
    angle_fn: Callable | None
    angles: tuple = ()
    params: tuple = ()

    def __getstate__(self) -> dict:
        """The generated functions travel as their source (:mod:`pfaff.numeric.generated`)."""
        state = dict(self.__dict__)
        state["fn"], state["angle_fn"] = portable(self.fn), portable(self.angle_fn)
        state["angles"] = tuple(str(a) for a in self.angles)  # (their count is what runs need)
        return state

    def __setstate__(self, state: dict) -> None:
        state["fn"], state["angle_fn"] = loaded(state["fn"]), loaded(state["angle_fn"])
        self.__dict__.update(state)


class StreamKernel:
    """Outputs of one template over all its instances; constants folded at build time.

    Parameters
    ----------
    columns : list of Index or ndarray
        Global coordinate indices of each local coordinate over the instances.
    code : StreamCode or callable
        The generated functions (:func:`pfaff.derive.codegen.stream_code`), or a function that
        makes them, called on first use. An output flagged
        summed is returned as its total over the instances (a float) instead of an array: it is
        reduced chunk by chunk while in cache and never stored (a force on an ordinary
        coordinate, an energy).
    count : int
        Number of instances.

    Attributes
    ----------
    const : list of float or None
        Per output: its value when it does not depend on the state, else None (summed outputs:
        the constant times ``count``).
    """

    _LAZY = frozenset(
        {"varying", "const", "angles", "_fn", "_angle_fn", "_params", "_slot", "_n_stored",
         "_n_summed", "_partial"}
    )  # fmt: skip

    def __init__(
        self, columns: list, code: StreamCode | Callable[[], StreamCode], count: int
    ) -> None:
        self.columns, self.count = columns, count
        # the key that takes each column's values for all instances at once: an index (fixed),
        # a slice (progression) or an index array (what ``take`` does, without its calls)
        self._keys = [
            (c.start if c.fixed else c.whole) if isinstance(c, Index) else c for c in columns
        ]
        self._out: np.ndarray | None = None
        # trigjit's compiled sin and cos (read at build time: tests change JIT_FROM), loaded by
        # the first call; None: trig.sincos's NumPy passes
        self._jit: Callable | bool | None = False if count >= streams.JIT_FROM else None
        self.chunk = (
            streams.CHUNK
        )  # (read at build time: tests change it) instances per call of the generated function
        self._local = threading.local()
        if isinstance(code, StreamCode):
            self._bind(code)
        else:  # generated on first use (a general model served by its fused kernel may never)
            self._make = code

    def __getattr__(self, name: str) -> object:
        make = self.__dict__.get("_make")
        if name not in StreamKernel._LAZY or make is None:
            raise AttributeError(name)
        del self._make
        self._bind(make())
        return getattr(self, name)

    def __getstate__(self) -> dict:
        """Its columns and code, or the maker of its code when it is not generated yet (the
        compile stage's makers pickle: the receiver generates only what it uses); no work
        arrays."""
        code = self.__dict__.get("_code")
        if code is None:
            code = self.__dict__["_make"]
        return {"columns": self.columns, "count": self.count, "code": code, "chunk": self.chunk}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["columns"], state["code"], state["count"])  # type: ignore[misc]
        self.chunk = state["chunk"]

    def _bind(self, code: StreamCode) -> None:
        self._code = code
        self.varying = list(code.varying)
        self.const: list[float | None] = list(code.const)
        self.angles = code.angles
        self._fn, self._angle_fn, self._params = code.fn, code.angle_fn, code.params
        # per varying output: its row in the stored outputs, or -1 - its row in the partial sums
        self._slot, ns, nv = [], 0, 0
        for i in self.varying:
            flag = code.summed[i]
            self._slot.append(-1 - ns if flag else nv)
            ns, nv = ns + flag, nv + (not flag)
        self._n_stored, self._n_summed = nv, ns
        self._partial = np.zeros((ns, -(-self.count // streams.CHUNK)))

    def _run(self, t_: float, q: np.ndarray, qd: np.ndarray, start: int, stop: int) -> None:
        out, partial = self._out, self._partial
        step = self.chunk
        for lo in range(start, stop, step):
            hi = min(lo + step, stop)
            args = [take(c, q, lo, hi) for c in self.columns]
            args += [take(c, qd, lo, hi) for c in self.columns]
            trig = self._trig(args, t_, hi - lo) if self.angles else []
            for j, r in zip(self._slot, self._fn(*args, t_, *trig, *self._params), strict=True):
                if j >= 0:
                    out[j, lo:hi] = r  # type: ignore[index]
                else:
                    partial[-1 - j, lo // step] = np.sum(r) if np.ndim(r) else r * (hi - lo)

    def _direct(self, t_: float, q: np.ndarray, qd: np.ndarray) -> list:
        """One chunk (the common case below 2^15 instances): outputs as the function returns
        them, no buffer (half the cost of a call on a small model)."""
        n = self.count
        keys = self._keys
        args = [q[k] for k in keys] + [qd[k] for k in keys]
        trig = self._trig(args, t_, n) if self.angles else []
        res: list = list(self.const)
        for i, j, r in zip(self.varying, self._slot, self._fn(*args, t_, *trig, *self._params)):  # noqa: B905
            if j < 0:
                res[i] = float(np.sum(r)) if np.ndim(r) else r * n
            else:
                res[i] = r if type(r) is np.ndarray and r.shape == (n,) else np.full(n, r, float)
        return res

    def _trig(self, args: list, t_: float, size: int) -> list:
        """sin and cos of every angle over one chunk, sharing the argument reduction (in one
        compiled pass when :meth:`__call__` found :mod:`pfaff.numeric.trigjit`'s)."""
        buf = getattr(self._local, "buf", None)
        if buf is None:
            buf = self._local.buf = (np.empty((2 * len(self.angles), self.chunk)), workspace())
        jit, res = self._jit, []
        for i, a in enumerate(self._angle_fn(*args, t_)):
            if np.ndim(a) == 0:
                res += [math.sin(a), math.cos(a)]
                continue
            s, c = buf[0][2 * i, :size], buf[0][2 * i + 1, :size]
            if not jit or np.ndim(a) != 1:
                res += sincos(a, s, c, buf[1])
            else:
                jit_sincos(jit, np.asarray(a, dtype=float), s, c, buf[1].k)
                res += [s, c]
        return res

    def warm(self) -> None:
        """Allocate and touch the output buffers now (page faults at build time, not in a solve)."""
        if self._fn is not None and self._out is None:
            self._out = np.zeros((self._n_stored, self.count))
            self._out.fill(0.0)

    def __call__(self, t_: float, q: np.ndarray, qd: np.ndarray) -> list:
        """Every output over the instances: a float (a constant per instance, or the total of a
        summed output) or an array, shape (count,).

        The arrays are buffers owned by the kernel, overwritten by the next call.
        """
        if self._fn is None:
            return list(self.const)
        try:
            if self.count <= self.chunk:
                return self._direct(t_, q, qd)
            if self._out is None:
                self._out = np.empty((self._n_stored, self.count))
            if self.angles and self._jit is False:  # (loaded here: not on a kernel thread)
                self._jit = compiled()
            in_spans(self.count, self.chunk, lambda lo, hi: self._run(t_, q, qd, lo, hi))
        except (ValueError, ArithmeticError) as e:  # an overflow in the user's equations, ...
            if not raised_in_generated_code(e):
                raise
            raise undefined_at(e, t_) from None
        out = self._out
        res: list = list(self.const)
        for j, i in zip(self._slot, self.varying, strict=True):
            res[i] = out[j] if j >= 0 else math.fsum(self._partial[-1 - j])
        return res

    def local(self, t_: float, args: list) -> list:
        """Every output per instance from the local arguments ``args`` = [q_0.., q_{k-1},
        qd_0.., qd_{k-1}] (arrays over all instances, or scalars shared by all): constants as
        floats, the others as the generated function returns them, never summed and in one
        call (no chunks, no buffers). What a Jacobian by local differences perturbs
        (:mod:`pfaff.numeric.ggl`).
        """
        res: list = list(self.const)
        if self._fn is None:
            return res
        trig: list = []
        if self.angles and self._jit is False:
            self._jit = compiled()
        for a in self._angle_fn(*args, t_) if self.angles else ():
            if self._jit and np.ndim(a) == 1:  # (one compiled pass, as __call__'s)
                a = np.asarray(a, dtype=float)
                s, c = np.empty(a.size), np.empty(a.size)
                jit_sincos(self._jit, a, s, c, np.empty(a.size))
                trig += [s, c]
            else:
                trig += [np.sin(a), np.cos(a)]
        try:
            values = self._fn(*args, t_, *trig, *self._params)
        except (ValueError, ArithmeticError) as e:
            if not raised_in_generated_code(e):
                raise
            raise undefined_at(e, t_) from None
        for i, r in zip(self.varying, values, strict=True):
            res[i] = r
        return res
