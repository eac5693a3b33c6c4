"""The linearization of a compiled model at a state, from its kernel factory: no SymPy at run time.

:func:`linearize_model` is :meth:`pfaff.NumericModel.linearize`: the arguments checked and
matched against the factory's names (:class:`LinearizerFactory`, made by the derive stage:
:func:`pfaff.derive.linearize.linearizer_for`), then :func:`linearize_kernel` evaluates the
exact Jacobians the factory generated once and reduces them
(:func:`pfaff.numeric.linearization.reduce_linear`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np

from pfaff.core.errors import ConstraintError, ModelError, ModelTypeError, OptionError, StateError
from pfaff.numeric.checks import real_number, real_vector
from pfaff.numeric.linearization import (
    NUMPY,
    TOL,
    Linearization,
    OperatingMatrices,
    ignorable,
    operating_solve,
    reduce_linear,
)


@runtime_checkable
class LinearizationKernel(Protocol):
    """Generated code of the matrices a linearization needs, at x = (t, q, q̇, q̈, λ, p).

    ``x`` is a float array of shape (1 + 3n + m + n_p,): the time, the coordinates, rates,
    accelerations and multipliers, then every parameter value in the model's order
    (``NumericModel.parameters``). Both methods return dicts of float arrays.
    """

    def values(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``M`` (n, n), ``A`` (m, n), ``E``, ``G``, ``V`` (as columns) and ``f`` (holonomic rows)."""
        ...

    def jacobians(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``E_q``, ``E_qd``, ``E_u``, ``G_q``, ``G_qd``, ``G_u``, ``V_q``, ``V_u``
        (:class:`OperatingMatrices`), by the inputs the kernel was made for."""
        ...


@runtime_checkable
class LinearizerFactory(Protocol):
    """What a compiled model linearizes with (``NumericModel.linearizer``).

    Made once by the derivation stage (:func:`pfaff.derive.linearize.linearizer_for`) and
    shared by the models of other parameter values; picklable (a model sent to another process
    makes its kernels again on first use there).

    Attributes
    ----------
    coordinates, speeds : sequence, length n
        What :attr:`Linearization.states` lists for each coordinate and its rate.
    parameters : sequence, length n_p
        What :attr:`Linearization.inputs` lists for each parameter, in the model's order.
    holonomic_rows : list of int
        The constraint rows with a holonomic f (the rows of ``f``).
    """

    coordinates: Sequence[Any]
    speeds: Sequence[Any]
    parameters: Sequence[Any]
    holonomic_rows: list[int]

    def kernel(self, inputs: tuple[int, ...]) -> LinearizationKernel:
        """The kernel whose ``*_u`` Jacobians are by the parameters of these indices (made on the
        first request, then the same object)."""
        ...


def _index_of(key: object, names: Sequence[str], objects: Sequence[Sequence[Any]], arg: str) -> int:
    if isinstance(key, str):
        if key in names:
            return names.index(key)
    elif isinstance(key, int | float | bytes | bool | None):
        raise ModelTypeError(
            f"`{arg}` must list coordinates (functions of pfaff.t) or their names; got "
            f"{type(key).__name__} {key!r:.60}"
        )
    else:
        for objs in objects:
            for i, c in enumerate(objs):
                if key == c:
                    return i
    rate = " or its rate" * (arg != "independent")
    raise ModelError(
        f"`{arg}`: {key!s:.60} is not a coordinate{rate} of this system "
        f"(coordinates: {', '.join(names)})"
    )


def _indices(keys: object, names: Sequence[str], objects: Sequence[Sequence[Any]], arg: str):
    """Indices of the coordinates (or rates) ``keys`` names, by name or object; each once."""
    if isinstance(keys, str) or hasattr(keys, "free_symbols"):  # one name, one coordinate
        keys = [keys]
    try:
        keys = list(keys)  # type: ignore[call-overload]
    except TypeError:
        raise ModelTypeError(f"`{arg}` must be a list of coordinates; got {keys!r:.60}") from None
    idx = [_index_of(k, names, objects, arg) for k in keys]
    twice = sorted({i for i in idx if idx.count(i) > 1})
    if twice:
        raise ModelError(f"`{arg}` names {', '.join(f'`{names[i]}`' for i in twice)} twice")
    return idx


def _input_indices(inputs: object, names: list[str], symbols: Sequence[Any]) -> list[int]:
    """Indices of the parameters ``inputs`` names (by name or symbol)."""
    if isinstance(inputs, str) or hasattr(inputs, "free_symbols"):
        inputs = [inputs]
    out: list[int] = []
    for u in inputs:  # type: ignore[union-attr]
        name = u if isinstance(u, str) else getattr(u, "name", None)
        if name not in names:
            raise ModelError(
                f"`inputs`: {u!s:.60} is not a parameter of the model (a compiled model takes "
                f"parameters as inputs; parameters: {', '.join(names) or 'none'})"
            )
        if names.index(name) in out:
            raise ModelError(f"`inputs` names {name} twice")
        out.append(names.index(name))
    return out


def _parameter_vector(model: Any, input_values: Mapping[str, object] | None) -> np.ndarray:
    """The model's parameter values with the declared inputs' values of this call (given
    ``input_values``, an input it leaves out is 0)."""
    p = np.array(list(model.parameters.values()), dtype=float)
    if input_values is None:
        return p
    if not isinstance(input_values, Mapping):
        raise OptionError(
            f"`input_values` must be a dict of input name -> value, got {input_values!r:.60}"
        )
    declared = list(model.inputs)
    names = list(model.parameters)
    for name in declared:  # a declared input left out is 0 in this call
        if name in names:
            p[names.index(name)] = 0.0
    for name, v in input_values.items():
        if name not in declared:
            raise OptionError(
                f"`input_values`: `{name}` is not an input of this model (declared with "
                f"System.add_input: {', '.join(declared) or 'none'})"
            )
        value = real_number(v, f"input_values[{name!r}]", OptionError)
        if name in names:  # declared, but no equation uses it: nothing to set
            p[names.index(name)] = value
    return p


def linearize_model(
    model: Any,
    t: float,
    q: object,
    qd: object,
    independent: object,
    independent_speeds: object = None,
    inputs: object = (),
    input_values: Mapping[str, object] | None = None,
) -> Linearization:
    """:meth:`pfaff.NumericModel.linearize`: the arguments checked, then
    :func:`linearize_kernel` with the model's :class:`LinearizerFactory`."""
    factory = model.linearizer
    if factory is None:
        raise ModelError(
            "this model cannot be linearized: compile it with EquationsOfMotion.compile "
            "(models with families are not supported yet)"
        )
    t = real_number(t, "t")
    q = real_vector(q, "q", model.n, model.coordinate_names)
    qd = real_vector(qd, "qd", model.n, model.coordinate_names)
    names = list(model.coordinate_names)
    ind = _indices(independent, names, [factory.coordinates], "independent")
    spd = (
        ind
        if independent_speeds is None
        else _indices(
            independent_speeds, names, [factory.coordinates, factory.speeds], "independent_speeds"
        )
    )
    ins = _input_indices(inputs, list(model.parameters), factory.parameters)
    p = _parameter_vector(model, input_values)
    lin = linearize_kernel(
        factory.kernel(tuple(ins)), factory.holonomic_rows, t, q, qd, p, ind, spd, model
    )
    lin.states = [factory.coordinates[i] for i in ind] + [factory.speeds[i] for i in spd]
    lin.inputs = [factory.parameters[k] for k in ins]
    return lin


def linearize_kernel(
    kernel: LinearizationKernel,
    hol: list[int],
    t: float,
    q: np.ndarray,
    qd: np.ndarray,
    p: np.ndarray,
    ind: list[int],
    spd: list[int],
    model: Any,
) -> Linearization:
    """The linearization at (t, q, q̇) with parameters ``p``: the point checked (constraints
    met, kept rates not accelerating, moving kept coordinates ignorable), the accelerations and
    multipliers solved, then :func:`reduce_linear` of the kernel's Jacobians.

    ``model`` gives ``n``, ``m``, ``coordinate_names`` and ``constraint_names``. The result's
    ``states`` are the indices ``ind + spd`` and its ``inputs`` empty: the caller names them.
    """
    n, m = model.n, model.m
    names = list(model.coordinate_names)
    x = np.concatenate(([t], q, qd, np.zeros(n + m), p))
    vals = kernel.values(x)
    _check_constraints(vals, hol, list(model.constraint_names), q, qd)
    M, A = vals["M"], vals["A"]
    sol = np.asarray(operating_solve(NUMPY, M, A, vals["E"], vals["G"]))[:, 0]
    qdd0, lam0 = sol[:n], sol[n:]
    scale = TOL * (1.0 + np.abs(vals["E"]).max(initial=0.0) / max(np.abs(M).max(), 1e-300))
    moving = [f"q̈ of `{names[j]}` = {qdd0[j]}" for j in spd if abs(qdd0[j]) > scale]
    if moving:
        raise StateError(
            "the operating point is not an equilibrium or steady motion: the kept rates "
            "accelerate (" + "; ".join(moving) + ")"
        )
    x[1 + 2 * n : 1 + 3 * n + m] = sol
    mats = OperatingMatrices(M, A, list(hol), **kernel.jacobians(x))
    Amat, B, C, D = reduce_linear(mats, ind, spd, names)
    check_steady(Amat, ind, qd, names)
    return Linearization(Amat, B, ind + spd, [], (C, D), lam0 + 0.0)


def _check_constraints(vals: dict, hol: list[int], names: list[str], q, qd) -> None:
    """Every constraint met at the point: f = 0 (holonomic rows), A q̇ + b = 0 (every row)."""
    tol_f = TOL * (1.0 + np.abs(q).max(initial=0.0))
    amax = np.abs(vals["A"]).max(initial=0.0)
    tol_v = TOL * (1.0 + np.abs(qd).max(initial=0.0)) * (1.0 + amax)
    f, V = vals["f"][:, 0], vals["V"][:, 0]
    bad = [f"`{names[i]}`: f = {f[k]}" for k, i in enumerate(hol) if not abs(f[k]) <= tol_f]
    bad += [f"`{names[i]}`: A q̇ + b = {V[i]}" for i in range(len(V)) if not abs(V[i]) <= tol_v]
    if bad:
        raise ConstraintError(
            "the operating point violates the constraints (give values that satisfy them): "
            + "; ".join(bad)
        )


def check_steady(A: np.ndarray, ind: list[int], qd0: Sequence[float], names: list[str]) -> None:
    """A kept coordinate that moves must be one the linearized equations ignore."""
    free = set(ignorable(A))
    scale = TOL * (1.0 + float(np.abs(np.asarray(qd0, dtype=float)).max(initial=0.0)))
    bad = [
        f"`{names[j]}` (rate {qd0[j]:.6g})"
        for k, j in enumerate(ind)
        if abs(qd0[j]) > scale and k not in free
    ]
    if bad:
        raise StateError(
            "the operating point is not a steady motion: the kept coordinates "
            + ", ".join(bad)
            + " change while the linearized equations depend on them"
        )
