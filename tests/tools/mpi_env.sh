# Sourced by the multi-rank tests: mpirun as root, more ranks than cores,
# and no network interfaces but loopback.
export OMPI_ALLOW_RUN_AS_ROOT=1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
# Each rank gets one thread: the cores are oversubscribed already.
mpirun_n() { local n=$1; shift; mpirun --oversubscribe -np "$n" "$@"; }
