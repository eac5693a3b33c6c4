"""Animations of a trajectory: GIF (matplotlib + Pillow) or MP4 (where ffmpeg exists).

What is drawn comes from the model's geometry (``model.geometry``, built when the model is
compiled, carried by the :class:`~pfaff.results.trajectory.Trajectory`; see
:mod:`pfaff.derive.geometry`): particles as dots, the lines its link rule finds (or the pairs
given as ``links=``), each rigid body (and ``add_shape`` shape) as a solid — the ellipsoid or box
of its mass and inertia (:mod:`pfaff.results.solids`), shaded faces in 3-D, its section in 2-D —
with its three axes from its mass centre (red x, green y, blue z; scaled to the figure), a family of particles (the ring) as its points, its centre and a spoke
to its first drawn member, and the points where forces act as crosses. Planar systems are drawn in
2-D, spatial ones in 3-D (mplot3d). The title shows t.

At most ``frames`` frames (default 200), at evenly spaced times over the run: the coordinates the
geometry reads are interpolated there (quintic Hermite, from q, q̇, q̈ of the reported states; the
Taylor polynomial of the nearer state inside an interval holding an MRP shadow-set switch, where
the coordinates jump), so memory and time depend on ``frames`` and on the drawn points (a few thousand at most),
never on the run's length or the model's size. A GIF's frames are kept as 8-bit palette images
(about width × height bytes each) until written; an MP4 streams to ffmpeg. The file is written
atomically: nothing half-written, an existing file untouched on failure.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pfaff.core.errors import OptionError, StateError
from pfaff.core.files import atomic_path
from pfaff.results.solids import Solids, outline, shaded, solids_of, unit_faces

if TYPE_CHECKING:
    from pfaff.results.trajectory import Trajectory

FORMATS = ("gif", "mp4")
MAX_FRAMES = 10_000
AXIS_COLOURS = ("tab:red", "tab:green", "tab:blue")
SOLID_COLOURS = ("tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:cyan", "tab:olive")


def check_path(path: str | os.PathLike) -> str:
    """The format of an animation file from its extension, checked before any work.

    Refuses an extension other than ``.gif`` or ``.mp4``, a missing or read-only folder, a
    folder as target, and MP4 when matplotlib finds no ffmpeg.

    Raises
    ------
    OptionError

    Examples
    --------
    >>> check_path("run.gif")
    'gif'
    >>> check_path("run.avi")
    Traceback (most recent call last):
    ...
    pfaff.core.errors.OptionError: the animation `run.avi` must end in .gif or .mp4
    """
    if not isinstance(path, str | os.PathLike):
        raise OptionError(f"`path` must be a file name, got {type(path).__name__}")
    target = Path(path)
    fmt = target.suffix.lstrip(".").lower()
    if fmt not in FORMATS:
        raise OptionError(f"the animation `{path}` must end in .gif or .mp4")
    folder = target.parent
    if not folder.is_dir():
        raise OptionError(f"cannot write the animation `{path}`: folder `{folder}` does not exist")
    if target.is_dir():
        raise OptionError(f"cannot write the animation `{path}`: it is a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OptionError(f"cannot write the animation `{path}`: folder `{folder}` is not writable")
    if fmt == "mp4" and not ffmpeg_available():
        raise OptionError(
            f"writing the MP4 `{path}` needs ffmpeg, which was not found (matplotlib looks for "
            "`ffmpeg` on PATH, or in rcParams['animation.ffmpeg_path']): install ffmpeg, or "
            "write a .gif"
        )
    return fmt


def ffmpeg_available() -> bool:
    """True when matplotlib can write MP4 through ffmpeg."""
    from matplotlib import animation

    return bool(animation.writers.is_available("ffmpeg"))


@dataclass
class Frames:
    """What the frames of an animation show.

    Attributes
    ----------
    t : ndarray, shape (F,)
        Times of the frames.
    points : ndarray, shape (F, P, d)
        Positions of the geometry's points.
    centres : ndarray, shape (F, B, d)
        Mass centres of the bodies.
    dcm : ndarray, shape (F, B, 3, 3)
        Their direction cosine matrices (columns: body axes).
    """

    t: np.ndarray
    points: np.ndarray
    centres: np.ndarray
    dcm: np.ndarray


def sample_frames(traj: Trajectory, frames: int = 200) -> Frames:
    """Positions at ``frames`` evenly spaced times over the run (one frame for a single state).

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> traj = pfaff.simulate(model, [0.5], [0.0], (0.0, 1.0))
    >>> f = sample_frames(traj, 5)
    >>> f.t.tolist(), f.points.shape
    ([0.0, 0.25, 0.5, 0.75, 1.0], (5, 1, 2))
    >>> bool(np.allclose(f.points[0, 0], [np.sin(0.5), -np.cos(0.5)]))
    True
    """
    geo = _geometry(traj)
    k = len(traj.t)
    if k == 0:
        raise StateError("the trajectory has no states: nothing to animate")
    cols = geo.columns
    if k == 1:
        ts = traj.t[:1].astype(float)
        qc = traj.q[:1][:, cols]
    else:
        ts = np.linspace(traj.t[0], traj.t[-1], frames)
        qc = traj._columns_at(ts, cols)
    centres, dcm = geo.bodies(qc, ts)
    return Frames(ts, geo.points(qc, ts), centres, dcm)


def _geometry(traj: Trajectory) -> Any:
    geo = getattr(traj, "geometry", None)
    if geo is None:
        raise StateError(
            "this trajectory has no geometry to draw: animations need a model compiled from a "
            "pfaff.System with particles or rigid bodies (not from matrices, or reduced "
            "equations, or energies alone)"
        )
    return geo


def _frames_option(frames: object) -> int:
    if isinstance(frames, bool) or not isinstance(frames, numbers.Integral):
        raise OptionError(f"`frames` must be a whole number, got {frames!r:.80}")
    if not 1 <= int(frames) <= MAX_FRAMES:
        raise OptionError(f"`frames` must be between 1 and {MAX_FRAMES}, got {frames}")
    return int(frames)


def _positive(value: object, name: str, top: float) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OptionError(f"`{name}` must be a number, got {value!r:.80}")
    v = float(value)
    if not (math.isfinite(v) and 0 < v <= top):
        raise OptionError(f"`{name}` must be positive and at most {top:g}, got {value!r:.80}")
    return v


def _links(geo: Any, links: object) -> list[tuple[int, int]]:
    """The links to draw: the geometry's, or the given pairs of point indices or names."""
    if links is None:
        return geo.links
    if isinstance(links, str | bytes) or not isinstance(links, Iterable):
        raise OptionError("`links` must be pairs of point indices or names, e.g. [(-1, 0), (0, 1)]")
    by_name = {"origin": -1, **{name: i for i, name in enumerate(geo.names)}}
    P = len(geo.names)
    out = []
    for pair in links:
        if isinstance(pair, str | bytes) or not isinstance(pair, Iterable) or len(pair) != 2:
            raise OptionError(f"`links`: each link must be a pair of points, got {pair!r:.80}")
        ends = []
        for end in pair:
            if isinstance(end, str) and end in by_name:
                ends.append(by_name[end])
            elif isinstance(end, numbers.Integral) and not isinstance(end, bool) and -1 <= end < P:
                ends.append(int(end))
            else:
                raise OptionError(
                    f"`links`: {end!r:.60} is not a point: give an index from -1 (the origin) to "
                    f"{P - 1}, or a name ({', '.join(list(by_name)[:8])}, ...)"
                )
        out.append((ends[0], ends[1]))
    return out


