"""Frames per second of the 3-D viewer in headless Chromium (software WebGL, SwiftShader).

Writes the pages of 2 s of the pushed 1,024-particle ring and 6 s of a tumbling body, opens each
with ``#bench`` (the page then draws 120 frames back to back, waiting for each, and records the
rate and the script's own share of a frame), interleaved, three times, and prints the medians.
The body page (one solid) is the baseline: what a frame costs with almost nothing in it. The
issue asks for at least 30 frames per second for the ring.

    python benchmarks/viewer.py [--particles 1024] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np

import pfaff

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--window-size=800,600",
    "--host-resolver-rules=MAP * ~NOTFOUND",
]


def pages(folder: Path, n: int) -> dict[str, Path]:
    ring = pfaff.models.rolling_ring(n, force=True, family=True).equations()
    ring = ring.compile({"M": 1.0, "r": 0.5, "F": 2.0})
    q, qd = pfaff.models.ring_state(n, 0.5, 0.0)
    body = pfaff.models.torque_free_body("quaternion")
    model = body.equations().compile({"I1": 1.0, "I2": 2.0, "I3": 2.5})
    att = body.bodies[0].attitude
    q0 = att.from_dcm(np.eye(3))
    return {
        f"ring N={n}": pfaff.simulate(ring, q, qd, (0.0, 2.0)).to_html(folder / "ring.html"),
        "tumbling body": pfaff.simulate(
            model, q0, att.rates(q0, [0.01, 2.0, 0.05]), (0.0, 6.0)
        ).to_html(folder / "body.html"),
    }


def measure(browser: str, page: Path) -> tuple[float, float]:
    out = subprocess.run(
        [browser, *FLAGS, "--dump-dom", page.as_uri() + "#bench"],
        capture_output=True,
        text=True,
        timeout=300,
    ).stdout
    fps = re.search(r'data-bench-fps="([^"]+)"', out)
    fill = re.search(r'data-bench-fill-ms="([^"]+)"', out)
    if fps is None or fill is None:
        raise SystemExit(f"the page did not report its rate: {page}")
    return float(fps.group(1)), float(fill.group(1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=1024)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    browser = next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)
    if browser is None:
        raise SystemExit("no chromium on PATH")
    with tempfile.TemporaryDirectory() as tmp:
        found = pages(Path(tmp), args.particles)
        runs: dict[str, list] = {name: [] for name in found}
        for _ in range(args.repeats):  # interleaved
            for name, page in found.items():
                runs[name].append(measure(browser, page))
        sizes = {name: page.stat().st_size for name, page in found.items()}
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores\n")
    print(f"{'page':<16} {'MB':>6} {'frames/s':>10} {'script ms/frame':>16}")
    for name, vals in runs.items():
        fps = statistics.median(v[0] for v in vals)
        ms = statistics.median(v[1] for v in vals)
        print(f"{name:<16} {sizes[name] / 1e6:>6.2f} {fps:>10.1f} {ms:>16.2f}")


if __name__ == "__main__":
    main()
