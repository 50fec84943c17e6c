// An array that owns its elements, or shares memory that something else keeps
// alive: the scene's mesh and texel arrays, which a rank loading its part file
// takes straight from the file's mapping instead of copying (io/part_file), and
// which the Embree backend in turn shares (no second copy anywhere).
//
// It behaves as a value, like the std::vector it wraps: copies are independent.
// A shared array is read in place; the first access that could change it (a
// non-const element access, a size change) first copies it into an owned
// vector, so nobody ever writes into the mapping or into another copy's
// elements. Code that reads through a const Mesh or Scene (rendering, the
// trace backends, partitioning, part writing) never copies; `isShared()`
// tells, and the part-loading tests check that it stays true through a render.
#pragma once

#include <cstddef>
#include <initializer_list>
#include <memory>
#include <span>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace ferry {

template <typename T>
class SharedArray {
  static_assert(std::is_trivially_copyable_v<T>, "shared memory holds plain values");

 public:
  using value_type = T;
  using const_iterator = const T*;
  using iterator = T*;

  SharedArray() = default;
  // Implicit, so that code building a std::vector assigns it as before.
  SharedArray(std::vector<T> owned) : owned_(std::move(owned)) {}
  SharedArray(std::initializer_list<T> values) : owned_(values) {}
  template <typename It>
  SharedArray(It first, It last) : owned_(first, last) {}

  // `size` elements at `data`, alive as long as `keeper` is (a mapping).
  // `spareElement`: at least one more element's bytes are readable after the
  // last (a trace backend may read a few bytes past the end: Embree reads 16
  // bytes at the last vertex).
  static SharedArray shared(const T* data, size_t size, std::shared_ptr<const void> keeper,
                            bool spareElement) {
    SharedArray a;
    if (size == 0) return a;
    a.shared_ = data;
    a.sharedSize_ = size;
    a.keeper_ = std::move(keeper);
    a.sharedSpare_ = spareElement;
    return a;
  }

  bool isShared() const { return keeper_ != nullptr; }
  size_t size() const { return isShared() ? sharedSize_ : owned_.size(); }
  bool empty() const { return size() == 0; }
  const T* data() const { return isShared() ? shared_ : owned_.data(); }
  const T& operator[](size_t i) const { return data()[i]; }
  const T& at(size_t i) const { return isShared() ? (check(i), shared_[i]) : owned_.at(i); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size(); }
  const T& front() const { return data()[0]; }
  const T& back() const { return data()[size() - 1]; }
  std::span<const T> span() const { return {data(), size()}; }
  operator std::span<const T>() const { return span(); }
  // At least one element's bytes readable after the last, without a copy.
  bool hasSpareElement() const {
    return isShared() ? sharedSpare_ : owned_.capacity() > owned_.size();
  }
  // Bytes this array holds itself (a shared array holds none: its memory is
  // the mapping's, counted where the mapping is).
  size_t ownedBytes() const { return owned_.capacity() * sizeof(T); }

  // Everything below may change the elements: a shared array becomes owned first.
  std::vector<T>& owned() {
    if (isShared()) {
      std::vector<T> copy;
      copy.reserve(sharedSize_ + (sharedSpare_ ? 1 : 0));  // keeps the spare element's promise
      copy.assign(shared_, shared_ + sharedSize_);
      *this = SharedArray(std::move(copy));
    }
    return owned_;
  }
  T* data() { return owned().data(); }
  T& operator[](size_t i) { return owned()[i]; }
  T& at(size_t i) { return owned().at(i); }
  T* begin() { return owned().data(); }
  T* end() { return owned().data() + owned_.size(); }
  T& back() { return owned().back(); }
  void push_back(const T& v) { owned().push_back(v); }
  template <typename... Args>
  T& emplace_back(Args&&... args) {
    return owned().emplace_back(std::forward<Args>(args)...);
  }
  void pop_back() { owned().pop_back(); }
  void reserve(size_t n) { owned().reserve(n); }
  void resize(size_t n) { owned().resize(n); }
  void resize(size_t n, const T& v) { owned().resize(n, v); }
  template <typename It>
  void assign(It first, It last) {
    std::vector<T> v(first, last);
    *this = SharedArray(std::move(v));
  }
  void assign(size_t n, const T& v) { *this = SharedArray(std::vector<T>(n, v)); }
  template <typename It>
  void insert(const T* at, It first, It last) {
    const size_t offset = size_t(at - data());
    std::vector<T>& v = owned();
    v.insert(v.begin() + ptrdiff_t(offset), first, last);
  }
  void shrink_to_fit() {
    if (!isShared()) owned_.shrink_to_fit();
  }
  // Empties the array and lets go of the shared memory (or frees the vector).
  void clear() { *this = SharedArray(); }

  friend bool operator==(const SharedArray& a, const SharedArray& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (!(a[i] == b[i])) return false;
    return true;
  }

 private:
  void check(size_t i) const {
    if (i >= sharedSize_) throw std::out_of_range("SharedArray::at");
  }

  std::vector<T> owned_;
  const T* shared_ = nullptr;
  size_t sharedSize_ = 0;
  bool sharedSpare_ = false;
  std::shared_ptr<const void> keeper_;  // set: the elements are at shared_
};

}  // namespace ferry
