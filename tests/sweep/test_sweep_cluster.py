"""pfaff.sweep on Dask: a local cluster, an existing one by address, a worker killed mid-sweep,
a run that kills its worker. Slow: each cluster takes seconds to start."""

from __future__ import annotations

import logging
import os
import signal
import threading

import numpy as np
import pytest

import pfaff

pytestmark = pytest.mark.slow

VARY = {"L": np.linspace(0.5, 2.0, 4), "q0.theta": np.linspace(0.1, 1.5, 6)}


def local_cluster(n: int = 2, **config: object):
    import dask
    from distributed import LocalCluster

    with dask.config.set(config):
        return LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
            silence_logs=logging.ERROR,
        )  # fmt: skip


@pytest.fixture(scope="module")
def cluster():
    cl = local_cluster(2)
    yield cl
    cl.close()


def same_runs(a, b) -> None:
    """Bit for bit: the same compiled model (shipped), evaluator and thread policy everywhere."""
    assert (a.status.values == b.status.values).all()
    np.testing.assert_array_equal(a.q.values, b.q.values)
    np.testing.assert_array_equal(a.qd.values, b.qd.values)
    np.testing.assert_array_equal(a.multipliers.values, b.multipliers.values)
    np.testing.assert_array_equal(a.energy_error.values, b.energy_error.values)


def test_default_local_cluster_matches_this_process(pendulum):
    ds = pfaff.sweep(pendulum, VARY, workers=2, progress=False)
    ref = pfaff.sweep(pendulum, VARY, scheduler="synchronous")
    assert ds.attrs["workers"] == 2 and ds.attrs["scheduler"].startswith("tcp://")
    assert (ds.status == "success").all()
    same_runs(ds, ref)


def test_existing_cluster_by_address_and_client(cluster, cartesian):
    from distributed import Client

    vary = {"g": [9.81, 1.62, 3.7], "qd0.x": [0.0, 0.5, 1.0, 2.0]}
    ref = pfaff.sweep(cartesian, vary, scheduler="synchronous")
    ds = pfaff.sweep(cartesian, vary, scheduler=cluster.scheduler_address, progress=False)
    same_runs(ds, ref)
    with Client(cluster) as client:  # a client of the caller's: used, left open
        ds = pfaff.sweep(cartesian, vary, scheduler=client, progress=False)
        assert client.status == "running"
    same_runs(ds, ref)


def test_a_killed_worker_does_not_lose_the_sweep(cluster, pendulum, tmp_path):
    """A worker killed (SIGKILL) inside a run of a batch: its nanny starts another, the batch
    runs again, and the sweep is the one this process makes, bit for bit.

    The kill is made by the run itself, the first time the last grid point starts on any
    worker (a marker file made exclusively: once), not by a thread of the test watching the
    scheduler, which could see the sweep end before it saw two batches running."""
    from distributed import Client
    from distributed.diagnostics.plugin import WorkerPlugin

    marker = str(tmp_path / "killed")

    class KillOnce(WorkerPlugin):
        name = "kill-once"

        def setup(self, worker):
            from pfaff.sweep import worker as w  # (pfaff.sweep is the function)

            self.real = real = w._run

            def _run(entry, spec, i):
                point = spec.grid.point(i)
                if point["L"] == 2.0 and point["q0.theta"] == 1.5:
                    try:
                        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
                    except FileExistsError:
                        pass
                    else:
                        os.kill(os.getpid(), signal.SIGKILL)
                return real(entry, spec, i)

            w._run = _run

        def teardown(self, worker):
            from pfaff.sweep import worker as w

            w._run = self.real

    vary = {"L": np.linspace(0.5, 2.0, 6), "q0.theta": np.linspace(0.1, 1.5, 4)}
    ref = pfaff.sweep(pendulum, vary, t_end=20.0, scheduler="synchronous")
    with Client(cluster) as client:
        before = client.run(os.getpid)
        client.register_plugin(KillOnce())
        try:
            ds = pfaff.sweep(pendulum, vary, t_end=20.0, scheduler=client, progress=False)
        finally:
            client.unregister_worker_plugin(KillOnce.name)
        assert os.path.exists(marker)  # a worker was killed inside a run of the sweep
        client.wait_for_workers(2, timeout=60)
        after = client.run(os.getpid)
    assert set(before.values()) != set(after.values())  # the nanny started a new worker
    assert (ds.status == "success").all()
    same_runs(ds, ref)


