#!/usr/bin/env python3
"""The bathroom's worst blocks, each with a render that changes one thing
(docs/fidelity.md, "The bathroom's worst blocks").

Renders the scene as given and with one change at a time, at 300x190 (as
bench/fidelity), and prints Ferry / reference (luminance of block means) in
the regions that hold the ten worst blocks:

  as given         the scene
  wood flat        the counters' wood texture (a stand-in in this copy)
                   replaced by its own mean colour
  coat off         the counters' glossy coat off (bois_ "Ks" 0)
  balance          MIS by the balance heuristic (--mis-heuristic balance)
  by power         lights chosen by power alone (--light-choice power)
  bdpt's weights   both: pbrt-v3's bdpt weighs its strategies so. The image
                   differs in expectation only where pbrt-v3's mirrored
                   emitters show a BSDF sample their dark side.

Then the metal fitting's worst block converged (a crop at 16x the samples,
three seeds).
Then it traces the camera's rays (bathroom_scene.py) to find which faces
of the walls under the window the big mirror's blocks show, and prints
Ferry / reference on each face seen directly and through the mirror, as
given and with bdpt's weights.

  /usr/bin/python3 bench/bathroom_experiments.py [--ferry build/ferry] [--spp 256]

About 8 minutes on 2 cores at 256 spp.
"""
import atexit, os, shutil, subprocess, sys, tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bathroom_scene
from bathroom_scene import H, W, camera_ray, read_image as read

ap = bathroom_scene.arguments(spp=256)
ap.add_argument("--threads", type=int, default=0)
ap.add_argument("--step", type=int, default=2, help="trace every STEP-th pixel of the crops")
args = ap.parse_args()
scene_dir, reference = bathroom_scene.paths(args)
RW, RH = 300, 190  # the render size; the reference is brought to it by 4x4 means
LUM = np.array([0.2126, 0.7152, 0.0722])
REGIONS = [  # name, (x0, x1, y0, y1) as fractions, y down
    ("hand mirror (4 of the 10 worst)", (0.28, 0.30, 0.81, 0.83)),
    ("big mirror (5 of the 10 worst)", (0.33, 0.39, 0.08, 0.10)),
    ("metal fitting (1 of the 10 worst)", (0.72, 0.74, 0.32, 0.34)),
    ("whole image", (0.0, 1.0, 0.0, 1.0)),
]


def srgb_mean(path):
    a = read(path)
    return np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4).reshape(-1, 3).mean(0)


work = tempfile.mkdtemp(prefix="bathroom-experiments-")
atexit.register(shutil.rmtree, work, True)
for d in ("geometry", "bsdfs", "spds", "textures"):
    os.symlink(os.path.join(scene_dir, d), os.path.join(work, d))
text = open(os.path.join(scene_dir, "bathroom.pbrt")).read()


def variant(name, old, new):
    """The scene with `old` (which must occur once) replaced by `new`."""
    if text.count(old) != 1:
        sys.exit(f"bathroom_experiments: '{old}' occurs {text.count(old)} times in bathroom.pbrt")
    path = os.path.join(work, name + ".pbrt")
    open(path, "w").write(text.replace(old, new))
    return path


wood = '"color" "imagemap" "string filename" "textures/WoodFine0016_L.png"'
mean = srgb_mean(os.path.join(scene_dir, "textures", "WoodFine0016_L.png"))
coat = '"texture Kd" "wood"\n        "rgb Ks" [ 0.2 0.2 0.2 ]'
given = os.path.join(scene_dir, "bathroom.pbrt")
variants = [  # name, scene, render flags
    ("as given", given, []),
    ("wood flat", variant("wood-flat", wood, '"color" "constant" "rgb value" [%g %g %g]' % tuple(mean)), []),
    ("coat off", variant("coat-off", coat, coat.replace('"rgb Ks" [ 0.2 0.2 0.2 ]', '"rgb Ks" [ 0 0 0 ]')), []),
    ("balance", given, ["--mis-heuristic", "balance"]),
    ("by power", given, ["--light-choice", "power"]),
    ("bdpt's weights", given, ["--mis-heuristic", "balance", "--light-choice", "power"]),
]

