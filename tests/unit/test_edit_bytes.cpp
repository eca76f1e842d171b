// The edit file's bytes (edit.h, docs/deformation.md "The edit file"): a round trip in memory,
// undo, streams that give the same bytes in bounded writes, and refusals that change nothing,
// over every region of the header and the body.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/common.hpp>
#include <random>
#include <thread>

#include "edit_test_util.h"
#include "ridgeline/detail.h"
#include "ridgeline/edit.h"
#include "ridgeline/roam_view.h"
#include "ridgeline/scenes.h"
#include "roam_test_util.h"

using namespace ridgeline;
using namespace ridgeline::test;

TEST(EditFile, RoundTripUndoAndRefusals) {
  auto t = noise_terrain(129);
  auto l = Landscape::create(t, {.patch_exponent = 4}).value();
  const auto h0 = t->surface().heights_hash();
  const std::string a = save_edits_to_memory(*t);  // empty layer
  EXPECT_EQ(a.size(), 72u) << "header and checksum only";
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  ASSERT_TRUE(
      t->apply_edit({.brush = Brush::kFlatten, .x = 200, .z = 250, .radius = 20, .height = 50}));
  const auto h1 = t->surface().heights_hash();
  ASSERT_NE(h0, h1);
  const std::string b = save_edits_to_memory(*t);
  ASSERT_TRUE(t->apply_edit({.x = 100, .z = 100, .radius = 30, .depth = 9}));
  // Undo by loading the earlier saves; bounds follow.
  auto r = load_edits_from_memory(*t, b);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(t->surface().heights_hash(), h1);
  expect_bounds_equal_rebuild(*l);
  ASSERT_TRUE(load_edits_from_memory(*t, a));
  EXPECT_EQ(t->surface().heights_hash(), h0);
  EXPECT_EQ(t->surface().edited_chunks(), 0u);
  ASSERT_TRUE(load_edits_from_memory(*t, b));
  EXPECT_EQ(t->surface().heights_hash(), h1);
  EXPECT_EQ(save_edits_to_memory(*t), b) << "loading and saving again gives the same bytes";
  // A fresh terrain with the same base loads it to the same hash.
  auto t2 = noise_terrain(129);
  ASSERT_TRUE(load_edits_from_memory(*t2, b));
  EXPECT_EQ(t2->surface().heights_hash(), h1);

  // Refusals change nothing.
  const std::string& bytes = b;
  ASSERT_TRUE(t->apply_edit({.x = 10, .z = 10, .radius = 5}));
  const auto h2 = t->surface().heights_hash();
  for (std::size_t cut : {std::size_t{0}, std::size_t{10}, std::size_t{63}, std::size_t{72},
                          bytes.size() / 2, bytes.size() - 1}) {
    auto bad = load_edits_from_memory(*t, std::string_view(bytes).substr(0, cut));
    ASSERT_FALSE(bad) << "truncated to " << cut;
    EXPECT_NE(bad.error().message.find("edit file"), std::string::npos);
  }
  for (std::size_t at : {std::size_t{0}, std::size_t{9}, std::size_t{20}, std::size_t{70},
                         bytes.size() / 2, bytes.size() - 3}) {
    std::string c = bytes;
    c[at] ^= 0x5a;
    EXPECT_FALSE(load_edits_from_memory(*t, c)) << "corrupted at " << at;
  }
  auto other = noise_terrain(129, 8);  // another base
  auto foreign = load_edits_from_memory(*other, b);
  ASSERT_FALSE(foreign);
  EXPECT_NE(foreign.error().message.find("another terrain"), std::string::npos);
  EXPECT_EQ(t->surface().heights_hash(), h2);
  expect_bounds_equal_rebuild(*l);
}

namespace {

// A sink that keeps what it gets, one write() at a time, and fails the write numbered `fail_at`.
struct RecordingSink final : EditSink {
  std::vector<std::string> writes;
  std::size_t fail_at = SIZE_MAX;
  Status write(std::string_view bytes) override {
    if (writes.size() == fail_at) return Error{"sink full"};
    writes.emplace_back(bytes);
    return {};
  }
  std::string all() const {
    std::string out;
    for (const std::string& w : writes) out += w;
    return out;
  }
};

// A source over `bytes` that hands out at most `step` bytes a read and fails after `fail_after`
// bytes; counts what it handed out.
struct ChunkedSource final : EditSource {
  std::string bytes;
  std::size_t step = 1, fail_after = SIZE_MAX, at = 0;
  Result<std::size_t> read(std::span<char> buffer) override {
    if (at >= fail_after) return Error{"source broke"};
    const std::size_t n = std::min({buffer.size(), step, bytes.size() - at});
    std::memcpy(buffer.data(), bytes.data() + at, n);
    at += n;
    return n;
  }
};

}  // namespace

