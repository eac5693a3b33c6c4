"""The summary of a sweep's dataset: counts, the worst errors, the first failed runs.

Used by the CLI's report (JSON) and by the dataset's notebook view
(:class:`pfaff.sweep.dataset.SweepDataset`); it reads the dataset only through its variables.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def summary(ds: Any, failures: int = 5) -> dict[str, Any]:
    """Counts, the worst errors and the first failed runs of a sweep's dataset (JSON-ready).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> ds = xr.Dataset({"status": ("L", np.array(["success", "failed"])),
    ...                  "message": ("L", np.array(["", "blew up"])),
    ...                  "energy_error": ("L", [1e-9, np.nan]),
    ...                  "constraint_residual": ("L", [0.0, np.nan])},
    ...                 coords={"L": [1.0, 2.0]})
    >>> s = summary(ds)
    >>> s["runs"], s["succeeded"], s["failures"]
    (2, 1, [{'point': {'L': 2.0}, 'status': 'failed', 'message': 'blew up'}])
    """
    status = ds["status"].values
    bad = np.argwhere(status != "success")
    dims = ds["status"].dims
    out: dict[str, Any] = {
        "runs": int(status.size),
        "succeeded": int((status == "success").sum()),
        "failed": int(bad.shape[0]),
        "dims": {d: int(ds.sizes[d]) for d in dims},
        "max_energy_error": _finite_max(ds["energy_error"].values),
        "max_constraint_residual": _finite_max(ds["constraint_residual"].values),
    }
    out["failures"] = [
        {
            "point": {d: float(ds[d].values[j]) for d, j in zip(dims, idx, strict=True)},
            "status": str(status[tuple(idx)]),
            "message": str(ds["message"].values[tuple(idx)]),
        }
        for idx in bad[:failures]
    ]
    return out


def _finite_max(a: np.ndarray) -> float | None:
    a = a[np.isfinite(a)]
    return float(a.max()) if a.size else None
