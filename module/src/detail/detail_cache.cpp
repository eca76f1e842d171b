// The detail tile cache (detail.h): tiles generated on demand by worker threads or the engine's
// job system, kept under a byte budget with LRU eviction, published to readers as immutable
// snapshots once per update().
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <list>
#include <mutex>
#include <thread>
#include <unordered_map>

#include "format.h"
#include "platform/thread_priority.h"
#include "ridgeline/detail.h"
#include "ridgeline/log.h"

namespace ridgeline {

std::ptrdiff_t DetailSnapshot::find_index(const DetailTileKey& key) const noexcept {
  if (index_.empty()) return -1;
  const std::size_t mask = index_.size() - 1;
  for (std::size_t h = DetailTileKeyHash{}(key)&mask;; h = (h + 1) & mask) {
    const std::int32_t e = index_[h];
    if (e < 0 || tiles_[std::size_t(e)]->key() == key) return e;
  }
}

const DetailTile* DetailSnapshot::find(const DetailTileKey& key) const noexcept {
  const std::ptrdiff_t e = find_index(key);
  return e < 0 ? nullptr : tiles_[std::size_t(e)].get();
}

struct DetailCache::State {
  std::shared_ptr<const DetailField> field;
  std::size_t budget = 0;
  bool synchronous = false;
  std::function<void(std::function<void()>)> executor;

  mutable std::mutex mu;
  // The published snapshot has its own lock, held only to copy or swap the pointer, so readers
  // never wait behind request() or update(). (std::atomic<std::shared_ptr> would do the same
  // with libstdc++'s internal spin bit, which ThreadSanitizer cannot see.)
  mutable std::mutex snapshot_mu;
  std::shared_ptr<const DetailSnapshot> snapshot;
  std::condition_variable work_cv, idle_cv;
  bool stop = false;
  std::vector<std::thread> workers;

  struct Entry {
    std::shared_ptr<const DetailTile> tile;
    std::list<DetailTileKey>::iterator lru;
  };
  std::unordered_map<DetailTileKey, Entry, DetailTileKeyHash> resident;
  std::list<DetailTileKey> lru;  // front: most recently used
  std::deque<DetailTileKey> queue;
  std::unordered_map<DetailTileKey, std::uint64_t, DetailTileKeyHash> pending;  // -> request frame
  std::unordered_map<DetailTileKey, std::shared_ptr<const DetailTile>, DetailTileKeyHash> done;
  std::size_t in_flight = 0;
  std::size_t bytes = 0;
  DetailCacheStats stats;
  std::chrono::steady_clock::time_point window_start = std::chrono::steady_clock::now();
  std::uint64_t window_generated = 0;

  // Swaps in a new snapshot; the old one is released outside snapshot_mu.
  void publish(std::shared_ptr<const DetailSnapshot> next) {
    static std::atomic<std::uint64_t> next_generation{1};
    {
      std::lock_guard<std::mutex> lock(snapshot_mu);
      snapshot.swap(next);
      generation.store(next_generation.fetch_add(1, std::memory_order_relaxed),
                       std::memory_order_release);
    }
  }
  std::atomic<std::uint64_t> generation{0};

  void touch(Entry& e) { lru.splice(lru.begin(), lru, e.lru); }
  /// Under the lock, asynchronous modes: what a request of `key` finds. Resident: marked used.
  /// Otherwise pending from now on, and queued (first when urgent) unless it already was or was
  /// generated as an ancestor (integrated at update()).
  enum class Admit { kResident, kWaiting, kQueued };
  Admit admit(const DetailTileKey& key, bool urgent) {
    if (auto it = resident.find(key); it != resident.end()) {
      touch(it->second);
      return Admit::kResident;
    }
    if (pending.count(key)) return Admit::kWaiting;
    pending.emplace(key, stats.frame);
    if (done.count(key)) return Admit::kWaiting;
    if (urgent)
      queue.push_front(key);
    else
      queue.push_back(key);
    return Admit::kQueued;
  }

  // A tile already generated (resident or waiting for integration), or null. Holds mu.
  std::shared_ptr<const DetailTile> available(const DetailTileKey& key) {
    if (auto it = resident.find(key); it != resident.end()) {
      touch(it->second);
      return it->second.tile;
    }
    if (auto it = done.find(key); it != done.end()) return it->second;
    return nullptr;
  }

  // Keys to generate for `key`, deepest ancestor last, and the nearest available ancestor.
  // Holds mu.
  std::vector<DetailTileKey> chain(const DetailTileKey& key,
                                   std::shared_ptr<const DetailTile>& parent) {
    std::vector<DetailTileKey> keys{key};
    DetailTileKey k = key;
    parent = nullptr;
    while (k.level > 1) {
      k = k.parent();
      if ((parent = available(k))) break;
      keys.push_back(k);
    }
    return keys;
  }

