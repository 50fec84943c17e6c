// The viewer's page: plain HTML and JavaScript, no library, served by
// ViewerServer at GET /. It long-polls /frame.png for each new frame, reads
// /stats after each, and posts camera and settings changes (orbit, pan,
// zoom and fly with mouse, touch and keys; named views; size, samples per
// frame, depth, exposure; quit).
#pragma once

#include <string>

namespace ferry {

const std::string& viewerPage();

}  // namespace ferry
