"""
A tumbling body on three attitude sets
======================================

A free rigid body (I = 1, 2, 3) spun near its intermediate axis flips over (the Dzhanibekov
effect). The same motion is integrated with a quaternion (and its unit-norm
constraint), with modified Rodrigues parameters (switching to the shadow set when the norm of σ exceeds 1) and
with 3-2-1 Euler angles away from their singularity; the direction cosine matrices agree.
"""

import matplotlib.pyplot as plt
import numpy as np

import pfaff

values = {"I1": 1.0, "I2": 2.0, "I3": 3.0}
omega = [0.1, 1.5, 0.05]
C0 = np.eye(3)
te = np.linspace(0.0, 10.0, 501)
dcm = {}
for kind in ("quaternion", "mrp", "euler"):
    system = pfaff.models.torque_free_body(kind)
    model = system.equations().compile(values)
    att = system.bodies[0].attitude
    q0 = att.from_dcm(C0)
    traj = pfaff.simulate(
        model,
        q0,
        att.rates(q0, omega),
        (0.0, 10.0),
        t_eval=te,
        rtol=1e-10,
        atol=1e-10,
        throw=False,
    )
    dcm[kind] = model.geometry.bodies(traj.q, traj.t)[1][:, 0]
    print(kind, traj.status, traj.message)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.5))
for kind, C in dcm.items():
    ax1.plot(te[: len(C)], C[:, 1, 1], label=kind)
ax1.set(xlabel="t (s)", ylabel="C₂₂ (body y · inertial y)", title="the body flips")
ax1.legend()
for kind in ("mrp", "euler"):
    n = min(len(dcm[kind]), len(dcm["quaternion"]))
    diff = np.abs(dcm[kind][:n] - dcm["quaternion"][:n]).max(axis=(1, 2))
    ax2.semilogy(te[:n], diff + 1e-17, label=f"{kind} − quaternion")
ax2.set(xlabel="t (s)", ylabel="max |ΔC|", title="agreement of the attitude sets")
ax2.legend()
fig.tight_layout()
