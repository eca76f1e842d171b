// Storage for an array that grows in place: address space reserved once, pages committed as the
// array grows. Nothing ever moves (a vector's doubling copies the whole array, inside an update),
// and an element's address is base + index (fixed chunks cost a lookup of the chunk on every
// access: ~7 % of a ROAM update's instructions).
#pragma once

#include <cstddef>

namespace ridgeline::roam {

class Reservation {
 public:
  Reservation() = default;
  Reservation(const Reservation&) = delete;
  Reservation& operator=(const Reservation&) = delete;
  ~Reservation();

  /// Start of the range (nullptr until the first grow_to()).
  void* data() const noexcept { return base_; }
  /// Bytes usable from data() on.
  std::size_t committed() const noexcept { return committed_; }
  /// Makes the first `bytes` usable, committing whole `step`s; what was not usable before holds
  /// unspecified bytes (zeros, or what a destroyed reservation left). Reserves the range on
  /// first use: a destroyed reservation's range of the same `max_bytes`, its committed pages
  /// kept (a few are kept for reuse, up to 64 MiB committed in all), or else `max_bytes` of new
  /// address space, or less when the system refuses so much (halved down to 64 MiB). Throws
  /// std::bad_alloc when `bytes` exceeds the reservation or the system refuses the pages, like
  /// any allocation.
  void grow_to(std::size_t bytes, std::size_t step, std::size_t max_bytes);
  /// Gives the pages past the first `bytes` (rounded up to a page) back to the system; the range
  /// stays reserved. Their contents are lost.
  void shrink_to(std::size_t bytes) noexcept;

 private:
  void* base_ = nullptr;
  std::size_t reserved_ = 0, committed_ = 0;
};

}  // namespace ridgeline::roam
