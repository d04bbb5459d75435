// A small C++23-style expected<T, E> for C++20: expected failures are values (STYLE rule 9).
// Holds either a value or an error; never throws on access in release (asserts in debug).
#pragma once

#include <cassert>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

namespace stac::rt {

template <class E>
struct Unexpected {
  E error;
};

template <class E>
Unexpected(E) -> Unexpected<E>;

template <class T, class E>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : storage_(std::in_place_index<0>, std::move(value)) {}  // NOLINT implicit
  Expected(Unexpected<E> u) : storage_(std::in_place_index<1>, std::move(u.error)) {}  // NOLINT

  [[nodiscard]] bool has_value() const noexcept { return storage_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }

  T& value() & noexcept {
    assert(has_value());
    return *std::get_if<0>(&storage_);
  }
  const T& value() const& noexcept {
    assert(has_value());
    return *std::get_if<0>(&storage_);
  }
  T&& value() && noexcept {
    assert(has_value());
    return std::move(*std::get_if<0>(&storage_));
  }
  T& operator*() & noexcept { return value(); }
  const T& operator*() const& noexcept { return value(); }
  T* operator->() noexcept { return &value(); }
  const T* operator->() const noexcept { return &value(); }

  const E& error() const& noexcept {
    assert(!has_value());
    return *std::get_if<1>(&storage_);
  }
  E&& error() && noexcept {
    assert(!has_value());
    return std::move(*std::get_if<1>(&storage_));
  }

 private:
  std::variant<T, E> storage_;
};

// The result of a step that yields nothing but success or an error: a default-constructed
// Expected<void, E> is success (`return {};`).
template <class E>
class [[nodiscard]] Expected<void, E> {
 public:
  Expected() = default;
  Expected(Unexpected<E> u) : error_(std::move(u.error)), failed_(true) {}  // NOLINT implicit

  [[nodiscard]] bool has_value() const noexcept { return !failed_; }
  explicit operator bool() const noexcept { return has_value(); }

  const E& error() const& noexcept {
    assert(failed_);
    return error_;
  }
  E&& error() && noexcept {
    assert(failed_);
    return std::move(error_);
  }

 private:
  E error_{};
  bool failed_ = false;
};

// Start-up errors carry a message meant for a person: what failed and what to fix.
struct Error {
  std::string message;
};

template <class T>
using Result = Expected<T, Error>;

// Success or an error, for steps that produce no value (write a file, apply a schedule).
using Status = Expected<void, Error>;

inline Unexpected<Error> make_error(std::string message) {
  return {Error{std::move(message)}};
}

}  // namespace stac::rt
