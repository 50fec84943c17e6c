#include "comm/communicator.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <utility>

namespace ferry {

CommunicationError::CommunicationError(std::string operation, int rank, const std::string& detail)
    : std::runtime_error(rank >= 0 ? fmt::format("{} on rank {}: {}", operation, rank, detail)
                                   : fmt::format("{}: {}", operation, detail)),
      operation_(std::move(operation)),
      rank_(rank) {}

std::string Communicator::failureMessage(bool failed, const std::string& message) const {
  if (sum(uint64_t(failed ? 1 : 0)) == 0) return "";
  // Gather every rank's message on rank 0, merge, and give the result to every rank.
  std::string mine = failed ? message : std::string();
  std::vector<int> lengths = gatherInt(int(mine.size()));
  std::vector<int> offsets(lengths.size(), 0);
  std::string all;
  if (isRoot()) {
    int total = 0;
    for (size_t r = 0; r < lengths.size(); ++r) {
      offsets[r] = total;
      total += lengths[r];
    }
    all.resize(total);
  }
  gatherBytes(mine.data(), int(mine.size()), all.data(), lengths, offsets);
  std::string merged;
  if (isRoot()) {
    std::vector<std::pair<std::string, std::vector<int>>> distinct;
    for (int r = 0; r < size(); ++r) {
      if (lengths[r] == 0) continue;
      std::string m = all.substr(offsets[r], lengths[r]);
      auto it = std::find_if(distinct.begin(), distinct.end(),
                             [&](const auto& d) { return d.first == m; });
      if (it == distinct.end())
        distinct.push_back({m, {r}});
      else
        it->second.push_back(r);
    }
    for (const auto& [m, ranks] : distinct) {
      if (!merged.empty()) merged += '\n';
      if (int(ranks.size()) == size() || size() == 1) {
        merged += m;
      } else {
        std::string list;
        for (int r : ranks) {
          if (!list.empty()) list += ',';
          list += std::to_string(r);
        }
        merged += fmt::format("on rank {}: {}", list, m);
      }
    }
    if (merged.empty()) merged = "a rank failed without a message";
  }
  uint64_t length = merged.size();
  broadcastBytes(std::as_writable_bytes(std::span(&length, 1)));
  merged.resize(length);
  broadcastBytes(std::as_writable_bytes(std::span(merged.data(), merged.size())));
  return merged;
}

bool Communicator::agreeOnFailure(bool failed, const std::string& message) const {
  const std::string merged = failureMessage(failed, message);
  if (merged.empty()) return false;
  if (isRoot()) {
    size_t begin = 0;
    while (begin <= merged.size()) {
      size_t end = merged.find('\n', begin);
      if (end == std::string::npos) end = merged.size();
      const std::string line = merged.substr(begin, end - begin);
      fmt::print(stderr, "ferry: error{}{}\n", line.rfind("on rank ", 0) == 0 ? " " : ": ", line);
      begin = end + 1;
    }
    std::fflush(stderr);
  }
  return true;
}

void Communicator::abortAll(const std::string& message, int code) const {
  abortEveryRank(message, code);
  std::terminate();  // an implementation that returned: end at least this process
}

}  // namespace ferry

namespace ferry {

void Communicator::throwMalformed(int from, size_t bytes, size_t headerBytes,
                                  size_t itemBytes) const {
  throw CommunicationError(
      "receive", rank(),
      fmt::format("a message of {} bytes from rank {} is not a {}-byte header and {}-byte items",
                  bytes, from, headerBytes, itemBytes));
}

}  // namespace ferry
