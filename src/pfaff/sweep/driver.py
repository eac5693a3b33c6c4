"""``pfaff.sweep``: a grid of simulations of a model file, on Dask or in this process.

The client reads the file (nothing is derived here), checks the grid, and sends tasks that each
carry the file's text and a batch of run indices (:func:`pfaff.sweep.worker.run_batch`); workers
derive and compile the file once per process and give each run its values at run time. The
first task is a probe of two runs: its timing sets the batch size, so that each task lasts at
least :data:`TASK_SECONDS` (scheduling costs about a millisecond per task) and the sweep still
makes several tasks per worker to balance the load. Dask reschedules the tasks of a worker that
dies; the runs of a batch that killed its worker more than Dask allows (``KilledWorker``) are run
again at the end, one at a time, and a run that still kills its worker is reported failed.
"""

from __future__ import annotations

import logging
import math
import os
import socket
import sys
import threading
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from pfaff.core.errors import OptionError, SimulationError
from pfaff.core.keywords import checked_keywords
from pfaff.core.memory import refuse_beyond
from pfaff.modelfile import ModelFile
from pfaff.numeric.value import ModelValue
from pfaff.sweep.grid import make_grid
from pfaff.sweep.result import Results
from pfaff.sweep.source import names_of, source
from pfaff.sweep.worker import SweepSpec, run_batch

TASK_SECONDS = 0.1  # shortest task (Dask's overhead is ~1 ms per task)
LONGEST_TASK = 2.0  # longest task aimed at when the sweep is large (load balance, progress)
TASKS_PER_WORKER = 4
SAMPLES = 201
SYNC = ("synchronous", "sync")
ALONE_TRIES = 2  # a suspect run alone on the cluster: failed only if its workers die this often
NO_WORKERS_SECONDS = 60.0  # a cluster left without workers this long: its unfinished runs fail
POLL_SECONDS = 2.0  # how often a wait for a task looks whether the cluster still has workers
CONNECT_SECONDS = 10.0  # a scheduler address must answer as Dask within this (then OptionError)


