// Storage for an array that grows in place: address space reserved once, pages committed as the
// array grows (platform/virtual_memory.h). Nothing ever moves (a vector's doubling copies the
// whole array, inside an update), and an element's address is base + index (fixed chunks cost a
// lookup of the chunk on every access: ~7 % of a ROAM update's instructions).
//
// Where no address space can be reserved (a build with RIDGELINE_PORTABLE, or a system that
// refuses even 64 MiB of it), the array is one plain allocation instead, which grows by half
// again (at least to what is asked) and moves when it grows or shrinks: its users read data()
// again after every grow_to() and shrink_to() and keep no pointer into it across them.
//
// A RangePool (what a public RoamMemory holds) keeps the ranges of destroyed reservations for
// the next ones, pages and all, and caps what all of its reservations commit.
#pragma once

#include <cstddef>
#include <mutex>
#include <new>
#include <string>
#include <vector>

namespace ridgeline::roam {

/// An array could not grow: past its reservation, past its pool's cap, or refused by the system.
/// Thrown inside a view's update (like std::bad_alloc, which it is) and turned into an error by
/// RoamView::update() (roam_view.h).
class OutOfMemory : public std::bad_alloc {
 public:
  explicit OutOfMemory(std::string what) : what_(std::move(what)) {}
  const char* what() const noexcept override { return what_.c_str(); }

 private:
  std::string what_;
};

/// Ranges of destroyed reservations, kept with their pages for the next reservation of the same
/// size (a view created after another reuses its pages instead of faulting in new ones: ~9 us a
/// page on the virtual machine the benchmarks run on; a build of 58k triangles commits ~1,100
/// pages), and the bytes its reservations commit, live and kept, under an optional cap.
/// Every call may run on any thread.
class RangePool {
 public:
  /// Keeps at most `max_spare_bytes` committed in kept ranges (and at most kMaxSpares ranges);
  /// refuses commits past `max_bytes` in all (0: no cap).
  RangePool(std::size_t max_spare_bytes, std::size_t max_bytes) noexcept
      : max_spare_bytes_(max_spare_bytes), max_bytes_(max_bytes) {}
  ~RangePool();
  RangePool(const RangePool&) = delete;
  RangePool& operator=(const RangePool&) = delete;

  struct Range {
    void* base = nullptr;
    std::size_t reserved = 0, committed = 0;
    bool in_place = false;  // reserved address space (else a plain allocation)
  };
  /// Takes the kept range of `reserved` bytes with the most pages committed; false when none.
  bool take(std::size_t reserved, Range& out);
  /// Keeps a destroyed reservation's range; false when the pool is full (the caller releases it).
  bool keep(const Range& r);
  /// Counts `bytes` more committed; when that would pass the cap, gives the kept ranges back
  /// first, and returns false (counting nothing) when it still would.
  bool charge(std::size_t bytes);
  /// Counts `bytes` fewer committed.
  void refund(std::size_t bytes) noexcept;
  /// Gives every kept range back to the system; returns the committed bytes they held.
  std::size_t release_spares() noexcept;

  std::size_t bytes() const noexcept;
  std::size_t spare_bytes() const noexcept;
  std::size_t max_bytes() const noexcept { return max_bytes_; }
  std::size_t max_spare_bytes() const noexcept { return max_spare_bytes_; }

  static constexpr std::size_t kMaxSpares = 8;

 private:
  std::size_t release_spares_locked() noexcept;
  const std::size_t max_spare_bytes_, max_bytes_;
  mutable std::mutex mutex_;
  std::vector<Range> spares_;
  std::size_t bytes_ = 0;        // committed by the pool's reservations, live and kept
  std::size_t spare_bytes_ = 0;  // of which kept
};

class Reservation {
 public:
  /// `name` says what the array holds in out-of-memory messages ("node array"); `pool`, when
  /// given, must outlive the reservation.
  explicit Reservation(const char* name = "array", RangePool* pool = nullptr) noexcept
      : name_(name), pool_(pool) {}
  Reservation(const Reservation&) = delete;
  Reservation& operator=(const Reservation&) = delete;
  ~Reservation();

  /// Start of the array (nullptr until the first grow_to()). Read again after grow_to() and
  /// shrink_to() unless grows_in_place().
  void* data() const noexcept { return base_; }
  /// Bytes usable from data() on.
  std::size_t committed() const noexcept { return committed_; }
  /// True when the array lives in reserved address space and never moves; false for a plain
  /// allocation (RIDGELINE_PORTABLE) and before the first grow_to().
  bool grows_in_place() const noexcept { return in_place_; }

  /// Makes the first `bytes` usable, committing whole `step`s; what was not usable before holds
  /// unspecified bytes (zeros, or what a destroyed reservation left). On first use takes a kept
  /// range of the same `max_bytes` from the pool, or else reserves `max_bytes` of address space
  /// (less when the system refuses so much: halved down to 64 MiB; a plain allocation when even
  /// that is refused). Throws OutOfMemory when `bytes` exceeds `max_bytes`, the pool's cap is
  /// reached or the system refuses the memory; what was usable stays usable then.
  void grow_to(std::size_t bytes, std::size_t step, std::size_t max_bytes);
  /// Gives the memory past the first `bytes` (rounded up to a page) back; the range stays
  /// reserved. Its contents are lost.
  void shrink_to(std::size_t bytes) noexcept;

 private:
  void grow_plain(std::size_t bytes, std::size_t step);
  [[noreturn]] void refuse(std::size_t bytes, const char* why) const;

  const char* name_;
  RangePool* pool_;
  void* base_ = nullptr;
  std::size_t reserved_ = 0, committed_ = 0;
  bool in_place_ = false;
};

}  // namespace ridgeline::roam
