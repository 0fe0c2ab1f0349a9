"""Checks radcol's lightmapped glTF and EXR with independent readers.

trimesh reads the GLB (its triangles and TEXCOORD_0), OpenEXR the linear
lightmap; at a point inside every triangle (barycentric 0.47, 0.31, 0.22,
off the lines where refinement splits) the texel under its UV must hold
radcol's own u_n / pi there, which `radcol solve --at` computes by another
path (a BVH point location, no atlas). See README.

    python3 check.py RADCOL_BINARY
"""
import csv
import subprocess
import sys

import numpy as np
import OpenEXR
import trimesh

radcol = sys.argv[1] if len(sys.argv) > 1 else "radcol"
solve = [radcol, "solve", "cornell", "--target-error", "1e-2", "--keep-negative", "-q", "--force"]
subprocess.run(solve + ["--lightmap", "lm.exr", "--lightmap-size", "2048", "-o", "lm.glb"],
               check=True, stdout=subprocess.DEVNULL)

scene = trimesh.load("lm.glb", force="scene")
w = np.array([0.47, 0.31, 0.22])
points = []
for name, g in scene.geometry.items():
    for f in g.faces:
        v = g.vertices[f]
        n = np.cross(v[1] - v[0], v[2] - v[0])
        points.append((name, (v * w[:, None]).sum(0), (g.visual.uv[f] * w[:, None]).sum(0),
                       n / np.linalg.norm(n)))
with open("pts.csv", "w") as fh:
    fh.write("label,x,y,z,nx,ny,nz\n")
    for i, (name, x, _, n) in enumerate(points):
        fh.write(f"{name}-{i},{x[0]},{x[1]},{x[2]},{n[0]},{n[1]},{n[2]}\n")
subprocess.run(solve + ["--at", "pts.csv", "--at-out", "vals.csv"], check=True,
               stdout=subprocess.DEVNULL)

channels = OpenEXR.File("lm.exr").parts[0].channels
rgb = channels["RGB"].pixels if "RGB" in channels else np.stack(
    [channels[c].pixels for c in "RGB"], -1)
height, width = rgb.shape[:2]
errors = []
for (_, _, (u, v), _), row in zip(points, csv.DictReader(open("vals.csv"))):
    # trimesh turns glTF's top-left UV origin into the bottom-left one.
    texel = rgb[min(int((1 - v) * height), height - 1), min(int(u * width), width - 1)]
    want = np.array([float(row[f"u_{c}"]) for c in "RGB"]) / np.pi
    errors.append(np.max(np.abs(texel - want)) / np.max(np.abs(want)))
errors = np.array(errors)
print(f"{len(errors)} triangles of {len(scene.geometry)} objects: texel against u_n/pi, "
      f"relative difference median {np.median(errors):.1e}, max {errors.max():.1e}")
sys.exit(0 if errors.max() < 0.02 else 1)