@checked_keywords
def sweep(
    model: str | os.PathLike | ModelFile | ModelValue,
    vary: Mapping[str, Sequence[float] | np.ndarray],
    *,
    q0: Sequence[float] | np.ndarray | None = None,
    qd0: Sequence[float] | np.ndarray | None = None,
    t_span: tuple[float, float] | None = None,
    t_end: float | None = None,
    samples: int | None = None,
    options: Mapping[str, Any] | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool | None = None,
    run_timeout: float | None = None,
) -> Any:
    """Simulate a model file or a compiled model over a grid of parameter values and initial
    states.

    Every run starts at t0 (0 for a file) with the base initial state (the varied entries
    replaced), uses the run settings (a file's ``[simulate]``: method, tolerances, ...;
    ``options`` added) and is sampled at ``t_eval = linspace(t0, t_end, samples)``.

    Parameters
    ----------
    model : str, PathLike, ModelFile or compiled model
        A model file, one loaded by :func:`pfaff.load_model` (its ``parameters``, ``q0``,
        ``qd0`` and ``simulate`` as they are now; its file is read again for the workers), or a
        compiled model (``eom.compile(...)``, its parameter values the base; then ``q0`` and
        ``t_span`` are required).
    vary : dict of str to array_like
        Name -> values, one dimension of the result each, in this order: a parameter (``"L"``),
        an initial coordinate ``"q0.<coordinate>"`` or an initial speed ``"qd0.<coordinate>"``.
        The runs are the outer product.
    q0, qd0 : array_like, shape (n,), optional
        The base initial state (a file's ``[initial]`` by default; ``qd0`` of a compiled model
        defaults to zero).
    t_span : (float, float), optional
        Start and end time (a file's: 0 and its ``t_end``).
    t_end : float, optional
        End time from t = 0 (instead of ``t_span``); default: the file's ``[simulate] t_end``.
    samples : int, optional
        Reported times per run; default: the file's ``[simulate] samples``, else 201.
    options : dict, optional
        Keyword arguments of :func:`pfaff.simulate` for every run (``method``, ``rtol``, ...),
        over a file's ``[simulate]`` settings.
    scheduler : None, str or distributed.Client
        None: start a local Dask cluster of ``workers`` processes, closed at the end.
        ``"tcp://host:8786"``: an existing cluster's scheduler. A ``distributed.Client`` (TLS,
        other protocols) or a cluster object: used as it is. ``"synchronous"``: every run in
        this process, without Dask (small sweeps, tests, debugging).
    workers : int, optional
        Processes of the local cluster; default: the number of CPUs (at most one per run).
    progress : bool, optional
        A progress bar on stderr; default: when stderr is a terminal.
    run_timeout : float, optional
        Seconds of wall-clock time one run may take (its integration, from its first step); a
        run over it stops with status "timeout" (its states up to there kept) and the sweep goes
        on. Default: no limit.

    Returns
    -------
    xarray.Dataset
        Dimensions: the varied names (coordinates: their values), ``time``, ``coordinate`` and
        ``multiplier`` (with its ``constraint`` names) as in :meth:`pfaff.Trajectory.to_xarray`.
        Variables ``q``, ``qd`` (varied..., time, coordinate), ``multipliers`` (varied..., time,
        multiplier), NaN past the end of a failed run, and per run ``status`` ("success",
        "failed", "timeout", "interrupted"), ``message``, ``energy_error`` (max |T + V − E₀ − W_nc|),
        ``constraint_residual`` (max |f|, |A q̇ + b|) and ``seconds``. Attributes: the model,
        ``t_end``, ``runs``, ``succeeded``, ``failed``, ``workers``, ``batch``, ``wall_seconds``,
        and ``status``: "complete", or "interrupted" after Ctrl-C or SIGTERM (the cluster shut
        down, the runs done kept, the others with status "interrupted" and NaN states).
        In a notebook it shows a summary first (:class:`pfaff.sweep.dataset.SweepDataset`).

    Raises
    ------
    OptionError
        A bad name or value in ``vary``, no end time, a bad option.
    StateError
        A bad ``q0`` or ``qd0``.
    ModelFileError
        The file cannot be read.
    PfaffError
        The model cannot be derived or compiled at all. (A run that fails is a status.)

    Notes
    -----
    With the local cluster (processes are started with ``spawn``), call ``sweep`` under
    ``if __name__ == "__main__":`` in a script. Workers of an existing cluster need pfaff
    installed; a worker process runs one batch of a model at a time (its compiled kernels own
    their buffers), so start them with one thread each (``dask worker --nthreads 1 --nworkers
    N``). The model is compiled once, here, and shipped pickled; each run takes its values
    through :meth:`pfaff.NumericModel.with_parameters`. (``pfaff.sweep`` is this function, so
    ``import pfaff.sweep.worker as w`` fails: ``from pfaff.sweep import worker`` reaches the
    module.)

    Examples
    --------
    >>> import pathlib, tempfile, numpy as np, pfaff
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "spring.toml"
    >>> _ = path.write_text('''
    ... [model]
    ... coordinates = ["x"]
    ... parameters = { m = 1.0, k = 1.0 }
    ... kinetic = "m*dot(x)**2/2"
    ... potential = "k*x**2/2"
    ... [initial]
    ... q = { x = 1.0 }
    ... [simulate]
    ... t_end = 3.141592653589793
    ... ''')
    >>> ds = pfaff.sweep(path, {"k": [1.0, 4.0], "q0.x": [1.0, 2.0]}, samples=3,
    ...                  scheduler="synchronous")
    >>> ds.q.dims, ds.status.values.tolist()
    (('k', 'q0.x', 'time', 'coordinate'), [['success', 'success'], ['success', 'success']])
    >>> np.round(ds.q.sel(time=np.pi, coordinate="x").values, 6).tolist()  # x0 cos(√k t)
    [[-1.0, -2.0], [1.0, 2.0]]

    A compiled model, its initial state and time span given here:

    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> ds = pfaff.sweep(model, {"L": [1.0, 2.0]}, q0=[0.1], t_span=(0.0, 1.0), samples=2,
    ...                  scheduler="synchronous")
    >>> ds.status.values.tolist(), ds.time.values.tolist()
    (['success', 'success'], [0.0, 1.0])
    """
    start = time.perf_counter()
    src = source(model, q0=q0, qd0=qd0, t_span=t_span, t_end=t_end, options=options)
    grid = make_grid(vary, list(src.base.parameters), list(src.base.coordinates))
    samples = _samples(src.samples if samples is None else samples)
    refuse_beyond(  # the results: q and q̇ of every run at every reported time
        16.0 * grid.size * samples * max(len(src.base.coordinates), 1),
        f"a sweep of {grid.size} runs of {samples} samples",
        "vary fewer values, or report fewer samples",
    )
    spec = src.spec(grid, samples)
    if run_timeout is not None:
        spec = replace(spec, options={**spec.options, "max_seconds": _run_timeout(run_timeout)})
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int | np.integer) or workers < 1
    ):
        raise OptionError(f"`workers` must be a whole number of at least 1, got {workers!r:.40}")
    show = sys.stderr.isatty() if progress is None else bool(progress)
    results = Results(grid, samples, len(spec.coordinates))
    run_info = _execute(spec, results, scheduler, workers, show)
    if not results.names:
        results.names = names_of(src)
    attrs = {
        "model": src.name,
        **({"file": src.file} if src.file is not None else {}),
        "t0": src.t0,
        "t_end": src.t_end,
        "samples": samples,
        "method": str(spec.options.get("method", "projection")),
        **run_info,
        "wall_seconds": time.perf_counter() - start,
    }
    return results.dataset(spec.t_eval, attrs)


