// Private helpers for building error messages.
#pragma once

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace ridgeline::detail {

/// printf-style formatting into a std::string (format strings checked where the compiler can).
#if defined(__GNUC__) || defined(__clang__)
inline std::string fmt(const char* format, ...) __attribute__((format(printf, 1, 2)));
#endif
inline std::string fmt(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::string out(n > 0 ? static_cast<std::size_t>(n) : 0, '\0');
  if (n > 0) std::vsnprintf(out.data(), out.size() + 1, format, args);
  va_end(args);
  return out;
}

/// A number as the shortest text that reads back to the same double ("nan", "inf" spelled out).
inline std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  // Prefer a short form when it round-trips.
  for (int prec = 1; prec < 17; ++prec) {
    char shorter[32];
    std::snprintf(shorter, sizeof shorter, "%.*g", prec, v);
    if (std::strtod(shorter, nullptr) == v) return shorter;
  }
  return buf;
}

/// A float as the shortest text that reads back to the same float (3e+38 rather than the
/// double expansion 2.9999999521443642e+38).
inline std::string numf(float v) {
  char buf[32];
  for (int prec = 1; prec < 9; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, double(v));
    if (std::strtof(buf, nullptr) == v) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.9g", double(v));
  return buf;
}

}  // namespace ridgeline::detail

namespace ridgeline {
using detail::fmt;
using detail::num;
}  // namespace ridgeline
