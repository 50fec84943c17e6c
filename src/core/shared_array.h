// An array that owns its elements, or shares memory that something else keeps
// alive: the scene's mesh and texel arrays, which a rank loading its part file
// takes straight from the file's mapping instead of copying (io/parts/part_file), and
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
  SharedArray(std::vector<T> owned) : owned_(std::move(owned)) { sync(); }
  SharedArray(std::initializer_list<T> values) : owned_(values) { sync(); }
  template <typename It>
  SharedArray(It first, It last) : owned_(first, last) {
    sync();
  }
  SharedArray(const SharedArray& other)
      : owned_(other.owned_),
        shared_(other.shared_),
        sharedSpare_(other.sharedSpare_),
        keeper_(other.keeper_) {
    sync(other.size_);
  }
  SharedArray(SharedArray&& other) noexcept
      : owned_(std::move(other.owned_)),
        shared_(other.shared_),
        sharedSpare_(other.sharedSpare_),
        keeper_(std::move(other.keeper_)) {
    sync(other.size_);
    other.reset();
  }
  SharedArray& operator=(const SharedArray& other) {
    if (this != &other) *this = SharedArray(other);
    return *this;
  }
  SharedArray& operator=(SharedArray&& other) noexcept {
    if (this == &other) return *this;
    owned_ = std::move(other.owned_);
    shared_ = other.shared_;
    sharedSpare_ = other.sharedSpare_;
    keeper_ = std::move(other.keeper_);
    sync(other.size_);
    other.reset();
    return *this;
  }

  // `size` elements at `data`, alive as long as `keeper` is (a mapping).
  // `spareElement`: at least one more element's bytes are readable after the
  // last (a trace backend may read a few bytes past the end: Embree reads 16
  // bytes at the last vertex).
  static SharedArray shared(const T* data, size_t size, std::shared_ptr<const void> keeper,
                            bool spareElement) {
    SharedArray a;
    if (size == 0) return a;
    a.shared_ = data;
    a.keeper_ = std::move(keeper);
    a.sharedSpare_ = spareElement;
    a.sync(size);
    return a;
  }

  // Reads are branch-free (data_ and size_ always describe the elements):
  // shading reads mesh arrays at every hit.
  bool isShared() const { return keeper_ != nullptr; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T* data() const { return data_; }
  const T& operator[](size_t i) const { return data_[i]; }
  const T& at(size_t i) const {
    if (i >= size_) throw std::out_of_range("SharedArray::at");
    return data_[i];
  }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  const T& front() const { return data_[0]; }
  const T& back() const { return data_[size_ - 1]; }
  std::span<const T> span() const { return {data_, size_}; }
  operator std::span<const T>() const { return span(); }
  // At least one element's bytes readable after the last, without a copy.
  bool hasSpareElement() const {
    return isShared() ? sharedSpare_ : owned_.capacity() > owned_.size();
  }
  // Bytes this array holds itself (a shared array holds none: its memory is
  // the mapping's, counted where the mapping is).
  size_t ownedBytes() const { return owned_.capacity() * sizeof(T); }

  // Everything below may change the elements: a shared array becomes owned first.
  T* data() { return own().data(); }
  T& operator[](size_t i) { return own()[i]; }
  T& at(size_t i) { return own().at(i); }
  T* begin() { return own().data(); }
  T* end() { return own().data() + size_; }
  T& back() { return own().back(); }
  void push_back(const T& v) {
    change([&](std::vector<T>& o) { o.push_back(v); });
  }
  template <typename... Args>
  void emplace_back(Args&&... args) {
    change([&](std::vector<T>& o) { o.emplace_back(std::forward<Args>(args)...); });
  }
  void pop_back() {
    change([](std::vector<T>& o) { o.pop_back(); });
  }
  void reserve(size_t n) {
    change([&](std::vector<T>& o) { o.reserve(n); });
  }
  void resize(size_t n) {
    change([&](std::vector<T>& o) { o.resize(n); });
  }
  void resize(size_t n, const T& v) {
    change([&](std::vector<T>& o) { o.resize(n, v); });
  }
  template <typename It>
  void assign(It first, It last) {
    *this = SharedArray(std::vector<T>(first, last));
  }
  void assign(size_t n, const T& v) { *this = SharedArray(std::vector<T>(n, v)); }
  template <typename It>
  void insert(const T* at, It first, It last) {
    const size_t offset = size_t(at - data_);
    change([&](std::vector<T>& o) { o.insert(o.begin() + ptrdiff_t(offset), first, last); });
  }
  void shrink_to_fit() {
    if (!isShared()) change([](std::vector<T>& o) { o.shrink_to_fit(); });
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
  // The owned vector, a shared array first copied into it.
  std::vector<T>& own() {
    if (isShared()) {
      std::vector<T> copy;
      copy.reserve(size_ + (sharedSpare_ ? 1 : 0));  // keeps the spare element's promise
      copy.assign(shared_, shared_ + size_);
      *this = SharedArray(std::move(copy));
    }
    return owned_;
  }
  template <typename Change>
  void change(Change&& f) {
    f(own());
    sync();
  }
  // data_ and size_ from whichever holds the elements.
  void sync(size_t sharedSize = 0) {
    data_ = isShared() ? shared_ : owned_.data();
    size_ = isShared() ? sharedSize : owned_.size();
  }
  void reset() {
    owned_.clear();
    shared_ = nullptr;
    keeper_.reset();
    sync();
  }

  std::vector<T> owned_;
  const T* shared_ = nullptr;
  bool sharedSpare_ = false;
  std::shared_ptr<const void> keeper_;  // set: the elements are at shared_
  const T* data_ = nullptr;             // the elements: shared_ or owned_.data()
  size_t size_ = 0;
};

}  // namespace ferry