HUNG = 600.0  # seconds (the test takes 20 s to 2 min): a guard against a hang, never a limit


def test_a_run_that_kills_its_worker_is_a_failed_run(pendulum):
    """Every worker gets a plugin that kills the process at L = 1.5: that run alone fails.

    Twice at load 12 the cluster was left with no workers (both nannies stopped restarting
    theirs, after a good run's workers had died twice too) and the sweep waited for one forever:
    the cluster is closed after ``HUNG`` seconds, so such a run fails instead of hanging CI."""
    from distributed import Client
    from distributed.diagnostics.plugin import WorkerPlugin

    class Crash(WorkerPlugin):
        def setup(self, worker):
            from pfaff.sweep import worker as w  # (pfaff.sweep is the function)

            real = w._run

            def _run(entry, spec, i):
                if spec.grid.point(i)["L"] == 1.5:
                    os._exit(1)
                return real(entry, spec, i)

            w._run = _run

    cl = local_cluster(2, **{"distributed.scheduler.allowed-failures": 0})  # fewest deaths
    guard = threading.Timer(HUNG, cl.close)  # the sweep's wait then raises (FutureCancelledError)
    guard.start()
    try:
        with Client(cl) as client:
            client.register_plugin(Crash())
            vary = {"L": [0.5, 1.0, 1.5, 2.0]}  # a probe of two, then a batch of the other two
            ds = pfaff.sweep(pendulum, vary, t_end=1.0, scheduler=client, progress=False)
    finally:
        guard.cancel()
        cl.close()
    assert ds.status.values.tolist() == ["success", "success", "failed", "success"]
    assert "worker process died" in str(ds.message.sel(L=1.5).values)
    assert np.isfinite(ds.q.sel(L=2.0)).all() and np.isnan(ds.q.sel(L=1.5)).all()


def test_a_compiled_model_on_a_cluster(cluster):
    """The model pickled once and shipped: the same runs as in this process, bit for bit."""
    model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    kw = {"q0": [1.0, 0.0], "t_span": (0.0, 2.0), "samples": 21}
    vary = {"g": [9.81, 1.62], "qd0.y": [0.0, 0.5]}
    ref = pfaff.sweep(model, vary, scheduler="synchronous", **kw)
    ds = pfaff.sweep(model, vary, scheduler=cluster.scheduler_address, progress=False, **kw)
    assert (ref.status == "success").all()
    same_runs(ds, ref)


def test_a_cluster_left_without_workers_fails_the_runs_it_has_not_finished(pendulum, monkeypatch):
    """A scheduler with no worker at all (as when every nanny stopped restarting its worker):
    after ``NO_WORKERS_SECONDS`` every run fails, naming why, instead of a wait that never ends."""
    from distributed import Client

    from pfaff.sweep import driver

    monkeypatch.setattr(driver, "NO_WORKERS_SECONDS", 1.0)
    monkeypatch.setattr(driver, "POLL_SECONDS", 0.2)
    cl = local_cluster(0)
    guard = threading.Timer(HUNG, cl.close)
    guard.start()
    try:
        with Client(cl) as client:
            ds = pfaff.sweep(pendulum, {"L": [0.5, 1.0, 1.5]}, t_end=0.5, scheduler=client,
                             progress=False)  # fmt: skip
    finally:
        guard.cancel()
        cl.close()
    assert ds.status.values.tolist() == ["failed"] * 3
    assert all("no worker for 1 s" in str(m) for m in ds.message.values)
