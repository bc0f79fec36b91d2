#include "laser_raycast/core/mesh.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {
namespace {

// Union-find over vertex indices: triangles sharing a vertex index are in one component. Only
// shared indices count (not equal positions): they are what makes a shared edge watertight.
// count (if not null): how many there are.
std::vector<std::uint32_t> labelComponents(std::size_t vertex_count,
                                           const std::vector<TriangleIndices>& triangles,
                                           std::uint32_t* count = nullptr) {
  std::vector<std::uint32_t> parent(vertex_count);
  for (std::uint32_t v = 0; v < parent.size(); ++v) parent[v] = v;
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const TriangleIndices& tri : triangles) {
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(tri[0]), b = find(tri[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::uint32_t> number(vertex_count, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> component(triangles.size());
  std::uint32_t next = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    std::uint32_t& n = number[find(triangles[t][0])];
    if (n == std::numeric_limits<std::uint32_t>::max()) n = next++;
    component[t] = n;
  }
  if (count) *count = next;
  return component;
}

// Which of the count components are closed: every edge between two of their vertex indices used by
// exactly two of their triangles, once in each direction. component: each triangle's;
// vertex_component: each used vertex's.
std::vector<char> closedByEdges(std::size_t vertex_count,
                                const std::vector<TriangleIndices>& triangles,
                                const std::vector<std::uint32_t>& component,
                                const std::vector<std::uint32_t>& vertex_component,
                                std::uint32_t count) {
  // A closed surface wound one way has every edge exactly twice, once each way. Each edge between
  // two vertices is listed under its lower vertex as (higher << 1 | whether it runs from the
  // higher); sorted, a vertex's list holds each of its edges' uses side by side. An edge's vertices
  // are in its triangle's component (components join the triangles that share a vertex), so the
  // vertex tells which component the edge decides.
  // Vertex indices too wide for the packed edges: taken as open (back faces are tested, which costs
  // time, never a range).
  if (vertex_count > (std::size_t{1} << 31)) return std::vector<char>(count, 0);
  std::vector<char> closed(count, 1);
  std::vector<std::uint32_t> start(vertex_count + 1, 0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = triangles[t][k], to = triangles[t][(k + 1) % 3];
      if (from == to) {
        closed[component[t]] = 0;
        continue;
      }
      ++start[std::min(from, to) + 1];
    }
  }
  for (std::size_t v = 0; v < vertex_count; ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> edges(start.back()), next(start.begin(), start.end() - 1);
  for (const TriangleIndices& tri : triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = tri[k], to = tri[(k + 1) % 3];
      if (from == to) continue;
      edges[next[std::min(from, to)]++] = std::max(from, to) << 1 | (from > to ? 1 : 0);
    }
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    const auto first = edges.begin() + start[v], last = edges.begin() + start[v + 1];
    std::sort(first, last);
    for (auto i = first; i != last;) {
      const std::uint32_t higher = *i >> 1;
      auto end = i + 1;
      while (end != last && *end >> 1 == higher) ++end;
      // Sorted, the one use each way is (higher << 1 | 0) then (higher << 1 | 1).
      const bool once_each_way = end - i == 2 && (i[0] & 1) == 0 && (i[1] & 1) == 1;
      if (!once_each_way) closed[vertex_component[v]] = 0;
      i = end;
    }
  }
  return closed;
}

}  // namespace

std::vector<Eigen::Vector3d> MeshVertices::toVector() const {
  if (!packed()) return full_;
  std::vector<Eigen::Vector3d> out;
  out.reserve(size());
  for (std::size_t i = 0; i < size(); ++i) out.push_back((*this)[i]);
  return out;
}

bool MeshVertices::pack(const Eigen::Vector3d& scale) {
  if (full_.empty() || packed()) return packed();
  if (!packableScale(scale)) return false;
  std::vector<std::array<float, 3>> packed(full_.size());
  for (std::size_t i = 0; i < full_.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      if (!floatTimesScale(full_[i][a], scale[a], &packed[i][a])) return false;
    }
  }
  packed_ = std::move(packed);
  scale_ = scale;
  std::vector<Eigen::Vector3d>().swap(full_);
  return true;
}

