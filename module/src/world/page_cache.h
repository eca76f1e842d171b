// Private: the cache behind a PageStore (page_store.cpp, page_store_edit.cpp): the resident set,
// its LRU order and pins, the load queue and the workers.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "world/page_store.h"

namespace ridgeline::world {

struct PageStore::Cache {
  std::size_t budget = 0;  // 0: nothing is evicted (a terrain made in memory)
  bool synchronous = true;
  std::function<void(std::function<void()>)> executor;

  mutable std::mutex mu;
  std::condition_variable work_cv, idle_cv;
  bool stop = false;
  std::vector<std::thread> workers;

  struct Entry {
    std::shared_ptr<const Page> page;
    std::list<PageKey>::iterator lru;
    std::uint32_t pins = 0;
    bool forever = false;  // coarse levels and every page of a terrain made in memory
    std::size_t bytes = 0;
  };
  std::unordered_map<PageKey, Entry, PageKeyHash> resident;
  std::list<PageKey> lru;  // front: most recently used
  std::deque<PageKey> queue;
  std::unordered_set<PageKey, PageKeyHash> pending;  // queued or loading
  std::unordered_set<PageKey, PageKeyHash> failed;   // the source refused: not asked again
  std::unordered_set<PageKey, PageKeyHash> coarse;   // the resident levels: kept once loaded
  std::vector<std::shared_ptr<const Page>> done;     // loaded, waiting for update()
  std::size_t in_flight = 0;
  std::size_t bytes = 0;
  WorldStats stats;

  std::shared_ptr<const Page> available(const PageKey& k) const {
    if (auto it = resident.find(k); it != resident.end()) return it->second.page;
    for (const auto& p : done)
      if (p->key == k) return p;
    return nullptr;
  }
  void touch(Entry& e) { lru.splice(lru.begin(), lru, e.lru); }
  std::size_t page_bytes(const Page& p, const PageStore& s) const {
    std::size_t b = p.memory_bytes();
    const auto makers = s.makers();
    for (std::size_t k = 0; k < kRecordSlots; ++k)
      if (p.records[k] && makers[k]) b += makers[k]->bytes(*p.records[k]);
    return b;
  }
  // Puts a page in the resident set (replacing an older version). Holds mu.
  void insert(const std::shared_ptr<const Page>& p, const PageStore& s, bool forever) {
    auto it = resident.find(p->key);
    if (it != resident.end()) {
      bytes -= it->second.bytes;
      it->second.page = p;
      it->second.forever |= forever || p->edited;
      it->second.bytes = page_bytes(*p, s);
      bytes += it->second.bytes;
      touch(it->second);
      return;
    }
    lru.push_front(p->key);
    Entry e{p, lru.begin(), 0, forever || p->edited || coarse.count(p->key) != 0, page_bytes(*p, s)};
    bytes += e.bytes;
    resident.emplace(p->key, std::move(e));
    pending.erase(p->key);
  }
  std::vector<std::shared_ptr<const Page>> all() const {
    std::vector<std::shared_ptr<const Page>> v;
    v.reserve(resident.size());
    for (const auto& [k, e] : resident) v.push_back(e.page);
    return v;
  }
};

}  // namespace ridgeline::world
