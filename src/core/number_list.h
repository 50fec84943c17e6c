// Comma-separated numbers as command-line flags take them ("x,y,z",
// "x0,x1,y0,y1"): one parser, so that every such flag accepts and refuses
// the same texts.
#pragma once

#include <span>
#include <string>

namespace ferry {

// Fills `out` from `text`: exactly out.size() finite numbers separated by
// single commas, nothing else. False for anything else (the caller names its
// flag in the error it raises).
bool parseNumberList(const std::string& text, std::span<float> out);

}  // namespace ferry
