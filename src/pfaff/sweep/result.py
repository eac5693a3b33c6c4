"""A sweep's results gathered into one :class:`xarray.Dataset`, and its netCDF file."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pfaff.core.files import atomic_path
from pfaff.sweep.grid import Grid

NAMES = ("coordinate_names", "multiplier_names", "constraint_names")


class Results:
    """The runs of a sweep as they come back from the tasks, in arrays over the flat run index."""

    def __init__(self, grid: Grid, samples: int, n: int) -> None:
        self.grid, N = grid, grid.size
        self.q, self.qd = np.full((N, samples, n), np.nan), np.full((N, samples, n), np.nan)
        self.multipliers: np.ndarray | None = None
        self.status = np.full(N, "", dtype=object)
        self.message = np.full(N, "", dtype=object)
        self.energy_error, self.constraint_residual = np.full(N, np.nan), np.full(N, np.nan)
        self.seconds = np.full(N, np.nan)
        self.names: dict[str, list[str]] = {}
        self.pids: set[int] = set()

    def add(self, out: dict[str, Any]) -> int:
        """Store one task's output (:func:`pfaff.sweep.worker.run_batch`); its number of runs."""
        i = out["index"]
        self.q[i], self.qd[i] = out["q"], out["qd"]
        if out["multipliers"] is not None:
            if self.multipliers is None:
                shape = (*self.q.shape[:2], out["multipliers"].shape[2])
                self.multipliers = np.full(shape, np.nan)
            self.multipliers[i] = out["multipliers"]
        self.status[i], self.message[i] = out["status"], out["message"]
        self.energy_error[i] = out["energy_error"]
        self.constraint_residual[i] = out["constraint_residual"]
        self.seconds[i] = out["seconds"]
        if "coordinate_names" in out and not self.names:
            self.names = {k: out[k] for k in NAMES}
        self.pids.add(out["pid"])
        return len(i)

    def fail(self, indices: list[int], message: str) -> None:
        """Mark runs failed without output (their worker process died every time)."""
        self.status[indices], self.message[indices] = "failed", message

    def dataset(self, t_eval: np.ndarray, attrs: dict[str, Any]) -> Any:
        """The :class:`xarray.Dataset` of the sweep (see :func:`pfaff.sweep`), as a
        :class:`~pfaff.sweep.dataset.SweepDataset` (a summary in notebooks)."""
        from pfaff.sweep.dataset import SweepDataset

        g, names = self.grid, self.names
        dims, shape = g.names, g.shape
        m = len(names["multiplier_names"])
        lam = self.multipliers
        if lam is None:  # every run failed before its model was compiled
            lam = np.full((g.size, len(t_eval), m), np.nan)
        coords: dict[str, Any] = {n: a for n, a in zip(g.names, g.axes, strict=True)}
        coords |= {
            "time": t_eval,
            "coordinate": list(names["coordinate_names"]),
            "multiplier": list(names["multiplier_names"]),
            "constraint": ("multiplier", list(names["constraint_names"])),
        }
        ok = self.status == "success"
        data = {
            "q": ((*dims, "time", "coordinate"), self.q.reshape(*shape, *self.q.shape[1:])),
            "qd": ((*dims, "time", "coordinate"), self.qd.reshape(*shape, *self.qd.shape[1:])),
            "multipliers": ((*dims, "time", "multiplier"), lam.reshape(*shape, *lam.shape[1:])),
            "status": (dims, self.status.astype(str).reshape(shape)),
            "message": (dims, self.message.astype(str).reshape(shape)),
            "energy_error": (dims, self.energy_error.reshape(shape)),
            "constraint_residual": (dims, self.constraint_residual.reshape(shape)),
            "seconds": (dims, self.seconds.reshape(shape)),
        }
        attrs = {**attrs, "runs": g.size, "succeeded": int(ok.sum()), "failed": int((~ok).sum())}
        ds = SweepDataset(data, coords=coords, attrs=attrs)
        ds["energy_error"].attrs["description"] = "max |T + V - E0 - W_nc| over the run"
        ds["constraint_residual"].attrs["description"] = "max |f|, |A qd + b| over the run"
        ds["seconds"].attrs["description"] = "wall time of the run in its worker"
        return ds


def write_netcdf(ds: Any, path: str | Path) -> Path:
    """Write a sweep's dataset as netCDF, atomically (netCDF4 or h5netcdf if present, else
    SciPy's netCDF3). A dimension of length zero (``multiplier`` of a system without
    constraints) is left out with its variables: SciPy cannot read such a file back."""
    from pfaff.results.trajectory import _netcdf_engine

    empty = [d for d, k in ds.sizes.items() if k == 0]
    if empty:
        ds = ds.drop_dims(empty)
        ds.attrs["omitted_empty_dimensions"] = ", ".join(map(str, empty))
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine=_netcdf_engine())
    return Path(path)
