"""The interactive 3-D viewer: one self-contained HTML file per trajectory, or a notebook cell.

:func:`to_html` writes a page that plays the run in any browser with WebGL2, offline: the scene
(float32 arrays in base64 inside a JSON block) and the renderer (``viewer.js``, a small WebGL2
renderer written for pfaff, shipped as package data with ``viewer.html``) are inlined, and the
page fetches nothing (no ``src=``/``href=`` to another file, no ``import``, ``fetch`` or XHR).
:func:`show` wraps the same page in an ``<iframe srcdoc=…>`` for Jupyter (JupyterLab, classic, VS
Code): a :class:`Viewer` whose ``_repr_html_`` a notebook displays.

Why not three.js: the scene needs point sprites shaded as spheres and three instanced meshes (ellipsoids, boxes, rods) and
two lights; a 300-line renderer does that, adds ~15 KB to a file instead of ~650 KB, has no
vendored code to keep updated and no strings that name a network address.

What is drawn comes from the model's geometry (:mod:`pfaff.derive.geometry`), as in the GIF/MP4
animations: particles as spheres (a rigid body's own mass-centre particle is not drawn), rigid
bodies and shapes (``add_shape``) as the solids of :mod:`pfaff.results.solids`, links as rods.
Frames are evenly spaced in time (``fps`` per second of the run, at most ``max_frames``, and no
more than ``max_bytes`` of data); the browser interpolates between them (positions linearly,
attitudes by normalized quaternions) and plays at real time × the chosen speed.
"""

from __future__ import annotations

import base64
import html
import json
import math
import numbers
import os
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pfaff.core.errors import OptionError
from pfaff.core.files import atomic_path
from pfaff.results.animation import _decimals, _geometry, sample_frames
from pfaff.results.solids import solids_of

if TYPE_CHECKING:
    from pfaff.results.trajectory import Trajectory

UP = ("x", "y", "z", "-x", "-y", "-z")
MAX_BYTES = 3_000_000  # scene data at most (raw; the file is about 4/3 of it plus ~20 KB)
_POINT_COLOURS = {
    "particle": [0.12, 0.45, 0.75],
    "family": [0.25, 0.55, 0.85],
    "force": [0.35, 0.35, 0.35],
}


class Viewer:
    """A trajectory's 3-D scene for a notebook: displays itself, or is saved as a page.

    Attributes
    ----------
    html : str
        The self-contained page.
    height : int
        Height of the notebook frame, pixels.

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> viewer = pfaff.simulate(model, [0.5], [0.0], (0.0, 1.0)).show()
    >>> viewer._repr_html_().startswith("<iframe")
    True
    """

    def __init__(self, page: str, height: int = 480) -> None:
        self.html = page
        self.height = int(height)

    def _repr_html_(self) -> str:
        doc = html.escape(self.html, quote=True)
        return (
            f'<iframe srcdoc="{doc}" sandbox="allow-scripts" '
            f'style="width: 100%; height: {self.height}px; border: 0"></iframe>'
        )

    def save(self, path: str | os.PathLike) -> Path:
        """Write the page to ``path`` (atomically)."""
        return _write(self.html, path)

    def __repr__(self) -> str:
        return f"<pfaff.Viewer: {len(self.html) / 1e6:.2f} MB page>"


