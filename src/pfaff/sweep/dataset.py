"""The dataset a sweep returns: an :class:`xarray.Dataset` that a notebook shows with a summary.

:class:`SweepDataset` adds nothing but its HTML representation (the runs, the failures, the
largest energy and constraint errors, then xarray's own view); every operation of
:class:`xarray.Dataset` works on it unchanged. This module imports xarray: the sweep imports it
only when it builds its result.
"""

from __future__ import annotations

import xarray as xr

from pfaff.core.display import number, summary_html
from pfaff.sweep.overview import summary


class SweepDataset(xr.Dataset):
    """A sweep's results (see :func:`pfaff.sweep`), summarized in a notebook.

    Examples
    --------
    >>> import numpy as np
    >>> ds = SweepDataset({"status": ("L", np.array(["success", "failed"])),
    ...                    "message": ("L", np.array(["", "blew up"])),
    ...                    "energy_error": ("L", [1e-9, np.nan]),
    ...                    "constraint_residual": ("L", [0.0, np.nan])},
    ...                   coords={"L": [1.0, 2.0]}, attrs={"t_end": 3.0})
    >>> "1 of 2 succeeded" in ds._repr_html_()
    True
    """

    __slots__ = ()

    def _repr_html_(self) -> str:
        try:
            s = summary(self, failures=3)
        except KeyError:  # a dataset derived from the sweep's without its per-run variables
            return super()._repr_html_()
        rows = [
            ("runs", f"{s['succeeded']} of {s['runs']} succeeded"),
            ("grid", ", ".join(f"{d} × {k}" for d, k in s["dims"].items())),
        ]
        if "t_end" in self.attrs:
            span = f"t = 0 … {number(self.attrs['t_end'])}"
            rows.append(
                ("span", span + (f" ({self.sizes['time']} times)" if "time" in self.sizes else ""))
            )
        rows.append(("max energy balance error", number(s["max_energy_error"])))
        rows.append(("max constraint residual", number(s["max_constraint_residual"])))
        for f in s["failures"]:
            point = ", ".join(f"{k} = {number(v)}" for k, v in f["point"].items())
            rows.append((f"{f['status']} at {point}", f["message"]))
        if "wall_seconds" in self.attrs:
            rows.append(("wall time", f"{number(self.attrs['wall_seconds'])} s"))
        details = f"<details><summary>dataset</summary>{super()._repr_html_()}</details>"
        return summary_html(f"pfaff.sweep: {self.attrs.get('model', 'model')}", rows, details)
