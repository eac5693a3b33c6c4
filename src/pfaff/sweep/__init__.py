"""Parameter sweeps: a grid of simulations of a model file, on a Dask cluster or in this process.

:func:`sweep` (re-exported as ``pfaff.sweep``) reads the file, checks the grid (:mod:`.grid`) and
sends batches of runs to the workers (:mod:`.worker`: the file compiled once per process,
parameter values given at run time through :meth:`pfaff.NumericModel.with_parameters`); the
results come back as one :class:`xarray.Dataset` (:mod:`.result`).
"""

from pfaff.sweep.driver import sweep
from pfaff.sweep.grid import Grid, make_grid, parse_vary
from pfaff.sweep.result import write_netcdf
from pfaff.sweep.summary import summary
from pfaff.sweep.worker import SweepSpec, run_batch

__all__ = [
    "Grid",
    "SweepSpec",
    "make_grid",
    "parse_vary",
    "run_batch",
    "summary",
    "sweep",
    "write_netcdf",
]