def _run_timeout(value: object) -> float:
    """``run_timeout`` checked: a positive, finite number of seconds."""
    ok = isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)
    if not ok or not (0 < float(value) < math.inf):  # type: ignore[arg-type]
        raise OptionError(
            f"`run_timeout` must be a positive number of seconds (or None), got {value!r:.40}"
        )
    return float(value)  # type: ignore[arg-type]


def _samples(samples: object) -> int:
    if samples is None:
        samples = SAMPLES
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 2:
        raise OptionError(f"`samples` must be a whole number of at least 2, got {samples!r:.40}")
    return int(samples)


def _execute(
    spec: SweepSpec, results: Results, scheduler: Any, workers: int | None, show: bool
) -> dict[str, Any]:
    """Run every grid point into ``results``; how it ran (for the dataset's attributes)."""
    from tqdm.auto import tqdm

    sync = isinstance(scheduler, str) and scheduler in SYNC
    info = {
        "scheduler": "synchronous" if sync else str(scheduler or "local"),
        "workers": 1,
        "batch": 0,
    }
    try:
        with tqdm(total=spec.grid.size, disable=not show, unit="run", desc="sweep") as bar:
            if sync:
                for batch in _chunks(range(spec.grid.size), max(1, spec.grid.size // 100)):
                    bar.update(results.add(run_batch(spec, batch)))
                return {**info, "status": "complete"}
            with _ClientContext(scheduler, workers, spec.grid.size) as client:
                return {**_distributed(client, spec, results, bar), "status": "complete"}
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the cluster is shut down (the context's
        left = results.status == ""  # exit); the runs done are kept, the rest marked
        results.status[left] = "interrupted"
        results.message[left] = "not run: the sweep was interrupted"
        return {**info, "status": "interrupted"}


class _ClientContext:
    """A context giving a ``distributed.Client``: a new local cluster (closed at exit), an
    address, or the caller's client (left open)."""

    def __init__(self, scheduler: Any, workers: int | None, runs: int) -> None:
        self.scheduler, self.workers, self.runs = scheduler, workers, runs
        self.owned: list[Any] = []

    def __enter__(self) -> Any:
        from distributed import Client, LocalCluster

        s = self.scheduler
        if isinstance(s, Client):
            return s
        if s is not None and self.workers is not None:
            raise OptionError("`workers` sets the size of the local cluster: not with `scheduler`")
        if s is None:
            n = self.workers or min(os.cpu_count() or 1, self.runs)
            try:
                cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    silence_logs=logging.ERROR,
                )
            except Exception as e:  # e.g. "Nanny failed to start": a worker died as it started
                raise SimulationError(
                    f"the local Dask cluster of {n} worker process{'es' if n > 1 else ''} could not start: "
                    f"{type(e).__name__}: {str(e)[:200]} (a worker process died as it started: "
                    "check that `python -c 'import pfaff'` works in a new process, the memory "
                    "free, and Dask's worker settings; or pass scheduler='synchronous')"
                ) from None
            self.owned.append(cluster)
            s = cluster
        elif not isinstance(s, str) and not hasattr(s, "scheduler_address"):
            raise OptionError(
                "`scheduler` must be None, a scheduler address (tcp://host:8786), "
                f"'synchronous' or a distributed.Client, got {s!r:.60}"
            )
        try:
            if isinstance(s, str):
                _reachable(s)
            client = _connect(Client, s)
        except OSError as e:  # (a TimeoutError too: a server that accepts and never answers)
            self.__exit__()
            raise OptionError(
                f"cannot reach the Dask scheduler at {s!r:.80}: {e} (a server that accepts but "
                f"does not answer as a Dask scheduler within {CONNECT_SECONDS:g} s is refused)"
            ) from None
        except Exception as e:  # a server answering something else than Dask's protocol
            self.__exit__()
            raise OptionError(
                f"the address {s!r:.80} did not answer as a Dask scheduler: {type(e).__name__}: "
                f"{str(e)[:200]}"
            ) from None
        self.owned.insert(0, client)
        return client

    def __exit__(self, *exc: object) -> None:
        for thing in self.owned:
            try:
                thing.close()
            except Exception:  # a cluster already gone
                pass


def _connect(client_class: Any, scheduler: Any) -> Any:
    """A client of ``scheduler``, or TimeoutError after ``2 * CONNECT_SECONDS``: Dask's own
    timeout covers its connection, not a server that accepts and then never answers, so the
    client is made in a thread that is given up on (left to end with its daemon loop)."""
    box: dict[str, Any] = {}

    def connect() -> None:
        try:
            box["client"] = client_class(scheduler, timeout=CONNECT_SECONDS, set_as_default=False)
        except BaseException as e:  # handed to the caller
            box["error"] = e

    thread = threading.Thread(target=connect, name="pfaff-connect", daemon=True)
    thread.start()
    thread.join(2 * CONNECT_SECONDS)
    if thread.is_alive():
        raise TimeoutError(f"no answer within {2 * CONNECT_SECONDS:g} s")
    if "error" in box:
        raise box["error"]
    return box["client"]


def _reachable(address: str, timeout: float = 5.0) -> None:
    """Refuse what is not a ``tcp://host[:port]`` address (OptionError), and fail at once
    (OSError) when nothing listens there, instead of after the client's retries."""
    scheme, _, rest = address.rpartition("://")
    host, _, port = rest.rpartition(":") if ":" in rest else (rest, "", "8786")  # Dask's port
    if scheme not in ("", "tcp") or not host or not port.isdigit():
        raise OptionError(
            f"`scheduler`: {address!r:.80} is not a scheduler address tcp://host:port (for TLS "
            "or another protocol, pass a distributed.Client) or 'synchronous'"
        )
    if not 0 < int(port) < 65536:
        raise OptionError(f"`scheduler`: the port {int(port)} of {address!r:.80} is not 1-65535")
    with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
        pass


def _distributed(client: Any, spec: SweepSpec, results: Results, bar: Any) -> dict[str, Any]:
    """A probe task of two runs, then the rest in batches sized on its timing, results taken as
    they complete; then, each alone on the cluster, the runs of the batches that killed their
    workers more often than Dask allows (a run that still kills its worker is reported failed)."""
    n = spec.grid.size
    futures: dict[Any, list[int]] = {}
    suspects: list[int] = []

    def submit(indices: list[int]) -> None:
        futures[client.submit(run_batch, spec, indices, pure=False)] = indices

    probe = list(range(min(2, n)))
    submit(probe)
    workers, batch = 1, 0
    while futures:
        try:
            done = _first_done(client, futures)
        except _NoWorkers as e:  # every unfinished run fails (never a wait forever)
            unsent = [list(range(len(probe), n))] if batch == 0 and n > len(probe) else []
            for rest in [*futures.values(), *([i] for i in suspects), *unsent]:
                results.fail(rest, str(e))
                bar.update(len(rest))
            return {"scheduler": str(client.scheduler.address), "workers": 0, "batch": batch}
        for fut in done:
            indices = futures.pop(fut)
            out = _result(fut, client, futures)
            if out is None:
                suspects += indices
            else:
                bar.update(results.add(out))
            if batch == 0:  # the probe is back: the rest in batches
                workers = max(1, len(client.scheduler_info(n_workers=-1).get("workers", {})))
                seconds = float(out["seconds"][-1]) if out is not None else TASK_SECONDS
                batch = batch_size(seconds, n - len(probe), workers)
                for b in _chunks(range(len(probe), n), batch):
                    submit(b)
    for i in suspects:  # alone: no other task dies with its worker
        why = "its worker process died each time it ran (a crash of Python)"
        for _ in range(ALONE_TRIES):  # (a worker still restarting can take a good run down)
            fut = client.submit(run_batch, spec, [i], pure=False)
            try:
                _first_done(client, {fut: [i]})
            except _NoWorkers as e:
                out, why = None, str(e)
                break
            out = _result(fut, client, {})
            if out is not None:
                break
        if out is None:
            results.fail([i], why)
            bar.update(1)
        else:
            bar.update(results.add(out))
    return {"scheduler": str(client.scheduler.address), "workers": workers, "batch": batch}


class _NoWorkers(Exception):
    """The cluster has had no worker for :data:`NO_WORKERS_SECONDS` (its message says so)."""


def _first_done(client: Any, futures: dict) -> set:
    """The tasks of ``futures`` that have finished, once one has; :class:`_NoWorkers` (every
    one cancelled) when the cluster has had no worker for :data:`NO_WORKERS_SECONDS` meanwhile
    (nannies that stopped restarting theirs: a wait that would never end)."""
    ready = threading.Event()
    for fut in futures:  # (the callbacks run on the client's thread)
        fut.add_done_callback(lambda _: ready.set())
    alone_since = None
    while True:
        done = {fut for fut in futures if fut.done()}
        if done:
            return done
        if ready.wait(POLL_SECONDS):
            ready.clear()
            continue
        if _worker_count(client) != 0:
            alone_since = None
            continue
        now = time.monotonic()
        alone_since = now if alone_since is None else alone_since
        if now - alone_since >= NO_WORKERS_SECONDS:
            client.cancel(list(futures))
            raise _NoWorkers(
                f"the Dask cluster has had no worker for {NO_WORKERS_SECONDS:g} s (its worker "
                "processes died and were not restarted): the run was not finished"
            )


def _worker_count(client: Any) -> int:
    """How many workers the scheduler has now (-1 when it cannot say: then waiting goes on)."""
    try:
        return len(client.nthreads())
    except Exception:  # a scheduler busy or going away: no verdict from this look
        return -1


def _result(fut: Any, client: Any, others: dict) -> dict[str, Any] | None:
    """A finished task's output; None when its workers died (``KilledWorker``); other errors
    raised, the ``others`` cancelled."""
    try:
        return fut.result()
    except Exception as e:
        if type(e).__name__ == "KilledWorker":
            return None
        client.cancel(list(others))
        raise


def batch_size(seconds: float, runs: int, workers: int) -> int:
    """Runs per task: each at least ``TASK_SECONDS``, and for large sweeps about
    ``TASKS_PER_WORKER`` tasks per worker, up to ``LONGEST_TASK`` each.

    Examples
    --------
    >>> batch_size(0.01, 256, 2), batch_size(0.5, 256, 2), batch_size(1e-3, 10**6, 8)
    (32, 4, 2000)
    """
    seconds = max(seconds, 1e-5) if math.isfinite(seconds) else TASK_SECONDS
    target = min(LONGEST_TASK, max(TASK_SECONDS, seconds * runs / (TASKS_PER_WORKER * workers)))
    return max(1, min(runs, math.ceil(target / seconds)))


def _chunks(indices: range, size: int) -> Iterator[list[int]]:
    for lo in range(indices.start, indices.stop, size):
        yield list(range(lo, min(lo + size, indices.stop)))
