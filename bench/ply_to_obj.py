#!/usr/bin/env python3
"""Converts a PLY triangle mesh (ascii or binary) to a bare OBJ: positions and
faces only, one material-less shape. Used only by bench/pathtracer_vs_embree.sh
so that Ferry (OBJ loader) and Embree's pathtracer (OBJ loader) read the same
geometry; extra vertex properties (the bunny's confidence and intensity) are
skipped. Polygons are written as they are (both loaders triangulate).

    python3 bench/ply_to_obj.py IN.ply OUT.obj
"""
import struct
import sys

TYPES = {  # PLY scalar type -> struct code
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B",
    "short": "h", "int16": "h", "ushort": "H", "uint16": "H",
    "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}


def read_header(f):
    if f.readline().strip() != b"ply":
        sys.exit("not a PLY file")
    fmt, elements = None, []  # elements: [name, count, [(name, type | (count type, item type))]]
    while True:
        line = f.readline()
        if not line:
            sys.exit("PLY header has no end_header")
        words = line.decode("ascii", "replace").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append([words[1], int(words[2]), []])
        elif words[0] == "property":
            if words[1] == "list":
                elements[-1][2].append((words[4], (words[2], words[3])))
            else:
                elements[-1][2].append((words[2], words[1]))
        elif words[0] == "end_header":
            return fmt, elements


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    with open(sys.argv[1], "rb") as f:
        fmt, elements = read_header(f)
        endian = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
        if fmt != "ascii" and endian is None:
            sys.exit(f"unsupported PLY format {fmt}")
        tokens = iter(f.read().split()) if fmt == "ascii" else None
        data = None if fmt == "ascii" else f.read()
        offset = 0

        def scalar(t):
            nonlocal offset
            if tokens is not None:
                return float(next(tokens)) if TYPES[t] in "fd" else int(next(tokens))
            code = endian + TYPES[t]
            (v,) = struct.unpack_from(code, data, offset)
            offset += struct.calcsize(code)
            return v

        vertices, faces = [], []
        for name, count, props in elements:
            for _ in range(count):
                row = {}
                for pname, ptype in props:
                    if isinstance(ptype, tuple):
                        n = scalar(ptype[0])
                        row[pname] = [scalar(ptype[1]) for _ in range(n)]
                    else:
                        row[pname] = scalar(ptype)
                if name == "vertex":
                    vertices.append((row["x"], row["y"], row["z"]))
                elif name == "face":
                    faces.append(row.get("vertex_indices", row.get("vertex_index")))
    with open(sys.argv[2], "w") as out:
        out.write(f"# converted from {sys.argv[1]} by bench/ply_to_obj.py\n")
        out.writelines(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in vertices)
        out.writelines("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces if len(face) >= 3)
    print(f"{sys.argv[2]}: {len(vertices)} vertices, {len(faces)} faces", file=sys.stderr)


if __name__ == "__main__":
    main()
