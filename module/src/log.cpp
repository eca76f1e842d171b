#include "ridgeline/log.h"

#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace ridgeline {
namespace {

std::mutex g_sink_mutex;
LogSinkFn g_sink = nullptr;
void* g_sink_user = nullptr;
AssertHandlerFn g_assert_handler = nullptr;

void default_sink(LogLevel level, std::string_view message) {
  if (level < LogLevel::kWarning) return;
  std::fprintf(stderr, "ridgeline %s: %.*s\n", level == LogLevel::kError ? "error" : "warning",
               static_cast<int>(message.size()), message.data());
}

}  // namespace

void set_log_sink(LogSinkFn sink, void* user) {
  std::lock_guard lock(g_sink_mutex);
  g_sink = sink;
  g_sink_user = user;
}

void log_message(LogLevel level, std::string_view message) {
  LogSinkFn sink;
  void* user;
  {
    std::lock_guard lock(g_sink_mutex);
    sink = g_sink;
    user = g_sink_user;
  }
  if (sink)
    sink(level, message, user);
  else
    default_sink(level, message);
}

void set_assert_handler(AssertHandlerFn handler) { g_assert_handler = handler; }

namespace detail {
void assert_failed(const char* expression, const char* file, int line) {
  if (g_assert_handler) g_assert_handler(expression, file, line);
  std::fprintf(stderr, "ridgeline: assertion failed: %s (%s:%d)\n", expression, file, line);
  std::abort();
}
}  // namespace detail

}  // namespace ridgeline
