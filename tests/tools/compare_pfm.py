#!/usr/bin/env python3
"""Compares two PFM images pixel by pixel.

Passes when every channel satisfies |a - b| <= rel * max(|a|, |b|) + abs,
except in at most --outliers (a fraction) of the pixels.
Prints the worst pixel and how many exceed the tolerance; on failure writes a
difference image (PFM) next to the second image for a person to look at.
"""
import argparse
import struct
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            raise SystemExit(f"{path}: not a PFM file")
        channels = 3 if kind == b"PF" else 1
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        endian = "<" if scale < 0 else ">"
        count = width * height * channels
        data = struct.unpack(f"{endian}{count}f", f.read(4 * count))
    return width, height, channels, data


def write_pfm(path, width, height, data):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (width, height))
        f.write(struct.pack(f"<{len(data)}f", *data))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reference")
    parser.add_argument("candidate")
    parser.add_argument("--rel", type=float, default=1e-4)
    parser.add_argument("--abs", type=float, default=1e-6)
    parser.add_argument("--outliers", type=float, default=0.0,
                        help="fraction of pixels allowed beyond the tolerance")
    args = parser.parse_args()
    wa, ha, ca, a = read_pfm(args.reference)
    wb, hb, cb, b = read_pfm(args.candidate)
    if (wa, ha, ca) != (wb, hb, cb):
        print(f"size differs: {wa}x{ha}x{ca} vs {wb}x{hb}x{cb}")
        return 1
    bad = 0
    bad_pixels = set()
    worst = (0.0, -1)
    diff = []
    for i, (x, y) in enumerate(zip(a, b)):
        d = abs(x - y)
        diff.append(d)
        limit = args.rel * max(abs(x), abs(y)) + args.abs
        if d > limit or d != d:
            bad += 1
            bad_pixels.add(i // ca)
        excess = d / limit if limit > 0 else 0.0
        if excess > worst[0]:
            worst = (excess, i)
    total = len(a)
    pixels = wa * ha
    print(f"{args.candidate}: {bad} of {total} values ({len(bad_pixels)} of {pixels} pixels) beyond "
          f"tolerance; worst {worst[0]:.3g}x the limit at index {worst[1]}")
    if bad_pixels:
        print("  pixels beyond tolerance (x, y): " +
              ", ".join(f"({p % wa}, {p // wa})" for p in sorted(bad_pixels)[:10]))
    if len(bad_pixels) > args.outliers * pixels:
        write_pfm(args.candidate + ".diff.pfm", wa, ha, diff)
        i = worst[1]
        print(f"  reference {a[i]!r} candidate {b[i]!r}; difference image: {args.candidate}.diff.pfm")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