def animate(
    traj: Trajectory,
    path: str | os.PathLike,
    *,
    frames: int = 200,
    fps: float = 20.0,
    links: Iterable | None = None,
    size: float = 4.0,
    dpi: int = 80,
    title: str | None = None,
    solid: str = "ellipsoid",
) -> Path:
    """Write an animation of ``traj`` (see :meth:`pfaff.Trajectory.animate`)."""
    fmt = check_path(path)
    n_frames = _frames_option(frames)
    fps = _positive(fps, "fps", 1000.0)
    size = _positive(size, "size", 50.0)
    dpi = int(_positive(dpi, "dpi", 1000.0))
    if title is not None and not isinstance(title, str):
        raise OptionError(f"`title` must be a string, got {type(title).__name__}")
    geo = _geometry(traj)
    pairs = _links(geo, links)
    data = sample_frames(traj, n_frames)
    from matplotlib.animation import FFMpegWriter, FuncAnimation

    solids = solids_of(geo, solid, _extent(geo, data))
    scene = _Scene(geo, data, pairs, size, dpi, title or geo.name, solids, blit=fmt == "gif")
    try:
        anim = FuncAnimation(
            scene.fig, scene.update, frames=len(data.t), repeat=False, cache_frame_data=False
        )
        writer = _palette_writer(scene, fps) if fmt == "gif" else FFMpegWriter(fps=fps)
        with atomic_path(path) as tmp:
            anim.save(str(tmp), writer=writer, dpi=dpi)
    finally:
        scene.fig.clear()
    return Path(path)


