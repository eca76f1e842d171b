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

/// CPU time of the calling thread, nanoseconds (CLOCK_THREAD_CPUTIME_ID): unlike wall time it
/// does not count the time the thread waits for a core, which on a shared machine can dominate.
double thread_cpu_ns();
/// Minor page faults of the calling thread so far (getrusage): a fresh page costs the first
/// write to it ~11 us on this project's virtual machines, so a first update's time is mostly
/// its faults (docs/benchmarks.md).
long thread_minor_faults();
/// For benchmarks that time one piece of work per frame and measure it between frames: keeps
/// the memory the measurement frees inside the process (glibc: no unmapping, no trimming).
/// Otherwise a measurement that frees a large buffer unmaps it, which flushes the TLB, and the
/// next timed frame pays for refilling it (here ~0.5 ms for a 50k-triangle view): a cost of
/// the benchmark, not of the work timed. Applies to every mode alike.
void keep_freed_memory();

/// The rest of a game's frame, for benchmarks that time one piece of work per frame: touch()
/// reads and writes one byte in every cache line of `mib` MiB of other memory, so the next
/// timed frame finds the caches holding that memory instead of the terrain's. Every mode of a
/// benchmark calls it at the same place (0 MiB: nothing).
class OtherWork {
 public:
  explicit OtherWork(double mib) : bytes_(std::size_t(mib * 1048576.0), 1) {}
  void touch() noexcept;

 private:
  std::vector<unsigned char> bytes_;
  unsigned sink_ = 0;
};

/// Installs a log sink that prints the library's info, warning and error messages to stderr.
void install_log_sink();

}  // namespace ridgeline::cli
