"""
The 3-D viewer
==============

``traj.to_html(path)`` writes one HTML file that plays a run offline (drag to turn, wheel to
zoom, play, pause, scrub, speed); ``traj.show()`` is the same scene in a notebook. Rigid bodies
are drawn as the ellipsoids of their mass and inertia. Here a free body spun near its
intermediate axis: first six moments of the run drawn by matplotlib, then the viewer itself,
live in this page.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import pfaff
from pfaff.results.animation import sample_frames
from pfaff.results.solids import solids_of, unit_faces

system = pfaff.models.torque_free_body("quaternion")
model = system.equations().compile({"I1": 1.0, "I2": 2.0, "I3": 2.5})
att = system.bodies[0].attitude
q0 = att.from_dcm(np.eye(3))
traj = pfaff.simulate(model, q0, att.rates(q0, [0.01, 2.0, 0.05]), (0.0, 8.0))

page = traj.to_html(Path(tempfile.mkdtemp()) / "tumbling.html")
print(f"{page.name}: {page.stat().st_size / 1e3:.0f} kB, fetches nothing")

frames = sample_frames(traj, 6)
solid = solids_of(model.geometry)
fig = plt.figure(figsize=(10, 2.2))
for i in range(6):
    ax = fig.add_subplot(1, 6, i + 1, projection="3d")
    w = solid.world(frames.dcm[i])[0]
    faces = unit_faces("ellipsoid", 16) @ w.T
    x, y, z = faces[..., 0], faces[..., 1], faces[..., 2]
    ax.scatter(x.ravel(), y.ravel(), z.ravel(), s=1, c=z.ravel(), cmap="copper")
    ax.set_axis_off()
    ax.set_title(f"t = {frames.t[i]:.1f} s", fontsize=8)
    lim = solid.half.max()
    ax.set(xlim=(-lim, lim), ylim=(-lim, lim), zlim=(-lim, lim))

# %%
# The scene itself, live (drag to turn it; it fetches nothing):

# sphinx_gallery_capture_repr = ('_repr_html_',)
traj.show(height=360)
