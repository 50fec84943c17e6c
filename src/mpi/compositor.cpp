#include "mpi/compositor.h"

#include "core/fault_injection.h"

namespace ferry {
namespace {

// Direct send: returns this rank's summed, scaled slice.
std::vector<Vec3f> sumOwnSlice(const Communicator& comm, const FrameBuffer& partial, float scale,
                               uint64_t& bytesSent) {
  maybeInjectFailure("composite", comm.rank());
  const int ranks = comm.size(), width = partial.width(), height = partial.height();
  std::vector<int> sendCounts(ranks), sendOffsets(ranks), receiveCounts(ranks),
      receiveOffsets(ranks);
  int myFirst, myLast;
  compositeSlice(height, ranks, comm.rank(), myFirst, myLast);
  const int slicePixels = (myLast - myFirst) * width;
  for (int r = 0; r < ranks; ++r) {
    int first, last;
    compositeSlice(height, ranks, r, first, last);
    sendCounts[r] = (last - first) * width * int(sizeof(Vec3f));
    sendOffsets[r] = first * width * int(sizeof(Vec3f));
    receiveCounts[r] = slicePixels * int(sizeof(Vec3f));
    receiveOffsets[r] = r * slicePixels * int(sizeof(Vec3f));
  }
  std::vector<Vec3f> pieces(size_t(slicePixels) * ranks);
  comm.exchangeBytes(partial.sum().data(), sendCounts, sendOffsets, pieces.data(), receiveCounts,
                     receiveOffsets);
  for (int r = 0; r < ranks; ++r)
    if (r != comm.rank()) bytesSent += uint64_t(sendCounts[r]);
  std::vector<Vec3f> slice(slicePixels, Vec3f(0));
  for (int r = 0; r < ranks; ++r)
    for (int i = 0; i < slicePixels; ++i) slice[i] += pieces[size_t(r) * slicePixels + i];
  for (Vec3f& v : slice) v = v * scale;
  return slice;
}

// `elementsPerPixel`: 1 for Vec3f pixels, 4 for RGBA8 bytes.
template <typename T>
std::vector<T> gatherSlices(const Communicator& comm, const std::vector<T>& slice, int width,
                            int height, int elementsPerPixel) {
  const int bytesPerRow = width * elementsPerPixel * int(sizeof(T));
  std::vector<int> counts(comm.size()), offsets(comm.size());
  for (int r = 0; r < comm.size(); ++r) {
    int first, last;
    compositeSlice(height, comm.size(), r, first, last);
    counts[r] = (last - first) * bytesPerRow;
    offsets[r] = first * bytesPerRow;
  }
  std::vector<T> image(comm.isRoot() ? size_t(width) * height * elementsPerPixel : 0);
  comm.gatherBytes(slice.data(), int(slice.size() * sizeof(T)), image.data(), counts, offsets);
  return image;
}

}  // namespace

void compositeSlice(int height, int ranks, int rank, int& firstRow, int& lastRow) {
  firstRow = int(int64_t(height) * rank / ranks);
  lastRow = int(int64_t(height) * (rank + 1) / ranks);
}

std::vector<Vec3f> compositeLinear(const Communicator& comm, const FrameBuffer& partial,
                                   float scale, uint64_t& bytesSent) {
  std::vector<Vec3f> slice = sumOwnSlice(comm, partial, scale, bytesSent);
  if (!comm.isRoot()) bytesSent += slice.size() * sizeof(Vec3f);
  return gatherSlices(comm, slice, partial.width(), partial.height(), 1);
}

std::vector<uint8_t> compositeToneMapped(const Communicator& comm, const FrameBuffer& partial,
                                         float scale, const ToneMapping& toneMapping,
                                         uint64_t& bytesSent) {
  std::vector<uint8_t> slice =
      toneMapToRgba8(sumOwnSlice(comm, partial, scale, bytesSent), toneMapping);
  if (!comm.isRoot()) bytesSent += slice.size();
  return gatherSlices(comm, slice, partial.width(), partial.height(), 4);
}

}  // namespace ferry
