// The PNG chunk walk before decoding (module/src/io/png_check.cpp): truncated files, chunks
// failing their CRC, a header claiming a size no one can allocate; one message each and nothing
// printed beside it.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "io/oiio_lsan_suppressions.h"
#include "io/tiff_tags.h"
#include "io_test_util.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"

using namespace ridgeline;
using namespace ridgeline::test;
namespace fs = std::filesystem;

TEST(IoBadInput, CorruptPngDataIsRefused) {
  const int w = 64, h = 64;
  auto values = pattern(std::size_t(w) * h, 65536, 5);
  std::vector<std::uint16_t> px(values.begin(), values.end());
  const auto path = tmp_path("c.png");
  write_image(path, w, h, 1, OIIO::TypeDesc::UINT16, px);
  auto bytes = read_bytes(path);
  for (std::size_t k = bytes.size() / 2; k < bytes.size() / 2 + 64; ++k) bytes[k] ^= 0x5a;
  write_bytes(path, bytes);
  testing::internal::CaptureStderr();
  auto hf = io::load_image(path, options());
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_FALSE(hf) << "a corrupt PNG loaded";
  EXPECT_TRUE(contains(hf.error().message,
                       "heightmap '" + path + "': corrupt PNG file: chunk 'IDAT' at byte "))
      << hf.error().message;
  EXPECT_TRUE(contains(hf.error().message, "fails its CRC check")) << hf.error().message;
  EXPECT_EQ(printed, "") << "printed beside the error";
}

// A PNG cut short anywhere is refused with one message naming the chunk where it ends, and
// nothing is printed beside it (libpng prints its own line for a read error it meets).
TEST(IoBadInput, ATruncatedPngIsOneMessageAndNothingPrinted) {
  const auto full = read_bytes(std::string(RIDGELINE_TEST_DATA) + "/ramp16.png");
  ASSERT_GT(full.size(), 60u);
  for (std::size_t n = 8; n < full.size(); ++n) {
    const auto path = tmp_path("cut.png");
    write_bytes(path, std::vector<char>(full.begin(), full.begin() + std::ptrdiff_t(n)));
    testing::internal::CaptureStderr();
    auto hf = io::load_image(path, options());
    const std::string printed = testing::internal::GetCapturedStderr();
    ASSERT_FALSE(hf) << n << " of " << full.size() << " bytes loaded";
    const std::string& m = hf.error().message;
    EXPECT_EQ(m.rfind("heightmap '" + path + "': truncated PNG file: ", 0), 0u) << m;
    EXPECT_EQ(m.find("truncated", m.find("truncated") + 1), std::string::npos) << m;
    EXPECT_EQ(printed, "") << n << " bytes: printed beside the error";
  }
}

TEST(IoBadInput, HugeDeclaredPngSizeIsRefusedWithoutAllocating) {
  // A valid 2 x 2 PNG whose IHDR claims 200000 x 150000 pixels (CRC fixed so the header parses).
  // Allocating that would need 60 GB; the sanitizer build would abort on the attempt.
  const auto path = tmp_path("huge.png");
  write_image(path, 2, 2, 1, OIIO::TypeDesc::UINT16, std::vector<std::uint16_t>{1, 2, 3, 4});
  auto bytes = read_bytes(path);
  ASSERT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
  put_be32(bytes, 16, 200000);
  put_be32(bytes, 20, 150000);
  put_be32(bytes, 29, crc32(reinterpret_cast<const unsigned char*>(bytes.data()) + 12, 17));
  write_bytes(path, bytes);
  auto hf = io::load_image(path, options());
  ASSERT_FALSE(hf);
  EXPECT_TRUE(contains(hf.error().message, "heightmap '" + path +
                                               "': 200000 x 150000 = 30000000000 samples exceeds "
                                               "the limit of 268468225 samples (HeightfieldDesc::max_samples)"))
      << hf.error().message;
}