ref_full = read(reference)
ref = ref_full.reshape(RH, H // RH, RW, W // RW, 3).mean((1, 3))
images = {}
for name, scene, flags in variants:
    out = os.path.join(work, name.replace(" ", "-").replace("'", "") + ".exr")
    subprocess.run([args.ferry, "render", scene, "--size", f"{RW}x{RH}", "--spp", str(args.spp),
                    "--threads", str(args.threads), "-q", "-o", out] + flags, check=True)
    images[name] = read(out)


def region(image, box):
    x0, x1, y0, y1 = box
    return float((image[int(y0 * RH):int(round(y1 * RH)), int(x0 * RW):int(round(x1 * RW))] @ LUM).mean())


print(f"Ferry / reference, {RW}x{RH}, {args.spp} spp (wood flat: the texture's mean, "
      f"linear rgb {mean[0]:.3f} {mean[1]:.3f} {mean[2]:.3f})")
print("| region | reference | " + " | ".join(v[0] for v in variants) + " |")
print("|---|---:|" + "---:|" * len(variants))
for label, box in REGIONS:
    r = region(ref, box)
    print(f"| {label} | {r:.3f} | " + " | ".join(f"{region(images[v[0]], box) / r:.3f}" for v in variants) + " |")

# The metal fitting's worst block (columns 220-221, rows 62-63 at 300x190):
# its highlight converged: a crop of the film around it (those pixels; light
# paths start from the crop's samples only, so it equals the whole render in
# expectation, not bit for bit) at 16x the samples, three seeds.
fitting = (0.70, 0.76, 0.30, 0.36)  # its crop starts at column 210, row 58
r = float((ref[62:64, 220:222] @ LUM).mean())
ratios = []
for seed in (1, 2, 3):
    out = os.path.join(work, f"fitting-{seed}.exr")
    subprocess.run([args.ferry, "render", given, "--size", f"{RW}x{RH}", "--spp", str(16 * args.spp),
                    "--crop", ",".join(map(str, fitting)), "--seed", str(seed),
                    "--threads", str(args.threads), "-q", "-o", out], check=True)
    ratios.append(float((read(out)[4:6, 10:12] @ LUM).mean()) / r)
print(f"\nThe metal fitting's worst block at {16 * args.spp} spp, seeds 1-3: Ferry / reference "
      + ", ".join(f"{q:.3f}" for q in ratios) + f" (reference {r:.3f}; as given at {args.spp} spp: "
      f"{float((images['as given'][62:64, 220:222] @ LUM).mean()) / r:.3f})")

# What the big mirror's worst blocks show, seen directly and through it: the
# faces of the walls mesh (mesh_00065) under the window, by plane.
scene = bathroom_scene.Scene(scene_dir)
views = {"directly": (0.60, 0.86, 0.0, 0.24), "big mirror": (0.33, 0.39, 0.07, 0.11)}
groups = {}
for label, (x0, x1, y0, y1) in views.items():
    for py in range(int(y0 * RH), int(round(y1 * RH)), args.step):
        for px in range(int(x0 * RW), int(round(x1 * RW)), args.step):
            o, d = camera_ray(px * (W // RW) + W // RW / 2, py * (H // RH) + H // RH / 2)
            h = scene.hit(o, d)
            if h is not None and h[1][1] == "mirror" and label == "big mirror":
                d = d - 2 * (d @ h[2]) * h[2]
                h = scene.hit(h[0], d)
            if h is None or h[1] != ("mesh_00065", "mur_blanc"):
                continue
            p, _, n = h
            axis = int(np.argmax(np.abs(n)))
            key = f"{'xyz'[axis]} = {p[axis]:.1f}"
            g = groups.setdefault(key, {}).setdefault(label, [0, 0.0, 0.0, [], 0.0])
            g[0] += 1
            g[1] += ref[py, px] @ LUM
            g[2] += images["as given"][py, px] @ LUM
            g[3].append(np.degrees(np.arcsin(abs(d @ n))))
            g[4] += images["bdpt's weights"][py, px] @ LUM
print("\nThe walls mesh's faces the big mirror's blocks show (mesh_00065, mur_blanc):")
print("| plane | seen | pixels | reference | Ferry / reference: as given | bdpt's weights | view's angle to the face |")
print("|---|---|---:|---:|---:|---:|---:|")
for key, by_view in sorted(groups.items()):
    if "big mirror" not in by_view:
        continue
    for label in views:
        if label in by_view:
            n, r, f, angles, b = by_view[label]
            print(f"| {key} | {label} | {n} | {r / n:.3f} | {f / r:.3f} | {b / r:.3f} | {np.median(angles):.0f} degrees |")
