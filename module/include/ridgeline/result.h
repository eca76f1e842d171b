// Result<T>: a value or a precise error message, returned by every call that validates input.
#pragma once

#include <string>
#include <utility>
#include <variant>

#include "ridgeline/log.h"

namespace ridgeline {

/// An error from validation or I/O. The message names the thing and the offending value, e.g.
/// "heightmap 'a.png': 0 x 17 samples; need at least 2 x 2".
struct Error {
  std::string message;
};

namespace detail {
/// Reports a misused Result through the assertion handler (log.h), whose `expression` argument
/// then reads "Result::value() called on an error: MESSAGE"; never returns. Out of line and cold
/// so that the checks cost one compare in the callers.
[[noreturn, gnu::cold, gnu::noinline]] inline void result_misuse(const char* what,
                                                                 const std::string* message,
                                                                 int line) {
  std::string text(what);
  if (message != nullptr) text += ": " + *message;
  assert_failed(text.c_str(), __FILE__, line);
}
}  // namespace detail

/// A value of type T or an Error. Move-only when T is. Check with `ok()` (or `if (result)`)
/// before calling `value()`.
///
/// Misuse is a programmer error, caught in every build type (not only with asserts on): calling
/// `value()`, `*` or `->` on an error calls the assertion handler (set_assert_handler in log.h)
/// with the text "Result::value() called on an error: " followed by the error's message, e.g.
/// "Result::value() called on an error: heightmap 'a.png': no such file"; calling `error()` on a
/// value calls it with "Result::error() called on a value". The default handler prints that text
/// to stderr and aborts; a handler that returns is followed by an abort too, and one that throws
/// (a test framework's) propagates its exception out of the accessor. No accessor throws
/// std::bad_variant_access.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : data_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const noexcept { return data_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  /// The value; on an error, the assertion handler is called with the error's message.
  T& value() & { return *checked(); }
  const T& value() const& { return *checked(); }
  T&& value() && { return std::move(*checked()); }
  T* operator->() { return checked(); }
  const T* operator->() const { return checked(); }
  T& operator*() & { return *checked(); }
  const T& operator*() const& { return *checked(); }

  /// The error; on a value, the assertion handler is called.
  const Error& error() const {
    const Error* e = std::get_if<1>(&data_);
    if (e == nullptr) [[unlikely]]
      detail::result_misuse("Result::error() called on a value", nullptr, __LINE__);
    return *e;
  }

 private:
  T* checked() {
    T* v = std::get_if<0>(&data_);
    if (v == nullptr) [[unlikely]]
      misuse();
    return v;
  }
  const T* checked() const {
    const T* v = std::get_if<0>(&data_);
    if (v == nullptr) [[unlikely]]
      misuse();
    return v;
  }
  [[noreturn]] void misuse() const {
    const Error* e = std::get_if<1>(&data_);
    if (e == nullptr)  // valueless: an exception escaped while the result was being assigned
      detail::result_misuse("Result::value() called on a result that holds nothing", nullptr,
                            __LINE__);
    detail::result_misuse("Result::value() called on an error", &e->message, __LINE__);
  }

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
