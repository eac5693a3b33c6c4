"""A local cluster whose worker process dies as it starts ("Nanny failed to start") ends the sweep
with a clear pfaff error naming the cluster and what to check, not Dask's traceback."""

from __future__ import annotations

from pathlib import Path

import dask
import pytest

import pfaff

EXAMPLE = Path(__file__).parents[2] / "examples" / "pendulum.toml"


@pytest.mark.slow  # starts (and loses) a worker process: ~15 s on a busy machine
def test_a_worker_that_dies_at_start_is_a_clear_error(tmp_path) -> None:
    preload = tmp_path / "die.py"
    preload.write_text('raise SystemExit("this worker dies as it starts")\n')
    with dask.config.set({"distributed.worker.preload": [str(preload)]}):
        with pytest.raises(pfaff.SimulationError, match="local Dask cluster of 1 worker process"):
            pfaff.sweep(EXAMPLE, {"L": [1.0, 2.0]}, samples=3, workers=1, progress=False)
