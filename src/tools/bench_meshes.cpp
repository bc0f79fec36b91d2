#include "bench_meshes.h"

#include <cmath>

namespace laser_raycast {
namespace bench {
namespace {

constexpr double kTwoPi = 2 * M_PI;

}  // namespace

PoseL poseFromParams(double x, double y, double z, double roll, double pitch, double yaw) {
  const Real cr = std::cos(static_cast<Real>(roll)), sr = std::sin(static_cast<Real>(roll));
  const Real cp = std::cos(static_cast<Real>(pitch)), sp = std::sin(static_cast<Real>(pitch));
  const Real cy = std::cos(static_cast<Real>(yaw)), sy = std::sin(static_cast<Real>(yaw));
  Mat3L rx, ry, rz;
  rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  PoseL pose;
  pose.rot = rz * ry * rx;
  pose.trans = Vec3L(x, y, z);
  return pose;
}

Eigen::Isometry3d toIsometry(const PoseL& pose) {
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = pose.rot.cast<double>();
  iso.translation() = pose.trans.cast<double>();
  return iso;
}

PoseL fromIsometry(const Eigen::Isometry3d& pose) {
  return PoseL{pose.linear().cast<Real>(), pose.translation().cast<Real>()};
}

std::shared_ptr<const core::Mesh> meshAsRead(const MeshData& mesh) {
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) {
    vertices.emplace_back(core::keptFloat(v.x()), core::keptFloat(v.y()), core::keptFloat(v.z()));
  }
  return std::make_shared<const core::Mesh>(std::move(vertices), mesh.triangles);
}

void MeshData::append(const MeshData& other) {
  const auto offset = static_cast<std::uint32_t>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles) {
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
}

void MeshData::quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  triangles.push_back({a, b, c});
  triangles.push_back({a, c, d});
}

MeshData cylinderMesh(double radius, const std::vector<double>& ring_z, int segments, bool caps) {
  return taperedCylinderMesh(radius, radius, ring_z, segments, caps);
}

MeshData taperedCylinderMesh(double bottom_radius, double top_radius,
                             const std::vector<double>& ring_z, int segments, bool caps) {
  MeshData m;
  const double z0 = ring_z.front(), height = ring_z.back() - ring_z.front();
  for (const double z : ring_z) {
    // With equal radii the second term is exactly 0, whatever the height.
    const double radius =
        bottom_radius + (height > 0 ? (top_radius - bottom_radius) * ((z - z0) / height) : 0.0);
    for (int k = 0; k < segments; ++k) {
      const double a = kTwoPi * k / segments;
      m.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
    }
  }
  const auto n = static_cast<std::uint32_t>(segments);
  auto at = [n](std::size_t ring, std::uint32_t k) {
    return static_cast<std::uint32_t>(ring * n + k % n);
  };
  for (std::size_t r = 0; r + 1 < ring_z.size(); ++r) {
    for (std::uint32_t k = 0; k < n; ++k)
      m.quad(at(r, k), at(r, k + 1), at(r + 1, k + 1), at(r + 1, k));
  }
  if (caps) {
    const auto bottom = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.emplace_back(0, 0, ring_z.front());
    m.vertices.emplace_back(0, 0, ring_z.back());
    const std::size_t top_ring = ring_z.size() - 1;
    for (std::uint32_t k = 0; k < n; ++k) {
      m.triangles.push_back({bottom, at(0, k + 1), at(0, k)});
      m.triangles.push_back({bottom + 1, at(top_ring, k), at(top_ring, k + 1)});
    }
  }
  return m;
}

MeshData uvSphereMesh(double radius, int segments, int stacks) {
  MeshData m;
  m.vertices.emplace_back(0, 0, radius);  // north pole
  for (int j = 1; j < stacks; ++j) {
    const double polar = M_PI * j / stacks;
    for (int k = 0; k < segments; ++k) {
      const double a = kTwoPi * k / segments;
      m.vertices.emplace_back(radius * std::sin(polar) * std::cos(a),
                              radius * std::sin(polar) * std::sin(a), radius * std::cos(polar));
    }
  }
  m.vertices.emplace_back(0, 0, -radius);  // south pole
  const auto n = static_cast<std::uint32_t>(segments);
  auto at = [n](int ring, std::uint32_t k) {
    return 1 + static_cast<std::uint32_t>(ring) * n + k % n;
  };
  const auto south = static_cast<std::uint32_t>(m.vertices.size() - 1);
  for (std::uint32_t k = 0; k < n; ++k) {
    m.triangles.push_back({0, at(0, k), at(0, k + 1)});
    for (int r = 0; r + 2 < stacks; ++r)
      m.quad(at(r, k), at(r + 1, k), at(r + 1, k + 1), at(r, k + 1));
    m.triangles.push_back({south, at(stacks - 2, k + 1), at(stacks - 2, k)});
  }
  return m;
}

MeshData boxMesh(const Eigen::Vector3d& size) {
  MeshData m;
  const Eigen::Vector3d h = size / 2;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  }
  // Faces -x, +x, -y, +y, -z, +z, each counter-clockwise seen from outside.
  m.quad(0, 4, 6, 2);
  m.quad(1, 3, 7, 5);
  m.quad(0, 1, 5, 4);
  m.quad(2, 6, 7, 3);
  m.quad(0, 2, 3, 1);
  m.quad(4, 5, 7, 6);
  return m;
}

MeshData boxMesh(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose) {
  MeshData m = boxMesh(size);
  for (auto& v : m.vertices) v = pose * v;
  return m;
}

MeshData wallBandMesh(const std::vector<Eigen::Vector2d>& corners, int columns,
                      const std::vector<double>& row_z) {
  std::vector<Eigen::Vector2d> perimeter;
  for (std::size_t c = 0; c < corners.size(); ++c) {
    const Eigen::Vector2d& p = corners[c];
    const Eigen::Vector2d& q = corners[(c + 1) % corners.size()];
    for (int i = 0; i < columns; ++i) perimeter.push_back(p + (q - p) * (double(i) / columns));
  }
  MeshData m;
  for (const double z : row_z) {
    for (const auto& p : perimeter) m.vertices.emplace_back(p.x(), p.y(), z);
  }
  const auto n = static_cast<std::uint32_t>(perimeter.size());
  for (std::uint32_t r = 0; r + 1 < row_z.size(); ++r) {
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t k1 = (k + 1) % n;
      m.quad(r * n + k, r * n + k1, (r + 1) * n + k1, (r + 1) * n + k);
    }
  }
  return m;
}

}  // namespace bench
}  // namespace laser_raycast
