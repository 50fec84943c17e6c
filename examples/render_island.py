"""Renders the island on every rank of the MPI job, spread over the ranks
(each holds only its part), and writes the image on rank 0.

    mpirun -np 4 python3 examples/render_island.py [out.png] [WIDTHxHEIGHT] [SPP]

Needs the module on the path: PYTHONPATH=build/python (docs/library.md).
"""
import sys

from mpi4py import MPI

import ferry

out = sys.argv[1] if len(sys.argv) > 1 else "island.png"
width, height = (int(v) for v in (sys.argv[2] if len(sys.argv) > 2 else "480x270").split("x"))
spp = int(sys.argv[3]) if len(sys.argv) > 3 else 4

session = ferry.Session(comm=MPI.COMM_WORLD, size=(width, height), spp=spp, threads=1)
session.load("builtin:island")
image = session.render()  # (height, width, 3) float32 on rank 0, None elsewhere
stats = session.stats
if session.rank == 0:
    ferry.write_image(out, image)
    print(f"render_island: {session.size} ranks, {width}x{height} at {spp} spp, "
          f"{stats['rays_traced']:,} rays traced, {stats['rays_forwarded']:,} forwarded, "
          f"{stats['seconds']:.2f} s; wrote {out}")
