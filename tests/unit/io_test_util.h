// Shared by the Ridgeline::io loader tests (test_io_*.cpp): scratch files, images written with
// OpenImageIO, byte helpers, a log capture.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "ridgeline/io.h"
#include "ridgeline/log.h"

namespace ridgeline::test {

namespace fs = std::filesystem;

/// A file name unique to the running test (ctest runs each test in its own process, in parallel).
inline std::string tmp_path(const std::string& leaf) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(RIDGELINE_TEST_TMP) / "io";
  fs::create_directories(dir);
  return (dir / (std::string(info->test_suite_name()) + "_" + info->name() + "_" + leaf)).string();
}

template <class T>
void write_image(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type,
                 const std::vector<T>& pixels) {
  ASSERT_EQ(pixels.size(), static_cast<std::size_t>(w) * h * channels);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, channels, type);
  if (channels == 2) {
    spec.channelnames = {"Y", "A"};
    spec.alpha_channel = 1;
    spec.attribute("oiio:UnassociatedAlpha", 1);  // store grey as given, not divided by alpha
  }
  ASSERT_TRUE(out->open(path, spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(type, pixels.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

inline std::vector<char> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline io::LoadOptions options() {
  io::LoadOptions o;
  return o;
}

/// Every sample's local height (relative to the offset), row-major.
inline std::vector<float> locals(const Heightfield& hf) {
  return {hf.local_heights().begin(), hf.local_heights().end()};
}

inline bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

/// A deterministic pseudo-random pattern of `n` values in [0, range).
inline std::vector<std::uint32_t> pattern(std::size_t n, std::uint32_t range, std::uint32_t seed = 7) {
  std::vector<std::uint32_t> v(n);
  std::uint32_t s = seed;
  for (auto& x : v) {
    s = s * 1664525u + 1013904223u;
    x = (s >> 8) % range;
  }
  return v;
}

inline std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  std::uint32_t c = 0xffffffffu;
  for (std::size_t k = 0; k < n; ++k) {
    c ^= p[k];
    for (int b = 0; b < 8; ++b) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}

inline void put_be32(std::vector<char>& b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<char>(v >> 24);
  b[at + 1] = static_cast<char>(v >> 16);
  b[at + 2] = static_cast<char>(v >> 8);
  b[at + 3] = static_cast<char>(v);
}

/// Captures log messages for the duration of a test.
struct LogCapture {
  std::vector<std::string> messages;
  LogCapture() {
    set_log_sink([](LogLevel, std::string_view m,
                    void* user) { static_cast<LogCapture*>(user)->messages.emplace_back(m); },
                 this);
  }
  ~LogCapture() { set_log_sink(nullptr); }
};

}  // namespace ridgeline::test
