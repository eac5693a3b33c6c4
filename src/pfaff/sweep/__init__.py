"""Parameter sweeps: a grid of simulations of a model file, on a Dask cluster or in this process.

:func:`sweep` (re-exported as ``pfaff.sweep``) reads the file, checks the grid (:mod:`.grid`) and
sends batches of runs to the workers (:mod:`.worker`: the file compiled once per process,
parameter values given at run time through :meth:`pfaff.NumericModel.with_parameters`); the
results come back as one :class:`xarray.Dataset` (:mod:`.result`).
"""

from pfaff.core.exports import lazy_exports

# imported when first used: ``import pfaff`` imports this package (see pfaff/__init__.py)
_EXPORTS = {
    "Grid": "pfaff.sweep.grid",
    "SweepSpec": "pfaff.sweep.worker",
    "make_grid": "pfaff.sweep.grid",
    "parse_vary": "pfaff.sweep.grid",
    "run_batch": "pfaff.sweep.worker",
    "summary": "pfaff.sweep.overview",
    "sweep": "pfaff.sweep.driver",
    "write_netcdf": "pfaff.sweep.result",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
