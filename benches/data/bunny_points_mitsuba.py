"""Independent reference radiances at points of scenes/bunny_room.obj, from
the Mitsuba 3 path tracer (PyPI `mitsuba`, variant scalar_rgb): under the
bunny, beside it, on it and on the walls.

    pip install mitsuba
    python3 benches/data/bunny_points_mitsuba.py [SAMPLES_PER_BATCH [BATCHES]]
    python3 benches/data/bunny_points_mitsuba.py --compare AT_OUT.csv

Writes tests/data/bunny_room_points.csv (the points, for `radcol solve
--at`) and tests/data/bunny_room_points_mitsuba.csv (label, x, y, z, nx, ny,
nz, radiance and the standard error of its batch mean per channel).

The scene is given to Mitsuba from the same triangles (each group of the OBJ
a mesh) and materials: diffuse reflectance = Kd (two-sided), the light an
area emitter of radiance Ke/pi (radcol's convention: Ke is the emitted
exitance E, so the radiance of a diffuse point is u/pi) with its own
reflectance. Path tracer, max depth 64, Russian roulette off. Each point is
seen by a radiance meter 1e-3 mm off the surface looking back at it.

With --compare, reads radcol's values at the same points (`radcol solve
scenes/bunny_room.obj ... --at tests/data/bunny_room_points.csv --at-out
AT_OUT.csv`) and prints, per point and channel, the differences of u_n/pi
and of the iterated û_n/pi from the reference against their estimates, and
how many lie within their estimate plus three standard errors.
"""

import csv
import math
import os
import sys
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))


def read_scene(path):
    verts, groups, mtl_of, cur = [], {}, {}, None
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t[0] == "g":
            cur = t[1]
            groups[cur] = []
        elif t[0] == "usemtl":
            mtl_of[cur] = t[1]
        elif t[0] == "f":
            groups[cur].append([int(x.split("/")[0]) - 1 for x in t[1:4]])
    mats, name = {}, None
    for line in open(os.path.join(os.path.dirname(path), "bunny_room.mtl")):
        t = line.split()
        if not t:
            continue
        if t[0] == "newmtl":
            name = t[1]
            mats[name] = {}
        elif t[0] in ("Kd", "Ke"):
            mats[name][t[0]] = [float(x) for x in t[1:4]]
    return np.array(verts), {g: np.array(f) for g, f in groups.items()}, mtl_of, mats


def write_obj(path, verts, faces):
    """One group of the scene as its own OBJ (its vertices renumbered)."""
    used = np.unique(faces)
    index = {v: i + 1 for i, v in enumerate(used)}
    with open(path, "w") as f:
        for v in verts[used]:
            f.write(f"v {v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n")
        for t in faces:
            f.write("f " + " ".join(str(index[v]) for v in t) + "\n")


