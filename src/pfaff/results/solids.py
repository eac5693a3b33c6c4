"""The solid drawn for each rigid body: a box or an ellipsoid of the body's mass and inertia.

A uniform solid ellipsoid of mass m and semi-axes (a₁, a₂, a₃) has principal moments
Iᵢ = m (aⱼ² + aₖ²)/5, a uniform box of half-sides (a₁, a₂, a₃) has Iᵢ = m (aⱼ² + aₖ²)/3. Solving for
the semi-axes from the principal moments of a body's inertia (eigen-decomposition, so the solid
is turned to the body's principal axes):

    aᵢ² = c/(2m) (Iⱼ + Iₖ − Iᵢ),   c = 5 (ellipsoid) or 3 (box).

The box is exact for rods and plates, the ellipsoid for spheres and discs look like discs. A planar
body, known by its one moment about z, is drawn as the disc of that moment (a rod and a disc of
the same moment cannot be told apart: declare the shape with ``add_shape(size=...)``). A
semi-axis that comes out zero or imaginary (a thin disc, a point mass, a planar body with one
moment) is raised to :data:`THIN` of the largest; a body with no usable size at all gets
:data:`FALLBACK` of the scene's extent. Shapes given by their semi-axes (``add_shape(size=…)``)
are drawn as they are.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pfaff.core.errors import OptionError

SOLIDS = ("ellipsoid", "box")
THIN = 0.06  # the smallest semi-axis, relative to the largest
FALLBACK = 0.05  # a solid of unknown size: this fraction of the scene's extent
_FACTOR = {"ellipsoid": 5.0, "box": 3.0}


@dataclass
class Solids:
    """The solids of a geometry's bodies.

    Attributes
    ----------
    kinds : list of str, length B
        ``"ellipsoid"`` or ``"box"``.
    half : ndarray, shape (B, 3)
        Semi-axes (half-sides of a box) along the solid's own axes.
    axes : ndarray, shape (B, 3, 3)
        The solid's axes in body axes (columns): principal axes of the inertia.
    """

    kinds: list[str]
    half: np.ndarray
    axes: np.ndarray

    def world(self, dcm: np.ndarray) -> np.ndarray:
        """Columns of each solid's axes in inertial components, scaled by its semi-axes.

        Parameters
        ----------
        dcm : ndarray, shape (..., B, 3, 3)

        Returns
        -------
        ndarray, shape (..., B, 3, 3)
        """
        return dcm @ self.axes * self.half[:, None, :]


def semi_axes(mass: float, inertia: np.ndarray, solid: str = "ellipsoid") -> tuple:
    """Semi-axes and principal axes of the uniform ``solid`` of this mass and inertia.

    Parameters
    ----------
    mass : float
    inertia : array_like, shape (3, 3)
        About the mass centre, in body axes.
    solid : {"ellipsoid", "box"}

    Returns
    -------
    half : ndarray, shape (3,)
        NaN where nothing can be said (no mass).
    axes : ndarray, shape (3, 3)
        Principal axes (columns), a proper rotation.

    Examples
    --------
    A rod of length 2 along x (I = m L²/12 about y and z) is a box of half-length 1:

    >>> half, axes = semi_axes(3.0, np.diag([0.0, 1.0, 1.0]), "box")
    >>> half.round(12).tolist()
    [1.0, 0.06, 0.06]
    >>> half, _ = semi_axes(1.0, np.diag([0.4, 0.4, 0.4]))  # the unit sphere
    >>> half.round(12).tolist()
    [1.0, 1.0, 1.0]
    """
    inertia = np.asarray(inertia, dtype=float).reshape(3, 3)
    if not (np.isfinite(mass) and mass > 0 and np.isfinite(inertia).all()):
        return np.full(3, np.nan), np.eye(3)
    moments, axes = np.linalg.eigh((inertia + inertia.T) / 2)
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1
    sq = _FACTOR[solid] / (2 * mass) * (moments.sum() - 2 * moments)
    half = np.sqrt(np.clip(sq, 0.0, None))
    top = half.max()
    if top <= 0:
        return np.full(3, np.nan), np.eye(3)
    return np.maximum(half, THIN * top), axes


def solids_of(geo: Any, solid: str = "ellipsoid", extent: float = 1.0) -> Solids:
    """The solids of ``geo``'s bodies and shapes (``geo.sizes()``), sized by ``solid``.

    Raises
    ------
    OptionError
        ``solid`` is not one of :data:`SOLIDS`.
    """
    if solid not in SOLIDS:
        raise OptionError(f"`solid` must be one of {SOLIDS}, got {solid!r:.40}")
    sizes = geo.sizes() if hasattr(geo, "sizes") else []
    kinds, halves, axes = [], [], []
    for kind, vals in sizes:
        if kind == "inertia":
            half, ax = semi_axes(float(vals[0]), vals[1:], solid)
            kinds.append(solid)
        else:
            half, ax = np.where(np.isfinite(vals) & (vals > 0), vals, np.nan), np.eye(3)
            kinds.append(kind)
        halves.append(np.where(np.isnan(half), FALLBACK * max(extent, 1e-9), half))
        axes.append(ax)
    B = len(kinds)
    return Solids(kinds, np.array(halves).reshape(B, 3), np.array(axes).reshape(B, 3, 3))


def unit_faces(kind: str, n: int = 12) -> np.ndarray:
    """Quadrilateral faces of the unit solid (the sphere of radius 1 or the cube [-1, 1]³).

    Returns
    -------
    ndarray, shape (faces, 4, 3)

    Examples
    --------
    >>> unit_faces("box").shape, unit_faces("ellipsoid", 8).shape
    ((6, 4, 3), (32, 4, 3))
    """
    if kind == "box":
        faces = []
        for a in range(3):
            b, c = (a + 1) % 3, (a + 2) % 3
            for s in (-1.0, 1.0):
                quad = np.zeros((4, 3))
                quad[:, a] = s
                quad[:, b] = [-1, 1, 1, -1]
                quad[:, c] = [-1, -1, 1, 1]
                faces.append(quad)
        return np.array(faces)
    th = np.linspace(0.0, np.pi, n // 2 + 1)
    ph = np.linspace(0.0, 2 * np.pi, n + 1)
    T, PH = np.meshgrid(th, ph, indexing="ij")
    pts = np.stack([np.sin(T) * np.cos(PH), np.sin(T) * np.sin(PH), np.cos(T)], axis=-1)
    quads = np.stack([pts[:-1, :-1], pts[:-1, 1:], pts[1:, 1:], pts[1:, :-1]], axis=2)
    return quads.reshape(-1, 4, 3)


def outline(kind: str, axes2: np.ndarray, n: int = 32) -> np.ndarray:
    """The outline in the plane of a solid whose in-plane semi-axis vectors are ``axes2``.

    Parameters
    ----------
    axes2 : ndarray, shape (2, 2)
        Columns: the two semi-axis vectors (x, y components) that span the drawn section.

    Returns
    -------
    ndarray, shape (k, 2)
        Points of the closed outline about the centre.
    """
    if kind == "box":
        signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    else:
        a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        signs = np.stack([np.cos(a), np.sin(a)], axis=1)
    return signs @ axes2.T


def shaded(faces: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """RGBA of each face: ``colour`` lit by one light from above and in front.

    Parameters
    ----------
    faces : ndarray, shape (F, 4, 3)
    colour : ndarray, shape (F, 3)
    """
    normal = np.cross(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1])
    norm = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = normal / np.where(norm > 0, norm, 1.0)
    light = np.array([0.4, -0.5, 0.8]) / np.linalg.norm([0.4, -0.5, 0.8])
    lit = 0.4 + 0.6 * np.abs(normal @ light)
    return np.concatenate([np.clip(colour * lit[:, None], 0, 1), np.ones((len(faces), 1))], axis=1)
