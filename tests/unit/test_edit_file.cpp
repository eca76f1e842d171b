// Edit files on disk (Ridgeline::io: io/edit_file.cpp) and the durable write under them
// (io/durable_file.cpp): round trips through files, missing and unreadable files, saves that fail
// and keep the previous file, temporary files never left behind. The bytes themselves are
// test_edit.cpp's; killed saves and full disks are test_faults.cpp's.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "io/durable_file.h"
#include "ridgeline/edit.h"
#include "ridgeline/edit_file.h"
#include "ridgeline/edit_json.h"
#include "ridgeline/heightfield.h"

using namespace ridgeline;
namespace fs = std::filesystem;

namespace {

std::shared_ptr<Terrain> noise_terrain(std::uint32_t n, std::uint32_t seed = 7) {
  return Terrain::create(
             std::move(make_default_heightfield({.size = n, .spacing = 2.0, .seed = seed})).value())
      .value();
}

// A fresh folder of its own for the running test (ctest runs tests in parallel).
fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(RIDGELINE_TEST_TMP) / ("edit_file_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Names in `dir` other than `keep`.
std::vector<std::string> others(const fs::path& dir, const std::string& keep) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != keep) out.push_back(e.path().filename());
  return out;
}

}  // namespace

TEST(EditFileIo, AFileHoldsTheBytesOfMemoryAndLoadsBack) {
  const fs::path dir = fresh_dir("round_trip");
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  const std::string file = (dir / "state.bin").string();
  ASSERT_TRUE(io::save_edits(*t, file));
  EXPECT_EQ(read_bytes(file), save_edits_to_memory(*t));
  EXPECT_EQ(others(dir, "state.bin"), std::vector<std::string>{}) << "temporary file left";
  auto fresh = noise_terrain(129);
  auto r = io::load_edits(*fresh, file);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(fresh->surface().heights_hash(), t->surface().heights_hash());
  // Saving again replaces the file.
  ASSERT_TRUE(t->apply_edit({.x = 200, .z = 200, .radius = 9, .depth = 3}));
  ASSERT_TRUE(io::save_edits(*t, file));
  EXPECT_EQ(read_bytes(file), save_edits_to_memory(*t));
}

TEST(EditFileIo, MissingForeignAndUnreadableFilesNameThePathAndChangeNothing) {
  const fs::path dir = fresh_dir("refusals");
  auto t = noise_terrain(129);
  const auto h0 = t->surface().heights_hash();
  auto missing = io::load_edits(*t, (dir / "missing.bin").string());
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("load edits '" + (dir / "missing.bin").string() + "'"),
            std::string::npos)
      << missing.error().message;
  auto folder = io::load_edits(*t, dir.string());
  ASSERT_FALSE(folder);
  EXPECT_NE(folder.error().message.find("load edits '"), std::string::npos);
  auto other = noise_terrain(129, 8);
  ASSERT_TRUE(other->apply_edit({.x = 40, .z = 60, .radius = 12, .depth = 4}));
  const std::string foreign = (dir / "other.bin").string();
  ASSERT_TRUE(io::save_edits(*other, foreign));
  auto r = io::load_edits(*t, foreign);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("load edits '" + foreign + "': edit file: saved for another "
                                   "terrain"),
            std::string::npos)
      << r.error().message;
  // A file far larger than any edit file of this terrain is refused without reading it whole.
  const std::string huge = (dir / "huge.bin").string();
  {
    std::string bytes = save_edits_to_memory(*t);
    bytes.resize(std::size_t{8} << 20, '\0');
    std::ofstream(huge, std::ios::binary) << bytes;
  }
  r = io::load_edits(*t, huge);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("larger than any edit file of this terrain"), std::string::npos)
      << r.error().message;
  EXPECT_EQ(t->surface().heights_hash(), h0);
  EXPECT_EQ(t->edit_version(), 0u);
}

TEST(EditFileIo, AFailedSaveKeepsThePreviousFileAndLeavesNoTemporaryFile) {
  const fs::path dir = fresh_dir("failed_save");
  auto t = noise_terrain(65);
  const std::string f = (dir / "state.bin").string();
  ASSERT_TRUE(io::save_edits(*t, f));  // the empty state
  std::string before = read_bytes(f);
  ASSERT_TRUE(t->apply_edit({.x = 32, .z = 32, .radius = 5}));
  // The folder is read-only: the temporary file cannot be created (root ignores the mode, so
  // the check needs another user).
  ::chmod(dir.c_str(), 0555);
  const bool root = ::geteuid() == 0;
  auto s = io::save_edits(*t, f);
  ::chmod(dir.c_str(), 0755);
  if (!root) {
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("save edits '" + f + "': cannot create"), std::string::npos)
        << s.message();
    EXPECT_NE(s.message().find("the previous file is unchanged"), std::string::npos)
        << s.message();
    EXPECT_EQ(read_bytes(f), before);
  } else {
    ASSERT_TRUE(s) << s.message();  // root wrote it: the edited state is what must now survive
    before = read_bytes(f);
  }
  // A folder that does not exist.
  const std::string nowhere = (dir / "no/such/dir/state.bin").string();
  s = io::save_edits(*t, nowhere);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("save edits '" + nowhere + "'"), std::string::npos) << s.message();
  EXPECT_EQ(read_bytes(f), before);
  EXPECT_EQ(others(dir, "state.bin"), std::vector<std::string>{}) << "temporary file left";
}

