// Arrays that grow in place in reserved address space, or in plain allocations where there is
// none, and the pool of destroyed arrays' ranges (reserved.h).
#include "roam/reserved.h"

#include <algorithm>
#include <cstring>

#include "format.h"
#include "platform/virtual_memory.h"

namespace ridgeline::roam {

namespace {

std::size_t round_up(std::size_t n, std::size_t step) noexcept {
  return (n + step - 1) / step * step;
}

// Plain allocations are line aligned, like the pages (the front's blocks are 64-byte aligned).
constexpr std::align_val_t kPlainAlign{64};

void release_range(const RangePool::Range& r) noexcept {
  if (r.in_place)
    platform::release(r.base, r.reserved);
  else
    ::operator delete(r.base, kPlainAlign);
}

}  // namespace

// ---- the pool ----------------------------------------------------------------------------------

RangePool::~RangePool() {
  (void)release_spares();
}

bool RangePool::take(std::size_t reserved, Range& out) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto best = spares_.end();
  for (auto it = spares_.begin(); it != spares_.end(); ++it)
    if (it->reserved == reserved && (best == spares_.end() || it->committed > best->committed))
      best = it;
  if (best == spares_.end()) return false;
  out = *best;
  spare_bytes_ -= best->committed;
  spares_.erase(best);
  return true;
}

bool RangePool::keep(const Range& r) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (spares_.size() >= kMaxSpares || spare_bytes_ + r.committed > max_spare_bytes_) return false;
  spares_.push_back(r);
  spare_bytes_ += r.committed;
  return true;
}

bool RangePool::charge(std::size_t bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (max_bytes_ != 0 && bytes_ + bytes > max_bytes_) {
    (void)release_spares_locked();
    if (bytes_ + bytes > max_bytes_) return false;
  }
  bytes_ += bytes;
  return true;
}

void RangePool::refund(std::size_t bytes) noexcept {
  std::lock_guard<std::mutex> lock(mutex_);
  bytes_ -= std::min(bytes, bytes_);
}

std::size_t RangePool::release_spares() noexcept {
  std::lock_guard<std::mutex> lock(mutex_);
  return release_spares_locked();
}

std::size_t RangePool::release_spares_locked() noexcept {
  const std::size_t freed = spare_bytes_;
  for (const Range& r : spares_) release_range(r);
  spares_.clear();
  bytes_ -= std::min(freed, bytes_);
  spare_bytes_ = 0;
  return freed;
}

std::size_t RangePool::bytes() const noexcept {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

std::size_t RangePool::spare_bytes() const noexcept {
  std::lock_guard<std::mutex> lock(mutex_);
  return spare_bytes_;
}

// ---- one array ---------------------------------------------------------------------------------

Reservation::~Reservation() {
  if (base_ == nullptr) return;
  const RangePool::Range r{base_, reserved_, committed_, in_place_};
  if (pool_ != nullptr && pool_->keep(r)) return;
  release_range(r);
  if (pool_ != nullptr) pool_->refund(committed_);
}

void Reservation::refuse(std::size_t bytes, const char* why) const {
  throw OutOfMemory(detail::fmt("%s of %zu bytes: %s", name_, bytes, why));
}

void Reservation::grow_to(std::size_t bytes, std::size_t step, std::size_t max_bytes) {
  if (bytes <= committed_) return;
  const std::size_t page = platform::page_size();
  const std::size_t range = round_up(max_bytes, page);
  if (base_ == nullptr && pool_ != nullptr) {
    // A destroyed reservation of the same size, the one with the most pages committed.
    RangePool::Range r;
    if (pool_->take(range, r)) {
      base_ = r.base, reserved_ = r.reserved, committed_ = r.committed, in_place_ = r.in_place;
      if (bytes <= committed_) return;
    }
  }
  if (base_ == nullptr) {
    // A process limited in address space (ulimit -v) gets a smaller range, and one refused
    // even the floor (or a build without virtual memory) a plain allocation.
    constexpr std::size_t kFloor = std::size_t{64} << 20;
    for (std::size_t r = range;; r = round_up(r / 2, page)) {
      if (void* p = platform::reserve(r)) {
        base_ = p, reserved_ = r, in_place_ = true;
        break;
      }
      if (r / 2 < std::min(kFloor, max_bytes)) break;
    }
    if (base_ == nullptr) reserved_ = range;
  }
  if (bytes > reserved_)
    refuse(bytes, in_place_ ? "past its reserved address space" : "past its largest size");
  if (!in_place_) {
    grow_plain(bytes, step);
    return;
  }
  const std::size_t want = std::min(round_up(round_up(bytes, step), page), reserved_);
  const std::size_t more = want - committed_;
  if (pool_ != nullptr && !pool_->charge(more))
    throw OutOfMemory(detail::fmt("%s of %zu bytes: past the RoamMemory's limit of %zu bytes",
                                  name_, bytes, pool_->max_bytes()));
  if (!platform::commit(static_cast<char*>(base_) + committed_, more)) {
    if (pool_ != nullptr) pool_->refund(more);
    refuse(bytes, "the system refused the pages");
  }
  committed_ = want;
}

void Reservation::grow_plain(std::size_t bytes, std::size_t step) {
  // A plain array is copied when it grows: by half again at least, so that a growing mesh
  // copies it a few times, not once per step.
  const std::size_t want =
      std::min(round_up(std::max(bytes, committed_ + committed_ / 2), step), reserved_);
  const std::size_t more = want - committed_;
  if (pool_ != nullptr && !pool_->charge(more))
    throw OutOfMemory(detail::fmt("%s of %zu bytes: past the RoamMemory's limit of %zu bytes",
                                  name_, bytes, pool_->max_bytes()));
  void* p = ::operator new(want, kPlainAlign, std::nothrow);
  if (p == nullptr) {
    if (pool_ != nullptr) pool_->refund(more);
    refuse(bytes, "the allocation failed");
  }
  if (base_ != nullptr) {
    std::memcpy(p, base_, committed_);
    ::operator delete(base_, kPlainAlign);
  }
  std::memset(static_cast<char*>(p) + committed_, 0, more);
  base_ = p;
  committed_ = want;
}

void Reservation::shrink_to(std::size_t bytes) noexcept {
  const std::size_t keep = round_up(bytes, platform::page_size());
  if (base_ == nullptr || keep >= committed_) return;
  if (in_place_) {
    if (!platform::decommit(static_cast<char*>(base_) + keep, committed_ - keep))
      return;  // keeps the pages: still correct, just not given back
  } else {
    // A plain array is copied to shrink: only when that gives back half of it at least (a mesh
    // that shrinks a little and grows back would copy it every update).
    if (keep > committed_ / 2) return;
    void* p = ::operator new(keep, kPlainAlign, std::nothrow);
    if (p == nullptr) return;
    std::memcpy(p, base_, keep);
    ::operator delete(base_, kPlainAlign);
    base_ = p;
  }
  if (pool_ != nullptr) pool_->refund(committed_ - keep);
  committed_ = keep;
}

}  // namespace ridgeline::roam