def scene(
    traj: Trajectory,
    *,
    fps: float = 30.0,
    max_frames: int = 3000,
    max_bytes: int = MAX_BYTES,
    solid: str = "ellipsoid",
    up: str | None = None,
    title: str | None = None,
    arrows: dict | None = None,
) -> dict[str, Any]:
    """The scene of a trajectory as the viewer reads it (JSON-ready; arrays in base64).

    ``arrows`` maps a name to a function ``f(t, q, qd, multipliers) -> (at, vector)`` (two
    sequences of ``dim`` numbers: where the arrow starts, and the force), evaluated at every
    reported state and interpolated linearly to the frames; arrows are drawn to one scale, the
    largest a quarter of the scene.

    Examples
    --------
    >>> import pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 1})
    >>> s = scene(pfaff.simulate(model, [0.5], [0.0], (0.0, 2.0)), fps=10)
    >>> s["nframes"], s["npoints"], s["nbodies"], s["links"]
    (21, 1, 0, [[-1, 0]])
    """
    geo = _geometry(traj)
    fps = _number(fps, "fps", 1e-6, 1e4)
    max_frames = int(_number(max_frames, "max_frames", 2, 1e5))
    max_bytes = int(_number(max_bytes, "max_bytes", 1e3, 1e9))
    if title is not None and not isinstance(title, str):
        raise OptionError(f"`title` must be a string, got {type(title).__name__}")
    up = _up(up, geo.dim)
    P, B, d = len(geo.names), len(geo.body_names), geo.dim
    span = float(traj.t[-1] - traj.t[0]) if len(traj.t) else 0.0
    per_frame = 4 * (P * d + 7 * B) + 8
    count = min(max_frames, math.ceil(span * fps) + 1, max(2, max_bytes // per_frame))
    data = sample_frames(traj, max(count, 2))
    lo, hi = _bounds(data)
    extent = float((hi - lo).max()) if np.isfinite(hi - lo).all() else 1.0
    extent = extent if extent > 0 else 1.0
    solids = solids_of(geo, solid, extent)
    quats = _quaternions(data.dcm @ solids.axes)
    radius = _radii(geo, data.points[0], extent)
    body_points = set(geo.body_names)
    radius = [
        0.0 if n in body_points and k == "particle" else r
        for n, k, r in zip(geo.names, geo.kinds, radius, strict=True)
    ]
    half_top = float(solids.half.max()) if B else 0.0
    arrow_data = _arrows(traj, arrows, data.t, d)
    anchored = any(-1 in pair for pair in geo.links)  # a link to the fixed origin: it is drawn
    local = _local_extent(data, anchored) + 2 * half_top
    follow = bool(local < 0.5 * extent)
    shown = (local if follow else extent) or 1.0
    U = _up_matrix(up)
    ground = _ground(data, solids, radius, U) if d == 3 else None
    return {
        "title": title if title is not None else str(geo.name),
        "t": _b64(data.t.astype(np.float64)),
        "nframes": len(data.t),
        "decimals": _decimals(data.t),
        "dim": d,
        "npoints": P,
        "nbodies": B,
        "points": _b64(np.nan_to_num(data.points).astype(np.float32)),
        "centres": _b64(np.nan_to_num(_pad3(data.centres)).astype(np.float32)),
        "quaternions": _b64(quats.astype(np.float32)),
        "half": solids.half.round(6).tolist(),
        "kinds": solids.kinds,
        "links": [list(p) for p in geo.links],
        "radius": [round(float(r), 6) for r in radius],
        "rod_radius": 0.35 * float(np.median([r for r in radius if r > 0] or [0.02 * extent])),
        "point_colours": _colours(geo),
        "centre": _pad3((lo + hi) / 2).tolist(),
        "extent": (size := shown if follow else extent + 2 * half_top),
        "follow": follow,
        "ground": ground,
        "spacing": _nice(shown / 4),
        "up_matrix": U.reshape(-1).tolist(),
        "view": [-math.pi / 2, 0.0] if d == 2 else [-math.pi / 3, 0.45],
        "narrows": arrow_data.shape[1],
        "arrows": _b64(arrow_data.astype(np.float32)),
        "arrow_names": list(arrows or {}),
        "arrow_scale": _arrow_scale(arrow_data, size),
    }


def render(traj: Trajectory, **options: Any) -> str:
    """The self-contained HTML page of ``traj`` (options as :func:`scene`)."""
    data = json.dumps(scene(traj, **options), separators=(",", ":"), allow_nan=False)
    data = data.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
    folder = resources.files("pfaff.results")
    page = (folder / "viewer.html").read_text(encoding="utf-8")
    script = (folder / "viewer.js").read_text(encoding="utf-8")
    title = html.escape(json.loads(data)["title"])
    return page.replace("@TITLE@", title).replace("@SCRIPT@", script).replace("@DATA@", data)


def to_html(traj: Trajectory, path: str | os.PathLike, **options: Any) -> Path:
    """Write the viewer page of ``traj`` to ``path`` (see :meth:`pfaff.Trajectory.to_html`)."""
    target = _html_path(path)
    return _write(render(traj, **options), target)


def show(traj: Trajectory, *, height: int = 480, **options: Any) -> Viewer:
    """The viewer of ``traj`` for a notebook (see :meth:`pfaff.Trajectory.show`)."""
    height = int(_number(height, "height", 100, 10_000))
    return Viewer(render(traj, **options), height)


# ---------------------------------------------------------------------------- helpers
def _write(page: str, path: str | os.PathLike) -> Path:
    with atomic_path(path) as tmp:
        Path(tmp).write_text(page, encoding="utf-8")
    return Path(path)


def _html_path(path: object) -> Path:
    if not isinstance(path, str | os.PathLike):
        raise OptionError(f"`path` must be a file name, got {type(path).__name__}")
    target = Path(path)
    if target.suffix.lower() not in (".html", ".htm"):
        raise OptionError(f"the viewer page `{path}` must end in .html")
    if not target.parent.is_dir():
        raise OptionError(f"cannot write `{path}`: folder `{target.parent}` does not exist")
    if target.is_dir():
        raise OptionError(f"cannot write `{path}`: it is a folder")
    return target


def _number(value: object, name: str, low: float, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise OptionError(f"`{name}` must be a number, got {value!r:.60}")
    v = float(value)
    if not (math.isfinite(v) and low <= v <= high):
        raise OptionError(f"`{name}` must be between {low:g} and {high:g}, got {value!r:.60}")
    return v


def _up(up: object, dim: int) -> str:
    if up is None:
        return "y" if dim == 2 else "z"
    if up not in UP:
        raise OptionError(f"`up` must be one of {', '.join(UP)}, got {up!r:.40}")
    return str(up)


def _up_matrix(up: str) -> np.ndarray:
    """Rows: the model's directions that become the viewer's x, y and z (z up), right-handed."""
    sign = -1.0 if up.startswith("-") else 1.0
    axis = "xyz".index(up[-1])
    z = sign * np.eye(3)[axis]
    x = np.eye(3)[1 if axis == 0 else 0]
    return np.array([x, np.cross(z, x), z])


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _pad3(a: np.ndarray) -> np.ndarray:
    """Pad the last axis to 3 components (planar systems lie in z = 0)."""
    a = np.asarray(a, dtype=float)
    return np.concatenate([a, np.zeros((*a.shape[:-1], 3 - a.shape[-1]))], axis=-1)


def _bounds(data: Any) -> tuple[np.ndarray, np.ndarray]:
    pts = np.concatenate(
        [
            data.points.reshape(-1, data.points.shape[-1]),
            data.centres.reshape(-1, data.centres.shape[-1]),
        ]
    )
    pts = _pad3(pts[np.isfinite(pts).all(axis=1)]) if len(pts) else np.zeros((0, 3))
    if not len(pts):
        return np.zeros(3), np.zeros(3)
    return pts.min(axis=0), pts.max(axis=0)


def _arrows(traj: Trajectory, arrows: object, times: np.ndarray, dim: int) -> np.ndarray:
    """Arrow starts and vectors at the frame times, shape (F, A, 6) (3-D components)."""
    if arrows is None:
        return np.zeros((len(times), 0, 6))
    if not isinstance(arrows, dict) or not all(
        isinstance(k, str) and callable(f) for k, f in arrows.items()
    ):
        raise OptionError("`arrows` must map names to functions f(t, q, qd, multipliers)")
    out = np.zeros((len(times), len(arrows), 6))
    for a, (name, fn) in enumerate(arrows.items()):
        rows = []
        for k in range(len(traj.t)):
            try:
                at, vec = fn(traj.t[k], traj.q[k], traj.qd[k], traj.multipliers[k])
                row = np.concatenate([_pad3(np.ravel(at)), _pad3(np.ravel(vec))])
            except (TypeError, ValueError, IndexError) as e:
                raise OptionError(
                    f"`arrows['{name}']` must return (at, vector), each of {dim} numbers: {e}"
                ) from e
            if row.shape != (6,):
                raise OptionError(f"`arrows['{name}']` must return two points of {dim} numbers")
            rows.append(row)
        values = np.array(rows, dtype=float)
        for c in range(6):
            out[:, a, c] = np.interp(times, traj.t, values[:, c])
    return out


def _arrow_scale(arrow_data: np.ndarray, extent: float) -> float:
    """Length per unit force: the largest arrow a quarter of the scene."""
    top = float(np.nanmax(np.linalg.norm(arrow_data[..., 3:], axis=-1), initial=0.0))
    return 0.25 * extent / top if top > 0 else 0.0


def _colours(geo: Any) -> list[list[float]]:
    """Point colours by kind; a family's first drawn member red, so that it is seen to turn."""
    out = [_POINT_COLOURS[k] for k in geo.kinds]
    for _, start, _stop in geo.families:
        out[start] = [0.8, 0.15, 0.1]
    return out


def _local_extent(data: Any, anchored: bool = False) -> float:
    """The largest extent of the scene at one time (what a camera that follows must show),
    the fixed origin included when something is linked to it."""
    parts = [a for a in (data.points, data.centres) if a.shape[1]]
    if anchored:
        parts.append(np.zeros((len(data.t), 1, data.points.shape[-1])))
    if not parts:
        return 0.0
    every = np.concatenate(parts, axis=1)
    with np.errstate(invalid="ignore"):
        size = np.nanmax(every, axis=1) - np.nanmin(every, axis=1)
    size = size[np.isfinite(size).all(axis=1)]
    return float(size.max()) if size.size else 0.0


def _ground(data: Any, solids: Any, radius: list[float], U: np.ndarray) -> float | None:
    """Height (viewer's z) of the lowest point of anything drawn over the run."""
    low = []
    if data.points.shape[1]:
        z = _pad3(data.points) @ U[2]
        low.append(np.nanmin(z - np.asarray(radius)))
    if data.centres.shape[1]:
        zc = _pad3(data.centres) @ U[2]
        along = U[2] @ solids.world(data.dcm)  # (F, B, 3): z of each semi-axis
        box = np.array([k == "box" for k in solids.kinds])
        reach = np.where(box, np.abs(along).sum(axis=-1), np.linalg.norm(along, axis=-1))
        low.append(np.nanmin(zc - reach))
    finite = [float(v) for v in low if np.isfinite(v)]
    return min(finite) if finite else None


def _nice(x: float) -> float:
    """1, 2 or 5 times a power of ten, near x."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    e = 10.0 ** math.floor(math.log10(x))
    return min((1.0, 2.0, 5.0, 10.0), key=lambda m: abs(m * e - x)) * e


def _radii(geo: Any, first: np.ndarray, extent: float) -> list[float]:
    """Sphere radii: a few per cent of the scene, less than half the nearest neighbour."""
    from scipy.spatial import cKDTree

    kinds = np.array(geo.kinds)
    out = np.where(kinds == "force", 0.015, 0.03) * extent
    ok = np.isfinite(first).all(axis=1)
    if ok.sum() > 1:
        dist, _ = cKDTree(first[ok]).query(first[ok], k=2)
        nn = dist[:, 1]
        spacing = float(np.median(nn[nn > 0])) if (nn > 0).any() else extent
        # apart where there is room; a dense family (the ring) as touching beads, still visible
        floor = np.where(kinds[ok] == "family", 0.004 * extent, 0.0)
        out[ok] = np.minimum(out[ok], np.maximum(0.3 * spacing, floor))
    return out.tolist()


def _quaternions(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices, shape (..., 3, 3) → (..., 4)."""
    R = np.nan_to_num(np.asarray(R, dtype=float))
    m = R.reshape(-1, 3, 3)
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    cand = np.stack(
        [
            np.stack(
                [1 + tr, m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]],
                -1,
            ),
            np.stack(
                [
                    m[:, 2, 1] - m[:, 1, 2],
                    1 + 2 * m[:, 0, 0] - tr,
                    m[:, 0, 1] + m[:, 1, 0],
                    m[:, 0, 2] + m[:, 2, 0],
                ],
                -1,
            ),
            np.stack(
                [
                    m[:, 0, 2] - m[:, 2, 0],
                    m[:, 0, 1] + m[:, 1, 0],
                    1 + 2 * m[:, 1, 1] - tr,
                    m[:, 1, 2] + m[:, 2, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    m[:, 1, 0] - m[:, 0, 1],
                    m[:, 0, 2] + m[:, 2, 0],
                    m[:, 1, 2] + m[:, 2, 1],
                    1 + 2 * m[:, 2, 2] - tr,
                ],
                -1,
            ),
        ],
        axis=1,
    )  # (N, 4 candidates, 4): each is 4·q_k·q, best where its own entry is largest
    diag = np.stack(
        [1 + tr, 1 + 2 * m[:, 0, 0] - tr, 1 + 2 * m[:, 1, 1] - tr, 1 + 2 * m[:, 2, 2] - tr], -1
    )
    best = cand[np.arange(len(m)), np.argmax(diag, axis=1)]
    norm = np.linalg.norm(best, axis=1, keepdims=True)
    q = np.where(norm > 0, best / np.where(norm > 0, norm, 1.0), [1.0, 0.0, 0.0, 0.0])
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(*R.shape[:-2], 4)
