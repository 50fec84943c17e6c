# Sourced by the multi-rank image tests (distributed, partition, replay) after
# `ferry=$1 source_dir=$2`: mpirun settings, a work folder removed on exit,
# the image comparison and the stats invariants.
source "$source_dir/tests/tools/mpi_env.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
compare="python3 $source_dir/tests/tools/compare_pfm.py"
check_stats() { python3 "$source_dir/tests/tools/check_stats.py" "$1"; }