def _palette_writer(scene: _Scene, fps: float) -> Any:
    """A PillowWriter that draws only what moves over the figure's still background and keeps
    each frame as an 8-bit palette image (a quarter of its RGBA)."""
    from matplotlib.animation import PillowWriter
    from PIL import Image

    class PaletteWriter(PillowWriter):
        def setup(self, fig: Any, outfile: Any, dpi: float | None = None) -> None:
            super().setup(fig, outfile, dpi=dpi)
            fig.canvas.draw()  # everything but the moving (animated) artists
            self._background = fig.canvas.copy_from_bbox(fig.bbox)

        def grab_frame(self, **savefig_kwargs: Any) -> None:
            canvas = self.fig.canvas
            canvas.restore_region(self._background)
            scene.draw_moving()
            rgb = np.asarray(canvas.buffer_rgba())[..., :3]
            im = Image.fromarray(np.ascontiguousarray(rgb))
            self._frames.append(im.quantize(255, method=Image.Quantize.FASTOCTREE))

    return PaletteWriter(fps=fps)


def _decimals(ts: np.ndarray) -> int:
    """Decimals of t that tell consecutive frames apart."""
    if len(ts) < 2:
        return 3
    dt = float(np.min(np.diff(ts)))
    return int(min(9, max(2, math.ceil(-math.log10(dt)) + 1))) if dt > 0 else 3


def _extent(geo: Any, data: Frames) -> float:
    """The largest side of the box holding every point and mass centre over the run."""
    allp = np.concatenate([data.points.reshape(-1, geo.dim), data.centres.reshape(-1, geo.dim)])
    allp = allp[np.isfinite(allp).all(axis=1)]
    return float(np.ptp(allp, axis=0).max()) if len(allp) else 1.0


def _limits(
    geo: Any, data: Frames, pairs: list, solids: Solids
) -> tuple[np.ndarray, np.ndarray, float]:
    """Lower and upper corners of the drawing (a square or cube), and the length of body axes."""
    pts = [data.points.reshape(-1, geo.dim), data.centres.reshape(-1, geo.dim)]
    if any(-1 in p for p in pairs):
        pts.append(np.zeros((1, geo.dim)))
    allp = np.concatenate(pts)
    allp = allp[np.isfinite(allp).all(axis=1)]
    if not len(allp):
        allp = np.zeros((1, geo.dim))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    extent = float((hi - lo).max())
    axis = 0.2 * extent if extent > 0 else 1.0
    if len(geo.body_names):
        reach = max(axis, float(solids.half.max()))
        lo, hi = lo - reach, hi + reach
    mid, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-9) * 1.1
    return mid - half, mid + half, axis


