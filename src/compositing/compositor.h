// Merging the ranks' partial frame buffers by parallel direct send (paper,
// Section 5.3): rank r owns a horizontal slice of the image, receives every
// other rank's pixels of that slice, sums them (in rank order, so the result
// does not depend on timing), scales, and, for PNG, tone maps its slice. The
// slices are then gathered on rank 0.
#pragma once

#include <cstdint>
#include <vector>

#include "comm/communicator.h"
#include "core/math.h"
#include "render/frame_buffer.h"

namespace ferry {

// Rows [first, last) of the slice rank `rank` owns.
void compositeSlice(int height, int ranks, int rank, int& firstRow, int& lastRow);

// The full linear image (sum of all ranks' buffers times `scale`) on rank 0;
// empty on the other ranks. Also returns bytes this rank sent.
std::vector<Vec3f> compositeLinear(const Communicator& comm, const FrameBuffer& partial,
                                   float scale, uint64_t& bytesSent);
// The exact fixed-point sums of all ranks' buffers (3 per pixel) on rank 0;
// empty elsewhere: what a checkpoint stores.
std::vector<int64_t> compositeFixed(const Communicator& comm, const FrameBuffer& partial,
                                    uint64_t& bytesSent);
// The AOVs' averages (the sums of all ranks' FrameBuffer::fixedAovSum()
// times `scale`, aovChannels() floats a pixel) on rank 0; empty elsewhere,
// and everywhere when the buffer has no AOVs.
std::vector<float> compositeAovs(const Communicator& comm, const FrameBuffer& partial, float scale,
                                 uint64_t& bytesSent);
// The colour, tone mapped to RGBA8 on the slice owners before gathering.
std::vector<uint8_t> compositeToneMapped(const Communicator& comm, const FrameBuffer& partial,
                                         float scale, const ToneMapping& toneMapping,
                                         uint64_t& bytesSent);

}  // namespace ferry
