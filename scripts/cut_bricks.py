#!/usr/bin/env python3
"""Cuts a raw volume into the bricks a "bricks:" manifest lists (docs/volumes.md,
"Natively distributed bricks"): each brick file holds its cells' samples and the
one-sample ghost layer around them, as a simulation that already holds its
piece would write it.

  python3 scripts/cut_bricks.py VOLUME.raw X,Y,Z FORMAT BRICK OUTDIR [--ranks N]

FORMAT is uint8, uint16 or float32 (little-endian, x fastest). Writes
OUTDIR/brick_K.raw and OUTDIR/volume.json; --ranks N sets each brick's rank
to K modulo N (without it the renderer deals them out the same way).
"""
import argparse
import json
import os

import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("volume")
    p.add_argument("dims")
    p.add_argument("format", choices=["uint8", "uint16", "float32"])
    p.add_argument("brick", type=int)
    p.add_argument("outdir")
    p.add_argument("--ranks", type=int, default=0)
    a = p.parse_args()
    nx, ny, nz = (int(v) for v in a.dims.split(","))
    dtype = {"uint8": "<u1", "uint16": "<u2", "float32": "<f4"}[a.format]
    grid = np.fromfile(a.volume, dtype=dtype).reshape(nz, ny, nx)
    os.makedirs(a.outdir, exist_ok=True)
    bricks = []
    k = 0
    for z0 in range(0, nz, a.brick):
        for y0 in range(0, ny, a.brick):
            for x0 in range(0, nx, a.brick):
                lo = [x0, y0, z0]
                hi = [min(x0 + a.brick, nx), min(y0 + a.brick, ny), min(z0 + a.brick, nz)]
                first = [max(v - 1, 0) for v in lo]
                last = [min(h, n - 1) for h, n in zip(hi, (nx, ny, nz))]
                piece = grid[first[2]:last[2] + 1, first[1]:last[1] + 1, first[0]:last[0] + 1]
                name = f"brick_{k}.raw"
                np.ascontiguousarray(piece).tofile(os.path.join(a.outdir, name))
                entry = {"file": name, "lo": lo, "hi": hi}
                if a.ranks > 0:
                    entry["rank"] = k % a.ranks
                bricks.append(entry)
                k += 1
    manifest = {"dims": [nx, ny, nz], "format": a.format, "bricks": bricks}
    if a.format == "float32":
        manifest["range"] = [float(grid.min()), float(grid.max())]
    with open(os.path.join(a.outdir, "volume.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    print(f"{k} bricks in {a.outdir}/volume.json")


if __name__ == "__main__":
    main()
