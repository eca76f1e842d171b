// A terrain's pages, continued (world/page_store.h): the tessellator's record slots, the ray
// pyramid above the pages, and edits (copy on write, published on commit).
#include <algorithm>
#include <cmath>

#include "world/page_cache.h"
#include "world/page_store.h"

namespace ridgeline::world {

// ---- record slots -------------------------------------------------------------------------------

int PageStore::add_slot(std::shared_ptr<const RecordMaker> maker) {
  std::lock_guard lock(makers_mu_);
  for (std::size_t k = 0; k < kRecordSlots; ++k)
    if (!makers_[k]) {
      makers_[k] = std::move(maker);
      return int(k);
    }
  return -1;
}

void PageStore::remove_slot(int slot) {
  if (slot < 0 || std::size_t(slot) >= kRecordSlots) return;
  std::vector<std::shared_ptr<const Page>> changed;
  {
    std::lock_guard lock(cache_->mu);
    for (auto& [k, e] : cache_->resident) {
      if (!e.page->records[std::size_t(slot)]) continue;
      auto p = e.page->copy();
      p->records[std::size_t(slot)] = nullptr;
      cache_->bytes -= e.bytes;
      e.page = p;
      e.bytes = e.page->memory_bytes();
      cache_->bytes += e.bytes;
      changed.push_back(e.page);
    }
    std::lock_guard mlock(makers_mu_);
    makers_[std::size_t(slot)] = nullptr;
  }
  if (!changed.empty()) publish(changed, {});
}

const RecordMaker* PageStore::maker(int slot) const noexcept {
  std::lock_guard lock(makers_mu_);
  return slot >= 0 && std::size_t(slot) < kRecordSlots ? makers_[std::size_t(slot)].get()
                                                         : nullptr;
}

void PageStore::set_records(
    int slot,
    const std::vector<std::pair<PageKey, std::shared_ptr<const roam::RecordBlock>>>& blocks,
    bool edited) {
  std::vector<std::shared_ptr<const Page>> changed;
  {
    std::lock_guard lock(cache_->mu);
    for (const auto& [key, block] : blocks) {
      auto it = cache_->resident.find(key);
      if (it == cache_->resident.end()) continue;
      auto p = it->second.page->copy();
      p->records[std::size_t(slot)] = block;
      p->edited |= edited;
      std::shared_ptr<const Page> cp = std::move(p);
      cache_->insert(cp, *this, it->second.forever);
      changed.push_back(std::move(cp));
    }
  }
  if (!changed.empty()) publish(changed, {});
}

// ---- the pyramid above pages --------------------------------------------------------------------

void PageStore::rebuild_upper(std::int32_t px0, std::int32_t pz0, std::int32_t px1,
                              std::int32_t pz1) {
  if (upper_.empty()) {
    RayLevel l;
    l.nx = grid_.px[0], l.nz = grid_.pz[0];
    l.max.resize(std::size_t(l.nx) * l.nz), l.min.resize(l.max.size());
    upper_.push_back(std::move(l));
    while (upper_.back().nx > 1 || upper_.back().nz > 1) {
      RayLevel u;
      u.nx = (upper_.back().nx + 1) / 2, u.nz = (upper_.back().nz + 1) / 2;
      u.max.resize(std::size_t(u.nx) * u.nz), u.min.resize(u.max.size());
      upper_.push_back(std::move(u));
    }
  }
  for (std::int32_t z = pz0; z <= pz1; ++z)
    for (std::int32_t x = px0; x <= px1; ++x) {
      const PageSummary& s = summary(x, z);
      const std::size_t k = std::size_t(x) + std::size_t(z) * upper_[0].nx;
      upper_[0].min[k] = s.lo, upper_[0].max[k] = s.hi;
    }
  for (std::size_t l = 1; l < upper_.size(); ++l) {
    px0 >>= 1, px1 >>= 1, pz0 >>= 1, pz1 >>= 1;
    const RayLevel& b = upper_[l - 1];
    RayLevel& u = upper_[l];
    for (std::int32_t z = pz0; z <= pz1; ++z)
      for (std::int32_t x = px0; x <= px1; ++x) {
        float lo = INFINITY, hi = -INFINITY;
        for (int c = 0; c < 4; ++c) {
          const std::int32_t cx = 2 * x + (c & 1), cz = 2 * z + (c >> 1);
          if (cx >= b.nx || cz >= b.nz) continue;
          const std::size_t k = std::size_t(cx) + std::size_t(cz) * b.nx;
          lo = std::min(lo, b.min[k]), hi = std::max(hi, b.max[k]);
        }
        const std::size_t k = std::size_t(x) + std::size_t(z) * u.nx;
        u.min[k] = lo, u.max[k] = hi;
      }
  }
}

// ---- edits --------------------------------------------------------------------------------------

std::unique_ptr<PageEdit> PageStore::begin_edit() { return std::make_unique<PageEdit>(*this); }

Page& PageEdit::writable(const PageKey& key) {
  if (auto it = pages_.find(key); it != pages_.end()) return *it->second;
  last_ = nullptr;  // the page read last may be the one copied here
  const Page* cur = store_.require(key, keep_);
  RIDGELINE_ASSERT(cur != nullptr);
  auto p = cur->copy();
  // Edited pages hold floats.
  auto s = std::make_shared<PageSamples>();
  s->f32.resize(kPageEntries);
  for (std::size_t e = 0; e < kPageEntries; ++e) s->f32[e] = cur->local(e);
  s->materials = cur->samples->materials;
  p->set_samples(s, cur->scale);
  p->edited = true;
  samples_[key] = s;
  pages_[key] = p;
  touched_[key] = {kPageCells + kPageApron, kPageCells + kPageApron, -kPageApron, -kPageApron};
  return *p;
}

float PageEdit::height(std::int64_t i, std::int64_t j) {
  const PageKey key = store_.grid().page_of(0, i, j);
  const std::int32_t a = std::int32_t(i - (std::int64_t(key.px) << 8));
  const std::int32_t b = std::int32_t(j - (std::int64_t(key.pz) << 8));
  // Reads come in runs over one page (a brush's footprint, the pyramid above it): the page of
  // the last read is kept, and otherwise the edit's own copy, then the snapshot it holds, are
  // looked in before the store (whose require() takes its lock).
  if (last_ == nullptr || !(last_key_ == key)) {
    if (auto it = pages_.find(key); it != pages_.end())
      last_ = it->second.get();
    else if (const Page* p = keep_ ? keep_->find(key) : nullptr)
      last_ = p;
    else
      last_ = store_.require(key, keep_);
    last_key_ = key;
  }
  return last_ ? last_->local(a, b) : 0.0f;
}

void PageEdit::write(std::int64_t i, std::int64_t j, float h) {
  const PageGrid& g = store_.grid();
  for (std::uint32_t k = 0; k < g.levels; ++k) {
    const int ls = level_shift(k);
    const std::int64_t stride = std::int64_t{1} << ls;
    // The positions (in this level's entries) whose clamped sample is (i, j): the sample itself
    // when it lies on the stride, and the padding past the first and last samples.
    auto positions = [&](std::int64_t v, std::int64_t last, std::int32_t pages) {
      std::vector<std::int64_t> out;
      if ((v & (stride - 1)) == 0) out.push_back(v >> ls);
      if (v == 0) out.insert(out.end(), {-1, -2});
      if (v == last) {
        const std::int64_t end = std::int64_t(pages) * kPageCells + kPageApron;
        for (std::int64_t m = (last >> ls) + 1; m <= end; ++m) out.push_back(m);
      }
      return out;
    };
    const auto xs = positions(i, g.last_i, g.px[k]);
    const auto zs = positions(j, g.last_j, g.pz[k]);
    for (std::int64_t z : zs)
      for (std::int64_t x : xs) {
        // Pages whose entries -6 .. 262 hold position x: 256 px in x - 262 .. x + 6.
        const auto first = [](std::int64_t v) {
          return std::int32_t(std::max<std::int64_t>(0, floor_div(v - kPageCells - kPageApron + kPageCells - 1, kPageCells)));
        };
        const auto last = [](std::int64_t v, std::int32_t pages) {
          return std::int32_t(std::min<std::int64_t>(pages - 1, floor_div(v + kPageApron, kPageCells)));
        };
        const std::int32_t px0 = first(x), px1 = last(x, g.px[k]);
        const std::int32_t pz0 = first(z), pz1 = last(z, g.pz[k]);
        for (std::int32_t pz = pz0; pz <= pz1; ++pz)
          for (std::int32_t px = px0; px <= px1; ++px) {
            const std::int32_t a = std::int32_t(x - std::int64_t(px) * kPageCells);
            const std::int32_t b = std::int32_t(z - std::int64_t(pz) * kPageCells);
            if (a < -kPageApron || b < -kPageApron || a > kPageCells + kPageApron ||
                b > kPageCells + kPageApron)
              continue;
            const PageKey key{k, px, pz};
            writable(key);
            samples_[key]->f32[entry_index(a, b)] = h;
            auto& t = touched_[key];
            t[0] = std::min(t[0], a), t[1] = std::min(t[1], b);
            t[2] = std::max(t[2], a), t[3] = std::max(t[3], b);
          }
      }
  }
  WorldInfo& info = store_.info_;
  info.min_local = std::min(info.min_local, h);
  info.max_local = std::max(info.max_local, h);
}

std::vector<PageKey> PageEdit::commit() {
  std::vector<std::shared_ptr<const Page>> changed;
  std::vector<PageKey> level0;
  std::int32_t px0 = INT32_MAX, pz0 = INT32_MAX, px1 = -1, pz1 = -1;
  for (auto& [key, page] : pages_) {
    if (key.level == 0) {
      const auto& t = touched_[key];
      auto rays = std::make_shared<PageRays>(*page->rays);
      update_rays(*rays, *page, t[0], t[1], t[2], t[3]);
      page->rays = std::move(rays);
      level0.push_back(key);
      px0 = std::min(px0, key.px), px1 = std::max(px1, key.px);
      pz0 = std::min(pz0, key.pz), pz1 = std::max(pz1, key.pz);
    }
    changed.push_back(page);
  }
  {
    std::lock_guard lock(store_.cache_->mu);
    for (const auto& p : changed) store_.cache_->insert(p, store_, true);
  }
  store_.publish(changed, {});
  // Summaries of every page whose widened region holds a changed sample (exact: read back).
  if (px1 >= 0) {
    const PageGrid& g = store_.grid_;
    const std::int32_t sx0 = std::max(0, px0 - 1), sx1 = std::min(g.px[0] - 1, px1 + 1);
    const std::int32_t sz0 = std::max(0, pz0 - 1), sz1 = std::min(g.pz[0] - 1, pz1 + 1);
    for (std::int32_t pz = sz0; pz <= sz1; ++pz)
      for (std::int32_t px = sx0; px <= sx1; ++px)
        store_.summaries_[std::size_t(px) + std::size_t(pz) * std::size_t(g.px[0])] =
            summarize(g, px, pz, [&](std::int64_t i, std::int64_t j) { return height(i, j); });
    store_.rebuild_upper(sx0, sz0, sx1, sz1);
  }
  pages_.clear();
  samples_.clear();
  touched_.clear();
  return level0;
}

}  // namespace ridgeline::world
