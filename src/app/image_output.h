// Writing the rendered image: the format follows the extension (PNG tone
// mapped; EXR and PFM linear), always through a temporary file and a rename.
#pragma once

#include <string>
#include <vector>

#include "core/math.h"
#include "render/frame_buffer.h"

namespace ferry {

// Throws InputError before any rendering if `path` cannot be written
// (unknown extension, missing directory).
void checkOutputPath(const std::string& path);
void writeRenderedImage(const std::string& path, int width, int height,
                        const std::vector<Vec3f>& linear, const ToneMapping& toneMapping);

}  // namespace ferry
