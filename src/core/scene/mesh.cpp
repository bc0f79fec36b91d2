#include "laser_raycast/core/mesh.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {

Mesh::Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
           const BvhConfig& bvh_config, const Eigen::Vector3d& float_scale)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
  if (triangles_.empty()) throw std::invalid_argument("mesh has no triangles");
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    if (!vertices_[i].allFinite()) {
      std::ostringstream msg;
      msg << "mesh vertex " << i << " is not finite (" << vertices_[i].transpose() << ")";
      throw std::invalid_argument(msg.str());
    }
  }
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    for (const std::uint32_t v : triangles_[i]) {
      if (v >= vertices_.size()) {
        std::ostringstream msg;
        msg << "mesh triangle " << i << " refers to vertex " << v << " but there are only "
            << vertices_.size() << " vertices";
        throw std::invalid_argument(msg.str());
      }
    }
  }
  labelComponents();
  bvh_ = Bvh::build(vertices_, triangles_, bvh_config, component_);
  if (bvh_.empty()) {
    std::ostringstream msg;
    msg << "mesh has " << triangles_.size() << " triangles but all of them have zero area";
    throw std::invalid_argument(msg.str());
  }
  bvh_.packSlots(float_scale);
  // Bounds and sphere over the vertices that triangles use.
  for (const TriangleIndices& tri : triangles_) {
    for (const std::uint32_t v : tri) bounds_.grow(vertices_[v]);
  }
  sphere_center_ = bounds_.center();
  double r2 = 0;
  for (const TriangleIndices& tri : triangles_) {
    for (const std::uint32_t v : tri)
      r2 = std::max(r2, (vertices_[v] - sphere_center_).squaredNorm());
  }
  // Rounding of the squared norm and sqrt could put the farthest vertex just outside; widen by a
  // few ulps.
  sphere_radius_ = std::sqrt(r2) * (1 + 4 * std::numeric_limits<double>::epsilon());
  std::vector<std::uint32_t> slot_component;
  slot_component.reserve(bvh_.triangleIds().size());
  for (const std::uint32_t id : bvh_.triangleIds()) slot_component.push_back(component_[id]);
  wide_ = std::make_unique<const WideBvh>(bvh_, slot_component);
  // Everything walks the wide BVH from here on.
  bvh_.releaseTree();
  findClosedComponents();
}

void Mesh::visit(const std::function<bool(const Aabb&)>& descend,
                 const std::function<void(std::uint32_t)>& leaf) const {
  wide_->visit(descend, leaf);
}

Mesh::~Mesh() = default;

std::size_t Mesh::bytes() const {
  return vertices_.capacity() * sizeof(Eigen::Vector3d) +
         triangles_.capacity() * sizeof(TriangleIndices) +
         component_.capacity() * sizeof(std::uint32_t) +
         component_bounds_.capacity() * sizeof(Aabb) +
         slot_facing_.capacity() * sizeof(std::int8_t) + bvh_.bytes() + wide_->bytes();
}

void Mesh::findClosedComponents() {
  component_bounds_.assign(component_count_, Aabb{});
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    for (const std::uint32_t v : triangles_[t]) component_bounds_[component_[t]].grow(vertices_[v]);
  }
  // Every directed edge once, and its reverse once: a closed surface wound one way.
  std::vector<char> closed(component_count_, 1);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;  // (from << 32 | to, component)
  edges.reserve(triangles_.size() * 3);
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t from = triangles_[t][k], to = triangles_[t][(k + 1) % 3];
      if (from == to) closed[component_[t]] = 0;
      edges.emplace_back(from << 32 | to, component_[t]);
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const std::uint64_t e = edges[i].first;
    const bool repeated = i + 1 < edges.size() && edges[i + 1].first == e;
    const std::uint64_t reverse = (e & 0xffffffffull) << 32 | e >> 32;
    const bool paired =
        std::binary_search(edges.begin(), edges.end(), std::make_pair(reverse, std::uint32_t{0}),
                           [](const auto& x, const auto& y) { return x.first < y.first; });
    if (repeated || !paired) closed[edges[i].second] = 0;
  }
  // The orientation: the sign of the enclosed volume (six times it: the tetrahedra from a point of
  // the component's bounds to each triangle), kept only if it stands clear of the rounding.
  std::vector<double> volume(component_count_, 0.0), magnitude(component_count_, 0.0);
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const std::uint32_t c = component_[t];
    const Eigen::Vector3d o = component_bounds_[c].center();
    const auto& v = triangles_[t];
    const Eigen::Vector3d a = vertices_[v[0]] - o, b = vertices_[v[1]] - o, d = vertices_[v[2]] - o;
    const double term = a.dot(b.cross(d));
    volume[c] += term;
    magnitude[c] += a.norm() * b.norm() * d.norm();
  }
  slot_facing_.clear();
  slot_facing_.reserve(bvh_.triangleIds().size());
  for (const std::uint32_t id : bvh_.triangleIds()) {
    const std::uint32_t c = component_[id];
    const bool clear = std::abs(volume[c]) > 1e-9 * magnitude[c];
    slot_facing_.push_back(!closed[c] || !clear ? 0 : (volume[c] > 0 ? 1 : -1));
    has_closed_ = has_closed_ || slot_facing_.back() != 0;
  }
}

// Union-find over vertex indices: triangles sharing a vertex index are in one component. Only
// shared indices count (not equal positions): they are what makes a shared edge watertight.
void Mesh::labelComponents() {
  std::vector<std::uint32_t> parent(vertices_.size());
  for (std::uint32_t v = 0; v < parent.size(); ++v) parent[v] = v;
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const TriangleIndices& tri : triangles_) {
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(tri[0]), b = find(tri[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::uint32_t> number(vertices_.size(), std::numeric_limits<std::uint32_t>::max());
  component_.resize(triangles_.size());
  component_count_ = 0;
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    std::uint32_t& n = number[find(triangles_[t][0])];
    if (n == std::numeric_limits<std::uint32_t>::max()) n = component_count_++;
    component_[t] = n;
  }
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
