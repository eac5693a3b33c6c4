"""What makes a compiled model a value: immutable, copied for runs, rebuilt for other values, pickled.

:class:`ModelValue` is the base of :class:`pfaff.numeric.base.StreamModel` and so of both model
kinds. A model is built once, by the compile stage, from parts that never change (kernels,
names, holonomic flags, attitude sets, geometry, the linearization factory, input names) and
its parameter values; after that:

- its attributes cannot be set (:meth:`ModelValue.__setattr__`), its ``parameters`` are a
  read-only mapping;
- what changes during a run (the KKT mode, ρ, counters, scratch arrays, the machine-code
  buffer, the inputs' values) lives in a *run copy* (:meth:`ModelValue.for_run`), which shares
  the parts; ``simulate`` makes one per run, so nothing a run does is seen by the user's model;
- :meth:`ModelValue.with_parameters` makes another model from the same parts;
- what depends on the parts alone and is costly to find (IDA's sparse pattern and band plan of a
  family) is made once per model by :meth:`ModelValue.derived` and shared by its run copies,
  never changed after; another parameter value or an unpickled copy makes its own;
- ``pickle`` carries the parts and the parameter values, not per-run or per-N work arrays;
  generated code travels as its source (:mod:`pfaff.numeric.generated`), machine code as
  SymEngine pickles it.

Thread policy: dense solves of small systems must not wait on BLAS threads (on a busy 2-core
machine a 10×10 solve with the default OpenBLAS threads took 5–15× longer). Every run
(``simulate``, a sweep's batch) limits BLAS to one thread, once, through :func:`single_threaded`;
a checked single-state call (:meth:`accelerations`) does so above
:data:`pfaff.numeric.checked.UNLIMITED_UP_TO` unknowns only.
"""

from __future__ import annotations

import contextlib
import functools
import threading
import types
from collections.abc import Callable, Hashable, Iterator, Mapping
from typing import Any, Self, TypeVar

import numpy as np

from pfaff.core.errors import ModelTypeError, OptionError, ParameterError
from pfaff.numeric.checks import real_number