TEST(EditJson, HoleAndFillHoleAreBrushes) {
  auto edits = io::parse_edits(R"({"edits": [
      {"brush": "hole", "x": 101, "z": 61, "radius": 3},
      {"brush": "fill_hole", "x": 101, "z": 61, "radius": 1}]})");
  ASSERT_TRUE(edits) << edits.error().message;
  ASSERT_EQ(edits->size(), 2u);
  EXPECT_EQ((*edits)[0].brush, Brush::kHole);
  EXPECT_EQ((*edits)[1].brush, Brush::kFillHole);
  auto t = noise_terrain(129);
  ASSERT_TRUE(t->apply_edit((*edits)[0]));
  EXPECT_EQ(t->surface().hole_cells(), 9u);  // 2 m cells: the centre's and its 8 neighbours'
  EXPECT_FALSE(t->height(103, 63));
  ASSERT_TRUE(t->apply_edit((*edits)[1]));
  EXPECT_EQ(t->surface().hole_cells(), 8u);  // the centre's given back
  EXPECT_TRUE(t->height(101, 61));
  auto bad = io::parse_edits(R"({"edits": [{"brush": "holes", "x": 1, "z": 1, "radius": 1}]})");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("hole or fill_hole"), std::string::npos) << bad.error().message;
}

TEST(DurableFile, ATemporaryFileIsRemovedUnlessCommitted) {
  const fs::path dir = fresh_dir("durable");
  const std::string target = (dir / "out.bin").string();
  std::ofstream(target) << "previous";
  {
    auto f = io::durable::File::create(target);
    ASSERT_TRUE(f) << f.error().message;
    EXPECT_EQ(f->temp_path(), io::durable::temp_path_of(target));
    EXPECT_EQ(fs::path(f->temp_path()).parent_path(), dir) << "beside the target";
    ASSERT_TRUE(f->write("abandoned"));
    EXPECT_TRUE(fs::exists(f->temp_path()));
  }  // dropped without commit()
  EXPECT_EQ(read_bytes(target), "previous");
  EXPECT_EQ(others(dir, "out.bin"), std::vector<std::string>{});
  auto f = io::durable::File::create(target);
  ASSERT_TRUE(f);
  ASSERT_TRUE(f->write("new "));
  ASSERT_TRUE(f->write("content"));
  ASSERT_TRUE(f->commit());
  EXPECT_EQ(read_bytes(target), "new content");
  EXPECT_EQ(others(dir, "out.bin"), std::vector<std::string>{});
}

TEST(DurableFile, PutInPlaceRenamesAFinishedTemporaryFileOrSaysWhyNot) {
  const fs::path dir = fresh_dir("put_in_place");
  const std::string target = (dir / "world.bin").string(), tmp = target + ".tmp.x";
  std::ofstream(tmp) << "baked";
  ASSERT_TRUE(io::durable::put_in_place(tmp, target));
  EXPECT_EQ(read_bytes(target), "baked");
  EXPECT_FALSE(fs::exists(tmp));
  // A temporary file that is not there, and a target that is a non-empty folder.
  Status s = io::durable::put_in_place(tmp, target);
  ASSERT_FALSE(s);
  fs::create_directories(dir / "folder" / "inside");
  std::ofstream(tmp) << "baked";
  s = io::durable::put_in_place(tmp, (dir / "folder").string());
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("rename failed"), std::string::npos) << s.message();
  EXPECT_TRUE(fs::exists(tmp)) << "left for the caller";
}

// The fuzz_edit_state harness loads its inputs onto the default terrain of 33 x 33 samples
// (tests/fuzz/fuzz_edit_state.cpp): its seeds in the current format must be saves of that very
// terrain, or every mutation stops at the terrain-hash check and the loader goes unfuzzed.
TEST(EditFile, TheEditStateFuzzSeedsAreSavesOfTheHarnessTerrain) {
  DefaultTerrainParams p;
  p.size = 33;
  auto terrain = Terrain::create(std::move(make_default_heightfield(p)).value()).value();
  for (const char* name : {"v3_two_edits.bin", "v3_crater_and_holes.bin"}) {
    const std::string path = std::string(RIDGELINE_TEST_DATA) + "/../fuzz/corpus/fuzz_edit_state/" + name;
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << "cannot read " << path;
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto copy = terrain->clone();
    auto r = load_edits_from_memory(*copy, bytes);
    ASSERT_TRUE(r) << name << ": " << r.error().message;
    EXPECT_GT(copy->edit_version(), 0u) << name << " loaded no edit";
  }
}
