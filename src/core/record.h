// A plug-in's parameters as bytes (a material model's, a shape's), as part
// files store them: written field by field, read back with every read
// checked; a short, long or non-finite record is an InputError naming where
// it is (the file and the item). A record read from a mapping can hand out
// its arrays in place (sharedArray), kept alive with the mapping.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/math.h"
#include "core/shared_array.h"

namespace ferry {

class RecordWriter {
 public:
  template <class T>
  void pod(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void array(std::span<const T> values) {
    pod(uint64_t(values.size()));
    for (const T& v : values) pod(v);
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

class RecordReader {
 public:
  RecordReader(std::span<const uint8_t> bytes, std::string where)
      : bytes_(bytes), where_(std::move(where)) {}
  // `bytes` stay alive as long as `keeper` does (a file's mapping).
  RecordReader(std::span<const uint8_t> bytes, std::string where,
               std::shared_ptr<const void> keeper)
      : bytes_(bytes), where_(std::move(where)), keeper_(std::move(keeper)) {}
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    if (bytes_.size() - at_ < sizeof(T)) fail("its record is too short");
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  // What array() wrote; the count is checked against the bytes left first.
  template <class T>
  std::vector<T> array() {
    const uint64_t n = pod<uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(T)) fail("its record is too short");
    std::vector<T> out(n);
    if (n) std::memcpy(out.data(), bytes_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return out;
  }
  // What array() wrote, in place when the record has a keeper and the
  // elements are aligned for T; otherwise a copy.
  template <class T>
  SharedArray<T> sharedArray() {
    const uint64_t n = pod<uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(T)) fail("its record is too short");
    const uint8_t* at = bytes_.data() + at_;
    at_ += n * sizeof(T);
    if (keeper_ && reinterpret_cast<uintptr_t>(at) % alignof(T) == 0)
      return SharedArray<T>::shared(reinterpret_cast<const T*>(at), n, keeper_, false);
    std::vector<T> out(n);
    if (n) std::memcpy(out.data(), at, n * sizeof(T));
    return out;
  }
  // A finite float.
  float number();
  // A finite colour or point.
  Vec3f color();
  // Whether every byte has been read (a record may end before optional fields).
  bool atEnd() const { return at_ == bytes_.size(); }
  // After the reader has read its fields: the record must be used up.
  void finish() const;
  [[noreturn]] void fail(const std::string& what) const;
  const std::string& where() const { return where_; }

 private:
  std::span<const uint8_t> bytes_;
  size_t at_ = 0;
  std::string where_;
  std::shared_ptr<const void> keeper_;
};

}  // namespace ferry
