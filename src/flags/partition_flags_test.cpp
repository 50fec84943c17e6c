// The partition flags are defined once (partition_flags.h) for `ferry
// partition` and `ferry render`: the same words give both the same options,
// and every bad value is refused naming its flag.
#include "flags/partition_flags.h"

#include <gtest/gtest.h>
#include <CLI/CLI.hpp>

#include "app/partition_command.h"
#include "app/render_command.h"
#include "core/error.h"

namespace ferry {
namespace {

const std::vector<std::string> kAllFlags = {"--partitioner",
                                            "ray-guided",
                                            "--keep-objects-whole",
                                            "--replication-budget",
                                            "0.1",
                                            "--mesh-proxies",
                                            "8",
                                            "--instance-proxies",
                                            "16",
                                            "--max-part",
                                            "2",
                                            "--max-proxies",
                                            "0",
                                            "--ray-paths",
                                            "100"};

// Parses `args` (after the scene) with the subcommand as the program defines it.
template <typename Options, typename Add>
Options parse(Add add, const char* name, std::vector<std::string> args) {
  CLI::App app;
  Options options;
  add(app, options);
  args.insert(args.begin(), {name, "builtin:cornell"});
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector in reverse order
  app.parse(args);
  return options;
}

PartitionCommandOptions parsePartition(const std::vector<std::string>& args) {
  return parse<PartitionCommandOptions>(addPartitionCommand, "partition", args);
}
RenderOptions parseRender(const std::vector<std::string>& args) {
  return parse<RenderOptions>(addRenderCommand, "render", args);
}

TEST(PartitionFlags, BothCommandsReadTheSameFlagsIntoTheSameOptions) {
  const PartitionerOptions a = checkedPartitionerOptions(parsePartition(kAllFlags).partition);
  const PartitionerOptions b = checkedPartitionerOptions(parseRender(kAllFlags).partition);
  for (const PartitionerOptions& p : {a, b}) {
    EXPECT_TRUE(p.keepObjectsWhole);
    EXPECT_DOUBLE_EQ(p.replicationBudget, 0.1);
    EXPECT_EQ(p.meshProxies, 8);
    EXPECT_EQ(p.instanceProxies, 16);
    EXPECT_DOUBLE_EQ(p.maxPart, 2);
    EXPECT_EQ(p.maxProxies, 0u);
    EXPECT_EQ(p.rayPaths, 100u);
  }
  EXPECT_EQ(parsePartition(kAllFlags).partition.partitioner, "ray-guided");
  EXPECT_EQ(parseRender(kAllFlags).partition.partitioner, "ray-guided");
}

TEST(PartitionFlags, DefaultsAreThePartitionersOwn) {
  const PartitionerOptions defaults;
  for (const PartitionerOptions& p : {checkedPartitionerOptions(parsePartition({}).partition),
                                      checkedPartitionerOptions(parseRender({}).partition)}) {
    EXPECT_EQ(p.keepObjectsWhole, defaults.keepObjectsWhole);
    EXPECT_EQ(p.replicationBudget, defaults.replicationBudget);
    EXPECT_EQ(p.meshProxies, defaults.meshProxies);
    EXPECT_EQ(p.instanceProxies, defaults.instanceProxies);
    EXPECT_EQ(p.maxPart, defaults.maxPart);
    EXPECT_EQ(p.maxProxies, defaults.maxProxies);
    EXPECT_EQ(p.rayPaths, defaults.rayPaths);
  }
  EXPECT_TRUE(parseRender({}).partition.partitioner.empty());  // best on more than one rank
}

TEST(PartitionFlags, BadValuesAreRefusedNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{"--replication-budget", "1.5"}, "--replication-budget 1.5"},
      {{"--replication-budget", "-0.1"}, "--replication-budget -0.1"},
      {{"--max-part", "0.5"}, "--max-part 0.5"},
      {{"--ray-paths", "0"}, "--ray-paths 0"},
      {{"--mesh-proxies", "0"}, "--mesh-proxies 0"},
      {{"--mesh-proxies", "5000"}, "--mesh-proxies 5000"},
      {{"--instance-proxies", "2000"}, "--instance-proxies 2000"},
  };
  for (const auto& [args, expected] : bad) {
    for (const PartitionFlags& flags :
         {parsePartition(args).partition, parseRender(args).partition}) {
      try {
        checkedPartitionerOptions(flags);
        ADD_FAILURE() << expected << " was accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      }
    }
  }
}

}  // namespace
}  // namespace ferry