TEST(EditFile, StreamsGiveTheBytesOfMemoryInBoundedWrites) {
  auto t = noise_terrain(257);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 512);
  for (int k = 0; k < 80; ++k)  // most of its 9 x 9 chunks: several 64 KiB writes
    ASSERT_TRUE(t->apply_edit({.x = u(rng), .z = u(rng), .radius = 20, .depth = 2}));
  const std::string bytes = save_edits_to_memory(*t);
  ASSERT_GT(bytes.size(), std::size_t{3} << 16);
  RecordingSink sink;
  ASSERT_TRUE(save_edits(*t, sink));
  EXPECT_EQ(sink.all(), bytes);
  EXPECT_GT(sink.writes.size(), 3u);
  for (const std::string& w : sink.writes) EXPECT_LE(w.size(), std::size_t{1} << 16);
  // A sink error stops the save and comes back unchanged.
  RecordingSink failing;
  failing.fail_at = 2;
  const Status s = save_edits(*t, failing);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), "sink full");
  EXPECT_EQ(failing.writes.size(), 2u) << "nothing written after the error";
  // Loaded through a source that gives a byte, or 7, or 64 KiB at a time: the same terrain.
  for (const std::size_t step : {std::size_t{1}, std::size_t{7}, std::size_t{1} << 16}) {
    auto fresh = noise_terrain(257);
    ChunkedSource src;
    src.bytes = bytes;
    src.step = step;
    auto r = load_edits(*fresh, src);
    ASSERT_TRUE(r) << "step " << step << ": " << r.error().message;
    EXPECT_EQ(fresh->surface().heights_hash(), t->surface().heights_hash()) << "step " << step;
  }
}

TEST(EditFile, ASourceErrorOrAnOversizedStreamChangesNothing) {
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  const std::string bytes = save_edits_to_memory(*t);
  auto target = noise_terrain(129);
  const auto h0 = target->surface().heights_hash();
  // The source fails half way: its error, unchanged; nothing applied.
  ChunkedSource broken;
  broken.bytes = bytes;
  broken.step = 100;
  broken.fail_after = bytes.size() / 2;
  auto r = load_edits(*target, broken);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "source broke");
  EXPECT_EQ(target->surface().heights_hash(), h0);
  EXPECT_EQ(target->edit_version(), 0u);
  // A stream longer than any edit file of this terrain (5 x 5 chunks, 4 x 4 blocks of holes):
  // refused after reading one chunk past that size, not to its end.
  const std::size_t chunk = 8 + 4 * 32 * 32, largest = 64 + 25 * chunk + 16 * (8 + 128) + 8;
  ChunkedSource endless;
  endless.bytes = bytes + std::string(std::size_t{64} << 20, '\0');
  endless.step = std::size_t{1} << 16;
  r = load_edits(*target, endless);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("larger than any edit file of this terrain"), std::string::npos)
      << r.error().message;
  EXPECT_EQ(endless.at, largest + chunk + 1) << "read no further than needed";
  // The same length with a foreign header names the header's problem instead.
  endless.bytes[0] = 'X';
  endless.at = 0;
  r = load_edits(*target, endless);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("bad magic"), std::string::npos) << r.error().message;
  EXPECT_EQ(target->surface().heights_hash(), h0);
}