  // Generates the chain with mu released; returns the tiles, deepest ancestor first.
  std::vector<std::shared_ptr<const DetailTile>> generate(
      std::unique_lock<std::mutex>& lock, const std::vector<DetailTileKey>& keys,
      std::shared_ptr<const DetailTile> parent) {
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::shared_ptr<const DetailTile>> tiles;
    for (auto it = keys.rbegin(); it != keys.rend(); ++it) {
      parent = field->make_tile(*it, parent.get());
      tiles.push_back(parent);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lock.lock();
    stats.generated += tiles.size();
    stats.generation_seconds += seconds;
    return tiles;
  }

  void insert_resident(const std::shared_ptr<const DetailTile>& tile) {
    auto it = resident.find(tile->key());
    if (it != resident.end()) {
      touch(it->second);
      return;
    }
    lru.push_front(tile->key());
    resident.emplace(tile->key(), Entry{tile, lru.begin()});
    bytes += tile->memory_bytes();
  }

  void evict_to_budget() {
    while (bytes > budget && !lru.empty()) {
      const DetailTileKey k = lru.back();
      lru.pop_back();
      auto it = resident.find(k);
      bytes -= it->second.tile->memory_bytes();
      resident.erase(it);
      ++stats.evicted;
    }
  }

  std::shared_ptr<const DetailSnapshot> make_snapshot() const {
    auto snap = std::make_shared<DetailSnapshot>();
    snap->tiles_.reserve(resident.size());
    std::size_t size = 16;
    while (size < 2 * resident.size()) size *= 2;
    snap->index_.assign(size, -1);
    const DetailTileKeyHash hash;
    for (const auto& [key, entry] : resident) {
      std::size_t h = hash(key) & (size - 1);
      while (snap->index_[h] >= 0) h = (h + 1) & (size - 1);
      snap->index_[h] = static_cast<std::int32_t>(snap->tiles_.size());
      snap->tiles_.push_back(entry.tile);
    }
    return snap;
  }

  // One queued request, run by a worker or the engine's job system.
  static void run_one(const std::shared_ptr<State>& s) {
    std::unique_lock<std::mutex> lock(s->mu);
    if (s->stop || s->queue.empty()) return;
    const DetailTileKey key = s->queue.front();
    s->queue.pop_front();
    ++s->in_flight;
    if (!s->available(key)) {
      std::shared_ptr<const DetailTile> parent;
      const std::vector<DetailTileKey> keys = s->chain(key, parent);
      for (auto& tile : s->generate(lock, keys, std::move(parent)))
        if (!s->resident.count(tile->key())) s->done.emplace(tile->key(), tile);
    }
    --s->in_flight;
    if (s->queue.empty() && s->in_flight == 0) s->idle_cv.notify_all();
  }
};

Result<std::unique_ptr<DetailCache>> DetailCache::create(std::shared_ptr<const DetailField> field,
                                                         const DetailCacheDesc& desc) {
  if (!field) return Error{"detail cache: no detail field given"};
  if (field->levels() == 0) return Error{"detail cache: the detail field has 0 levels"};
  const std::size_t tile_bytes = sizeof(DetailTile) + std::size_t{kDetailTileStride} *
                                                          kDetailTileStride * sizeof(std::int32_t);
  const std::size_t min_budget = tile_bytes * (field->levels() + 1);
  if (desc.budget_bytes < min_budget)
    return Error{
        fmt("detail cache: budget of %zu bytes holds fewer than %u tiles of %zu bytes "
            "(one per level plus one); need at least %zu bytes",
            desc.budget_bytes, field->levels() + 1, tile_bytes, min_budget)};
  if (desc.worker_threads > 64)
    return Error{fmt("detail cache: %u worker threads; need 0..64", desc.worker_threads)};
  std::unique_ptr<DetailCache> cache(new DetailCache());
  cache->field_ = field;
  auto s = std::make_shared<State>();
  s->field = std::move(field);
  s->budget = desc.budget_bytes;
  s->executor = desc.executor;
  s->synchronous = !desc.executor && desc.worker_threads == 0;
  if (!desc.executor) {
    for (std::uint32_t t = 0; t < desc.worker_threads; ++t) {
      State* raw = s.get();
      std::weak_ptr<State> weak = s;
      s->workers.emplace_back([raw, weak] {
        detail::lower_this_thread();
        for (;;) {
          {
            std::unique_lock<std::mutex> lock(raw->mu);
            raw->work_cv.wait(lock, [raw] { return raw->stop || !raw->queue.empty(); });
            if (raw->stop) return;
          }
          // The cache joins its workers before releasing the state, so this lock always works.
          if (auto strong = weak.lock()) State::run_one(strong);
        }
      });
    }
  }
  cache->state_ = std::move(s);
  cache->state_->snapshot = std::make_shared<const DetailSnapshot>();
  return cache;
}

DetailCache::~DetailCache() {
  if (!state_) return;
  {
    std::lock_guard<std::mutex> lock(state_->mu);
    state_->stop = true;
  }
  state_->work_cv.notify_all();
  for (std::thread& t : state_->workers) t.join();
}

bool DetailCache::request(const DetailTileKey& key, bool urgent) {
  RIDGELINE_ASSERT(key.level >= 1 && key.level <= field_->levels());
  if (key.level < 1 || key.level > field_->levels()) return false;  // fallback after the assert
  State& s = *state_;
  std::unique_lock<std::mutex> lock(s.mu);
  if (s.synchronous) {
    if (auto it = s.resident.find(key); it != s.resident.end()) {
      s.touch(it->second);
      return true;
    }
    std::shared_ptr<const DetailTile> parent;
    const std::vector<DetailTileKey> keys = s.chain(key, parent);
    // Deepest ancestor first, the requested tile last: it ends most recently used, and the
    // budget holds a whole chain, so it is never the one evicted.
    for (auto& tile : s.generate(lock, keys, std::move(parent))) s.insert_resident(tile);
    if (auto it = s.resident.find(key); it != s.resident.end()) s.touch(it->second);
    s.evict_to_budget();
    s.publish(s.make_snapshot());
    return true;
  }
  if (const State::Admit a = s.admit(key, urgent); a != State::Admit::kQueued)
    return a == State::Admit::kResident;
  lock.unlock();
  if (!s.executor) {
    s.work_cv.notify_one();
    return false;
  }
  try {
    s.executor([st = state_] { State::run_one(st); });
  } catch (...) {
    // The engine's job system refused the job: withdraw the request, or every later job would
    // drain the queue one key behind (each job takes the front key) and one tile would never come.
    lock.lock();
    if (auto q = std::find(s.queue.begin(), s.queue.end(), key); q != s.queue.end()) {
      s.queue.erase(q);
      s.pending.erase(key);
    }
    throw;
  }
  return false;
}

std::size_t DetailCache::request_many(const DetailTileKey* keys, std::size_t count, bool urgent) {
  State& s = *state_;
  if (s.synchronous || s.executor) {  // each generates or hands a job out: one by one
    std::size_t resident = 0;
    for (std::size_t k = 0; k < count; ++k) resident += request(keys[k], urgent) ? 1 : 0;
    return resident;
  }
  std::size_t resident = 0, queued = 0;
  {
    std::lock_guard<std::mutex> lock(s.mu);
    for (std::size_t k = 0; k < count; ++k) {
      const DetailTileKey& key = keys[k];
      RIDGELINE_ASSERT(key.level >= 1 && key.level <= field_->levels());
      if (key.level < 1 || key.level > field_->levels()) continue;
      const State::Admit a = s.admit(key, urgent);
      resident += a == State::Admit::kResident ? 1 : 0;
      queued += a == State::Admit::kQueued ? 1 : 0;
    }
  }
  if (queued == 1)
    s.work_cv.notify_one();
  else if (queued > 1)
    s.work_cv.notify_all();
  return resident;
}

void DetailCache::update(std::size_t max_integrations) {
  State& s = *state_;
  std::lock_guard<std::mutex> lock(s.mu);
  ++s.stats.frame;
  bool changed = false;
  std::size_t n = 0;
  for (auto it = s.done.begin();
       it != s.done.end() && (max_integrations == 0 || n < max_integrations);) {
    s.insert_resident(it->second);
    if (auto p = s.pending.find(it->first); p != s.pending.end()) {
      s.stats.worst_lag_frames = std::max(s.stats.worst_lag_frames, s.stats.frame - p->second);
      s.pending.erase(p);
    }
    it = s.done.erase(it);
    ++n;
    changed = true;
  }
  s.stats.integrated += n;
  const std::uint64_t evicted_before = s.stats.evicted;
  s.evict_to_budget();
  changed |= s.stats.evicted != evicted_before;
  const auto now = std::chrono::steady_clock::now();
  const double dt = std::chrono::duration<double>(now - s.window_start).count();
  if (dt >= 1.0) {
    s.stats.generated_per_second = double(s.stats.generated - s.window_generated) / dt;
    s.window_start = now;
    s.window_generated = s.stats.generated;
  }
  if (changed) s.publish(s.make_snapshot());
}

std::shared_ptr<const DetailSnapshot> DetailCache::snapshot() const {
  std::lock_guard<std::mutex> lock(state_->snapshot_mu);
  return state_->snapshot;
}

std::shared_ptr<const DetailTile> DetailCache::try_get(const DetailTileKey& key) const {
  const std::shared_ptr<const DetailSnapshot> snap = snapshot();
  const std::ptrdiff_t e = snap->find_index(key);
  return e < 0 ? nullptr : snap->tiles_[std::size_t(e)];
}

bool DetailCache::wait_idle(double timeout_seconds) {
  State& s = *state_;
  std::unique_lock<std::mutex> lock(s.mu);
  return s.idle_cv.wait_for(lock, std::chrono::duration<double>(timeout_seconds),
                            [&] { return s.queue.empty() && s.in_flight == 0; });
}

std::uint64_t DetailCache::generation() const noexcept {
  return state_->generation.load(std::memory_order_acquire);
}

DetailCacheStats DetailCache::stats() const {
  const State& s = *state_;
  std::lock_guard<std::mutex> lock(s.mu);
  DetailCacheStats out = s.stats;
  out.resident_tiles = s.resident.size();
  out.resident_bytes = s.bytes;
  out.pending = s.pending.size();
  return out;
}

}  // namespace ridgeline
