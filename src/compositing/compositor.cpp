#include "compositing/compositor.h"

#include "core/fault_injection.h"

namespace ferry {
namespace {

// Direct send: returns this rank's slice of the sum of every rank's partial
// fixed-point sums `sums` (`values` a pixel: the colour's 3, or the AOVs'),
// exactly (render/frame_buffer.h: the same whatever the rank count).
std::vector<int64_t> sumOwnSliceFixed(const Communicator& comm, const FrameBuffer& partial,
                                      const std::vector<int64_t>& sums, int values,
                                      uint64_t& bytesSent) {
  maybeInjectFailure("composite", comm.rank());
  const int ranks = comm.size();
  if (ranks == 1) return sums;  // the whole image is this rank's slice
  const int kPixelBytes = values * int(sizeof(int64_t));
  const int width = partial.width(), height = partial.height();
  std::vector<int> sendCounts(ranks), sendOffsets(ranks), receiveCounts(ranks),
      receiveOffsets(ranks);
  int myFirst, myLast;
  compositeSlice(height, ranks, comm.rank(), myFirst, myLast);
  const int slicePixels = (myLast - myFirst) * width;
  for (int r = 0; r < ranks; ++r) {
    int first, last;
    compositeSlice(height, ranks, r, first, last);
    sendCounts[r] = (last - first) * width * kPixelBytes;
    sendOffsets[r] = first * width * kPixelBytes;
    receiveCounts[r] = slicePixels * kPixelBytes;
    receiveOffsets[r] = r * slicePixels * kPixelBytes;
  }
  const size_t sliceValues = size_t(slicePixels) * size_t(values);
  std::vector<int64_t> pieces(sliceValues * size_t(ranks));
  comm.exchangeBytes(sums.data(), sendCounts, sendOffsets, pieces.data(), receiveCounts,
                     receiveOffsets);
  for (int r = 0; r < ranks; ++r)
    if (r != comm.rank()) bytesSent += uint64_t(sendCounts[r]);
  std::vector<int64_t> total(sliceValues, 0);
  for (int r = 0; r < ranks; ++r)
    for (size_t i = 0; i < sliceValues; ++i) total[i] += pieces[size_t(r) * sliceValues + i];
  return total;
}

// The same slice as floats, times `scale`.
std::vector<Vec3f> sumOwnSlice(const Communicator& comm, const FrameBuffer& partial, float scale,
                               uint64_t& bytesSent) {
  const std::vector<int64_t> total =
      sumOwnSliceFixed(comm, partial, partial.fixedSum(), 3, bytesSent);
  std::vector<Vec3f> slice(total.size() / 3);
  for (size_t i = 0; i < slice.size(); ++i)
    slice[i] = Vec3f(FrameBuffer::toLinear(total[3 * i], scale),
                     FrameBuffer::toLinear(total[3 * i + 1], scale),
                     FrameBuffer::toLinear(total[3 * i + 2], scale));
  return slice;
}

// `elementsPerPixel`: 1 for Vec3f pixels, 3 for fixed-point sums, 4 for RGBA8
// bytes, the AOV channel count for AOV floats.
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

std::vector<int64_t> compositeFixed(const Communicator& comm, const FrameBuffer& partial,
                                    uint64_t& bytesSent) {
  std::vector<int64_t> slice = sumOwnSliceFixed(comm, partial, partial.fixedSum(), 3, bytesSent);
  if (!comm.isRoot()) bytesSent += slice.size() * sizeof(int64_t);
  return gatherSlices(comm, slice, partial.width(), partial.height(), 3);
}

std::vector<float> compositeAovs(const Communicator& comm, const FrameBuffer& partial, float scale,
                                 uint64_t& bytesSent) {
  const int channels = partial.aovChannels();
  if (channels == 0) return {};
  const std::vector<int64_t> total =
      sumOwnSliceFixed(comm, partial, partial.fixedAovSum(), channels, bytesSent);
  std::vector<float> slice(total.size());
  for (size_t i = 0; i < slice.size(); ++i) slice[i] = FrameBuffer::toLinear(total[i], scale);
  if (!comm.isRoot()) bytesSent += slice.size() * sizeof(float);
  return gatherSlices(comm, slice, partial.width(), partial.height(), channels);
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
