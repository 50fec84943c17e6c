#include "io/byte_stream.h"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

namespace {
constexpr size_t kBufferSize = size_t(1) << 16;
}

ByteStream ByteStream::openFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw InputError(fmt::format("{}: no such file", path));
  if (!fs::is_regular_file(status)) throw InputError(fmt::format("{}: not a regular file", path));
  ByteStream s;
  s.name_ = path;
  s.file_.reset(std::fopen(path.c_str(), "rb"));
  if (!s.file_) throw InputError(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
  uint64_t size = fs::file_size(path, ec);
  if (ec) throw InputError(fmt::format("{}: cannot read its size: {}", path, ec.message()));
  s.size_ = size;
  s.buffer_.resize(kBufferSize);
  s.data_ = s.buffer_.data();
  return s;
}

ByteStream ByteStream::fromMemory(std::string_view bytes, std::string name) {
  ByteStream s;
  s.name_ = std::move(name);
  s.memory_ = true;
  s.data_ = bytes.data();
  s.end_ = bytes.size();
  s.size_ = bytes.size();
  return s;
}

bool ByteStream::refill() {
  if (memory_ || !file_) return false;
  consumed_ += end_;
  pos_ = end_ = 0;
  size_t n = std::fread(buffer_.data(), 1, buffer_.size(), file_.get());
  if (n == 0) {
    if (std::ferror(file_.get()))
      throw InputError(fmt::format("{}: read error: {}", name_, std::strerror(errno)));
    return false;
  }
  end_ = n;
  return true;
}

size_t ByteStream::read(void* out, size_t n) {
  char* dst = static_cast<char*>(out);
  size_t done = 0;
  while (done < n) {
    if (pos_ == end_ && !refill()) break;
    size_t k = std::min(n - done, end_ - pos_);
    std::memcpy(dst + done, data_ + pos_, k);
    pos_ += k;
    done += k;
  }
  return done;
}

uint64_t ByteStream::skip(uint64_t n) {
  uint64_t done = 0;
  while (done < n) {
    if (pos_ == end_ && !refill()) break;
    size_t k = size_t(std::min<uint64_t>(n - done, end_ - pos_));
    pos_ += k;
    done += k;
  }
  return done;
}

}  // namespace ferry
