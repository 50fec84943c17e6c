#include "mpi/launcher.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace ferry {
namespace {

// Clears the launcher's variables for the test's lifetime and puts back what
// was there (the MPI unit tests run this binary under mpirun).
class LauncherEnvironment {
 public:
  LauncherEnvironment() {
    for (const char* name : kNames) {
      const char* value = std::getenv(name);
      saved_.push_back(value ? std::optional<std::string>(value) : std::nullopt);
      unsetenv(name);
    }
  }
  ~LauncherEnvironment() {
    for (size_t i = 0; i < std::size(kNames); ++i) {
      if (saved_[i])
        setenv(kNames[i], saved_[i]->c_str(), 1);
      else
        unsetenv(kNames[i]);
    }
  }

 private:
  static constexpr const char* kNames[] = {
      "OMPI_COMM_WORLD_RANK", "PMIX_RANK",      "PMI_RANK", "SLURM_PROCID",
      "OMPI_COMM_WORLD_SIZE", "PMI_SIZE",       "PMI_FD",   "PMIX_NAMESPACE",
      "HYDI_CONTROL_FD",      "MPI_LOCALNRANKS"};
  std::vector<std::optional<std::string>> saved_;
};

TEST(Launcher, StartedByHandIsRankZeroWithoutALauncher) {
  LauncherEnvironment clean;
  EXPECT_FALSE(startedByMpiLauncher());
  EXPECT_EQ(launcherRank(), 0);
}

TEST(Launcher, EachLaunchersRankVariableIsRead) {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK", "SLURM_PROCID"}) {
    LauncherEnvironment clean;
    setenv(name, "3", 1);
    EXPECT_TRUE(startedByMpiLauncher()) << name;
    EXPECT_EQ(launcherRank(), 3) << name;
  }
}

TEST(Launcher, AJobVariableAloneMeansALauncherAtRankZero) {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMI_FD", "PMIX_NAMESPACE",
                           "HYDI_CONTROL_FD", "MPI_LOCALNRANKS"}) {
    LauncherEnvironment clean;
    setenv(name, "4", 1);
    EXPECT_TRUE(startedByMpiLauncher()) << name;
    EXPECT_EQ(launcherRank(), 0) << name;
  }
}

}  // namespace
}  // namespace ferry