TEST(EditFile, EveryRegionOfTheHeaderAndBodyIsGuarded) {
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  ASSERT_TRUE(t->apply_edit({.brush = Brush::kRaise, .x = 200, .z = 230, .radius = 9, .depth = 3}));
  const std::string bytes = save_edits_to_memory(*t);
  const std::size_t chunk = 8 + 4 * 32 * 32;
  ASSERT_GE(t->surface().edited_chunks(), 2u);
  ASSERT_EQ(bytes.size(), 64 + t->surface().edited_chunks() * chunk + 8);
  // The fresh terrain the file is loaded onto; every refusal leaves it as it was.
  auto target = noise_terrain(129);
  const auto h0 = target->surface().heights_hash();
  ASSERT_TRUE(load_edits_from_memory(*target, bytes)) << "the intact file loads";
  ASSERT_EQ(target->surface().heights_hash(), t->surface().heights_hash());
  ASSERT_EQ(target->check_invariants(), "");
  target = noise_terrain(129);
  auto fnv = [](const std::string& b) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t k = 0; k + 8 < b.size(); ++k)
      h = (h ^ static_cast<unsigned char>(b[k])) * 1099511628211ull;
    return h;
  };
  auto reseal = [&](std::string b) {  // recompute the trailing checksum, little-endian
    const std::uint64_t h = fnv(b);
    std::memcpy(b.data() + b.size() - 8, &h, 8);
    return b;
  };
  auto refused = [&](const std::string& b, const std::string& why, std::size_t at) {
    auto r = load_edits_from_memory(*target, b);
    if (r) {
      ADD_FAILURE() << "byte " << at << ": accepted";
      return;
    }
    EXPECT_NE(r.error().message.find(why), std::string::npos)
        << "byte " << at << ": " << r.error().message << " (wanted '" << why << "')";
    EXPECT_EQ(r.error().message.rfind("edit file", 0), 0u) << r.error().message;
    EXPECT_EQ(target->surface().heights_hash(), h0) << "byte " << at << " changed the terrain";
    EXPECT_EQ(target->edit_version(), 0u);
  };
  // The header field each byte belongs to, and what a change there must say when the checksum is
  // left alone (fields checked before it) and when it is recomputed (the field's own check).
  struct Region {
    std::size_t from, to;
    const char *stale, *resealed;
  };
  const Region header[] = {
      {0, 8, "bad magic", "bad magic"},
      {8, 12, "version", "version"},
      {12, 16, "chunk size", "chunk size"},
      {16, 24, "another terrain", "another terrain"},
      {24, 32, "detail", "detail"},
      {32, 40, "terrain; this one is", "terrain; this one is"},
      {40, 48, "chunk", "chunk"},
      {48, 56, "hole block", "hole block"},  // the hole blocks' count (version 3)
      {56, 64, "checksum mismatch", "reserved header bytes"},
  };
  for (const Region& g : header)
    for (std::size_t at = g.from; at < g.to; ++at) {
      std::string c = bytes;
      c[at] = char(c[at] ^ 0x10);
      refused(c, g.stale, at);
      refused(reseal(c), g.resealed, at);
    }
  // The body: every chunk's indices and its first, a middle and its last value, and the checksum.
  for (std::size_t k = 0; k < t->surface().edited_chunks(); ++k) {
    const std::size_t base = 64 + k * chunk;
    for (std::size_t at = base; at < base + 8; ++at) {
      std::string c = bytes;
      c[at] = char(c[at] ^ 0x40);
      refused(c, "checksum mismatch", at);
      refused(reseal(c), "lies outside the terrain", at);  // 0x40 moves it off a 5 x 5 grid
    }
    for (std::size_t v : {std::size_t{0}, std::size_t{517}, std::size_t{1023}}) {
      const std::size_t at = base + 8 + 4 * v;
      std::string c = bytes;
      c[at + 1] = char(c[at + 1] ^ 0x01);
      refused(c, "checksum mismatch", at);
      for (float bad : {NAN, INFINITY, 3e5f}) {  // past the edit limits even when resealed
        std::memcpy(c.data() + at, &bad, 4);
        refused(reseal(c), "outside the edit limits", at);
      }
    }
  }
  for (std::size_t at = bytes.size() - 8; at < bytes.size(); ++at) {
    std::string c = bytes;
    c[at] = char(c[at] ^ 0x01);
    refused(c, "checksum mismatch", at);
  }
  // Chunks repeated or out of order (the second chunk's indices copied onto the first).
  {
    std::string c = bytes;
    std::memcpy(c.data() + 64, c.data() + 64 + chunk, 8);
    refused(reseal(c), "out of order or repeated", 64);
  }
  // Lengths: one byte short or long of what the chunk count says.
  refused(reseal(bytes.substr(0, bytes.size() - 1)), "truncated", bytes.size() - 1);
  refused(reseal(bytes + std::string(1, '\0')), "trailing bytes", bytes.size());
}
