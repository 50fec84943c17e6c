// Sequential reading of a file (or of bytes in memory, for tests and fuzzers)
// through a fixed buffer. The loaders read every input through this, so a
// file of any size costs 64 KiB of buffer, never its own size: nothing is
// held twice.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace ferry {

class ByteStream {
 public:
  // Opens `path`; throws InputError "PATH: no such file" / "cannot open".
  static ByteStream openFile(const std::string& path);
  // Reads `bytes` (not copied: they must outlive the stream); `name` is used in messages.
  static ByteStream fromMemory(std::string_view bytes, std::string name);

  ByteStream(ByteStream&&) noexcept = default;
  ByteStream& operator=(ByteStream&&) noexcept = default;

  const std::string& name() const { return name_; }
  // Total size in bytes (a file's size when opened).
  uint64_t size() const { return size_; }
  // Bytes consumed so far.
  uint64_t offset() const { return consumed_ + pos_; }
  uint64_t remaining() const { return size_ > offset() ? size_ - offset() : 0; }

  // The next byte without consuming it; -1 at the end.
  int peek() {
    if (pos_ == end_ && !refill()) return -1;
    return static_cast<unsigned char>(data_[pos_]);
  }
  // The next byte; -1 at the end.
  int get() {
    if (pos_ == end_ && !refill()) return -1;
    return static_cast<unsigned char>(data_[pos_++]);
  }
  // Copies up to `n` bytes into `out`; returns how many (fewer only at the end).
  size_t read(void* out, size_t n);
  // Skips up to `n` bytes; returns how many.
  uint64_t skip(uint64_t n);
  // The rest of the current buffer (refilled when empty); empty at the end.
  // consume(k) then advances by k <= its size. For scanning without copying.
  std::string_view buffered() {
    if (pos_ == end_) refill();
    return std::string_view(data_ + pos_, end_ - pos_);
  }
  void consume(size_t n) { pos_ += n; }

 private:
  ByteStream() = default;
  bool refill();

  std::string name_;
  std::unique_ptr<FILE, int (*)(FILE*)> file_{nullptr, &std::fclose};
  std::vector<char> buffer_;
  const char* data_ = nullptr;  // the buffer, or the memory being read
  size_t pos_ = 0, end_ = 0;
  uint64_t consumed_ = 0;  // bytes before data_[0]
  uint64_t size_ = 0;
  bool memory_ = false;
};

}  // namespace ferry
