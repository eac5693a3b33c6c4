"""The result of a simulation: states, multipliers, energies, residuals, statistics and status."""

from __future__ import annotations

import csv
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from pfaff.core.display import number, summary_html
from pfaff.core.errors import StateError
from pfaff.core.files import atomic_path


class Trajectory:
    """A simulated motion of a constrained system.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Reported times.
    q, qd, qdd : ndarray, shape (k, n)
        Coordinates, speeds and accelerations.
    multipliers : ndarray, shape (k, m)
        λ of M q̈ + h = Q + Aᵀλ (the constraint forces in generalized form).
    kinetic, potential : ndarray, shape (k,)
        T and V.
    energy : ndarray, shape (k,)
        T + V.
    jacobi : ndarray, shape (k,)
        Jacobi integral q̇·∂L/∂q̇ − L = T₂ − T₀ + V (equals the energy when T is quadratic in q̇).
    nc_work : ndarray, shape (k,)
        W_nc(t): the work done by the applied (non-conservative) forces since the start, ∫ Qᵀq̇ dt,
        integrated along the solution with the integrator's dense output.
    contact_open : ndarray of bool, shape (k, m)
        True on the rows of unilateral constraints that are open at that time (their
        ``multipliers`` are 0 and ``constraint_residual[:, 0]`` holds the gap, not a residual).
    impact_work : ndarray, shape (k,)
        W_impact(t): the work of the impulses of the impacts so far (unilateral constraints,
        ``System.add_unilateral_constraint``), ≤ 0 for a loss; zero without impacts.
    energy_balance : ndarray, shape (k,)
        T + V − E₀ − W_nc(t) − W_impact(t): zero up to the integration error while ideal
        constraints do no work (scleronomic constraints; a moving constraint's work shows here).
    constraint_residual : ndarray, shape (k, 2, m)
        ``[:, 0]`` position level f(q, t) (0 for velocity constraints), ``[:, 1]`` velocity level
        A q̇ + b.
    stats : dict
        ``steps``, ``nfev``, ``rejected``, ``projections``, ... of the run.
    status : str
        ``"success"``, ``"failed"`` or ``"interrupted"``; ``message`` says why.
    method : str
    coordinate_names, multiplier_names : list of str
    switches : list of (float, str)
        (t, body name) of every MRP shadow-set switch (empty without MRPs).
    events : list of EventRecord
        The events of the run in time order (:class:`pfaff.EventRecord`: name, t, q, q̇, kind):
        the zero crossings of user events (``simulate(events=...)``, ``System.add_event``), and
        the contacts' "impact", "rest" (closing without a bounce) and "release" (the multiplier
        crossing zero), whose q̇ is the one after the event. A zero crossing's state is also a
        reported state (in ``t``, ``q``, ...); at an impact two states share its time.
    output : Path or None
        The netCDF file a run wrote as it went (``simulate(output="run.nc")``): the per-state
        arrays above are then read-only memory maps of it, read when used. None otherwise.
    redundant_rows : ndarray of int, shape (k,)
        Per reported time, how many constraint rows depend on the others (the dimension of
        the null space of Aᵀ): on those directions only Aᵀλ is determined, and ``multipliers``
        holds the minimum-norm λ. Zero for a run whose constraints are independent.

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.cartesian_pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> traj = pfaff.simulate(model, [1.0, 0.0], [0.0, 0.0], (0.0, 1.0))
    >>> traj.status, bool(abs(traj.constraint_residual).max() < 1e-10)
    ('success', True)
    """

    def __init__(self, **fields: Any) -> None:
        self.t: np.ndarray = fields["t"]
        self.q: np.ndarray = fields["q"]
        self.qd: np.ndarray = fields["qd"]
        self.qdd: np.ndarray = fields["qdd"]
        self.multipliers: np.ndarray = fields["multipliers"]
        self.kinetic: np.ndarray = fields["kinetic"]
        self.potential: np.ndarray = fields["potential"]
        self.jacobi: np.ndarray = fields["jacobi"]
        self.nc_work: np.ndarray = fields.get("nc_work", np.zeros(len(fields["t"])))
        self.impact_work: np.ndarray = fields.get("impact_work", np.zeros(len(fields["t"])))
        self.contact_open: np.ndarray = np.asarray(
            fields.get("contact_open", np.zeros(self.multipliers.shape, dtype=bool)), dtype=bool
        )
        self.constraint_residual: np.ndarray = fields["constraint_residual"]
        self.stats: dict = fields["stats"]
        self.status: str = fields["status"]
        self.message: str = fields["message"]
        self.method: str = fields["method"]
        self.coordinate_names: list[str] = fields["coordinate_names"]
        self.multiplier_names: list[str] = fields["multiplier_names"]
        self.parameters: dict = fields.get("parameters", {})
        self._projector = fields.get("projector")
        self.switches: list[tuple[float, str]] = list(fields.get("switches", []))
        self.events: list = list(fields.get("events", []))  # of pfaff.EventRecord
        self.geometry = fields.get("geometry")  # the model's, for animate (derive/geometry.py)
        self.output: Path | None = fields.get("output")
        self.redundant_rows: np.ndarray = np.asarray(
            fields.get("redundant_rows", np.zeros(len(self.t), dtype=np.int64)), dtype=np.int64
        )

    # ------------------------------------------------------------------ derived quantities
    @property
    def energy(self) -> np.ndarray:
        """T + V, shape (k,)."""
        return self.kinetic + self.potential

    @property
    def energy_balance(self) -> np.ndarray:
        """T + V − E₀ − W_nc(t) − W_impact(t), shape (k,): the energy error once the work of
        the applied forces and of the impacts' impulses is accounted for (the pushed ring gains
        F·Δx; this stays at rounding level).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.rolling_ring(4, force=True).equations().compile(
        ...     {"M": 1, "r": 0.5, "F": 2})
        >>> traj = pfaff.simulate(model, *pfaff.models.ring_state(4, 0.5), (0.0, 1.0))
        >>> bool(abs(traj.energy_balance).max() < 1e-9), round(float(traj.nc_work[-1]), 9)
        (True, 1.0)
        """
        e = self.energy
        return e - (e[0] if e.size else 0.0) - self.nc_work - self.impact_work

    @property
    def success(self) -> bool:
        """True when the run reached the end of its time span."""
        return self.status == "success"

    @property
    def position_residual(self) -> np.ndarray:
        """f(q, t), shape (k, m)."""
        return self.constraint_residual[:, 0, :]

    @property
    def velocity_residual(self) -> np.ndarray:
        """A q̇ + b, shape (k, m)."""
        return self.constraint_residual[:, 1, :]

    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        span = f"t = {self.t[0]:g} … {self.t[-1]:g}" if len(self.t) else "empty"
        return (
            f"<Trajectory {self.method}: {len(self.t)} points, {span}, status {self.status!r}, "
            f"max |residual| {np.abs(self.constraint_residual).max(initial=0):.2e}>"
        )

    def summary(self) -> list[tuple[str, str]]:
        """The run in a few (label, value) rows: status, span, steps, residuals, energy
        balance, events; what a notebook shows (:meth:`_repr_html_`).

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 1.0), t_eval=[0.0, 0.5, 1.0])
        >>> dict(traj.summary())["span"]
        't = 0 … 1 (3 reported times)'
        """
        k = len(self.t)
        status = self.status if self.status == "success" else f"{self.status}: {self.message}"
        span = f"t = {number(self.t[0])} … {number(self.t[-1])}" if k else "no states"
        stats = ", ".join(
            f"{key} {self.stats[key]}"
            for key in ("steps", "rejected", "nfev", "projections")
            if isinstance(self.stats.get(key), int | np.integer)
        )
        rows = [
            ("status", status),
            ("method", self.method),
            ("span", f"{span} ({k} reported times)"),
        ]
        rows.append(("steps", stats or "—"))
        if self.multiplier_names and k:
            f, g = np.abs(self.position_residual).max(), np.abs(self.velocity_residual).max()
            rows.append(("constraint residual", f"max |f| {number(f)}, max |A q̇ + b| {number(g)}"))
        if k:
            balance = f"max |T + V − E₀ − W_nc| {number(np.abs(self.energy_balance).max())}"
            if np.any(self.nc_work):
                balance += f" (W_nc at the end {number(self.nc_work[-1])})"
            rows.append(("energy balance", balance))
        if self.events:
            names = Counter(e.name for e in self.events)
            rows.append(("events", ", ".join(f"{n} × {c}" for n, c in names.items())))
        if self.switches:
            rows.append(("MRP switches", str(len(self.switches))))
        if self.redundant_rows.size and self.redundant_rows.max() > 0:
            rows.append(("redundant rows", f"up to {int(self.redundant_rows.max())}"))
        return rows

    def _repr_html_(self) -> str:
        n, m = len(self.coordinate_names), len(self.multiplier_names)
        return summary_html(f"pfaff.Trajectory: {n} coordinates, {m} multipliers", self.summary())

    # ------------------------------------------------------------------ interpolation
    def at(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Coordinates and speeds at any time inside the run.

        Quintic Hermite interpolation of the reported (q, q̇, q̈), then projection onto the
        constraints (for projection and IDA runs).

        Parameters
        ----------
        t : float or ndarray, shape (k,)

        Returns
        -------
        q, qd : ndarray, shape (n,) or (k, n)
        """
        if len(self.t) < 2:
            raise StateError(
                f"`at` needs a run of at least two reported times; this one has {len(self.t)}"
            )
        if isinstance(t, str | bytes | bool) or t is None:
            raise StateError(f"`t` must be a time or an array of times, got {t!r:.80}")
        try:
            raw = np.asarray(t)
            if raw.dtype.kind not in "iuf" or raw.ndim > 1 or raw.size == 0:
                raise TypeError
            ts = np.atleast_1d(raw.astype(float))
        except (TypeError, ValueError):
            raise StateError(
                f"`t` must be a real time or a non-empty 1-D array of times, got {t!r:.80}"
            ) from None
        if not np.isfinite(ts).all() or ts.min() < self.t[0] or ts.max() > self.t[-1]:
            raise StateError(
                f"`t` must lie inside the simulated span [{self.t[0]:g}, {self.t[-1]:g}]"
            )
        i = np.clip(np.searchsorted(self.t, ts, side="right") - 1, 0, len(self.t) - 2)
        h = (self.t[i + 1] - self.t[i])[:, None]
        s = (ts - self.t[i])[:, None] / h
        q, qd = hermite5(s, h, self.q[i], self.qd[i], self.qdd[i], *self._ends(i))
        if self._projector is not None:
            for k in range(len(ts)):
                q[k], qd[k], _ = self._projector(float(ts[k]), q[k], qd[k])
        return (q[0], qd[0]) if np.ndim(t) == 0 else (q, qd)

    def _ends(self, i: np.ndarray) -> tuple:
        return self.q[i + 1], self.qd[i + 1], self.qdd[i + 1]

    def _columns_at(self, ts: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """The columns ``cols`` of q at ``ts`` (for animations: no projection, and no copy of
        the whole run): quintic Hermite; inside an interval that holds an MRP shadow-set switch
        (the coordinates jump there), the Taylor polynomial q + q̇Δ + q̈Δ²/2 of the nearer end."""
        t = self.t
        i = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, len(t) - 2)
        h = (t[i + 1] - t[i])[:, None]
        s = (ts - t[i])[:, None] / h
        ends = [a[np.ix_(j, cols)] for j in (i, i + 1) for a in (self.q, self.qd, self.qdd)]
        q = hermite5(s, h, *ends)[0]
        sw = np.sort(np.array([w for w, _ in self.switches], dtype=float))
        if sw.size:
            jump = np.searchsorted(sw, t[i + 1], "right") > np.searchsorted(sw, t[i], "right")
            left = s < 0.5
            qe, ve, ae = (np.where(left, ends[k], ends[k + 3]) for k in range(3))
            near = np.where(left, s, s - 1) * h  # Δ from the nearer end
            q[jump] = (qe + ve * near + ae * near**2 / 2)[jump]
        return q

    __call__ = at

    # ------------------------------------------------------------------ output
    def _columns(self) -> dict[str, np.ndarray]:
        """The CSV columns by name; a name already taken (a coordinate called ``t`` or ``T``,
        ``x_dot`` beside ``x``) gets a suffix ``~2``, ``~3``, ..., so that no column is lost."""
        pairs: list[tuple[str, np.ndarray]] = [("t", self.t)]
        names = self.coordinate_names
        pairs += [(name, self.q[:, j]) for j, name in enumerate(names)]
        pairs += [(f"{name}_dot", self.qd[:, j]) for j, name in enumerate(names)]
        pairs += [(f"{name}_ddot", self.qdd[:, j]) for j, name in enumerate(names)]
        pairs += [(name, self.multipliers[:, j]) for j, name in enumerate(self.multiplier_names)]
        pairs += [("T", self.kinetic), ("V", self.potential), ("energy", self.energy)]
        pairs += [("jacobi", self.jacobi), ("nc_work", self.nc_work)]
        if self.impact_work.any():
            pairs += [("impact_work", self.impact_work)]
        pairs += [("energy_balance", self.energy_balance)]
        for j, name in enumerate(self.multiplier_names):
            pairs += [(f"f_{name}", self.constraint_residual[:, 0, j])]
            pairs += [(f"g_{name}", self.constraint_residual[:, 1, j])]
        cols: dict[str, np.ndarray] = {}
        for name, values in pairs:
            key, k = name, 1
            while key in cols:
                k += 1
                key = f"{name}~{k}"
            cols[key] = values
        return cols

    def to_csv(self, path: str | Path) -> Path:
        """Write one row per reported time (atomically: temp file, then rename)."""
        cols = self._columns()
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            w.writerows(np.column_stack(list(cols.values())).tolist())
        return Path(path)

    def to_xarray(self) -> Any:
        """An :class:`xarray.Dataset` with dimensions ``time``, ``coordinate``, ``multiplier``."""
        import xarray as xr

        dims_q, dims_l = ("time", "coordinate"), ("time", "multiplier")
        ds = xr.Dataset(
            {
                "q": (dims_q, self.q),
                "qd": (dims_q, self.qd),
                "qdd": (dims_q, self.qdd),
                "multipliers": (dims_l, self.multipliers),
                "kinetic": ("time", self.kinetic),
                "potential": ("time", self.potential),
                "energy": ("time", self.energy),
                "jacobi": ("time", self.jacobi),
                "nc_work": ("time", self.nc_work),
                "impact_work": ("time", self.impact_work),
                "energy_balance": ("time", self.energy_balance),
                "constraint_residual": (("time", "level", "multiplier"), self.constraint_residual),
                **self._event_variables(),
            },
            coords={
                "time": self.t,
                "coordinate": list(self.coordinate_names),
                "multiplier": list(self.multiplier_names),
                "level": ["position", "velocity"],
            },
            attrs={
                "method": self.method,
                "status": self.status,
                "message": self.message,
                **{f"stat_{k}": v for k, v in self.stats.items() if isinstance(v, int | float)},
                **{f"parameter_{k}": float(v) for k, v in self.parameters.items()},
            },
        )
        return ds

    def _event_variables(self) -> dict[str, tuple]:
        """The events as variables over an ``event`` dimension: time, name, kind, q, q̇."""
        n, ev = len(self.coordinate_names), self.events
        return {
            "event_time": ("event", np.array([e.t for e in ev], dtype=float)),
            "event_name": ("event", np.array([e.name for e in ev], dtype=str)),
            "event_kind": ("event", np.array([e.kind for e in ev], dtype=str)),
            "event_q": (("event", "coordinate"), np.reshape([e.q for e in ev], (len(ev), n))),
            "event_qd": (("event", "coordinate"), np.reshape([e.qd for e in ev], (len(ev), n))),
        }

    def to_netcdf(self, path: str | Path) -> Path:
        """Write :meth:`to_xarray` as netCDF (atomically). A model without constraints has no
        ``multiplier`` dimension in the file (netCDF3 readers refuse a zero-length one; the
        attribute ``multipliers = 0`` says so)."""
        ds = self.to_xarray()
        empty = [d for d, size in ds.sizes.items() if size == 0]
        if empty:
            ds = ds.drop_dims(empty)
            ds.attrs.update({f"{d}s": 0 for d in empty})
        with atomic_path(path) as tmp:
            ds.to_netcdf(tmp, engine=_netcdf_engine())
        return Path(path)

    def plot(self, path: str | Path | None = None, *, units: dict[str, str] | None = None) -> Any:
        """Coordinates, multipliers, energy balance and residuals on one figure.

        Panels with nothing to show (multipliers and residuals of an unconstrained model) are
        left out.

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there (PNG, PDF, SVG, ...; from the extension; atomically).
        units : dict of str to str, optional
            Units by coordinate or multiplier name; ``"t"`` and ``"energy"`` default to s and J.

        Returns
        -------
        matplotlib.figure.Figure
            Made without pyplot. Without ``path``, Jupyter displays it exactly once (in a fresh
            kernel, with or without ``%matplotlib inline``). With ``path`` the file is written and
            the figure returned without being displayed (Jupyter shows the file's name; show the
            picture with ``IPython.display.Image(path)``).
        """
        from pfaff.results.figures import plot_trajectory

        return plot_trajectory(self, path, units=units)

    def animate(
        self,
        path: str | Path,
        *,
        frames: int = 200,
        fps: float = 20.0,
        links: Any = None,
        size: float = 4.0,
        dpi: int = 80,
        title: str | None = None,
        solid: str = "ellipsoid",
    ) -> Path:
        """Write an animation of the motion: a GIF, or an MP4 where ffmpeg exists.

        Particles and the lines between them, rigid bodies as solids with their axes, a family of particles
        (the ring) as its points and centre; 2-D or 3-D as the model; the title shows t. What
        is drawn and the link rule: :mod:`pfaff.results.animation`, :mod:`pfaff.derive.geometry`.

        Parameters
        ----------
        path : str or Path
            Ends in ``.gif`` or ``.mp4``; checked (and MP4 refused without ffmpeg) before any
            work. Written atomically.
        frames : int, optional
            At most this many frames (default 200), evenly spaced over the run; memory depends
            on it, not on the run's length.
        fps : float, optional
            Frames per second of the file (default 20).
        links : sequence of pairs, optional
            Lines to draw instead of the found ones: pairs of point indices or names
            (``geometry.names``), ``-1`` or ``"origin"`` for the fixed origin; ``[]`` for none.
        size : float, optional
            Width and height in inches (default 4).
        dpi : int, optional
            Pixels per inch (default 80: 320 × 320 pixels).
        title : str, optional
            Default: the system's name.
        solid : {"ellipsoid", "box"}, optional
            The solid drawn for a body of a given mass and inertia (:mod:`pfaff.results.solids`).

        Returns
        -------
        Path

        Raises
        ------
        OptionError
            A bad path, extension or option, or MP4 without ffmpeg.
        StateError
            The trajectory has no geometry (a model built from matrices) or no states.

        Examples
        --------
        >>> import tempfile, pathlib, pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 1.0))
        >>> gif = traj.animate(pathlib.Path(tempfile.mkdtemp()) / "swing.gif", frames=3, dpi=30)
        >>> from PIL import Image
        >>> Image.open(gif).n_frames
        3
        """
        from pfaff.results.animation import animate

        return animate(
            self,
            path,
            frames=frames,
            fps=fps,
            links=links,
            size=size,
            dpi=dpi,
            title=title,
            solid=solid,
        )

    def to_html(
        self,
        path: str | Path,
        *,
        fps: float = 30.0,
        solid: str = "ellipsoid",
        up: str | None = None,
        title: str | None = None,
        max_frames: int = 3000,
        arrows: dict | None = None,
    ) -> Path:
        """Write an interactive 3-D view of the motion: one HTML file that plays offline.

        The page holds its scene and its WebGL2 renderer and fetches nothing. Particles are
        spheres, rigid bodies (and ``System.add_shape`` shapes) solids of their mass and
        inertia, links rods; drag to turn, wheel to zoom, play / pause / scrub / speed, the time
        shown. What is drawn and how the data is kept small: :mod:`pfaff.results.viewer`.

        Parameters
        ----------
        path : str or Path
            Ends in ``.html``; written atomically.
        fps : float, optional
            Frames per second of the run's time kept in the file (default 30; the browser
            interpolates between them), at most ``max_frames`` and about 3 MB of data.
        solid : {"ellipsoid", "box"}, optional
            The solid drawn for a body of a given inertia (:mod:`pfaff.results.solids`).
        up : {"z", "y", "-z", "x", "-y", "-x"}, optional
            The model's upward direction (default z in 3-D, y in 2-D; the bicycle's is -z).
        title : str, optional
            Default: the system's name.
        max_frames : int, optional
        arrows : dict, optional
            Forces drawn as arrows (red, one scale): name → ``f(t, q, qd, multipliers)``
            returning ``(at, force)``, each of the model's 2 or 3 components; e.g. a contact
            force from its multipliers. Evaluated at the reported states.

        Returns
        -------
        Path

        Raises
        ------
        OptionError
            A bad path or option.
        StateError
            The trajectory has no geometry or no states.

        Examples
        --------
        >>> import tempfile, pathlib, pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
        >>> traj = pfaff.simulate(model, [1.0], [0.0], (0.0, 1.0))
        >>> page = traj.to_html(pathlib.Path(tempfile.mkdtemp()) / "swing.html")
        >>> "<script src" in page.read_text()
        False
        """
        from pfaff.results.viewer import to_html

        return to_html(
            self,
            path,
            fps=fps,
            solid=solid,
            up=up,
            title=title,
            max_frames=max_frames,
            arrows=arrows,
        )

    def show(self, *, height: int = 480, **options: Any) -> Any:
        """The interactive 3-D view for a notebook (Jupyter, VS Code): shown as a cell's value.

        Returns a :class:`pfaff.results.viewer.Viewer` (its ``_repr_html_`` is the page of
        :meth:`to_html` in a sandboxed frame ``height`` pixels high; ``.save(path)`` writes
        it); ``options`` as for :meth:`to_html`.
        """
        from pfaff.results.viewer import show

        return show(self, height=height, **options)


def _netcdf_engine() -> str:
    for engine, module in (("netcdf4", "netCDF4"), ("h5netcdf", "h5netcdf")):
        try:
            __import__(module)
            return engine
        except ImportError:
            continue
    return "scipy"  # netCDF3, always available with SciPy


def hermite5_weights(s, h):
    """Weights of (q0, v0, a0, q1, v1, a1) in the quintic Hermite interpolant at s = (t − t0)/h,
    and in its time derivative: two 6-tuples."""
    s2, s3 = s * s, s * s * s
    s4, s5 = s3 * s, s3 * s2
    wq = (
        1 - 10 * s3 + 15 * s4 - 6 * s5,
        h * (s - 6 * s3 + 8 * s4 - 3 * s5),
        h * h * 0.5 * (s2 - 3 * s3 + 3 * s4 - s5),
        10 * s3 - 15 * s4 + 6 * s5,
        h * (-4 * s3 + 7 * s4 - 3 * s5),
        h * h * 0.5 * (s3 - 2 * s4 + s5),
    )
    d00 = (-30 * s2 + 60 * s3 - 30 * s4) / h
    wd = (
        d00,
        1 - 18 * s2 + 32 * s3 - 15 * s4,
        h * 0.5 * (2 * s - 9 * s2 + 12 * s3 - 5 * s4),
        -d00,
        -12 * s2 + 28 * s3 - 15 * s4,
        h * 0.5 * (3 * s2 - 8 * s3 + 5 * s4),
    )
    return wq, wd


def hermite5(s, h, q0, v0, a0, q1, v1, a1) -> tuple[np.ndarray, np.ndarray]:
    """Quintic Hermite interpolant matching q, q̇, q̈ at both ends, and its derivative."""
    wq, wd = hermite5_weights(s, h)
    ends = (q0, v0, a0, q1, v1, a1)
    q = sum(w * x for w, x in zip(wq, ends, strict=True))
    qd = sum(w * x for w, x in zip(wd, ends, strict=True))
    return q, qd
