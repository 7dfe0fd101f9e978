// The planners' open list: a 4-ary min-heap of (f, h, state) with lazy deletion (stale
// entries are skipped by the caller when popped). Half the depth of a binary heap, and a
// branch-free choice among the children. Among equal f the state nearer the goal (smaller
// h) comes first; f and h are stored as the bit patterns of non-negative double / float,
// which order like the values: integer compares, no NaN branch.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace lf3pm {

class OpenList {
  struct Entry {
    std::uint64_t f;
    std::uint32_t h;  // tie-break: among equal f, expand the state nearer the goal first
    std::uint32_t state;
  };
  static bool before(const Entry& a, const Entry& b) { return (a.f < b.f) | ((a.f == b.f) & (a.h < b.h)); }

 public:
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }

  void push(std::uint32_t state, double f, double h) {
    Entry e{bits(f), bits(float(h)), state};
    std::size_t i = heap_.size();
    heap_.push_back(e);
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!before(e, heap_[parent])) break;
      heap_[i] = heap_[parent];
      i = parent;
    }
    heap_[i] = e;
  }

  std::uint32_t pop() {
    const std::uint32_t top = heap_[0].state;
    const Entry last = heap_.back();
    heap_.pop_back();
    const std::size_t n = heap_.size();
    if (n == 0) return top;
    std::size_t i = 0;
    for (;;) {
      const std::size_t first = 4 * i + 1;
      if (first >= n) break;
      std::size_t best = first;
      const std::size_t end = std::min(first + 4, n);
      for (std::size_t c = first + 1; c < end; ++c) best = before(heap_[c], heap_[best]) ? c : best;
      if (!before(heap_[best], last)) break;
      heap_[i] = heap_[best];
      i = best;
    }
    heap_[i] = last;
    return top;
  }

 private:
  static std::uint64_t bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  static std::uint32_t bits(float v) {
    std::uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  std::vector<Entry> heap_;
};

}  // namespace lf3pm
