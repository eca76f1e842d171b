// Private: a terrain's pages (world.h): the resident set and its snapshots, the cache that pages
// a world in from its PageSource under a byte budget (workers or the engine's executor, urgent
// requests first, LRU eviction, never blocking a reader), pins, the copy-on-write edit of
// samples, and the tessellator's record slots.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "ridgeline/world.h"
#include "world/page.h"

namespace ridgeline::world {

struct PageKeyHash {
  std::size_t operator()(const PageKey& k) const noexcept {
    std::uint64_t h = (std::uint64_t(k.level) << 56) ^ (std::uint64_t(std::uint32_t(k.px)) << 28) ^
                      std::uint32_t(k.pz);
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    return std::size_t(h ^ (h >> 33));
  }
};

class PageStore;

/// What makes the tessellator's bounds of a page for one record slot (installed by a Landscape;
/// module/src/roam). Called on the thread that loaded the page, concurrently for several pages.
class RecordMaker {
 public:
  virtual ~RecordMaker() = default;
  /// The bounds of `page` (just loaded; not yet resident), or null when they cannot be made
  /// (the page stays without them and the tessellator treats it as missing). From the page
  /// alone: its apron holds every sample its diamonds' bounds read.
  virtual std::shared_ptr<const roam::RecordBlock> make(const Page& page) const = 0;
  /// Bytes of a block this maker made.
  virtual std::size_t bytes(const roam::RecordBlock& block) const noexcept = 0;
  /// After an edit changed stored samples [i0, i1] x [j0, j1] (its pages published): the pages
  /// whose bounds changed and their new blocks.
  virtual std::vector<std::pair<PageKey, std::shared_ptr<const roam::RecordBlock>>> remake(
      const PageStore& store, std::int64_t i0, std::int64_t j0, std::int64_t i1,
      std::int64_t j1) const = 0;
};

/// A copy-on-write edit of stored samples (PageStore::begin_edit()): writes go to copies of the
/// pages holding each sample (every level whose stride it lies on, aprons included), which
/// replace the originals when commit() publishes them. Exclusive access (terrain.h).
class PageEdit;

class PageStore {
 public:
  /// A store holding every page of `hf` (a terrain made in memory): nothing is ever evicted.
  static std::shared_ptr<PageStore> from_heightfield(const Heightfield& hf, WorldInfo info);
  /// A store paging `source` in (a baked world). Reads the summaries and loads the coarse levels.
  static Result<std::shared_ptr<PageStore>> open(std::shared_ptr<const PageSource> source,
                                                 const WorldCacheDesc& desc);
  /// A snapshot copy for another thread (Terrain::clone()): the same pages (shared), no source
  /// work of its own beyond synchronous loads, no record makers.
  std::shared_ptr<PageStore> clone() const;
  ~PageStore();
  PageStore(const PageStore&) = delete;
  PageStore& operator=(const PageStore&) = delete;

  const WorldInfo& info() const noexcept { return info_; }
  const PageGrid& grid() const noexcept { return grid_; }
  bool paged() const noexcept { return source_ != nullptr; }
  const PageSource* source() const noexcept { return source_.get(); }
  /// The world's own holes (PageSource::holes, checked to lie inside the cells), which its baked
  /// bounds were made around; empty without any (and for a store made in memory).
  const std::vector<HoleRun>& hole_runs() const noexcept { return hole_runs_; }

  /// The current snapshot (a shared_ptr copy under a small lock).
  std::shared_ptr<const PageTable> snapshot() const;
  /// The snapshot's generation (one atomic load): readers keep a snapshot per thread and take a
  /// new one when this changes.
  std::uint64_t generation() const noexcept { return generation_.load(std::memory_order_acquire); }
  /// The current snapshot as seen by this thread (refreshed when the store publishes).
  const PageTable& current() const;

  /// The page, loading it (and the ancestors it needs) on this thread when it is not resident
  /// (a synchronous load: counted in stats). Null when the source fails. The returned page lives
  /// as long as `keep`, which receives the snapshot holding it.
  const Page* require(const PageKey& key, std::shared_ptr<const PageTable>& keep) const;
  /// Queues the pages that are not resident (urgent ones first) and marks the resident ones
  /// used (LRU). Never waits. Returns how many were resident.
  std::size_t request(std::span<const PageKey> keys, bool urgent) const;
  /// Integrates the pages loaded since the last call (at most `max_integrations`, 0 = all),
  /// evicts least recently used pages beyond the budget, publishes a snapshot. Any thread.
  void update(std::size_t max_integrations = 0) const;
  /// Blocks until nothing is pending or `timeout_seconds` passed (tests, tools).
  bool wait_idle(double timeout_seconds) const;

  /// Keeps the given level-0 pages (and their ancestors) resident, loading the missing ones on
  /// this thread; unpin() releases them.
  void pin(std::span<const PageKey> keys) const;
  void unpin(std::span<const PageKey> keys) const;

