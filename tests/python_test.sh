#!/usr/bin/env bash
# The Python module (build/python, Debian's python3 with numpy and mpi4py):
#  1. one process: ferry.render equals `ferry render -o x.pfm` bit for bit; a
#     numpy mesh is borrowed, not copied; the session's verbs; ferry.Error.
#  2. mpirun -np 5 python3: three ranks render on a communicator split off
#     COMM_WORLD (the one-process image) while the other two keep working;
#     then each of the three holds one strip of the terrain (distributed
#     data): the image of the terrain assembled; a missing scene on one
#     renderer fails every renderer with ferry.Error naming that rank.
#  3. examples/render_island.py on 3 ranks, as the README runs it.
set -euo pipefail
ferry=$(realpath "$1")
source_dir=$(realpath "$2")
source "$source_dir/tests/tools/mpi_env.sh"
python=/usr/bin/python3
build=$(dirname "$ferry")
export PYTHONPATH="$build/python"
if ! ls "$build"/python/ferry*.so > /dev/null 2>&1; then
  echo "python_test: no module in $build/python (configured with -DFERRY_BUILD_PYTHON=OFF?)" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "== one process"
"$python" "$source_dir/tests/python/check_ferry.py" "$ferry" single
echo "== mpirun -np 5: a sub-communicator of 3 renders"
timeout 120 mpirun --oversubscribe -np 5 "$python" "$source_dir/tests/python/check_ferry.py" "$ferry" ranks
echo "== examples/render_island.py on 3 ranks"
(cd "$work" && timeout 120 mpirun --oversubscribe -np 3 "$python" "$source_dir/examples/render_island.py" \
  island.png 96x54 1)
[ -s "$work/island.png" ] || { echo "FAIL: render_island.py wrote no image" >&2; exit 1; }
echo "python_test: all passed"
