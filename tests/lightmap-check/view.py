"""Renders radcol's lightmapped Cornell box GLB with pyrender (OpenGL through
OSMesa, headless), an independent viewer: the README's right-hand image.

    radcol solve cornell --target-error 1e-3 --lightmap-size 2048 -o lm.glb
    python3 view.py        # writes pyrender.png

Needs `apt install libosmesa6` and `pip install pyrender "PyOpenGL>=3.1.7"
pillow` (pyrender pins PyOpenGL 3.1.0, whose OSMesa binding lacks the
context call it uses). Flat shading with full ambient light: the texture's
colours as they are, as the unlit material asks.
"""
import os
os.environ["PYOPENGL_PLATFORM"] = "osmesa"
import numpy as np, trimesh, pyrender
from PIL import Image
tm = trimesh.load("lm.glb", force="scene")
scene = pyrender.Scene(ambient_light=[1.0, 1.0, 1.0], bg_color=[0, 0, 0, 0])
for node_name in tm.graph.nodes_geometry:
    transform, geom = tm.graph[node_name]
    mesh = pyrender.Mesh.from_trimesh(tm.geometry[geom], smooth=False)
    scene.add(mesh, pose=transform)
# radcol's Cornell camera: eye (278, 273, -800) mm looking at (278, 273, 0), 39.3° vertical fov; metres here
cam = pyrender.PerspectiveCamera(yfov=np.radians(2 * np.degrees(np.arctan(12.5 / 35.0))), aspectRatio=640 / 480)
pose = np.eye(4)
# looking along +z: rotate 180° about y (pyrender cameras look along -z)
pose[:3, :3] = np.array([[-1, 0, 0], [0, 1, 0], [0, 0, -1]])
pose[:3, 3] = [0.278, 0.273, -0.800]
scene.add(cam, pose=pose)
r = pyrender.OffscreenRenderer(640, 480)
color, _ = r.render(scene, flags=pyrender.RenderFlags.FLAT)
Image.fromarray(color).save("pyrender.png")
print("ok", color.shape, color.mean())
