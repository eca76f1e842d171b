// Helpers shared by the `ridge` subcommands: strict number parsing, output, error reporting.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "ridgeline/result.h"

namespace ridgeline::cli {

/// Exit codes: 0 success, 1 a runtime error (bad file, bad data), 2 a usage error (bad flags).
constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

/// A finite double from the whole of `text` (surrounding spaces allowed, nothing else). `what`
/// names the flag or field in the error: "--spacing 'nan': not a finite number".
Result<double> parse_finite(std::string_view text, const std::string& what);

/// A comma-separated list of between `min_count` and `max_count` finite doubles.
Result<std::vector<double>> parse_finite_list(std::string_view text, const std::string& what,
                                              std::size_t min_count, std::size_t max_count);

/// An unsigned integer in [lo, hi] from the whole of `text`.
Result<std::uint64_t> parse_count(std::string_view text, const std::string& what, std::uint64_t lo,
                                  std::uint64_t hi);

/// A number as written in CSV output: 17 significant digits ("%.17g").
std::string csv_number(double v);

/// Writes `text` to stdout when `path` is empty or "-", else to `path` through a temporary file
/// renamed into place (a crash never leaves a half-written file). Fails naming the file (and
/// the folder when it does not exist).
Status write_output(const std::string& text, const std::string& path);

/// write_output() of the JSON, indented by 2, with a final newline.
template <class Json>
Status write_json(const Json& json, const std::string& path) {
  return write_output(json.dump(2) + "\n", path);
}

/// Prints "ridge: error: MESSAGE" to stderr and returns kExitError.
int report_error(const std::string& message);

/// Prints "ridge: error: MESSAGE" to stderr and returns kExitUsage: for a flag the command
/// cannot run without (docs/cli.md, exit codes).
int report_usage(const std::string& message);

/// Fails, naming `what` and the folder, unless the folder `path` would be written into exists
/// ("output file 'a/b.glb': the folder 'a' does not exist"). An empty folder part is the
/// current directory.
Status check_output_folder(const std::string& path, const std::string& what);

/// Installs a log sink that prints the library's info, warning and error messages to stderr.
void install_log_sink();

}  // namespace ridgeline::cli
