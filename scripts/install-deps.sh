#!/usr/bin/env bash
# Installs everything Ferry needs to build, test and benchmark, from Debian's
# packages. Safe to run again: it only calls apt-get when something is missing.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libembree-dev embree-tools      # Embree 3 (and its pathtracer tutorial, our benchmark baseline)
  libtbb-dev                      # threads inside a rank
  libopenmpi-dev openmpi-bin      # ranks
  libstb-dev libtinyobjloader-dev libtinygltf-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libopenexr-dev
  libopenvdb-dev                  # .vdb volumes (io/volumes/vdb_file.cpp)
  libnanovdb-dev zlib1g-dev       # .nvdb volumes (io/volumes/nanovdb_file.cpp)
  libvtk9-dev                     # .vti and .vtp files (io/volumes/vtk_file.cpp)
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format                    # tests/format_test.sh keeps the tree clean under .clang-format
  libxxhash-dev                   # XXH64 digests of part files and checkpoints (core/hash64)
  clang libclang-rt-14-dev        # scripts/fuzz.sh: libFuzzer with ASan and UBSan (docs/fuzzing.md)
  libcpp-httplib-dev              # ferry view: the HTTP server on rank 0
  chromium chromium-driver        # tests/viewer_test.sh: the viewer page in a headless browser
  python3 python3-matplotlib   # python3-matplotlib: the plots of bench/paper-eval
  python3-openimageio             # bench/bathroom_*.py read the EXR reference
  linux-perf                      # bench/distribution_profile.sh: perf record of each rank
  valgrind                        # bench/instructions_per_path.sh: callgrind's instruction counts
  pybind11-dev python3-dev python3-numpy python3-mpi4py  # the Python module (python/)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
