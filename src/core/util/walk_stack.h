// The to-do list of a depth-first walk: entries pushed and popped last in, first out, in memory kept
// from walk to walk (a walk's stack would otherwise grow several times a scan). The mesh walk and
// the slice walk keep theirs in one; the frame walk orders its entries nearest first over the whole
// tree instead (a heap, frame_walk.cpp), and a traced beam's walk keeps a fixed array of node
// references (WideWalk, accel/wide_bvh.h).
#pragma once

#include <cstddef>
#include <vector>

namespace laser_raycast {
namespace core {

template <class Entry>
class WalkStack {
 public:
  explicit WalkStack(std::size_t capacity = 256) { items_.reserve(capacity); }

  bool empty() const { return items_.empty(); }
  void clear() { items_.clear(); }  // keeps the memory
  void push(const Entry& e) { items_.push_back(e); }
  Entry pop() {
    const Entry e = items_.back();
    items_.pop_back();
    return e;
  }

 private:
  std::vector<Entry> items_;
};

}  // namespace core
}  // namespace laser_raycast
