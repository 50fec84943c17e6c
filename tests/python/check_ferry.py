"""Checks the ferry Python module (tests/python_test.sh runs it).

    check_ferry.py FERRY_BINARY single    # one process: images, verbs, errors
    check_ferry.py FERRY_BINARY ranks     # under mpirun: a sub-communicator renders

single: ferry.render equals `ferry render ... -o x.pfm` bit for bit; a mesh
from numpy is borrowed (no mesh bytes owned) unless copy=True; the session's
verbs; errors raise ferry.Error. ranks: the even ranks of COMM_WORLD render
on their own communicator while the odd ones keep exchanging messages among
themselves, never blocked; the image equals the one-process image.
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

import ferry


def fail(message):
    print(f"FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def read_pfm(path):
    with open(path, "rb") as f:
        if f.readline().strip() != b"PF":
            fail(f"{path}: not a colour PFM")
        width, height = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(height, width, 3)[::-1].astype(np.float32)  # PFM rows run bottom to top


def terrain(n=64):
    """A height field: (N, 3) float32 positions and (M, 3) uint32 indices."""
    x, z = np.meshgrid(np.linspace(-1, 1, n + 1), np.linspace(-1, 1, n + 1))
    y = 0.25 * np.sin(6 * x) * np.cos(5 * z)
    positions = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    a = (j * (n + 1) + i).ravel()
    quads = np.stack([a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2], axis=-1)
    return positions, quads.reshape(-1, 3).astype(np.uint32)


def terrain_session(comm=None, copy=False):
    s = ferry.Session(comm=comm, size=(64, 48), spp=2, seed=5, threads=1)
    positions, indices = terrain()
    ground = s.add_material(name="ground", color=(0.6, 0.5, 0.3))
    s.place_mesh(positions, indices, material=ground, copy=copy)
    s.add_sun((0.3, 1, 0.4), (3, 3, 3))
    s.set_environment((0.4, 0.5, 0.7))
    s.set_camera(look_from=(0, 1.6, 2.4), look_at=(0, 0, 0), fov=40)
    return s, positions, indices


def strip_session(pieces, comm=None, distribution="replicated"):
    """The terrain cut into strips of rows; `pieces` says which strips this session adds."""
    s = ferry.Session(comm=comm, size=(64, 48), spp=2, seed=5, threads=1, distribution=distribution)
    positions, indices = terrain()
    ground = s.add_material(name="ground", color=(0.6, 0.5, 0.3))
    strips = np.array_split(indices, 3)
    for p in pieces:
        s.place_mesh(positions, strips[p], material=ground, name=f"strip {p}")
    s.add_sun((0.3, 1, 0.4), (3, 3, 3))
    s.set_environment((0.4, 0.5, 0.7))
    s.set_camera(look_from=(0, 1.6, 2.4), look_at=(0, 0, 0), fov=40)
    return s


def single(binary):
    work = tempfile.mkdtemp(prefix="ferry-python-")
    # The one call against the command, bit for bit.
    image = ferry.render("builtin:cornell", size=(64, 48), spp=4, seed=1)
    if image.shape != (48, 64, 3) or image.dtype != np.float32:
        fail(f"ferry.render: shape {image.shape} dtype {image.dtype}")
    pfm = os.path.join(work, "x.pfm")
    subprocess.run([binary, "render", "builtin:cornell", "--size", "64x48", "--spp", "4",
                    "--seed", "1", "-q", "-o", pfm], check=True)
    command = read_pfm(pfm)
    if not np.array_equal(image, command):
        fail(f"ferry.render differs from `ferry render -o x.pfm` "
             f"(max difference {np.abs(image - command).max()})")
    print("  ferry.render equals `ferry render -o x.pfm` bit for bit (64x48, 4 spp, seed 1)")

    # A mesh from numpy: borrowed, not copied; copy=True copies.
    s, positions, indices = terrain_session()
    borrowed = s.render()
    stats = s.stats
    array_bytes = positions.nbytes + indices.nbytes
    if stats["mesh_bytes_owned"] != 0 or stats["mesh_bytes_borrowed"] != array_bytes:
        fail(f"borrowed mesh: owned {stats['mesh_bytes_owned']}, borrowed "
             f"{stats['mesh_bytes_borrowed']} (arrays: {array_bytes} bytes)")
    c, _, _ = terrain_session(copy=True)
    copied = c.render()
    if c.stats["mesh_bytes_owned"] < array_bytes or c.stats["mesh_bytes_borrowed"] != 0:
        fail(f"copied mesh: owned {c.stats['mesh_bytes_owned']}")
    if not np.array_equal(borrowed, copied):
        fail("a borrowed mesh renders another image than a copied one")
    if not borrowed.mean() > 0.01:
        fail(f"the terrain image is black (mean {borrowed.mean()})")
    print(f"  numpy mesh: {array_bytes} bytes borrowed, none owned (copy=True: owned); "
          f"same image; {stats['rays_traced']} rays")

    # Camera, size and spp change without reloading; the image follows.
    s.set_camera(look_from=(0, 2.5, 0.1), look_at=(0, 0, 0), fov=50)
    s.set_image_size(32, 24)
    s.set_spp(1)
    top = s.render(frames=2)
    if top.shape != (24, 32, 3):
        fail(f"after set_image_size(32, 24): shape {top.shape}")
    ferry.write_image(os.path.join(work, "top.png"), top)
    if os.path.getsize(os.path.join(work, "top.png")) < 100:
        fail("write_image wrote no PNG")

    # A volume from numpy.
    v = ferry.Session(size=(32, 24), spp=1, threads=1)
    z, y, x = np.mgrid[0:16, 0:16, 0:16]
    v.add_volume(((x + y + z) / 45).astype(np.float32), color_map="viridis")
    v.add_sun((0.4, 1, 0.6))
    v.set_environment((0.5, 0.5, 0.5))
    volume = v.render()
    if not np.isfinite(volume).all() or volume[12, 16].tolist() == volume[0, 0].tolist():
        fail("the volume is not in the image")
    v.set_volume_look("inferno", 4)
    if np.array_equal(v.render(), volume):
        fail("set_volume_look('inferno', 4) did not restyle the volume")

    # Curves from numpy: 12 strands of 2 Bezier segments across the view.
    c = ferry.Session(size=(32, 24), spp=1, threads=1)
    points = np.array([[-0.6 + 0.1 * s, -0.6 + 0.2 * k, 0.1 * np.sin(k + s)]
                       for s in range(12) for k in range(7)], dtype=np.float32)
    indices = np.array([7 * s + 3 * j for s in range(12) for j in range(2)], dtype=np.uint32)
    c.place_curves(points, indices, widths=0.05, type="cylinder",
                   material=c.add_material(color=(0.9, 0.4, 0.1)))
    c.set_environment((0.5, 0.5, 0.5))
    c.set_camera(look_from=(0, 0, 3), look_at=(0, 0, 0), fov=40)
    fibres = c.render()
    if not np.isfinite(fibres).all() or abs(fibres - 0.5).max() < 0.05:
        fail("the curves are not in the image")
    try:
        c.place_curves(points, np.array([83], dtype=np.uint32), widths=0.05)
        fail("a segment past the last control point was accepted")
    except ferry.Error as e:
        if "needs control points up to 86" not in str(e):
            fail("place_curves: unexpected message: " + str(e))

    # AOVs by name: arrays like the colour, the albedo of the command's EXR channels.
    a = ferry.Session(size=(64, 48), spp=4, seed=1, threads=1,
                      settings={"aov": "albedo,normal,depth"})
    a.load("builtin:cornell")
    colour = a.render()
    albedo, normal, depth = a.aov("albedo"), a.aov("normal"), a.aov("depth")
    if albedo.shape != (48, 64, 3) or normal.shape != (48, 64, 3) or depth.shape != (48, 64, 1):
        fail(f"aov shapes {albedo.shape} {normal.shape} {depth.shape}")
    if not np.array_equal(colour, image):
        fail("the colour with AOVs is not the colour without")
    if not (albedo.min() >= 0 and albedo.max() <= 1 and (depth > 0).mean() > 0.5):
        fail(f"albedo {albedo.min()}..{albedo.max()}, {(depth > 0).mean():.0%} of the pixels hit")
    pfm = os.path.join(work, "aov.pfm")
    subprocess.run([binary, "render", "builtin:cornell", "--size", "64x48", "--spp", "4",
                    "--seed", "1", "-q", "--aov", "albedo", "-o", pfm], check=True)
    if not np.array_equal(albedo, read_pfm(os.path.join(work, "aov.albedo.pfm"))):
        fail("session.aov('albedo') differs from `ferry render --aov albedo`'s aov.albedo.pfm")
    try:
        a.aov("uv")
        fail("aov('uv') not asked for, but no error")
    except ferry.Error as e:
        if "albedo, normal, depth" not in str(e):
            fail(f"aov('uv'): {e!r} does not list the AOVs rendered")
    print("  session.aov(): albedo, normal, depth as (H, W, C) arrays; the albedo is the "
          "command's aov.albedo.pfm")

    # VTK data: its arrays with their ranges, and set_field renders another.
    vti = os.path.join(work, "two.vti")
    with open(vti, "w") as f:
        ramp = " ".join(str(i % 4) for i in range(64))
        f.write('<?xml version="1.0"?><VTKFile type="ImageData" version="0.1">'
                '<ImageData WholeExtent="0 3 0 3 0 3" Origin="0 0 0" Spacing="1 1 1">'
                '<Piece Extent="0 3 0 3 0 3"><PointData Scalars="ramp">'
                f'<DataArray type="Float32" Name="ramp" format="ascii">{ramp}</DataArray>'
                f'<DataArray type="Float32" Name="flat" format="ascii">{"1 " * 64}</DataArray>'
                '</PointData></Piece></ImageData></VTKFile>')
    d = ferry.Session(size=(32, 24), spp=1, threads=1)
    d.load(vti)
    first = d.render()
    fields = d.fields()
    if [(f["name"], f["range"], f["shown"]) for f in fields] != [
            ("ramp", (0.0, 3.0), True), ("flat", (1.0, 1.0), False)]:
        fail(f"session.fields(): {fields}")
    d.set_field("flat")
    if np.array_equal(first, d.render()) or not d.fields()[1]["shown"]:
        fail("set_field('flat') did not render the other array")
    print("  session.fields() lists a .vti's arrays with their ranges; set_field renders another")

    # Errors are ferry.Error, with the reason.
    for call, expected in [
        (lambda: ferry.render("/nonexistent/scene.pbrt"), "/nonexistent/scene.pbrt"),
        (lambda: ferry.Session().add_material(type="velvet"), "velvet"),
        (lambda: ferry.Session().place_mesh(np.zeros((3, 2), np.float32), np.zeros((1, 3), np.uint32)),
         "positions"),
        (lambda: ferry.Session().add_instance(3), "object 3"),
        (lambda: ferry.render("builtin:cornell", size=(0, 10)), "image size"),
    ]:
        try:
            call()
            fail(f"no error (expected one naming {expected!r})")
        except ferry.Error as e:
            if expected not in str(e):
                fail(f"error {e!r} does not name {expected!r}")
    print("  camera, size and spp changed without reloading; a volume; 5 bad calls raise ferry.Error")


def ranks(binary):
    from mpi4py import MPI
    world = MPI.COMM_WORLD
    color = world.rank % 2
    sub = world.Split(color, world.rank)
    if color == 0:
        if sub.size != 3:
            fail(f"run with 5 ranks (3 render), not {world.size}")
        s, _, _ = terrain_session(comm=sub)
        if s.size != sub.size or s.rank != sub.rank:
            fail(f"session rank {s.rank}/{s.size}, communicator {sub.rank}/{sub.size}")
        image = s.render()
        if sub.rank == 0:
            alone, _, _ = terrain_session()
            if not np.array_equal(image, alone.render()):
                fail(f"{sub.size} ranks of a sub-communicator render another image than one process")
            print(f"  {sub.size} of {world.size} ranks rendered on their own communicator: "
                  f"the one-process image, {s.stats['rays_forwarded']} rays forwarded")
        elif image is not None:
            fail("an image on a rank other than 0")
        # In situ: each renderer holds one strip of the terrain (distributed data).
        d = strip_session([sub.rank], comm=sub, distribution="distributed")
        pieces = d.render()
        if sub.rank == 0:
            if not np.array_equal(pieces, strip_session(range(sub.size)).render()):
                fail("distributed strips render another image than the terrain assembled")
            print(f"  each of {sub.size} renderers holding one strip (distributed): the assembled "
                  f"image, {d.stats['rays_forwarded']} rays forwarded")
        # One renderer's bad input fails the render on every renderer, with its message.
        bad = ferry.Session(comm=sub, size=(16, 12), threads=1)
        bad.load("/nonexistent/piece.obj" if sub.rank == 1 else "builtin:cornell")
        try:
            bad.render()
            fail(f"rank {sub.rank} rendered though rank 1's scene is missing")
        except ferry.Error as e:
            if "on rank 1" not in str(e) or "/nonexistent/piece.obj" not in str(e):
                fail(f"rank {sub.rank}: {e!r} does not name rank 1 and its file")
        if sub.rank == 0:
            print("  rank 1's missing scene: ferry.Error naming rank 1 and the file on every renderer")
    else:
        # The other ranks keep working among themselves while the renderers render.
        total = sub.allreduce(1)
        for _ in range(100):
            total = sub.allreduce(total) // sub.size
        if world.rank == 1:
            print(f"  the {sub.size} other rank(s) kept exchanging messages meanwhile")
    sub.Free()
    world.Barrier()


if __name__ == "__main__":
    {"single": single, "ranks": ranks}[sys.argv[2]](sys.argv[1])