@functools.cache
def _controller() -> Any:
    """threadpoolctl's view of the loaded BLAS libraries (made once: it scans them)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


_depth = [0]
_derived_lock = threading.RLock()
T = TypeVar("T")


@functools.cache
def _threaded() -> bool:
    """Whether some loaded BLAS runs on more than one thread (looked up once per process:
    with ``OPENBLAS_NUM_THREADS=1`` and the like, limiting costs nothing, not 10–30 µs)."""
    return any(info.get("num_threads", 1) > 1 for info in _controller().info()
               if info.get("user_api") == "blas")  # fmt: skip


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """BLAS limited to one thread inside (nested uses cost nothing: only the outermost limits).

    Examples
    --------
    >>> with single_threaded():
    ...     pass
    """
    if _depth[0] or not _threaded():
        yield
        return
    _depth[0] += 1
    try:
        with _controller().limit(limits=1, user_api="blas"):
            yield
    finally:
        _depth[0] -= 1


class ModelValue:
    """Immutability, run copies, other parameter values and pickling of a compiled model.

    Subclasses set their fields in ``__init__`` and call :meth:`_freeze` at its end.
    """

    _frozen = False
    _is_run = False
    parameters: Mapping[str, float]
    inputs: tuple[str, ...] = ()
    n: int
    m: int

    # ------------------------------------------------------------------ immutability
    def __setattr__(self, name: str, value: object) -> None:
        if self._frozen:
            raise AttributeError(
                f"a compiled model is immutable: `{name}` cannot be set (with_parameters makes a "
                "model with other parameter values; inputs take their values per call or per run)"
            )
        object.__setattr__(self, name, value)

    def _freeze(self) -> None:
        object.__setattr__(self, "parameters", types.MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "_p", tuple(self.parameters.values()))
        object.__setattr__(self, "_run_state", self._new_run_state())
        object.__setattr__(self, "_derived", {})
        object.__setattr__(self, "_frozen", True)

    def _new_run_state(self) -> dict:
        """The per-run state: KKT mode, ρ, the machine code's last state, scratch buffers."""
        return {"full": False, "rho": 0.0, "last": None, "live": False, "rows": None}

    def derived(self, key: Hashable, make: Callable[[], T]) -> T:
        """A structure found from this model's parts alone, made by ``make()`` the first time
        ``key`` is asked for and shared after that by the model and its run copies (it must
        not be changed by its users). Threads asking at once wait for one ``make``.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> first = model.derived("names", lambda: tuple(model.coordinate_names))
        >>> model.for_run().derived("names", lambda: ()) is first
        True
        """
        memo = self.__dict__.get("_derived")
        if memo is None:  # (a part made before the model was frozen: not remembered)
            return make()
        with _derived_lock:
            if key not in memo:
                memo[key] = make()
            return memo[key]

    # ------------------------------------------------------------------ runs
    def for_run(self) -> Self:
        """A run copy: the same parts and values, its own per-run state.

        ``simulate`` makes one per run; its mode (set by ``check_determined`` at the first
        state), counters and inputs' values are its own. The parts are shared, not copied.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> run = model.for_run()
        >>> run.parameters == model.parameters, run is model
        (True, False)
        """
        run = object.__new__(type(self))
        d = run.__dict__
        d.update(self.__dict__)
        d["_is_run"] = True
        d["_p"] = list(self._p)  # private: inputs write here during a run
        d["stats"] = {k: v for k, v in self.stats.items() if k == "solver"} | {"kkt_solves": 0}
        d["_run_state"] = self._new_run_state()
        run._fresh_run_parts()
        return run

    def _fresh_run_parts(self) -> None:
        """Per-run parts a subclass makes anew for a run copy (solvers with work arrays)."""

    @contextlib.contextmanager
    def _threads(self) -> Iterator[None]:
        with single_threaded():
            yield

    # ------------------------------------------------------------------ inputs and parameters
    def _with_inputs(self, values: Mapping[str, object] | None) -> Self:
        """This model with the declared inputs set to ``values`` (a missing input is 0) for one
        call; the model itself is unchanged."""
        if values is None:
            return self
        if not isinstance(values, Mapping):
            raise OptionError(f"`inputs` must be a dict of input name -> value, got {values!r:.60}")
        new = {}
        for name in self.inputs:
            if name in self.parameters:
                new[name] = 0.0
        for name, v in values.items():
            if name not in self.inputs:
                raise OptionError(
                    f"`inputs`: `{name}` is not an input of this model (declared with "
                    f"System.add_input: {', '.join(self.inputs) or 'none'})"
                )
            if name in self.parameters:
                new[name] = real_number(v, f"inputs['{name}']", OptionError)
        if not new:
            return self
        if self._runtime_parameters():
            run = self.for_run()
            names = list(self.parameters)
            for name, v in new.items():
                run._p[names.index(name)] = v
            run.__dict__["parameters"] = types.MappingProxyType({**self.parameters, **new})
            return run
        return self.with_parameters(new)

    def _runtime_parameters(self) -> bool:
        """Whether the compiled code takes the parameter vector at run time (fused kernels)."""
        return False

    def with_parameters(self, values: Mapping[str, float]) -> Self:
        """This compiled model with other parameter values: nothing derived or generated again.

        Parameters
        ----------
        values : mapping of str to float
            New values by parameter name; the parameters not named keep theirs.

        Returns
        -------
        model
            A new model of the same kind sharing this one's compiled parts (this one is
            unchanged).

        Notes
        -----
        A fused kernel and its machine code take the parameter values at run time: they are
        shared as they are. Template kernels fold the values into their code, so the templates
        whose expressions use a changed parameter get new kernels, generated on first use only.
        Particle masses are not checked again here: the inertia check at the first state of a
        simulation refuses a mass that is not positive.

        Raises
        ------
        ParameterError
            An unknown name, or a value that is not a finite real number.
        ModelTypeError
            The model was built without a way to change its values.

        Examples
        --------
        >>> import numpy as np, pfaff
        >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> heavy = model.with_parameters({"m": 3})
        >>> lam = heavy.accelerations(0.0, np.array([0.0, -2.0]), np.zeros(2))[1]
        >>> round(float(-2 * 2 * lam[0]), 12), model.parameters["m"]  # tension m g; m unchanged
        (29.43, 1.0)
        """
        if not isinstance(values, Mapping):
            raise ParameterError(f"`values` must be a dict of name -> value, got {values!r:.60}")
        new = dict(self.parameters)
        problems = []
        for name, v in values.items():
            if name not in new:
                problems.append(f"unknown parameter `{name}` (the model's: {', '.join(new)})")
                continue
            try:  # the one check of a finite real number (pfaff.numeric.checks)
                new[name] = real_number(v, name, ParameterError)
            except ParameterError as e:
                finite = "is not finite" not in str(e)
                problems.append(
                    f"parameter `{name}` must be a real number, got {v!r:.80}"
                    if finite
                    else f"parameter `{name}` is {float(v)} (NaN or infinite)"  # type: ignore[arg-type]
                )
        if problems:
            raise ParameterError("bad parameters: " + "; ".join(problems))
        if self._restream is None and list(new.values()) != list(self.parameters.values()):
            raise ModelTypeError("this model was not compiled with a way to change its parameters")
        return self._rebuilt(new)

    _restream: Any = None

    def _rebuilt(self, parameters: dict[str, float]) -> Self:
        """A model of this kind from the same parts with ``parameters`` (subclasses)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ pickling
    def __copy__(self) -> Self:
        return self  # immutable: a copy is the model itself

    def __deepcopy__(self, memo: dict) -> Self:
        return self

    def __getstate__(self) -> dict:
        state = {k: v for k, v in self.__dict__.items() if k not in self._unpickled()}
        state["parameters"] = dict(self.parameters)
        state["_p"] = tuple(self._p)
        state["_is_run"] = False
        state.pop("_frozen", None)
        h = state.get("holonomic")
        if isinstance(h, np.ndarray) and h.size > 64:  # 2^24 flags: packed, or one when all equal
            same = bool(h.all()) or not h.any()
            state["holonomic"] = ("packed", h.size, bool(h[0]) if same else np.packbits(h))
        return state

    def _unpickled(self) -> set[str]:
        """Fields not pickled: per-run state and work arrays, remade on unpickling."""
        return {"_run_state", "stats", "_derived"}

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "_frozen", False)
        h = state.get("holonomic")
        if isinstance(h, tuple) and h[0] == "packed":
            _, size, bits = h
            state["holonomic"] = (
                np.full(size, bits, dtype=bool)
                if isinstance(bits, bool)
                else np.unpackbits(bits, count=size).astype(bool)
            )
        for k, v in state.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "stats", {"kkt_solves": 0})
        if self.__dict__.get("solver", "none") != "none":
            self.stats["solver"] = self.solver
        self._restored()
        self._freeze()

    def _restored(self) -> None:
        """Remake what :meth:`_unpickled` left out (subclasses)."""

    _p: tuple | list = ()
    _run_state: dict = {}  # noqa: RUF012 (replaced per instance by _freeze)
    _derived: dict | None = None  # (set per instance by _freeze)
