#!/usr/bin/env python3
"""The bathroom's window pane seen directly and through the mirror, in the
reference and in Ferry's render (docs/fidelity.md, "The region left of the
mirror").

The pane (mesh_00062, pbrt-v3's default matte under the area light) is two
quads, A (x > 1.674) and B (x < 1.674). A Lambertian surface sends the same
radiance every way, so through the mirror (Kr 0.9) each quad must read at
most 0.9 of what it reads seen directly. For each renderer this prints the
mean radiance of each quad in both views and their ratio. Pixels are
classified by tracing the camera's rays (pinhole; the renders use the
scene's thin lens) through the scene's meshes here, in numpy.

  /usr/bin/python3 bench/bathroom_mirror_check.py [--ferry build/ferry] [--spp 64]

With --by-material IMAGE (a 300x190 render, as bench/fidelity makes), it
instead splits the squared error of IMAGE's 2x2 blocks against the reference
(bench/fidelity's figure, its excluded window left out) by what each block's
centre ray meets first (through mirrors: "mirror>" and what the mirror
shows): blocks, share of the squared error, both means. About 14,000 rays:
about half an hour on one core.
"""
import os, subprocess, sys, tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bathroom_scene
from bathroom_scene import H, W, camera_ray, read_image

ap = bathroom_scene.arguments(spp=64)
ap.add_argument("--step", type=int, default=3, help="trace every STEP-th pixel")
ap.add_argument("--by-material", metavar="IMAGE", help="split IMAGE's squared error by material")
args = ap.parse_args()
scene_dir, reference = bathroom_scene.paths(args)
# The mirror's top left (the worst blocks) and the pane seen directly.
MIRROR_CROP = (0.28, 0.40, 0.0, 0.08)
DIRECT_CROP = (0.62, 0.84, 0.0, 0.10)


scene = bathroom_scene.Scene(scene_dir)
hit = scene.hit


def quad(p):
    if not 16.3 < p[1] < 18.3:
        return None
    if -0.2 < p[0] < 1.2:
        return "B"
    if 2.2 < p[0] < 5.6:
        return "A"
    return None


def pixels(crop):
    x0, x1, y0, y1 = crop
    return range(int(round(x0 * W)), int(round(x1 * W))), range(int(round(y0 * H)), int(round(y1 * H)))


def render(crop, out):
    cmd = [args.ferry, "render", os.path.join(scene_dir, "bathroom.pbrt"), "--size", f"{W}x{H}",
           "--crop", ",".join(map(str, crop)), "--spp", str(args.spp), "-q", "-o", out]
    subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
    return read_image(out)


ref = read_image(reference)
if args.by_material:
    image = read_image(args.by_material)
    BX, BY = 150, 95  # 2x2 blocks of the 300x190 comparison: 8x8 reference pixels
    ref_blocks = ref.reshape(BY, 8, BX, 8, 3).mean((1, 3))
    image_blocks = image.reshape(BY, image.shape[0] // BY, BX, image.shape[1] // BX, 3).mean((1, 3))
    groups, total, kept = {}, 0.0, 0
    for by in range(BY):
        for bx in range(BX):
            cx, cy = (bx + 0.5) / BX, (by + 0.5) / BY
            if 0.315 <= cx <= 0.35 and cy <= 0.05:  # bench/fidelity's excluded window
                continue
            o, d = camera_ray(bx * 8 + 4, by * 8 + 4)
            label = []
            h = hit(o, d)
            while h is not None and len(label) < 3:
                p, (mesh, mat), n = h
                label.append(mat or mesh)
                if mat != "mirror":
                    break
                d = d - 2 * (d @ n) * n
                h = hit(p, d)
            key = "mirror>" + label[1] if label[:1] == ["mirror"] and len(label) > 1 else (label or ["(nothing)"])[0]
            e = float(((image_blocks[by, bx] - ref_blocks[by, bx]) ** 2).sum())
            g = groups.setdefault(key, [0, 0.0, 0.0, 0.0])
            g[0] += 1
            g[1] += e
            g[2] += ref_blocks[by, bx].mean()
            g[3] += image_blocks[by, bx].mean()
            total += e
            kept += 1
    print("| first surface | blocks | share of the squared error | reference mean | image mean | image / reference |")
    print("|---|---:|---:|---:|---:|---:|")
    for key, (n, e, r, f) in sorted(groups.items(), key=lambda kv: -kv[1][1])[:12]:
        print(f"| {key} | {n} ({100 * n / kept:.1f} %) | {100 * e / total:.1f} % | {r / n:.3f} | {f / n:.3f} | {f / r:.3f} |")
    sys.exit(0)
tmp = tempfile.mkdtemp()
ferry = {"mirror": render(MIRROR_CROP, os.path.join(tmp, "mirror.exr")),
         "direct": render(DIRECT_CROP, os.path.join(tmp, "direct.exr"))}
sums = {}
for view, crop in (("mirror", MIRROR_CROP), ("direct", DIRECT_CROP)):
    xs, ys = pixels(crop)
    for py in ys[:: args.step]:
        for px in xs[:: args.step]:
            o, d = camera_ray(px, py)
            h = hit(o, d)
            if h is None:
                continue
            p, (mesh, mat), n = h
            if view == "mirror":
                if mat != "mirror":
                    continue
                h = hit(p, d - 2 * (d @ n) * n)
                if h is None:
                    continue
                p, (mesh, mat), n = h
            if mesh != "mesh_00062" or quad(p) is None:
                continue
            key = (view, quad(p))
            s = sums.setdefault(key, [0, np.zeros(3), np.zeros(3)])
            s[0] += 1
            s[1] += ref[py, px]
            s[2] += ferry[view][py - ys[0], px - xs[0]]

lum = np.array([0.2126, 0.7152, 0.0722])
print("| quad | pixels direct / mirror | reference: direct, mirror, mirror/direct | Ferry: direct, mirror, mirror/direct |")
print("|---|---:|---:|---:|")
for q in ("A", "B"):
    nd, rd, fd = sums[("direct", q)]
    nm, rm, fm = sums[("mirror", q)]
    r_d, r_m, f_d, f_m = (float(lum @ (x / n)) for x, n in ((rd, nd), (rm, nm), (fd, nd), (fm, nm)))
    print(f"| {q} | {nd} / {nm} | {r_d:.3f}, {r_m:.3f}, **{r_m / r_d:.2f}** | {f_d:.3f}, {f_m:.3f}, **{f_m / f_d:.2f}** |")
