// Result<T> misuse reports the error's text through the assertion handler (result.h, log.h).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "ridgeline/log.h"
#include "ridgeline/result.h"

namespace ridgeline {
namespace {

// A handler that throws what it was given, so that a test can read it (an engine's test
// framework would do the same); the Result accessor then propagates the exception.
struct Reported {
  std::string expression;
};
void throwing_handler(const char* expression, const char*, int) {
  throw Reported{expression};
}

struct HandlerScope {
  HandlerScope() { set_assert_handler(throwing_handler); }
  ~HandlerScope() { set_assert_handler(nullptr); }
};

template <class F>
std::string reported(F&& f) {
  try {
    f();
  } catch (const Reported& r) {
    return r.expression;
  }
  return "(no report)";
}

Result<int> failing() {
  return Error{"heightmap 'a.png': no such file"};
}

TEST(Result, ValueOnAnErrorReportsTheMessageToTheHandler) {
  HandlerScope scope;
  const std::string want = "Result::value() called on an error: heightmap 'a.png': no such file";
  Result<int> r = failing();
  const Result<int>& cr = r;
  EXPECT_EQ(reported([&] { (void)r.value(); }), want);
  EXPECT_EQ(reported([&] { (void)cr.value(); }), want);
  EXPECT_EQ(reported([&] { (void)std::move(r).value(); }), want);
  EXPECT_EQ(reported([&] { (void)*r; }), want);
  EXPECT_EQ(reported([&] { (void)*cr; }), want);
  Result<std::string> s = Error{"bad"};
  EXPECT_EQ(reported([&] { (void)s->size(); }), "Result::value() called on an error: bad");
  // Move-only values work the same way.
  Result<std::unique_ptr<int>> u = Error{"no pointer"};
  EXPECT_EQ(reported([&] { (void)std::move(u).value(); }),
            "Result::value() called on an error: no pointer");
}

TEST(Result, ErrorOnAValueIsReported) {
  HandlerScope scope;
  Result<int> r = 7;
  EXPECT_EQ(reported([&] { (void)r.error(); }), "Result::error() called on a value");
}

TEST(Result, GoodResultsAreUntouched) {
  HandlerScope scope;
  Result<std::string> s = std::string("ok");
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(*s, "ok");
  EXPECT_EQ(s->size(), 2u);
  EXPECT_EQ(std::move(s).value(), "ok");
  Result<int> e = failing();
  EXPECT_FALSE(e);
  EXPECT_EQ(e.error().message, "heightmap 'a.png': no such file");
}

// The default handler prints the message and aborts, in every build type.
TEST(ResultDeathTest, DefaultHandlerPrintsTheMessageAndAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH((void)failing().value(),
               "assertion failed: Result::value\\(\\) called on an error: heightmap 'a.png': no "
               "such file");
}

// A handler that returns does not let the caller continue with a value that is not there.
void returning_handler(const char*, const char*, int) {}
TEST(ResultDeathTest, AHandlerThatReturnsStillAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        set_assert_handler(returning_handler);
        (void)failing().value();
      },
      "Result::value\\(\\) called on an error");
}

}  // namespace
}  // namespace ridgeline
