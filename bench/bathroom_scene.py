"""The bathroom benches' shared parts (bathroom_mirror_check.py,
bathroom_experiments.py): their common arguments and paths, reading an
image, and the bathroom's geometry in numpy: every mesh of
../shared/scenes/bathroom with its named material (the scene's `Scale -1 1 1`
applied), the nearest hit of a ray among them, and the camera's ray through a
pixel of the reference's 1200x760 film (pinhole; the renders use the scene's
thin lens). About 0.1 s a ray: brute force over every triangle.
"""
import argparse, os, re

import numpy as np
import OpenImageIO as oiio

W, H = 1200, 760
HERE = os.path.dirname(os.path.abspath(__file__))


def arguments(spp):
    """A parser with --ferry, --shared and --spp (default `spp`); add the script's own."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--ferry", default=os.path.join(HERE, "..", "build", "ferry"))
    ap.add_argument("--shared", default=os.path.join(HERE, "..", "..", "shared"))
    ap.add_argument("--spp", type=int, default=spp)
    return ap


def paths(args):
    """The scene's directory and the reference render under args.shared."""
    return (os.path.join(args.shared, "scenes", "bathroom"),
            os.path.join(args.shared, "references", "bathroom.exr"))


def read_image(path):
    """An image's RGB as float32, rows top down."""
    return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :3]


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode()
    nv = int(re.search(r"element vertex (\d+)", head).group(1))
    nf = int(re.search(r"element face (\d+)", head).group(1))
    props = re.findall(r"property float (\w+)", head)
    v = np.frombuffer(data, dtype="<f4", count=nv * len(props), offset=end).reshape(nv, len(props))
    off = end + nv * len(props) * 4
    faces = []
    for _ in range(nf):
        n = data[off]
        off += 1
        faces.append(np.frombuffer(data, dtype="<i4", count=n, offset=off))
        off += 4 * n
    return dict(zip(props, v.T)), np.array(faces)


class Scene:
    """Every triangle of the bathroom at scene_dir, with its (mesh, material)."""

    def __init__(self, scene_dir):
        text = open(os.path.join(scene_dir, "bathroom.pbrt")).read()
        material, self.items = None, []
        for line in text.splitlines():
            if line.strip().startswith("#"):
                continue
            m = re.match(r'\s*NamedMaterial\s+"([^"]+)"', line)
            if m:
                material = m.group(1)
            m = re.search(r'"(geometry/mesh_\d+)\.ply"', line)
            if m:
                self.items.append((m.group(1).split("/")[1], material))
        corners, owner = [], []
        for k, (name, _) in enumerate(self.items):
            v, f = read_ply(os.path.join(scene_dir, "geometry", name + ".ply"))
            p = np.stack([-v["x"], v["y"], v["z"]], 1).astype(np.float64)
            corners.append(p[f])
            owner += [k] * len(f)
        corners = np.concatenate(corners)
        self.owner = np.array(owner)
        self.v0 = corners[:, 0]
        self.e1 = corners[:, 1] - self.v0
        self.e2 = corners[:, 2] - self.v0

    def hit(self, o, d):
        """(point, (mesh, material), unit geometric normal) of the nearest hit, or None."""
        v0, e1, e2 = self.v0, self.e1, self.e2
        pv = np.cross(d, e2)
        det = (e1 * pv).sum(1)
        with np.errstate(all="ignore"):
            inv = 1 / det
            tv = o - v0
            u = (tv * pv).sum(1) * inv
            q = np.cross(tv, e1)
            w = (q @ d) * inv
            t = (e2 * q).sum(1) * inv
            ok = (np.abs(det) > 1e-12) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 1e-4)
        if not ok.any():
            return None
        i = np.flatnonzero(ok)[np.argmin(t[ok])]
        n = np.cross(e1[i], e2[i])
        return o + t[i] * d, self.items[self.owner[i]], n / np.linalg.norm(n)


def camera_ray(px, py):
    """Origin and unit direction of the ray through (px, py) of the 1200x760 film."""
    # pbrt's perspective camera: LookAt 0 23 30  10.2 5 0  0 1 0, fov 50 on
    # the shorter side; raster x runs along pbrt's camera +x (up x view).
    eye, at, up = np.array([0, 23, 30.0]), np.array([10.2, 5, 0.0]), np.array([0, 1, 0.0])
    view = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(up, view)
    right /= np.linalg.norm(right)
    true_up = np.cross(view, right)
    tan = np.tan(np.radians(50) / 2)
    sx = (-1 + 2 * (px + 0.5) / W) * W / H
    sy = 1 - 2 * (py + 0.5) / H
    d = view + (right * sx + true_up * sy) * tan
    return eye, d / np.linalg.norm(d)
