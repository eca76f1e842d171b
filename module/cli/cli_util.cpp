#include "cli_util.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "ridgeline/log.h"

namespace ridgeline::cli {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::string quoted(std::string_view what, std::string_view text) {
  return std::string(what) + " '" + std::string(text) + "'";
}

}  // namespace

Result<double> parse_finite(std::string_view text, const std::string& what) {
  const std::string_view t = trim(text);
  std::string_view digits = t;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  if (digits.empty()) return Error{quoted(what, text) + ": expected a number"};
  double v = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec == std::errc::result_out_of_range)
    return Error{quoted(what, text) + ": out of the range of double"};
  if (ec != std::errc() || end != digits.data() + digits.size())
    return Error{quoted(what, text) + ": not a number"};
  if (!std::isfinite(v)) return Error{quoted(what, text) + ": not a finite number"};
  return v;
}

Result<std::vector<double>> parse_finite_list(std::string_view text, const std::string& what,
                                              std::size_t min_count, std::size_t max_count) {
  const std::string expected =
      "expected " +
      (min_count == max_count ? std::to_string(max_count)
                              : std::to_string(min_count) + " or " + std::to_string(max_count)) +
      (max_count == 1 ? " number" : " comma-separated numbers");
  std::vector<double> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string_view field = text.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (out.size() == max_count) return Error{quoted(what, text) + ": " + expected};
    auto v = parse_finite(field, what);
    if (!v) {
      if (text.find(',') == std::string_view::npos) return v.error();
      return Error{v.error().message + " (in " + quoted(what, text) + ")"};
    }
    out.push_back(*v);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (out.size() < min_count) return Error{quoted(what, text) + ": " + expected};
  return out;
}

Result<std::uint64_t> parse_count(std::string_view text, const std::string& what, std::uint64_t lo,
                                  std::uint64_t hi) {
  const std::string_view t = trim(text);
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec == std::errc::invalid_argument || end != t.data() + t.size())
    return Error{quoted(what, text) + ": expected a whole number"};
  if (ec == std::errc::result_out_of_range || v < lo || v > hi)
    return Error{quoted(what, text) + ": must be between " + std::to_string(lo) + " and " +
                 std::to_string(hi)};
  return v;
}

std::string csv_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

Status write_output(const std::string& text, const std::string& path) {
  if (path.empty() || path == "-") {
    std::cout << text << std::flush;
    if (!std::cout) return Error{"cannot write to standard output"};
    return {};
  }
  if (auto s = check_output_folder(path, "output file '" + path + "'"); !s) return s;
  // Written beside the target and renamed, so a crash never leaves a half-written file.
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return Error{"output file '" + path + "': cannot create '" + tmp + "'"};
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      return Error{"output file '" + path + "': write failed"};
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return Error{"output file '" + path + "': cannot rename into place: " + ec.message()};
  }
  return {};
}

int report_error(const std::string& message) {
  std::fprintf(stderr, "ridge: error: %s\n", message.c_str());
  return kExitError;
}

int report_usage(const std::string& message) {
  std::fprintf(stderr, "ridge: error: %s\n", message.c_str());
  return kExitUsage;
}

Status check_output_folder(const std::string& path, const std::string& what) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (folder.empty()) return {};
  std::error_code ec;
  const auto st = std::filesystem::status(folder, ec);
  if (st.type() == std::filesystem::file_type::not_found)
    return Error{what + ": the folder '" + folder.string() + "' does not exist"};
  if (!ec && st.type() != std::filesystem::file_type::directory)
    return Error{what + ": '" + folder.string() + "' is not a folder"};
  return {};
}

void install_log_sink() {
  set_log_sink([](LogLevel level, std::string_view message, void*) {
    if (level == LogLevel::kDebug) return;
    const char* tag = level == LogLevel::kInfo      ? "note"
                      : level == LogLevel::kWarning ? "warning"
                                                    : "error";
    std::fprintf(stderr, "ridge: %s: %.*s\n", tag, static_cast<int>(message.size()),
                 message.data());
  });
}

}  // namespace ridgeline::cli