class _Scene:
    """The figure of an animation and its moving artists; ``update(i)`` shows frame i.

    With ``blit``, the moving artists are *animated*: a full draw leaves them out (the still
    background), and :meth:`draw_moving` draws them over it.
    """

    def __init__(
        self,
        geo: Any,
        data: Frames,
        pairs: list,
        size: float,
        dpi: int,
        title: str,
        solids: Solids | None = None,
        blit: bool = False,
    ) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        class Canvas(FigureCanvasAgg):
            def draw_idle(self, *args: Any, **kwargs: Any) -> None:
                pass  # FuncAnimation asks for a draw after each frame; the writer draws it

        self.geo, self.data, self.d = geo, data, geo.dim
        self.fig = Figure(figsize=(size, size), dpi=dpi, facecolor="white")
        Canvas(self.fig)
        self.title = title
        self.solids = (
            solids if solids is not None else solids_of(geo, "ellipsoid", _extent(geo, data))
        )
        self.lo, self.hi, self.axis_len = _limits(geo, data, pairs, self.solids)
        self.ax = self._axes()
        self.moving: list = []
        self._artists(pairs)
        for a in self.moving:
            a.set_animated(blit)
        self.decimals = _decimals(data.t)

    def _axes(self) -> Any:
        fig, lo, hi = self.fig, self.lo, self.hi
        if self.d == 3:
            ax = fig.add_subplot(projection="3d")
            ax.set_box_aspect((1, 1, 1))
            ax.set_zlim(lo[2], hi[2])
            ax.set_zlabel("z", fontsize=8)
        else:
            ax = fig.add_subplot()
            ax.set_aspect("equal")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_xlabel("x", fontsize=8)
        ax.set_ylabel("y", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.locator_params(nbins=4)
        return ax

    def _collection(self, **kw: Any) -> Any:
        empty = np.zeros((1, 2, self.d))
        if self.d == 3:
            from mpl_toolkits.mplot3d.art3d import Line3DCollection

            c = Line3DCollection(empty, **kw)
            self.ax.add_collection3d(c)
        else:
            from matplotlib.collections import LineCollection

            c = LineCollection(empty, **kw)
            self.ax.add_collection(c)
        self.moving.append(c)
        return c

    def _marker(self, **style: Any) -> Any:
        line = self.ax.plot(*([[]] * self.d), linestyle="none", **style)[0]
        self.moving.append(line)
        return line

    def _artists(self, pairs: list) -> None:
        ax, d = self.ax, self.d
        if any(-1 in p for p in pairs):  # the fixed origin (still)
            ax.plot(*([0.0] for _ in range(d)), marker="o", ms=4, color="k", linestyle="none")
        self.ia = np.array([a for a, _ in pairs], dtype=np.int64)
        self.ib = np.array([b for _, b in pairs], dtype=np.int64)
        self.bodies = self._solid_collection()
        self.lines = self._collection(colors="0.25", linewidths=1.5)
        self.axes = [
            self._collection(colors=AXIS_COLOURS[a], linewidths=2)
            for a in range(3 if d == 3 else 2)
        ]
        kinds = np.array(self.geo.kinds)
        styles = (
            ("particle", {"marker": "o", "ms": 6, "color": "tab:blue"}),
            ("family", {"marker": ".", "ms": _dot_size(len(kinds)), "color": "tab:blue"}),
            ("force", {"marker": "x", "ms": 6, "color": "0.3"}),
        )
        self.markers = [
            (np.flatnonzero(kinds == k), self._marker(**style))
            for k, style in styles
            if (kinds == k).any()
        ]
        self.centres = self._marker(marker="+", ms=8, color="k")
        self.text = ax.text2D if d == 3 else ax.text
        self.label = self.text(
            0.5, 1.02, "", transform=ax.transAxes, ha="center", va="bottom", fontsize=9
        )
        self.moving.append(self.label)

    def update(self, i: int) -> list:
        """Show frame i; returns the moving artists."""
        d, data = self.d, self.data
        pts = data.points[i]
        padded = np.concatenate([pts, np.zeros((1, d))])  # index -1: the origin
        for ix, artist in self.markers:
            _set(artist, pts[ix], d)
        segs = [np.stack([padded[self.ia], padded[self.ib]], axis=1)]
        centres = []
        for _, start, stop in self.geo.families:  # centre, and a spoke to the first member
            c = pts[start:stop].mean(axis=0)
            centres.append(c)
            segs.append(np.stack([c, pts[start]])[None])
        _set(self.centres, np.array(centres).reshape(-1, d), d)
        self.lines.set_segments(np.concatenate(segs))
        self._update_solids(i)
        for a, coll in enumerate(self.axes):
            tips = data.centres[i] + self.axis_len * data.dcm[i, :, :d, a]
            coll.set_segments(np.stack([data.centres[i], tips], axis=1))
        self.label.set_text(f"{self.title}\nt = {data.t[i]:.{self.decimals}f}")
        return self.moving

    def _solid_collection(self) -> Any:
        """The bodies' solids: shaded faces in 3-D, outlines filled in 2-D."""
        if not len(self.geo.body_names):
            return None
        from matplotlib.colors import to_rgb

        B = len(self.geo.body_names)
        self.body_colours = np.array(
            [to_rgb(SOLID_COLOURS[k % len(SOLID_COLOURS)]) for k in range(B)]
        )
        if self.d == 3:
            from mpl_toolkits.mplot3d.art3d import Poly3DCollection

            self.unit = [unit_faces(k) for k in self.solids.kinds]
            coll = Poly3DCollection([np.zeros((3, 3))], edgecolors="none")
            self.ax.add_collection3d(coll)
        else:
            from matplotlib.collections import PolyCollection

            coll = PolyCollection([np.zeros((3, 2))], edgecolors="0.2", linewidths=0.6, alpha=0.85)
            coll.set_facecolor(self.body_colours)
            self.ax.add_collection(coll)
        self.moving.append(coll)
        return coll

    def _update_solids(self, i: int) -> None:
        if self.bodies is None:
            return
        world = self.solids.world(self.data.dcm[i])  # (B, 3, 3): semi-axis vectors
        centres = self.data.centres[i]
        if self.d == 3:
            faces = [c + u @ w.T for c, u, w in zip(centres, self.unit, world, strict=True)]
            colours = [
                np.broadcast_to(col, (len(u), 3))
                for col, u in zip(self.body_colours, self.unit, strict=True)
            ]
            allf = self.faces = np.concatenate(faces)
            self.bodies.set_verts(allf)
            self.bodies.set_facecolor(shaded(allf, np.concatenate(colours)))
        else:
            polys = []
            for c, kind, w in zip(centres, self.solids.kinds, world, strict=True):
                inplane = w[:2]  # x, y of the three semi-axis vectors
                keep = np.argsort(np.linalg.norm(inplane, axis=0))[-2:]
                polys.append(c + outline(kind, inplane[:, np.sort(keep)]))
            self.bodies.set_verts(polys)

    def draw_moving(self) -> None:
        """Draw the moving artists over the canvas (after the background is restored)."""
        for a in self.moving:
            if self.d == 3 and hasattr(a, "do_3d_projection"):
                a.do_3d_projection()
            self.ax.draw_artist(a)


def _dot_size(count: int) -> float:
    """Marker size of a family's points: smaller as they get denser."""
    return 8.0 if count <= 16 else 5.0 if count <= 128 else 3.0 if count <= 512 else 1.5


def _set(artist: Any, xyz: np.ndarray, d: int) -> None:
    if d == 3:
        artist.set_data_3d(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    else:
        artist.set_data(xyz[:, 0], xyz[:, 1])
