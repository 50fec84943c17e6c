// A small text file (JSON manifests, transfer functions) read whole. Only a
// regular file is read: a directory or a missing file is the file's error
// (InputError naming it and `what` it was to be), never a stream exception.
#pragma once

#include <string>
#include <string_view>

namespace ferry {

std::string readTextFile(const std::string& path, std::string_view what);

}  // namespace ferry
