#!/usr/bin/env python3
"""Checks Ferry's layering: which folders of src/ each folder may include.

Usage: check_layering.py SRC_DIR NAME=DEP,DEP ... (one argument per folder, as
src/CMakeLists.txt declares them with ferry_module). Fails (exit 1, one line
per offence, file:line) when
  - a source file includes "other/header.h" from a folder its folder does not
    declare (unit tests, *_test.cpp, are exempt: they link every library);
  - Embree's headers appear outside src/trace/, MPI's outside src/mpi/, OpenVDB's and VTK's outside src/io/
    (tests included);
  - the declared dependencies form a cycle, or name an unknown folder;
  - a folder with sources is not declared.
A folder's subfolders (io/pbrt/, io/gltf/, ...) belong to it.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
THIRD_PARTY_HOMES = {"embree": "trace", "mpi": "mpi", "httplib": "viewer", "openvdb": "io", "vtk": "io"}


def third_party_of(header):
    if header.startswith("embree3/") or header.startswith("embree4/"):
        return "embree"
    if header == "httplib.h":
        return "httplib"
    if header.startswith("openvdb/") or header.startswith("nanovdb/"):
        return "openvdb"
    if header.startswith("vtk") and header.endswith(".h"):
        return "vtk"
    if header in ("mpi.h", "mpi.hpp") or header.startswith("openmpi/"):
        return "mpi"
    return None


def main():
    src = sys.argv[1]
    layers = {}
    for arg in sys.argv[2:]:
        name, _, deps = arg.partition("=")
        layers[name] = set(d for d in deps.split(",") if d)
    errors = []
    for name, deps in layers.items():
        for d in deps - set(layers):
            errors.append(f"src/CMakeLists.txt: {name} depends on unknown folder {d}")
    # Cycles (depth-first search over the declared graph).
    state = {}

    def visit(n, stack):
        if state.get(n) == "done":
            return
        if state.get(n) == "open":
            errors.append("src/CMakeLists.txt: dependency cycle " + " -> ".join(stack + [n]))
            return
        state[n] = "open"
        for d in sorted(layers.get(n, ())):
            visit(d, stack + [n])
        state[n] = "done"

    for n in sorted(layers):
        visit(n, [])

    for folder in sorted(os.listdir(src)):
        path = os.path.join(src, folder)
        if not os.path.isdir(path) or folder == "third_party":
            continue
        files = sorted(
            os.path.relpath(os.path.join(d, f), path)
            for d, _, names in os.walk(path)
            for f in names
            if f.endswith((".h", ".cpp")))
        if files and folder not in layers:
            errors.append(f"src/{folder}: not declared with ferry_module in src/CMakeLists.txt")
            continue
        allowed = layers.get(folder, set()) | {folder}
        for f in files:
            is_test = f.endswith("_test.cpp") or f.endswith("_test_util.h")
            with open(os.path.join(path, f), encoding="utf-8", errors="replace") as text:
                for line_number, line in enumerate(text, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    kind, header = m.groups()
                    where = f"src/{folder}/{f}:{line_number}"
                    lib = third_party_of(header)
                    if lib and THIRD_PARTY_HOMES[lib] != folder:
                        errors.append(f"{where}: includes {header}: {lib} belongs in src/{THIRD_PARTY_HOMES[lib]}/")
                    if kind == '"' and "/" in header and not is_test:
                        top = header.split("/", 1)[0]
                        if top in layers and top not in allowed:
                            errors.append(
                                f"{where}: includes {header}, but src/{folder} does not depend on src/{top} "
                                f"(src/CMakeLists.txt)")
    for e in errors:
        print(e, file=sys.stderr)
    if errors:
        print(f"check_layering: {len(errors)} layering error(s)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
