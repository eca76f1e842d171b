// Result<T>: a value or a precise error message, returned by every call that validates input.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace ridgeline {

/// An error from validation or I/O. The message names the thing and the offending value, e.g.
/// "heightmap 'a.png': 0 x 17 samples; need at least 2 x 2".
struct Error {
  std::string message;
};

/// A value of type T or an Error. Move-only when T is. Check with `ok()` (or `if (result)`)
/// before calling `value()`; calling `value()` on an error is a programmer error (asserts).
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}         // NOLINT(google-explicit-constructor)
  Result(Error error) : data_(std::move(error)) {}     // NOLINT(google-explicit-constructor)

  bool ok() const noexcept { return data_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  T& value() & { return std::get<0>(data_); }
  const T& value() const& { return std::get<0>(data_); }
  T&& value() && { return std::get<0>(std::move(data_)); }
  T* operator->() { return &std::get<0>(data_); }
  const T* operator->() const { return &std::get<0>(data_); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  /// The error; only valid when !ok().
  const Error& error() const { return std::get<1>(data_); }

 private:
  std::variant<T, Error> data_;
};

/// Result of an operation that produces no value: empty on success.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error.message)), failed_(true) {}  // NOLINT
  bool ok() const noexcept { return !failed_; }
  explicit operator bool() const noexcept { return ok(); }
  const std::string& message() const noexcept { return error_; }

 private:
  std::string error_;
  bool failed_ = false;
};

}  // namespace ridgeline
