// The `ferry` command: subcommands render, view, info and partition.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <exception>

#include "app/info_command.h"
#include "app/partition_command.h"
#include "app/render_command.h"
#include "app/view_command.h"
#include "comm/in_process_communicator.h"
#include "core/error.h"
#include "core/floating_point_mode.h"
#include "mpi/launcher.h"
#include "mpi/mpi_communicator.h"

namespace {

// Runs `command` on the ranks of the MPI job when a launcher started this
// process, else as the one rank of a job of one without starting MPI
// (mpi/launcher.h: MPI's singleton start is most of a small render's time).
// Alone, abortAll throws (in-process) instead of ending the job: it is an
// error on the only rank.
template <typename Command>
int runOnRanks(int* argc, char*** argv, Command command) {
  using namespace ferry;
  if (startedByMpiLauncher()) {
    MpiCommunicator comm(argc, argv);
    comm.reportFatalSignals();
    return command(comm);
  }
  InProcessGroup alone(1);
  try {
    return command(alone.communicator(0));
  } catch (const GroupAborted& e) {
    fmt::print(stderr, "ferry: error: {}\n", e.reason());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ferry;
  // Before any thread or TBB call, so that every thread shades alike.
  useFixedFloatingPointMode();
  CLI::App app{
      "Ferry: a data-parallel path tracer. Renders scenes spread over MPI ranks that each hold\n"
      "part of the scene, forwarding rays between them (Wald and Parker, \"Data Parallel Path\n"
      "Tracing in Object Space\")."};
  app.require_subcommand(1);
  RenderOptions renderOptions;
  InfoOptions infoOptions;
  PartitionCommandOptions partitionOptions;
  ViewOptions viewOptions;
  addRenderCommand(app, renderOptions);
  addViewCommand(app, viewOptions);
  addInfoCommand(app, infoOptions);
  addPartitionCommand(app, partitionOptions);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return launcherRank() == 0 ? app.exit(e) : 0;  // --help
    // Under mpirun every rank parses the same flags: rank 0 speaks, and the
    // others wait for it (else mpirun may end rank 0 before it has spoken).
    auto report = [&](const Communicator& comm) {
      if (comm.isRoot()) fmt::print(stderr, "ferry: error: {} (see ferry --help)\n", e.what());
      comm.barrier();
      return e.get_exit_code();
    };
    return runOnRanks(&argc, &argv, report);
  }
  try {
    if (app.got_subcommand("render"))
      return runOnRanks(&argc, &argv,
                        [&](const Communicator& comm) { return runRender(renderOptions, comm); });
    if (app.got_subcommand("view"))
      return runOnRanks(&argc, &argv,
                        [&](const Communicator& comm) { return runView(viewOptions, comm); });
    if (app.got_subcommand("info")) return runInfo(infoOptions);
    if (app.got_subcommand("partition")) return runPartition(partitionOptions);
  } catch (const InputError& e) {
    fmt::print(stderr, "ferry: error: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "ferry: internal error: {}\n", e.what());
    return 2;
  }
  return 0;
}
