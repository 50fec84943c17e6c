#!/usr/bin/env python3
"""Regenerates tests/corpus/bsdf: a small valid pbrt-v3 tabulated BSDF
(`.bsdf`, see src/io/fourier_bsdf_file.h) and malformed variants of it, each
wrong in one way. src/io/fourier_bsdf_file_test.cpp checks each file's
message. Plain Python (struct), no packages.

Run from anywhere: python3 tests/corpus/make_bsdf_corpus.py
"""
import os
import struct

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bsdf")

MU = [-1.0, -0.5, 0.0, 0.5, 1.0]


def table(magic=b"SCATFUN", version=1, flags=1, n_mu=None, n_coeffs=None, m_max=2,
          channels=1, bases=1, eta=1.0, mu=None, entries=None, coeffs=None, cut=None):
    """A table reflecting like a Lambertian surface of albedo 0.5 (a0 =
    0.5 |mu_i| / pi where mu_i and mu_o are on opposite sides), one extra
    zero coefficient per entry so that series have length 2."""
    mu = MU if mu is None else mu
    n = len(mu)
    cdf, offsets, values = [], [], []
    for o in range(n):
        running = 0.0
        row = []
        for i in range(n):
            a0 = 0.5 * abs(mu[i]) / 3.14159265 if mu[i] * mu[o] < 0 else 0.0
            row.append(running)  # (not the spline's integral: only the reader reads these)
            running += a0 * 0.5
            offsets.append((len(values), 2))
            values += [a0, 0.0]
        cdf += row
    if entries is not None:
        for k, v in entries.items():
            offsets[k] = v
    if coeffs is not None:
        values = coeffs
    head = magic + bytes([version])
    head += struct.pack("<6i", flags, n if n_mu is None else n_mu,
                        len(values) if n_coeffs is None else n_coeffs, m_max, channels, bases)
    head += struct.pack("<3i", 0, 0, 0) + struct.pack("<f", eta) + struct.pack("<4f", 0, 0, 0, 0)
    assert len(head) == 64
    body = struct.pack("<%df" % n, *mu) + struct.pack("<%df" % len(cdf), *cdf)
    for off, length in offsets:
        body += struct.pack("<2i", off, length)
    body += struct.pack("<%df" % len(values), *values)
    data = head + body
    return data if cut is None else data[:cut]


FILES = {
    "valid.bsdf": table(),
    "empty.bsdf": b"",
    "truncated_header.bsdf": table(cut=20),
    "wrong_magic.bsdf": table(magic=b"SCATFUX"),
    "version_2.bsdf": table(version=2),
    "harmonic_extrapolation.bsdf": table(flags=3),
    "textured.bsdf": table(bases=2),
    "two_channels.bsdf": table(channels=2),
    # nMu^2 * 12 overflows 64 bits when multiplied carelessly.
    "huge_nmu.bsdf": table(n_mu=0x7FFFFFFF),
    "huge_ncoeffs.bsdf": table(n_coeffs=0x7FFFFFFF),
    "negative_ncoeffs.bsdf": table(n_coeffs=-5),
    "truncated_data.bsdf": table(cut=64 + 4 * 5 + 10),
    "offset_out_of_range.bsdf": table(entries={7: (1000, 2)}),
    "offset_negative.bsdf": table(entries={3: (-8, 2)}),
    "offset_overflow.bsdf": table(entries={3: (0x7FFFFFFF, 0x7FFFFFFF)}),
    "series_too_long.bsdf": table(entries={3: (0, 3)}),
    "mu_not_increasing.bsdf": table(mu=[-1.0, 0.5, 0.0, 0.5, 1.0]),
    "nan_coefficient.bsdf": table(coeffs=[float("nan")] * 50),
}


def main():
    os.makedirs(HERE, exist_ok=True)
    for name, data in FILES.items():
        with open(os.path.join(HERE, name), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
