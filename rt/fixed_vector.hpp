// A vector whose capacity is fixed at construction, the only time it allocates (STYLE rule 7).
// Every element of the capacity is value-initialised once at start-up, which also touches the
// pages; afterwards size changes never construct, destroy or allocate. push_back/resize report
// overflow as `false` instead of growing; the caller counts it.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <type_traits>
#include <utility>

namespace stac::rt {

template <class T>
class FixedVector {
  static_assert(std::is_default_constructible_v<T>, "FixedVector needs default-constructible T");

 public:
  FixedVector() noexcept = default;
  explicit FixedVector(std::size_t capacity)
      : data_(std::make_unique<T[]>(capacity)), capacity_(capacity) {}
  FixedVector(const FixedVector&) = delete;
  FixedVector& operator=(const FixedVector&) = delete;
  FixedVector(FixedVector&& o) noexcept
      : data_(std::move(o.data_)),
        capacity_(std::exchange(o.capacity_, 0)),
        size_(std::exchange(o.size_, 0)) {}
  FixedVector& operator=(FixedVector&& o) noexcept {
    data_ = std::move(o.data_);
    capacity_ = std::exchange(o.capacity_, 0);
    size_ = std::exchange(o.size_, 0);
    return *this;
  }

  [[nodiscard]] bool push_back(const T& value) noexcept(std::is_nothrow_copy_assignable_v<T>) {
    if (size_ == capacity_) return false;
    data_[size_++] = value;
    return true;
  }
  // Appends a slot and returns it (its previous content is left as is); nullptr when full.
  [[nodiscard]] T* append() noexcept { return size_ == capacity_ ? nullptr : &data_[size_++]; }
  // Sets the size without touching elements (elements in [old, n) keep what was written
  // through data()). False, and no change, when n > capacity.
  [[nodiscard]] bool resize(std::size_t n) noexcept {
    if (n > capacity_) return false;
    size_ = n;
    return true;
  }
  void pop_back() noexcept {
    if (size_ > 0) --size_;
  }
  void clear() noexcept { size_ = 0; }

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  [[nodiscard]] bool full() const noexcept { return size_ == capacity_; }

  T* data() noexcept { return data_.get(); }
  const T* data() const noexcept { return data_.get(); }
  T& operator[](std::size_t i) noexcept { return data_[i]; }
  const T& operator[](std::size_t i) const noexcept { return data_[i]; }
  T& back() noexcept { return data_[size_ - 1]; }
  const T& back() const noexcept { return data_[size_ - 1]; }
  T* begin() noexcept { return data_.get(); }
  T* end() noexcept { return data_.get() + size_; }
  const T* begin() const noexcept { return data_.get(); }
  const T* end() const noexcept { return data_.get() + size_; }
  std::span<T> span() noexcept { return {data_.get(), size_}; }
  std::span<const T> span() const noexcept { return {data_.get(), size_}; }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
};

}  // namespace stac::rt
