// Joining vertices of equal coordinates as a mesh file is read (stl_reader.cpp, obj_reader.cpp):
// an open-addressing hash over the vertices returned so far, 4 bytes a slot, at most half full.
// Equal means equal coordinates (so -0 is 0): assimp's JoinIdenticalVertices also compares the
// facet normal it copies to every corner of an STL, and so keeps a vertex apart for each facet
// plane that meets there; joined on position alone, a closed surface shares its edges (the fan
// slicer's outlines and core::Mesh's closed components need that). Private to the loader.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "laser_raycast/loader/errors.h"

namespace laser_raycast {
namespace mesh_file {

class VertexJoiner {
 public:
  VertexJoiner(const Eigen::Vector3d& scale, std::vector<Eigen::Vector3d>* vertices)
      : to_link_(Eigen::Scaling(scale)), vertices_(vertices) {
    rehash(std::size_t(1) << 16);
  }

  // Room for about `count` vertices, to spare the growth copies of a mesh whose size is known.
  void reserve(std::size_t count) {
    vertices_->reserve(count);
    std::size_t slots = slots_.size();
    while (slots < 2 * count) slots *= 2;
    if (slots > slots_.size()) rehash(slots);
  }

  // The index of the vertex at (x, y, z), scaled, added if new.
  std::uint32_t add(float x, float y, float z) {
    const Eigen::Vector3d v = place(x, y, z);
    return add(v, hashOf(v));
  }

  // The indices of `count` corners (x y z each, one after the other) into indices. The same as
  // add() for each in turn, with the slots they hash to fetched ahead: on a large mesh nearly every
  // lookup misses the cache, and waiting for one at a time took twice as long.
  void addAll(const float* xyz, std::size_t count, std::uint32_t* indices) {
    constexpr std::size_t kAhead = 64;
    Eigen::Vector3d v[kAhead];
    std::size_t hash[kAhead];
    for (std::size_t first = 0; first < count; first += kAhead) {
      const std::size_t n = std::min(kAhead, count - first);
      for (std::size_t i = 0; i < n; ++i) {
        const float* p = xyz + 3 * (first + i);
        v[i] = place(p[0], p[1], p[2]);
        hash[i] = hashOf(v[i]);
        __builtin_prefetch(&slots_[hash[i] & mask_]);
      }
      for (std::size_t i = 0; i < n; ++i) indices[first + i] = add(v[i], hash[i]);
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

  // As the assimp path places a vertex: the scaling as an affine product, rounding included.
  Eigen::Vector3d place(float x, float y, float z) const {
    return to_link_ * Eigen::Vector3d(x, y, z);
  }

  std::uint32_t add(const Eigen::Vector3d& v, std::size_t hash) {
    for (std::size_t slot = hash & mask_;; slot = (slot + 1) & mask_) {
      const std::uint32_t index = slots_[slot];
      if (index == kEmpty) break;
      if ((*vertices_)[index] == v) return index;
    }
    if (vertices_->size() >= kEmpty) {
      throw SceneLoadError("more vertices than 32-bit indices can address");
    }
    const auto index = static_cast<std::uint32_t>(vertices_->size());
    // Grown by a quarter rather than doubled: the old and the new array are both held while it
    // moves, and a mesh a little beyond its reserve would otherwise take twice its size.
    if (vertices_->size() == vertices_->capacity()) {
      vertices_->reserve(vertices_->size() + vertices_->size() / 4 + 1024);
    }
    vertices_->push_back(v);
    if (2 * vertices_->size() > slots_.size()) {
      rehash(2 * slots_.size());
    } else {
      insert(index);
    }
    return index;
  }

  static std::uint64_t bits(double value) {
    value += 0.0;  // -0 becomes 0, which it equals
    std::uint64_t out;
    std::memcpy(&out, &value, sizeof(out));
    return out;
  }
  static std::size_t hashOf(const Eigen::Vector3d& v) {
    std::uint64_t h = bits(v.x()) * 0x9e3779b97f4a7c15ULL;
    h = (h ^ (h >> 31) ^ bits(v.y())) * 0xbf58476d1ce4e5b9ULL;
    h = (h ^ (h >> 29) ^ bits(v.z())) * 0x94d049bb133111ebULL;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }

  void insert(std::uint32_t index) {
    std::size_t slot = hashOf((*vertices_)[index]) & mask_;
    while (slots_[slot] != kEmpty) slot = (slot + 1) & mask_;
    slots_[slot] = index;
  }
  void rehash(std::size_t slots) {
    slots_.assign(slots, kEmpty);
    mask_ = slots - 1;
    for (std::size_t i = 0; i < vertices_->size(); ++i) insert(static_cast<std::uint32_t>(i));
  }

  Eigen::Affine3d to_link_;
  std::vector<Eigen::Vector3d>* vertices_;
  std::vector<std::uint32_t> slots_;
  std::size_t mask_ = 0;
};

}  // namespace mesh_file
}  // namespace laser_raycast
