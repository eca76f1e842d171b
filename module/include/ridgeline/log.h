// Embedding hooks: where Ridgeline's log messages and failed assertions go.
#pragma once

#include <string_view>

namespace ridgeline {

enum class LogLevel { kDebug, kInfo, kWarning, kError };

/// The engine's log sink. Called from whatever thread logs, possibly several at once: the sink
/// must be thread-safe. `user` is the pointer given to set_log_sink.
using LogSinkFn = void (*)(LogLevel level, std::string_view message, void* user);

/// Installs the process-wide log sink (like Jolt's `Trace`): the one deliberate piece of global
/// state, because an engine has one log. Pass nullptr to restore the default, which writes
/// warnings and errors to stderr. Set it before creating terrains; swapping it while other
/// threads log is safe (the pair is swapped under a lock) but messages may go to either sink.
void set_log_sink(LogSinkFn sink, void* user = nullptr);

/// Sends a message to the current sink.
void log_message(LogLevel level, std::string_view message);

/// Handler for programmer errors: failed RIDGELINE_ASSERTs (on in Debug and sanitizer builds)
/// and, in every build, a misused Result (result.h: `value()` on an error, `error()` on a value).
/// `expression` is the failed expression's text, or for a Result the misuse and the error's
/// message ("Result::value() called on an error: heightmap 'a.png': no such file"); it is valid
/// only during the call. The default prints "ridgeline: assertion failed: EXPRESSION (FILE:LINE)"
/// to stderr and aborts. An engine may install its own (log, break into the debugger, throw in a
/// test); if it returns, the process aborts. Set it at start-up, before other threads run;
/// nullptr restores the default.
using AssertHandlerFn = void (*)(const char* expression, const char* file, int line);
void set_assert_handler(AssertHandlerFn handler);

namespace detail {
[[noreturn]] void assert_failed(const char* expression, const char* file, int line);
}  // namespace detail

}  // namespace ridgeline

#if defined(RIDGELINE_ENABLE_ASSERTS) || !defined(NDEBUG)
#define RIDGELINE_ASSERT(expr) \
  ((expr) ? (void)0 : ::ridgeline::detail::assert_failed(#expr, __FILE__, __LINE__))
#else
#define RIDGELINE_ASSERT(expr) ((void)0)
#endif
