"""The stream parts of a compiled model: per template block, its kernels and where their outputs go.

Made by the compile stage (:mod:`pfaff.derive.compile`), read by the model kinds
(:mod:`pfaff.numeric.base`) and the solvers. A part holds no per-run state: its lazily made
kernels (energies, power) come from the factory it was given.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pfaff.numeric.kernel import StreamKernel
from pfaff.numeric.streams import Index


class DynStreams:
    """A dynamics block: mass entries (row, col) and forcing rows, as streams.

    Parameters
    ----------
    kernel : StreamKernel
        Outputs: the upper mass entries, then the forcing entries (summed where flagged).
    upper : list of (rows, cols, mirrored)
        Per upper mass entry (a <= b): its row and column streams and whether it also stands
        for (col, row).
    forcing : list of Index or ndarray
        Row of each forcing entry.
    energy_kernel : callable
        ``energy_kernel(which)`` makes the summed kernel of ``[T, V]`` (``"energy"``), of
        ``[T, V, T₀, T₂]`` (``"energies"``) or of the applied forces' power ``[Σ Q_a q̇_a]``
        (``"power"``), on first use.
    has_power : bool
        Whether the block has applied forces (else its power is zero and never evaluated).
    """

    def __init__(
        self,
        kernel: StreamKernel,
        upper: list[tuple[Index | np.ndarray, Index | np.ndarray, bool]],
        forcing: list[Index | np.ndarray],
        energy_kernel: Callable[[str], StreamKernel],
        has_power: bool = False,
    ) -> None:
        self.kernel, self.upper, self.forcing = kernel, upper, forcing
        # a force on a fixed coordinate (x of the ring) only ever counts summed over the instances
        self.summed = [isinstance(ix, Index) and ix.fixed for ix in forcing]
        self.mass = [(r, c) for r, c, _ in upper] + [(c, r) for r, c, sym in upper if sym]
        self._energy_kernel = energy_kernel
        self.has_power = has_power
        self._ekernel: StreamKernel | None = None
        self._pkernel: StreamKernel | None = None
        self._wkernel: StreamKernel | None = None

    def mass_values(self, outs: list) -> list:
        """Values of :attr:`mass` entries from the kernel outputs (mirrored entries repeated)."""
        nu = len(self.upper)
        return outs[:nu] + [v for (_, _, sym), v in zip(self.upper, outs, strict=False) if sym]

    def energy(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
        """(T, V) summed over the instances."""
        if self._ekernel is None:
            self._ekernel = self._energy_kernel("energy")
        return tuple(self._ekernel(t, q, qd))  # type: ignore[return-value]

    def power(self, t: float, q: np.ndarray, qd: np.ndarray) -> float:
        """Σ Q_a q̇_a of the applied forces, summed over the instances."""
        if not self.has_power:
            return 0.0
        if self._wkernel is None:
            self._wkernel = self._energy_kernel("power")
        return float(self._wkernel(t, q, qd)[0])

    def energies(self, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, ...]:
        """(T, V, T₀, T₂) summed over the instances: T₀ = T at q̇ = 0, T₂ its quadratic part."""
        if self._pkernel is None:
            self._pkernel = self._energy_kernel("energies")
        return tuple(self._pkernel(t, q, qd))


@dataclass
class ConStreams:
    """A constraint block: A entries over its rows, then b, bias (Ȧq̇ + ḃ) and f.

    Attributes
    ----------
    rows : Index or ndarray
        Constraint row of each instance.
    cols : list of Index or ndarray
        Column of each A entry.
    acc : StreamKernel
        Outputs ``[A entries..., bias]``.
    res : StreamKernel
        Outputs ``[A entries..., b, bias, f]``.
    """

    rows: Index | np.ndarray
    cols: list
    acc: StreamKernel
    res: StreamKernel
