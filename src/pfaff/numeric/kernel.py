"""A compiled template kernel: a generated function evaluated over all instances of a template.

The derivation stage generates the function (:func:`pfaff.derive.codegen.make_kernel`); this stage
only calls it on arrays.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from pfaff.core.errors import raised_in_generated_code, undefined_at


@dataclass(frozen=True)
class Kernel:
    """A compiled template kernel and where its instances live.

    Attributes
    ----------
    fn : callable
        ``fn(q_0, ..., q_{k-1}, qd_0, ..., qd_{k-1}, t, *params) -> list`` of outputs.
    columns : tuple of ndarray of int
        ``columns[a]`` (shape (n_inst,)) is the global coordinate index of local coordinate a.
    n_inst : int
        Number of instances.
    n_out : int
        Number of outputs.
    """

    fn: Callable
    columns: tuple[np.ndarray, ...]
    n_inst: int
    n_out: int

    def __call__(self, t_: float, q: np.ndarray, qd: np.ndarray, p: Sequence[float]) -> list:
        """Evaluate every output for every instance; each result has shape (n_inst,)."""
        args = [q[c] for c in self.columns] + [qd[c] for c in self.columns]
        try:
            outs = self.fn(*args, t_, *p)
        except (ValueError, ArithmeticError) as e:  # an overflow in the user's equations, ...
            if not raised_in_generated_code(e):
                raise
            raise undefined_at(e, t_) from None
        shape = (self.n_inst,)
        if self.n_inst > 4096:  # constant outputs as read-only views: no memory per instance
            return [np.broadcast_to(np.asarray(o, dtype=float), shape) for o in outs]
        # few instances: np.full is five times cheaper than broadcast_to for a constant
        return [
            o if type(o) is np.ndarray and o.shape == shape else np.full(shape, o, dtype=float)
            for o in outs
        ]
