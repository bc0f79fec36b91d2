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
  explicit WalkStack(std::size_t capacity = 256) : items_(capacity) {}

  bool empty() const { return top_ == 0; }
  void clear() { top_ = 0; }
  void push(const Entry& e) {
    if (top_ == items_.size()) items_.resize(items_.size() * 2);
    items_[top_++] = e;
  }
  Entry pop() { return items_[--top_]; }

 private:
  std::vector<Entry> items_;
  std::size_t top_ = 0;
};

}  // namespace core
}  // namespace laser_raycast