def first_hit(verts, faces, origin, direction):
    """Distance and unit normal of the first triangle the ray meets."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = origin - a
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ direction) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
    if not hit.any():
        return None
    i = np.argmin(np.where(hit, t, np.inf))
    n = np.cross(e1[i], e2[i])
    return t[i], n / np.linalg.norm(n)


def points(verts, groups):
    bunny = groups["bunny"]
    up = np.array([0.0, 1.0, 0.0])
    pts = [
        ("floor, lit corner", (100.0, 0.0, 100.0), (0, 1, 0)),
        ("back wall, centre", (275.0, 275.0, 550.0), (0, 0, -1)),
        ("left (red) wall, low", (550.0, 80.0, 275.0), (-1, 0, 0)),
        ("right (green) wall, high", (0.0, 400.0, 275.0), (1, 0, 0)),
        ("ceiling, front", (275.0, 550.0, 80.0), (0, -1, 0)),
    ]
    # On the floor under the bunny's overhang (the first triangle above
    # faces down, 10 to 60 mm up) and just beside it (nothing above,
    # within 5 to 20 mm of a bunny vertex in plan).
    under, beside = [], []
    plan = verts[np.unique(bunny)][:, [0, 2]]
    for x in np.arange(170.0, 384.0, 6.0):
        for z in np.arange(195.0, 358.0, 6.0):
            o = np.array([x, 1e-6, z])
            h = first_hit(verts, bunny, o, up)
            if h is not None:
                if h[1][1] < -0.3 and 10.0 <= h[0] <= 60.0:
                    under.append((h[0], x, z))
            else:
                d = np.min(np.hypot(plan[:, 0] - x, plan[:, 1] - z))
                if 5.0 <= d <= 20.0:
                    beside.append((d, x, z))
    under.sort()
    for k, (_, x, z) in enumerate([under[len(under) // 4], under[3 * len(under) // 4]]):
        pts.append((f"floor under the bunny {k + 1}", (x, 0.0, z), (0, 1, 0)))
    beside.sort()
    for k, (_, x, z) in enumerate([beside[0], beside[len(beside) // 2], beside[-1]]):
        pts.append((f"floor beside the bunny {k + 1}", (x, 0.0, z), (0, 1, 0)))
    # On the bunny: triangle centroids, facing up, sideways and down.
    a, b, c = verts[bunny[:, 0]], verts[bunny[:, 1]], verts[bunny[:, 2]]
    n = np.cross(b - a, c - a)
    area = np.linalg.norm(n, axis=1)
    n = n / area[:, None]
    mid = (a + b + c) / 3.0
    for label, want in [("bunny, top", n[:, 1]), ("bunny, side (-z)", -n[:, 2]), ("bunny, underside", -n[:, 1])]:
        score = np.where(area > np.median(area), want, -np.inf)
        i = int(np.argmax(score))
        pts.append((label, tuple(mid[i]), tuple(n[i])))
    return pts


def main():
    spb = int(sys.argv[1]) if len(sys.argv) > 1 else 1 << 16
    batches = int(sys.argv[2]) if len(sys.argv) > 2 else 8
    verts, groups, mtl_of, mats = read_scene(os.path.join(ROOT, "scenes", "bunny_room.obj"))
    scene_dict = {"type": "scene", "integrator": {"type": "path", "max_depth": 64, "rr_depth": 1000}}
    tmp = tempfile.mkdtemp()
    for g, faces in groups.items():
        m = mats[mtl_of[g]]
        path = os.path.join(tmp, g + ".obj")
        write_obj(path, verts, faces)
        shape = {
            "type": "obj",
            "filename": path,
            "face_normals": True,
            "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["Kd"]}}},
        }
        if "Ke" in m:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [k / math.pi for k in m["Ke"]]}}
        scene_dict[g] = shape
    scene = mi.load_dict(scene_dict)
    pts = points(verts, groups)
    out = []
    for label, x, nrm in pts:
        x, nrm = np.array(x), np.array(nrm, dtype=float)
        nrm /= np.linalg.norm(nrm)
        sensor = mi.load_dict({
            "type": "radiancemeter",
            "origin": (x + 1e-3 * nrm).tolist(),
            "direction": (-nrm).tolist(),
            "film": {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spb},
        })
        vals = []
        for k in range(batches):
            img = mi.render(scene, sensor=sensor, spp=spb, seed=k)
            vals.append(np.array(img).reshape(-1)[:3])
        vals = np.array(vals)
        mean, err = vals.mean(0), vals.std(0, ddof=1) / math.sqrt(batches)
        print(label, mean, err, flush=True)
        out.append((label, x, nrm, mean, err))
    data = os.path.join(ROOT, "tests", "data")
    with open(os.path.join(data, "bunny_room_points.csv"), "w") as f:
        f.write("label,x,y,z,nx,ny,nz\n")
        for label, x, nrm, _, _ in out:
            f.write(f"{label.replace(',', ';')},{x[0]:.6f},{x[1]:.6f},{x[2]:.6f},{nrm[0]:.6f},{nrm[1]:.6f},{nrm[2]:.6f}\n")
    with open(os.path.join(data, "bunny_room_points_mitsuba.csv"), "w") as f:
        f.write("label,x,y,z,nx,ny,nz,radiance_R,radiance_G,radiance_B,stderr_R,stderr_G,stderr_B\n")
        for label, x, nrm, mean, err in out:
            f.write(f"{label.replace(',', ';')},{x[0]:.6f},{x[1]:.6f},{x[2]:.6f},{nrm[0]:.6f},{nrm[1]:.6f},{nrm[2]:.6f},"
                    + ",".join(f"{v:.6e}" for v in list(mean) + list(err)) + "\n")


def compare(at_out):
    ref = list(csv.DictReader(open(os.path.join(ROOT, "tests", "data", "bunny_room_points_mitsuba.csv"))))
    at = list(csv.DictReader(open(at_out)))
    within_u = within_it = total = 0
    for a, r in zip(at, ref):
        for c in "RGB":
            u, it = float(a[f"u_{c}"]) / math.pi, float(a[f"uhat_{c}"]) / math.pi
            est, est_it = float(a[f"estimate_{c}"]) / math.pi, float(a[f"uhat_estimate_{c}"]) / math.pi
            m, s3 = float(r[f"radiance_{c}"]), 3.0 * float(r[f"stderr_{c}"])
            du, dit = abs(u - m), abs(it - m)
            total += 1
            within_u += du <= est + s3
            within_it += dit <= est_it + s3
            print(f"{r['label']:<28} {c}  reference {m:.4e}  u_n off {du / m:6.1%} (estimate {est / m:6.1%})"
                  f"  û_n off {dit / m:6.1%} (estimate {est_it / m:6.1%})  3σ {s3 / m:.1%}")
    print(f"{within_u} of {total} values u_n and {within_it} of {total} values û_n within their estimate + 3σ")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--compare":
        compare(sys.argv[2])
    else:
        main()