Mesh::Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
           const BvhConfig& bvh_config, const Eigen::Vector3d& float_scale)
    : triangles_(std::move(triangles)) {
  if (triangles_.empty()) throw std::invalid_argument("mesh has no triangles");
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (!vertices[i].allFinite()) {
      std::ostringstream msg;
      msg << "mesh vertex " << i << " is not finite (" << vertices[i].transpose() << ")";
      throw std::invalid_argument(msg.str());
    }
  }
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    for (const std::uint32_t v : triangles_[i]) {
      if (v >= vertices.size()) {
        std::ostringstream msg;
        msg << "mesh triangle " << i << " refers to vertex " << v << " but there are only "
            << vertices.size() << " vertices";
        throw std::invalid_argument(msg.str());
      }
    }
  }
  const std::vector<std::uint32_t> component =
      labelComponents(vertices.size(), triangles_, &component_count_);
  bvh_ = Bvh::build(vertices, triangles_, bvh_config, component);
  if (bvh_.empty()) {
    std::ostringstream msg;
    msg << "mesh has " << triangles_.size() << " triangles but all of them have zero area";
    throw std::invalid_argument(msg.str());
  }
  bvh_.packSlots(float_scale);
  vertices_ = MeshVertices(std::move(vertices));
  // Bounds and sphere over the vertices that triangles use (marked first, then read in order).
  std::vector<char> used(vertices_.size(), 0);
  for (const TriangleIndices& tri : triangles_) {
    for (const std::uint32_t v : tri) used[v] = 1;
  }
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (used[v]) bounds_.grow(vertices_[v]);
  }
  sphere_center_ = bounds_.center();
  double r2 = 0;
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (used[v]) r2 = std::max(r2, (vertices_[v] - sphere_center_).squaredNorm());
  }
  // Rounding of the squared norm and sqrt could put the farthest vertex just outside; widen by a
  // few ulps.
  sphere_radius_ = std::sqrt(r2) * (1 + 4 * std::numeric_limits<double>::epsilon());
  std::vector<std::uint32_t> slot_component;
  slot_component.reserve(bvh_.triangleIds().size());
  for (const std::uint32_t id : bvh_.triangleIds()) slot_component.push_back(component[id]);
  wide_ = std::make_unique<const WideBvh>(bvh_, slot_component);
  // Everything walks the wide BVH from here on.
  bvh_.releaseTree();
  findClosedComponents(component);
  vertices_.pack(float_scale);
}

void Mesh::visit(const std::function<bool(const Aabb&)>& descend,
                 const std::function<void(std::uint32_t)>& leaf) const {
  wide_->visit(descend, leaf);
}

Mesh::~Mesh() = default;

std::size_t Mesh::bytes() const {
  return vertices_.bytes() + triangles_.capacity() * sizeof(TriangleIndices) +
         closed_components_.capacity() * sizeof(ClosedComponent) +
         slot_closed_.capacity() * sizeof(std::uint32_t) + bvh_.bytes() + wide_->bytes();
}

void Mesh::findClosedComponents(const std::vector<std::uint32_t>& component) {
  // Each used vertex's component, from which the components' bounds, read in vertex order.
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> vertex_component(vertices_.size(), kUnused);
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    for (const std::uint32_t v : triangles_[t]) vertex_component[v] = component[t];
  }
  std::vector<Aabb> component_bounds(component_count_);
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (vertex_component[v] != kUnused) component_bounds[vertex_component[v]].grow(vertices_[v]);
  }
  const std::vector<char> closed =
      closedByEdges(vertices_.size(), triangles_, component, vertex_component, component_count_);
  // The orientation: the sign of the enclosed volume (six times it: the tetrahedra from a point of
  // the component's bounds to each triangle), kept only if it stands clear of the rounding.
  std::vector<double> volume(component_count_, 0.0), magnitude(component_count_, 0.0);
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const std::uint32_t c = component[t];
    const Eigen::Vector3d o = component_bounds[c].center();
    const auto& v = triangles_[t];
    const Eigen::Vector3d a = vertices_[v[0]] - o, b = vertices_[v[1]] - o, d = vertices_[v[2]] - o;
    const double term = a.dot(b.cross(d));
    volume[c] += term;
    magnitude[c] += a.norm() * b.norm() * d.norm();
  }
  // The closed components with a clear facing, numbered from 1 in a slot's entry.
  std::vector<std::uint32_t> closed_number(component_count_, 0);
  for (std::uint32_t c = 0; c < component_count_; ++c) {
    if (!closed[c] || !(std::abs(volume[c]) > 1e-9 * magnitude[c])) continue;
    closed_components_.push_back({component_bounds[c], volume[c] > 0 ? 1 : -1});
    closed_number[c] = static_cast<std::uint32_t>(closed_components_.size());
  }
  closed_components_.shrink_to_fit();
  if (closed_components_.empty()) return;
  slot_closed_.reserve(bvh_.triangleIds().size());
  for (const std::uint32_t id : bvh_.triangleIds())
    slot_closed_.push_back(closed_number[component[id]]);
}

std::vector<std::uint32_t> Mesh::components() const {
  return labelComponents(vertices_.size(), triangles_);
}

Eigen::Vector3d Mesh::normal(std::uint32_t triangle) const {
  const TriangleIndices& t = triangles_[triangle];
  return (vertices_[t[1]] - vertices_[t[0]]).cross(vertices_[t[2]] - vertices_[t[0]]).normalized();
}

void Mesh::setSurface(std::shared_ptr<const SurfaceAttributes> surface) {
  if (surface) surface->validate(vertices_.size(), triangles_.size());
  surface_ = std::move(surface);
}

}  // namespace core
}  // namespace laser_raycast
