#!/usr/bin/env python3
"""The thesis method of constant-cutting-speed spindle control, as a peer of
`millplan speed` for the benchmark table (NumPy and SciPy):

  - every facet of the binary STL is represented by its centre (the mean of
    its three corners) and its normal;
  - every GOTO of the APT file (tool tip of a ball-end mill) is moved up by R
    to the ball's centre and mapped to the facet with the nearest centre
    (a k-d tree: no exact closest point);
  - the inclination alpha of that facet's normal gives the working diameter
    D_w = D * sin(min(alpha + theta, 90 deg)), theta = arccos(1 - 2 ap / D)
    (the tool maker's tilted-ball formula);
  - n = 1000 vc / (pi D_w) within the spindle range, the feed F = n z fz,
    written as SPINDL/FEDRAT before every GOTO whose speed changed.

Usage: speed_peer.py PART.stl PATH.apt OUT.apt [--vc 63 --fz 0.125 --ap 0.3 --d 10 --flutes 2]
"""
import argparse
import re

import numpy as np
from scipy.spatial import cKDTree


def read_stl(path):
    data = np.fromfile(path, dtype=np.uint8)
    n = int(np.frombuffer(data[80:84].tobytes(), dtype="<u4")[0])
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    facets = np.frombuffer(data[84 : 84 + 50 * n].tobytes(), dtype=rec)
    v = facets["v"].astype(np.float64)
    centres = v.mean(axis=1)
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(normals, axis=1)
    normals /= np.where(length > 0, length, 1.0)[:, None]
    return centres, normals


GOTO = re.compile(rb"^GOTO/([-0-9.]+),([-0-9.]+),([-0-9.]+)", re.M)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("stl")
    ap.add_argument("apt")
    ap.add_argument("out")
    ap.add_argument("--vc", type=float, default=63.0)
    ap.add_argument("--fz", type=float, default=0.125)
    ap.add_argument("--ap", type=float, default=0.3)
    ap.add_argument("--d", type=float, default=10.0)
    ap.add_argument("--flutes", type=int, default=2)
    ap.add_argument("--smin", type=float, default=500.0)
    ap.add_argument("--smax", type=float, default=18000.0)
    a = ap.parse_args()

    centres, normals = read_stl(a.stl)
    text = open(a.apt, "rb").read()
    pts = np.array(GOTO.findall(text), dtype=np.float64)
    r = a.d / 2.0
    ball = pts + np.array([0.0, 0.0, r])
    _, idx = cKDTree(centres).query(ball, workers=-1)
    nz = np.abs(normals[idx, 2])
    alpha = np.arccos(np.clip(nz, 0.0, 1.0))
    theta = np.arccos(1.0 - 2.0 * a.ap / a.d)
    dw = a.d * np.sin(np.minimum(alpha + theta, np.pi / 2))
    n = np.clip(1000.0 * a.vc / (np.pi * dw), a.smin, a.smax)
    f = n * a.flutes * a.fz

    out = ["PARTNO SPEED_PEER", "UNITS/MM"]
    last = None
    for (x, y, z), s, feed in zip(pts.tolist(), np.round(n).tolist(), np.round(f).tolist()):
        if s != last:
            out.append(f"SPINDL/{s:.0f},RPM,CLW")
            out.append(f"FEDRAT/{feed:.0f},MMPM")
            last = s
        out.append(f"GOTO/{x:.4f},{y:.4f},{z:.4f}")
    out.append("FINI")
    with open(a.out, "w") as fh:
        fh.write("\n".join(out))
        fh.write("\n")
    print(f"{len(pts)} points, D_w {dw.min():.3f}..{dw.max():.3f} mm, n {n.min():.0f}..{n.max():.0f} 1/min")


if __name__ == "__main__":
    main()
