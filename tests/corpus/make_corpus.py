#!/usr/bin/env python3
"""Regenerates the binary files of the test corpus (tests/corpus/obj/*.png and
tests/corpus/images/*): small PNG textures and malformed images. Plain Python
(zlib + struct), no packages. The OBJ/MTL files are text, written by hand.

Run from anywhere: python3 tests/corpus/make_corpus.py
"""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OBJ = os.path.join(HERE, "obj")
IMAGES = os.path.join(HERE, "images")


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def png(width, height, color_type, rows, compressed=None):
    """color_type: 0 grey, 2 RGB, 4 grey+alpha, 6 RGBA; rows: bytes, top row first."""
    raw = b"".join(b"\x00" + r for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0)
    idat = zlib.compress(raw, 9) if compressed is None else compressed
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) +
            chunk(b"IEND", b""))


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def main():
    os.makedirs(OBJ, exist_ok=True)
    os.makedirs(IMAGES, exist_ok=True)

    # 4x4 RGB checker: red where (x + y) is even, blue elsewhere; row 0 is the top.
    red, blue = bytes([255, 0, 0]), bytes([0, 0, 255])
    checker = [b"".join(red if (x + y) % 2 == 0 else blue for x in range(4)) for y in range(4)]
    write(os.path.join(OBJ, "checker.png"), png(4, 4, 2, checker))
    # 4x4 grey mask without alpha: top two rows 255 (opaque), bottom two 0 (holes).
    mask = [bytes([255] * 4)] * 2 + [bytes([0] * 4)] * 2
    write(os.path.join(OBJ, "mask_grey.png"), png(4, 4, 0, mask))
    # 2x2 RGBA mask: white, alpha 255 0 / 128 64.
    rgba = [bytes([255, 255, 255, 255, 255, 255, 255, 0]),
            bytes([255, 255, 255, 128, 255, 255, 255, 64])]
    write(os.path.join(OBJ, "mask_rgba.png"), png(2, 2, 6, rgba))

    # Malformed images.
    gradient = [bytes((x * 7 + y * 13 + (x * y) % 5) % 256 for x in range(64 * 3)) for y in range(64)]
    whole = png(64, 64, 2, gradient, compressed=zlib.compress(b"".join(b"\x00" + r for r in gradient), 0))
    write(os.path.join(IMAGES, "truncated.png"), whole[: len(whole) // 2])
    # A 16000x16000 header (within the pixel limit) over a few bytes of data.
    write(os.path.join(IMAGES, "huge_header.png"),
          png(16000, 16000, 2, [], compressed=zlib.compress(b"\x00" * 16)))
    # 20000x20000 grey: over Ferry's pixel limit (stb would accept the header).
    write(os.path.join(IMAGES, "too_large.png"),
          png(20000, 20000, 0, [], compressed=zlib.compress(b"\x00" * 16)))
    # 100000x100000 RGB: beyond what stb accepts.
    write(os.path.join(IMAGES, "beyond_stb.png"),
          png(100000, 100000, 2, [], compressed=zlib.compress(b"\x00" * 16)))
    write(os.path.join(IMAGES, "empty.png"), b"")
    write(os.path.join(IMAGES, "not_an_image.png"), b"This is a text file, not a PNG.\n")
    write(os.path.join(IMAGES, "not_an_image.exr"), b"This is a text file, not an EXR.\n")
    # PFM: a header promising 1000x1000 RGB over 3 pixels of data.
    write(os.path.join(IMAGES, "lying_size.pfm"),
          b"PF\n1000 1000\n-1.0\n" + struct.pack("<9f", *range(9)))
    # A header promising less than the file holds.
    write(os.path.join(IMAGES, "extra_data.pfm"),
          b"PF\n1 1\n-1.0\n" + struct.pack("<6f", *range(6)))
    write(os.path.join(IMAGES, "bad_magic.pfm"), b"P6\n1 1\n255\n\x00\x00\x00")
    write(os.path.join(IMAGES, "bad_scale.pfm"), b"PF\n1 1\nabc\n" + struct.pack("<3f", 1, 2, 3))
    write(os.path.join(IMAGES, "zero_scale.pfm"), b"PF\n1 1\n0\n" + struct.pack("<3f", 1, 2, 3))
    write(os.path.join(IMAGES, "negative_width.pfm"), b"PF\n-4 1\n-1\n" + struct.pack("<3f", 1, 2, 3))
    write(os.path.join(IMAGES, "header_only.pfm"), b"PF\n2 2")
    write(os.path.join(IMAGES, "empty.pfm"), b"")
    # Good PFMs with known content: 2x1 little-endian RGB, and 1x2 big-endian grey.
    # Rows are stored bottom to top.
    write(os.path.join(IMAGES, "little_rgb.pfm"),
          b"PF\n2 1\n-1.0\n" + struct.pack("<6f", 0.5, 1.0, 2.0, -3.0, 4.25, 1e6))
    write(os.path.join(IMAGES, "big_grey.pfm"),
          b"Pf\n1 2\n1.0\n" + struct.pack(">2f", 0.25, 8.0))  # bottom 0.25, top 8


if __name__ == "__main__":
    main()
