// One name table per enum: the names that parameters, the CLI and the benchmark use, parsing, and
// the "one of ..." list that error messages print, all from the same entries.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <utility>

namespace laser_raycast {
namespace core {

template <typename E, std::size_t N>
class EnumNames {
 public:
  constexpr explicit EnumNames(std::array<std::pair<E, const char*>, N> entries)
      : entries_(entries) {}

  // The value's name; "unknown" for a value not in the table (a cast from a bad integer).
  const char* name(E value) const {
    for (const auto& [v, n] : entries_) {
      if (v == value) return n;
    }
    return "unknown";
  }

  // The value named `text`; false (and *value untouched) for anything else.
  bool parse(const std::string& text, E* value) const {
    for (const auto& [v, n] : entries_) {
      if (text == n) {
        *value = v;
        return true;
      }
    }
    return false;
  }

  // "a, b, c": every name, in table order.
  std::string list() const {
    std::string out;
    for (const auto& entry : entries_) out += (out.empty() ? "" : ", ") + std::string(entry.second);
    return out;
  }

  // "'x' is not one of a, b, c", for error messages.
  std::string notOneOf(const std::string& text) const {
    return "'" + text + "' is not one of " + list();
  }

  const std::array<std::pair<E, const char*>, N>& entries() const { return entries_; }

 private:
  std::array<std::pair<E, const char*>, N> entries_;
};

}  // namespace core
}  // namespace laser_raycast
