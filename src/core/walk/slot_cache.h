// SlotCache: the last values a walk computed for triangle slots.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

namespace laser_raycast {
namespace core {

// The last values computed for triangle slots, by slot (a direct-mapped cache of N entries), for
// a walk whose beams ask about the same slots again and again.
template <class T, std::uint32_t N>
class SlotCache {
 public:
  template <class Make>
  const T& get(std::uint32_t slot, Make&& make) {
    Entry& e = entries_[slot % N];
    if (e.slot != slot) {
      e.slot = slot;
      e.value = make();
    }
    return e.value;
  }

 private:
  struct Entry {
    std::uint32_t slot = std::numeric_limits<std::uint32_t>::max();
    T value{};
  };
  std::array<Entry, N> entries_;
};

}  // namespace core
}  // namespace laser_raycast