  WorldStats stats() const;

  // ---- record slots (the tessellator's bounds, one slot per configuration) ----------------

  /// A free slot for `maker` (its bounds are made for pages loaded from now on), or -1 when
  /// every slot is taken. `preferred`: the slot of the baked configuration.
  int add_slot(std::shared_ptr<const RecordMaker> maker);
  /// Frees a slot: its bounds are dropped from the pages published next.
  void remove_slot(int slot);
  /// Replaces pages with versions carrying `blocks` in `slot` (bounds computed in bulk, or after
  /// an edit), and publishes. `edited`: the blocks follow an edit, so the pages now differ from
  /// their source and are never evicted (Page::edited). Exclusive access or the store's own
  /// callers only.
  void set_records(int slot,
                   const std::vector<std::pair<PageKey, std::shared_ptr<const roam::RecordBlock>>>&
                       blocks,
                   bool edited = false);
  const RecordMaker* maker(int slot) const noexcept;

  // ---- summaries and the ray pyramid above pages ---------------------------------------------

  /// The summary of level-0 page (px, pz) (clamped into the grid).
  const PageSummary& summary(std::int32_t px, std::int32_t pz) const noexcept {
    px = std::clamp(px, 0, grid_.px[0] - 1);
    pz = std::clamp(pz, 0, grid_.pz[0] - 1);
    return summaries_[std::size_t(px) + std::size_t(pz) * std::size_t(grid_.px[0])];
  }
  /// Min/max pyramid over level-0 pages: level 0 one node per page, each level above halving
  /// the count per axis, up to one node.
  struct RayLevel {
    std::int32_t nx = 0, nz = 0;
    std::vector<float> max, min;
  };
  const std::vector<RayLevel>& upper_rays() const noexcept { return upper_; }

  // ---- edits ----------------------------------------------------------------------------------

  std::unique_ptr<PageEdit> begin_edit();

 private:
  friend class PageEdit;
  PageStore() = default;
  struct Cache;
  void publish(const std::vector<std::shared_ptr<const Page>>& changed,
               const std::vector<PageKey>& removed) const;
  void rebuild_upper(std::int32_t px0, std::int32_t pz0, std::int32_t px1, std::int32_t pz1);
  // Loads `key` and the missing ancestors on this thread; returns the pages made (ancestors
  // first). Holds no lock while loading.
  std::vector<std::shared_ptr<const Page>> load_chain(const PageKey& key) const;
  std::shared_ptr<const Page> make_page(const PageKey& key, PageData&& data) const;

  WorldInfo info_;
  PageGrid grid_;
  std::shared_ptr<const PageSource> source_;
  BakedRecords baked_;
  std::vector<HoleRun> hole_runs_;
  std::vector<PageSummary> summaries_;
  std::vector<RayLevel> upper_;
  // The record makers by slot (Landscapes add and remove theirs while workers make pages):
  // read through makers() under makers_mu_.
  mutable std::mutex makers_mu_;
  std::array<std::shared_ptr<const RecordMaker>, kRecordSlots> makers_;
  std::array<std::shared_ptr<const RecordMaker>, kRecordSlots> makers() const {
    std::lock_guard lock(makers_mu_);
    return makers_;
  }
  // `p` with the records of every slot it lacks (a page made before its slot was added).
  std::shared_ptr<const Page> with_all_records(std::shared_ptr<const Page> p) const;
  mutable std::mutex snapshot_mu_;
  mutable std::shared_ptr<const PageTable> snapshot_;
  mutable std::atomic<std::uint64_t> generation_{0};
  std::shared_ptr<Cache> cache_;  // resident set, LRU, queue, workers
};

class PageEdit {
 public:
  explicit PageEdit(PageStore& store) : store_(store) {}
  /// Local height of stored sample (i, j) as the edit sees it (its own writes included).
  float height(std::int64_t i, std::int64_t j);
  /// Writes local height `h` at stored sample (i, j) (inside the data).
  void write(std::int64_t i, std::int64_t j, float h);
  /// Publishes the edited pages (ray pyramids, summaries and the pyramid above pages refreshed,
  /// min/max widened); returns the level-0 pages written.
  std::vector<PageKey> commit();

 private:
  Page& writable(const PageKey& key);
  PageStore& store_;
  std::unordered_map<PageKey, std::shared_ptr<Page>, PageKeyHash> pages_;
  std::unordered_map<PageKey, std::shared_ptr<PageSamples>, PageKeyHash> samples_;
  std::unordered_map<PageKey, std::array<std::int32_t, 4>, PageKeyHash> touched_;  // a0 b0 a1 b1
  std::shared_ptr<const PageTable> keep_;
  // The page height() read last (in pages_ or keep_), and its key.
  const Page* last_ = nullptr;
  PageKey last_key_{};
};

}  // namespace ridgeline::world
