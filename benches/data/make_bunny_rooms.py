#!/usr/bin/env python3
"""Writes the bunny rooms: a 550 mm Cornell-like room (open front, the Cornell
box's materials, a 130 mm square light cut out of the ceiling) with the
Stanford bunny, scaled to about 220 mm, resting on the middle of the floor.

    npm install bunny@1.0.1 && node -e 'require("fs").writeFileSync("bunny.json",
        JSON.stringify(require("bunny")))'
    pip install fast-simplification numpy
    python3 make_bunny_rooms.py OUT_DIR BUNNY_JSON 100 200 400 600 1000 2000 3674

A count below 3 674 decimates the bunny to about that many triangles
(fast-simplification, quadric error); 3 674 keeps it whole (bunny_room.obj).
"""
import json, sys, numpy as np, fast_simplification
b = json.load(open(sys.argv[2]))
V = np.array(b['positions'], float); F = np.array(b['cells'], int)
def bunny(target):
    v, f = V, F
    if target < len(F):
        v, f = fast_simplification.simplify(V.astype(np.float32), F, target_reduction=1 - target / len(F))
        v = v.astype(float)
    # scale 22 (about 220 mm wide), centre on the floor
    v = v * 22.0
    v[:, 1] -= v[:, 1].min()
    v[:, 0] += 275 - 0.5 * (v[:, 0].min() + v[:, 0].max())
    v[:, 2] += 275 - 0.5 * (v[:, 2].min() + v[:, 2].max())
    return v, f
def room(path, target):
    S = 550.0; L0, L1 = 210.0, 340.0
    out = ["# Bunny room: a 550 mm Cornell-like room (Cornell box materials, open front) with a",
           "# 130 mm square light cut out of the ceiling and the Stanford bunny (npm package `bunny`,",
           "# public domain; the Stanford 3D Scanning Repository's scan) resting on the floor,",
           "# made by benches/data/make_bunny_rooms.py.", "mtllib bunny_room.mtl"]
    verts = []
    def vid(p):
        verts.append(p); return len(verts)
    def quad(ps, mat, group):
        ids = [vid(p) for p in ps]
        out.append(f"g {group}"); out.append(f"usemtl {mat}")
        out.append(f"f {ids[0]} {ids[1]} {ids[2]}"); out.append(f"f {ids[0]} {ids[2]} {ids[3]}")
    quad([(0,0,0),(0,0,S),(S,0,S),(S,0,0)], "white", "floor")       # normal +y
    quad([(0,0,S),(0,S,S),(S,S,S),(S,0,S)], "white", "back_wall")   # normal -z
    quad([(0,0,0),(0,S,0),(0,S,S),(0,0,S)], "green", "right_wall")  # normal +x
    quad([(S,0,0),(S,0,S),(S,S,S),(S,S,0)], "red", "left_wall")     # normal -x
    # ceiling ring around the light (normal -y)
    o = [vid(p) for p in [(0,S,0),(S,S,0),(S,S,S),(0,S,S)]]
    i = [vid(p) for p in [(L0,S,L0),(L1,S,L0),(L1,S,L1),(L0,S,L1)]]
    out.append("g ceiling"); out.append("usemtl white")
    for k in range(4):
        a, bb = o[k], o[(k+1)%4]; c, d = i[k], i[(k+1)%4]
        out.append(f"f {a} {d} {c}"); out.append(f"f {a} {bb} {d}")
    out.append("g light"); out.append("usemtl light")
    out.append(f"f {i[0]} {i[1]} {i[2]}"); out.append(f"f {i[0]} {i[2]} {i[3]}")
    v, f = bunny(target)
    base = len(verts)
    for p in v: verts.append(tuple(p))
    out.append("g bunny"); out.append("usemtl white")
    for t in f: out.append(f"f {t[0]+base+1} {t[1]+base+1} {t[2]+base+1}")
    with open(path, "w") as fh:
        fh.write("\n".join(out[:5]) + "\n")
        for p in verts: fh.write("v %.6f %.6f %.6f\n" % p)
        fh.write("\n".join(out[5:]) + "\n")
    print(path, len(f), "bunny triangles")
MTL = open(sys.argv[1] + "/bunny_room.mtl", "w")
MTL.write("""# The Cornell box's materials (B. Bitterli, "Rendering Resources", 2016, scene "Cornell box").
newmtl white
Kd 0.725 0.71 0.68

newmtl red
Kd 0.63 0.065 0.05

newmtl green
Kd 0.14 0.45 0.091

newmtl light
Kd 0.78 0.78 0.78
Ke 17 12 4
""")
MTL.close()
for t in [int(x) for x in sys.argv[3:]]:
    name = "bunny_room" if t >= len(F) else f"bunny_room_{t}"
    room(f"{sys.argv[1]}/{name}.obj", t)
