// A terrain's pages (world/page_store.h): the resident set and its snapshots, the cache that
// pages a world in and pins (record slots, the pyramid above pages and edits: page_store_edit.cpp).
//
// The cache follows the detail cache's design (detail.h): requests are queued (urgent first),
// loaded by workers or the engine's executor with no lock held, integrated and evicted (LRU,
// under a byte budget) in update(), and published as an immutable snapshot that readers use
// without a lock. A page's missing ancestors are loaded with it, coarsest first (the
// tessellator reads a diamond's coarser ancestors before it).
#include "world/page_store.h"
#include "platform/thread_priority.h"
#include "world/page_cache.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "format.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/log.h"

namespace ridgeline::world {

using detail::fmt;

namespace {

// Size of a page's samples as a source must deliver them.
Status check_page_data(const WorldInfo& info, const PageKey& key, const PageData& d) {
  const bool u16 = info.format == SampleFormat::kU16;
  const std::size_t n = u16 ? d.u16.size() : d.f32.size();
  if (n != kPageEntries || (u16 ? !d.f32.empty() : !d.u16.empty()))
    return Error{fmt("%s: page (%u, %d, %d) holds %zu %s heights; need %zu", info.name.c_str(),
                     key.level, key.px, key.pz, n, u16 ? "16-bit" : "float", kPageEntries)};
  if (!d.materials.empty() && d.materials.size() != kPageEntries)
    return Error{fmt("%s: page (%u, %d, %d) holds %zu material ids; need %zu", info.name.c_str(),
                     key.level, key.px, key.pz, d.materials.size(), kPageEntries)};
  if (!u16)
    for (float v : d.f32)
      if (!std::isfinite(v) || std::abs(v) > kMaxRelativeHeight)
        return Error{fmt("%s: page (%u, %d, %d) holds the height %s", info.name.c_str(), key.level,
                         key.px, key.pz, detail::num(v).c_str())};
  return {};
}

// A level-0 page's heights against its summary in the source's index, which rays read before the
// page is ever loaded: a source whose summary does not hold what the page holds (a damaged index
// whose checksum still matched, a faulty writer) would make rays miss ground. The page's own
// cells give lo and hi exactly; the ring around it must widen them.
Status check_summary(const WorldInfo& info, const PageKey& key, const PageData& d,
                     const PageSummary& have) {
  float lo = INFINITY, hi = -INFINITY;
  for (std::int32_t b = 0; b <= kPageCells; ++b)
    for (std::int32_t a = 0; a <= kPageCells; ++a) {
      const std::size_t e = entry_index(a, b);
      const float v =
          d.f32.empty() ? static_cast<float>(info.height_scale * double(d.u16[e])) : d.f32[e];
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
  if (lo != have.lo || hi != have.hi || !(have.lo8 <= lo) || !(have.hi8 >= hi))
    return Error{fmt("%s: page (0, %d, %d) holds heights %s .. %s but its summary says %s .. %s "
                     "(ring %s .. %s): corrupted",
                     info.name.c_str(), key.px, key.pz, detail::num(lo).c_str(),
                     detail::num(hi).c_str(), detail::num(have.lo).c_str(),
                     detail::num(have.hi).c_str(), detail::num(have.lo8).c_str(),
                     detail::num(have.hi8).c_str())};
  return {};
}

// A level-0 page's entries outside the data (past the world's first or last row or column) hold
// copies of the nearest sample inside it, as the writer makes them and as every reader of the
// surface assumes (summaries, rays and bounds are made with indices clamped into the data). A
// source whose page holds anything else there is not trusted: those entries are set from the
// nearest entry inside the data, which a level-0 page always holds.
void clamp_outside_data(const PageGrid& g, const PageKey& key, PageData& d) {
  const std::int64_t i0 = std::int64_t(key.px) << 8, j0 = std::int64_t(key.pz) << 8;
  if (i0 - kPageApron >= 0 && j0 - kPageApron >= 0 && i0 + kPageCells + kPageApron <= g.last_i &&
      j0 + kPageCells + kPageApron <= g.last_j)
    return;  // every entry inside the data (all pages but those on the world's border)
  auto inside = [](std::int64_t v, std::int64_t base, std::int64_t last) {
    return std::int32_t(std::clamp<std::int64_t>(base + v, 0, last) - base);
  };
  for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b) {
    const std::int32_t cb = inside(b, j0, g.last_j);
    for (std::int32_t a = -kPageApron; a <= kPageCells + kPageApron; ++a) {
      const std::int32_t ca = inside(a, i0, g.last_i);
      if (ca == a && cb == b) continue;
      const std::size_t e = entry_index(a, b), from = entry_index(ca, cb);
      if (!d.u16.empty()) d.u16[e] = d.u16[from];
      if (!d.f32.empty()) d.f32[e] = d.f32[from];
      if (!d.materials.empty()) d.materials[e] = d.materials[from];
    }
  }
}

// What every page a source delivers goes through before it is made resident: its sizes and
// values checked, a level-0 page's entries outside the data made copies of the data's edge, and
// its heights held against its summary (summary: the page's, for level 0).
Status accept_page(const WorldInfo& info, const PageGrid& g, const PageKey& key, PageData& d,
                   const PageSummary& summary) {
  if (auto st = check_page_data(info, key, d); !st) return st;
  if (key.level != 0) return {};
  clamp_outside_data(g, key, d);
  return check_summary(info, key, d, summary);
}

}  // namespace

// ---- creation ---------------------------------------------------------------------------------

std::shared_ptr<PageStore> PageStore::from_heightfield(const Heightfield& hf, WorldInfo info) {
  std::shared_ptr<PageStore> s(new PageStore());
  s->info_ = std::move(info);
  s->grid_ = PageGrid::of(hf.width(), hf.height());
  s->cache_ = std::make_shared<Cache>();
  const bool u16 = s->info_.format == SampleFormat::kU16;
  std::vector<std::shared_ptr<const Page>> pages;
  std::vector<std::uint64_t> hashes(s->grid_.count(0));
  for (std::uint32_t k = 0; k < s->grid_.levels; ++k)
    for (std::int32_t pz = 0; pz < s->grid_.pz[k]; ++pz)
      for (std::int32_t px = 0; px < s->grid_.px[k]; ++px) {
        auto p = std::make_shared<Page>();
        p->key = {k, px, pz};
        p->set_samples(samples_from(hf, p->key, u16), s->info_.height_scale);
        if (k == 0) {
          p->rays = make_rays(*p);
          hashes[std::size_t(px) + std::size_t(pz) * std::size_t(s->grid_.px[0])] =
              hash_page(*p, s->grid_, s->info_.has_materials);
        }
        pages.push_back(std::move(p));
      }
  s->info_.content_hash = combine_hashes(hash_header(s->info_), hashes);
  s->summaries_.resize(s->grid_.count(0));
  for (std::int32_t pz = 0; pz < s->grid_.pz[0]; ++pz)
    for (std::int32_t px = 0; px < s->grid_.px[0]; ++px)
      s->summaries_[std::size_t(px) + std::size_t(pz) * std::size_t(s->grid_.px[0])] =
          summarize(s->grid_, px, pz,
                    [&](std::int64_t i, std::int64_t j) { return hf.local(std::uint32_t(i), std::uint32_t(j)); });
  s->rebuild_upper(0, 0, s->grid_.px[0] - 1, s->grid_.pz[0] - 1);
  for (const auto& p : pages) s->cache_->insert(p, *s, true);
  s->snapshot_ = std::make_shared<PageTable>(s->grid_);
  s->publish(pages, {});
  return s;
}

Result<std::shared_ptr<PageStore>> PageStore::open(std::shared_ptr<const PageSource> source,
                                                   const WorldCacheDesc& desc) {
  if (!source) return Error{"world: no page source given"};
  const WorldInfo& info = source->info();
  if (info.width < 2 || info.height < 2)
    return Error{fmt("%s: %u x %u samples; need at least 2 x 2", info.name.c_str(), info.width,
                     info.height)};
  if (desc.budget_bytes < (std::size_t{4} << 20))
    return Error{fmt("world cache: budget of %zu bytes; need at least 4 MiB (WorldCacheDesc::"
                     "budget_bytes, ridge --cache-mb)",
                     desc.budget_bytes)};
  if (desc.worker_threads > 64)
    return Error{fmt("world cache: %u worker threads; need 0..64", desc.worker_threads)};
  std::shared_ptr<PageStore> s(new PageStore());
  s->info_ = info;
  s->source_ = std::move(source);
  s->baked_ = s->source_->baked_records();
  s->grid_ = PageGrid::of(info.width, info.height);
  if (auto st = s->source_->summaries(s->summaries_); !st) return Error{st.message()};
  if (s->summaries_.size() != s->grid_.count(0))
    return Error{fmt("%s: %zu page summaries; need %zu", info.name.c_str(), s->summaries_.size(),
                     s->grid_.count(0))};
  {
    // The world's own holes, inside the cells.
    if (auto st = s->source_->holes(s->hole_runs_); !st) return Error{st.message()};
    for (const HoleRun& r : s->hole_runs_)
      if (r.i0 > r.i1 || std::uint64_t(r.i1) + 1 >= info.width ||
          std::uint64_t(r.j) + 1 >= info.height)
        return Error{fmt("%s: a hole run (row %u, cells %u .. %u) lies outside its %u x %u cells",
                         info.name.c_str(), r.j, r.i0, r.i1, info.width - 1, info.height - 1)};
  }
  s->rebuild_upper(0, 0, s->grid_.px[0] - 1, s->grid_.pz[0] - 1);
  auto c = std::make_shared<Cache>();
  c->budget = desc.budget_bytes;
  c->executor = desc.executor;
  c->synchronous = !desc.executor && desc.worker_threads == 0;
  c->stats.budget_bytes = desc.budget_bytes;
  s->cache_ = c;
  s->snapshot_ = std::make_shared<PageTable>(s->grid_);
  // The coarse levels: every page of the top `resident_levels` levels, kept, as long as they
  // stay within 16 MiB (about 40 pages). The top level is read here (a first mesh needs it);
  // with workers the levels below it are queued first, so that opening reads a few pages
  // whatever the world's size.
  std::vector<std::shared_ptr<const Page>> top;
  std::vector<PageKey> queued;
  std::size_t planned = 0;
  for (std::uint32_t r = 0; r < desc.resident_levels && r < s->grid_.levels; ++r) {
    const std::uint32_t k = s->grid_.levels - 1 - r;
    planned += s->grid_.count(k);
    if (planned > 40) break;
    for (std::int32_t pz = 0; pz < s->grid_.pz[k]; ++pz)
      for (std::int32_t px = 0; px < s->grid_.px[k]; ++px) {
        const PageKey key{k, px, pz};
        c->coarse.insert(key);
        if (r > 0 && !c->synchronous) {
          queued.push_back(key);
          continue;
        }
        PageData d;
        if (auto st = s->source_->load(key, d); !st) return Error{st.message()};
        if (auto st = accept_page(info, s->grid_, key, d, s->summary(px, pz)); !st)
          return Error{st.message()};
        top.push_back(s->make_page(key, std::move(d)));
      }
  }
  {
    std::lock_guard lock(c->mu);
    for (const auto& p : top) c->insert(p, *s, true);
    c->stats.loaded += top.size();
  }
  s->publish(top, {});
  if (!c->synchronous && !c->executor) {
    PageStore* raw = s.get();
    for (std::uint32_t t = 0; t < desc.worker_threads; ++t)
      c->workers.emplace_back([raw] {
        detail::lower_this_thread();
        Cache& cc = *raw->cache_;
        for (;;) {
          PageKey key;
          {
            std::unique_lock lock(cc.mu);
            cc.work_cv.wait(lock, [&] { return cc.stop || !cc.queue.empty(); });
            if (cc.stop) return;
            key = cc.queue.front();
            cc.queue.pop_front();
            ++cc.in_flight;
          }
          auto pages = raw->load_chain(key);
          std::lock_guard lock(cc.mu);
          for (auto& p : pages)
            if (!cc.resident.count(p->key)) cc.done.push_back(std::move(p));
          if (pages.empty()) cc.pending.erase(key);
          --cc.in_flight;
          if (cc.queue.empty() && cc.in_flight == 0) cc.idle_cv.notify_all();
        }
      });
  }
  if (!queued.empty()) s->request(queued, true);
  return s;
}

std::shared_ptr<PageStore> PageStore::clone() const {
  std::shared_ptr<PageStore> s(new PageStore());
  s->info_ = info_;
  s->grid_ = grid_;
  s->source_ = source_;
  s->baked_ = baked_;
  s->hole_runs_ = hole_runs_;
  s->summaries_ = summaries_;
  s->upper_ = upper_;
  auto c = std::make_shared<Cache>();
  {
    std::lock_guard lock(cache_->mu);
    c->budget = cache_->budget;
    c->stats.budget_bytes = cache_->budget;
    for (const auto& [k, e] : cache_->resident) c->insert(e.page, *this, e.forever || e.pins > 0);
  }
  s->cache_ = c;
  s->snapshot_ = snapshot();
  s->generation_.store(s->snapshot_->generation(), std::memory_order_release);
  return s;
}

PageStore::~PageStore() {
  if (!cache_) return;
  {
    std::lock_guard lock(cache_->mu);
    cache_->stop = true;
  }
  cache_->work_cv.notify_all();
  for (std::thread& t : cache_->workers) t.join();
}

// ---- snapshots ----------------------------------------------------------------------------------

void PageStore::publish(const std::vector<std::shared_ptr<const Page>>& changed,
                        const std::vector<PageKey>& removed) const {
  static std::atomic<std::uint64_t> next_generation{1};
  // One publisher at a time; what goes in is checked against the resident set under its lock,
  // so a page evicted (or replaced) since it was made never reaches the table.
  std::lock_guard lock(snapshot_mu_);
  std::vector<std::shared_ptr<const Page>> all, put;
  std::vector<PageKey> gone;
  {
    std::lock_guard clock(cache_->mu);
    all = cache_->all();
    for (const auto& p : changed)
      if (auto it = cache_->resident.find(p->key);
          it != cache_->resident.end() && it->second.page == p)
        put.push_back(p);
    for (const PageKey& k : removed)
      if (!cache_->resident.count(k)) gone.push_back(k);
  }
  const std::uint64_t g = next_generation.fetch_add(1, std::memory_order_relaxed);
  snapshot_ = snapshot_->with(put, gone, std::move(all), g);
  generation_.store(g, std::memory_order_release);
}

std::shared_ptr<const PageTable> PageStore::snapshot() const {
  std::lock_guard lock(snapshot_mu_);
  return snapshot_;
}

const PageTable& PageStore::current() const {
  // One snapshot per thread, refreshed when the store publishes (generations are unique across
  // stores, so a thread that alternates between terrains refreshes each time).
  thread_local std::uint64_t generation = 0;
  thread_local std::shared_ptr<const PageTable> table;
  const std::uint64_t g = generation_.load(std::memory_order_acquire);
  if (g != generation || !table) {
    table = snapshot();
    generation = table->generation();
  }
  return *table;
}

// ---- loading ------------------------------------------------------------------------------------

std::shared_ptr<const Page> PageStore::make_page(const PageKey& key, PageData&& d) const {
  auto p = std::make_shared<Page>();
  p->key = key;
  auto samples = std::make_shared<PageSamples>();
  samples->u16 = std::move(d.u16);
  samples->f32 = std::move(d.f32);
  samples->materials = std::move(d.materials);
  p->set_samples(std::move(samples), info_.height_scale);
  if (key.level == 0) p->rays = make_rays(*p);
  if (!d.records.empty())
    p->baked = std::make_shared<const std::vector<std::uint8_t>>(std::move(d.records));
  const auto makers = this->makers();
  for (std::size_t k = 0; k < kRecordSlots; ++k)
    if (makers[k]) p->records[k] = makers[k]->make(*p);
  return p;
}

std::shared_ptr<const Page> PageStore::with_all_records(std::shared_ptr<const Page> p) const {
  const auto makers = this->makers();
  std::shared_ptr<Page> copy;
  for (std::size_t k = 0; k < kRecordSlots; ++k)
    if (makers[k] && !p->records[k]) {
      if (!copy) copy = p->copy();
      copy->records[k] = makers[k]->make(*copy);
    }
  if (copy) return copy;
  return p;
}

std::vector<std::shared_ptr<const Page>> PageStore::load_chain(const PageKey& key) const {
  const auto t0 = std::chrono::steady_clock::now();
  // The page and its ancestors up to the first one available, coarsest loaded first.
  std::vector<PageKey> chain{key};
  {
    std::lock_guard lock(cache_->mu);
    if (auto p = cache_->available(key)) return {};
    if (cache_->failed.count(key)) return {};
    PageKey k = key;
    while (k.level + 1 < grid_.levels) {
      k = {k.level + 1, k.px >> 2, k.pz >> 2};
      if (cache_->available(k)) break;
      chain.push_back(k);
    }
  }
  std::vector<std::shared_ptr<const Page>> made;
  std::string error;
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    PageData d;
    Status st = source_->load(*it, d);
    if (st) st = accept_page(info_, grid_, *it, d, summary(it->px, it->pz));
    if (!st) {
      error = st.message();
      std::lock_guard lock(cache_->mu);
      if (cache_->failed.insert(*it).second) {
        ++cache_->stats.failed;
        log_message(LogLevel::kError, error);
      }
      break;
    }
    made.push_back(make_page(*it, std::move(d)));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::lock_guard lock(cache_->mu);
  cache_->stats.loaded += made.size();
  cache_->stats.load_seconds += seconds;
  return made;
}

const Page* PageStore::require(const PageKey& key, std::shared_ptr<const PageTable>& keep) const {
  keep = snapshot();
  if (const Page* p = keep->find(key)) return p;
  if (!source_) return nullptr;
  std::vector<std::shared_ptr<const Page>> pages;
  {
    std::unique_lock lock(cache_->mu);
    // Loaded by a worker and waiting for update(): integrate it now.
    for (auto it = cache_->done.begin(); it != cache_->done.end();)
      if ((*it)->key.level >= key.level) {
        pages.push_back(*it);
        it = cache_->done.erase(it);
      } else {
        ++it;
      }
  }
  bool have = false;
  for (const auto& p : pages) have |= p->key == key;
  if (!have) {
    auto loaded = load_chain(key);
    std::lock_guard lock(cache_->mu);
    if (!loaded.empty()) ++cache_->stats.sync_loads;
    for (auto& p : loaded) pages.push_back(std::move(p));
  }
  if (pages.empty()) return nullptr;
  for (auto& p : pages) p = with_all_records(std::move(p));
  {
    std::lock_guard lock(cache_->mu);
    for (const auto& p : pages) cache_->insert(p, *this, false);
  }
  publish(pages, {});
  keep = snapshot();
  return keep->find(key);
}

std::size_t PageStore::request(std::span<const PageKey> keys, bool urgent) const {
  if (!source_) return keys.size();
  Cache& c = *cache_;
  std::size_t resident = 0, queued = 0;
  std::vector<PageKey> sync;
  {
    std::lock_guard lock(c.mu);
    for (const PageKey& k : keys) {
      if (auto it = c.resident.find(k); it != c.resident.end()) {
        c.touch(it->second);
        ++resident;
        continue;
      }
      if (c.pending.count(k) || c.failed.count(k)) continue;
      c.pending.insert(k);
      if (c.synchronous) {
        sync.push_back(k);
        continue;
      }
      if (urgent)
        c.queue.push_front(k);
      else
        c.queue.push_back(k);
      ++queued;
    }
  }
  for (const PageKey& k : sync) {
    auto pages = load_chain(k);
    std::lock_guard lock(c.mu);
    for (auto& p : pages) c.done.push_back(std::move(p));
    if (pages.empty()) c.pending.erase(k);
  }
  if (queued > 0) {
    if (c.executor) {
      for (std::size_t n = 0; n < queued; ++n) {
        std::weak_ptr<Cache> weak = cache_;
        const PageStore* self = this;
        // The job takes the front key when it runs; a store destroyed meanwhile leaves it
        // nothing to do.
        c.executor([weak, self] {
          auto cc = weak.lock();
          if (!cc) return;
          PageKey key;
          {
            std::lock_guard lock(cc->mu);
            if (cc->stop || cc->queue.empty()) return;
            key = cc->queue.front();
            cc->queue.pop_front();
            ++cc->in_flight;
          }
          auto pages = self->load_chain(key);
          std::lock_guard lock(cc->mu);
          for (auto& p : pages) cc->done.push_back(std::move(p));
          if (pages.empty()) cc->pending.erase(key);
          --cc->in_flight;
          if (cc->queue.empty() && cc->in_flight == 0) cc->idle_cv.notify_all();
        });
      }
    } else if (queued == 1) {
      c.work_cv.notify_one();
    } else {
      c.work_cv.notify_all();
    }
  }
  return resident;
}

void PageStore::update(std::size_t max_integrations) const {
  if (!source_) return;
  Cache& c = *cache_;
  std::vector<std::shared_ptr<const Page>> changed;
  std::vector<PageKey> removed;
  {
    std::lock_guard lock(c.mu);
    std::size_t n = 0;
    while (!c.done.empty() && (max_integrations == 0 || n < max_integrations)) {
      auto p = std::move(c.done.front());
      c.done.erase(c.done.begin());
      if (!c.resident.count(p->key)) {
        p = with_all_records(std::move(p));
        c.insert(p, *this, false);
        changed.push_back(std::move(p));
        ++n;
      }
    }
    // Least recently used first; pinned, edited and coarse pages stay.
    for (auto it = c.lru.end(); c.bytes > c.budget && it != c.lru.begin();) {
      --it;
      auto e = c.resident.find(*it);
      if (e->second.forever || e->second.pins > 0) continue;
      c.bytes -= e->second.bytes;
      removed.push_back(*it);
      c.resident.erase(e);
      it = c.lru.erase(it);
      ++c.stats.evicted;
    }
  }
  if (!changed.empty() || !removed.empty()) publish(changed, removed);
}

bool PageStore::wait_idle(double timeout_seconds) const {
  std::unique_lock lock(cache_->mu);
  return cache_->idle_cv.wait_for(lock, std::chrono::duration<double>(timeout_seconds), [&] {
    return cache_->queue.empty() && cache_->in_flight == 0;
  });
}

void PageStore::pin(std::span<const PageKey> keys) const {
  std::shared_ptr<const PageTable> keep;
  for (const PageKey& k : keys) {
    require(k, keep);
    std::lock_guard lock(cache_->mu);
    if (auto it = cache_->resident.find(k); it != cache_->resident.end()) ++it->second.pins;
  }
}

void PageStore::unpin(std::span<const PageKey> keys) const {
  std::lock_guard lock(cache_->mu);
  for (const PageKey& k : keys)
    if (auto it = cache_->resident.find(k); it != cache_->resident.end() && it->second.pins > 0)
      --it->second.pins;
}

WorldStats PageStore::stats() const {
  std::lock_guard lock(cache_->mu);
  WorldStats s = cache_->stats;
  s.resident_pages = cache_->resident.size();
  s.resident_bytes = cache_->bytes;
  s.pending = cache_->pending.size();
  for (const auto& [k, e] : cache_->resident) {
    s.pinned_pages += (e.forever || e.pins > 0) ? 1 : 0;
    s.resident_samples += std::size_t(kPageCells) * kPageCells;
  }
  return s;
}

}  // namespace ridgeline::world
