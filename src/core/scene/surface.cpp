// Surface attributes (surface.h): checks, texture look-up, colour to reflectance, barycentric
// coordinates. Also built into the mesh importer: import_protocol.cpp, which both ends build,
// checks the attributes of a reply with it.
#include "laser_raycast/core/surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {
namespace {

void checkSize(const char* what, std::size_t size, std::size_t expected, const char* per) {
  if (size != 0 && size != expected) {
    std::ostringstream msg;
    msg << "SurfaceAttributes." << what << " has " << size << " entries, expected 0 or " << expected
        << " (one per " << per << ")";
    throw std::invalid_argument(msg.str());
  }
}

template <typename Vector>
void checkFinite(const char* what, const std::vector<Vector>& values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i].allFinite()) {
      throw std::invalid_argument("SurfaceAttributes." + std::string(what) + "[" +
                                  std::to_string(i) + "] is not finite");
    }
  }
}

// Wraps t into [0, 1): textures repeat.
double wrap(double t) { return t - std::floor(t); }

}  // namespace

Eigen::Vector3d Texture::sample(double u, double v) const {
  if (width <= 0 || height <= 0 || !std::isfinite(u) || !std::isfinite(v)) {
    return Eigen::Vector3d::Zero();
  }
  const int x = std::min(width - 1, static_cast<int>(wrap(u) * width));
  // v = 0 is the bottom edge, row 0 the top row.
  const int y = std::min(height - 1, static_cast<int>((1.0 - wrap(v)) * height));
  const std::size_t at = 3 * (static_cast<std::size_t>(y) * width + x);
  return Eigen::Vector3d(rgb[at], rgb[at + 1], rgb[at + 2]) / 255.0;
}

bool SurfaceAttributes::hasColor() const {
  if (!colors.empty()) return true;
  for (const SurfaceMaterial& m : materials) {
    if (m.has_diffuse || (m.texture && !uvs.empty())) return true;
  }
  return false;
}

void SurfaceAttributes::validate(std::size_t vertices, std::size_t triangles) const {
  checkSize("colors", colors.size(), vertices, "vertex");
  checkSize("uvs", uvs.size(), vertices, "vertex");
  checkSize("normals", normals.size(), vertices, "vertex");
  checkSize("triangle_material", triangle_material.size(), triangles, "triangle");
  checkFinite("colors", colors);
  checkFinite("uvs", uvs);
  checkFinite("normals", normals);
  for (std::size_t t = 0; t < triangle_material.size(); ++t) {
    if (triangle_material[t] >= materials.size()) {
      std::ostringstream msg;
      msg << "SurfaceAttributes.triangle_material[" << t << "] = " << triangle_material[t]
          << " is out of range (" << materials.size() << " materials)";
      throw std::invalid_argument(msg.str());
    }
  }
  for (std::size_t m = 0; m < materials.size(); ++m) {
    const SurfaceMaterial& mat = materials[m];
    if (!mat.diffuse.allFinite()) {
      throw std::invalid_argument("SurfaceAttributes.materials[" + std::to_string(m) +
                                  "].diffuse is not finite");
    }
    if (mat.texture &&
        (mat.texture->width <= 0 || mat.texture->height <= 0 ||
         mat.texture->rgb.size() != 3 * static_cast<std::size_t>(mat.texture->width) *
                                        static_cast<std::size_t>(mat.texture->height))) {
      std::ostringstream msg;
      msg << "SurfaceAttributes.materials[" << m << "].texture is " << mat.texture->width << " x "
          << mat.texture->height << " pixels but holds " << mat.texture->rgb.size() << " bytes";
      throw std::invalid_argument(msg.str());
    }
  }
}

double reflectanceFromColor(const Eigen::Vector3d& rgb, double scale) {
  return scale * (0.2126 * rgb.x() + 0.7152 * rgb.y() + 0.0722 * rgb.z());
}

bool barycentricAt(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                   const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   Eigen::Vector3d* weights) {
  // origin + t dir = a + b1 (b - a) + b2 (c - a): three equations in t, b1, b2, solved by Cramer's
  // rule with the scalar triple products.
  const Eigen::Vector3d e1 = b - a, e2 = c - a, s = origin - a;
  const Eigen::Vector3d p = dir.cross(e2);
  const double det = p.dot(e1);
  // Written so that NaN fails: a ray in the plane, or a degenerate triangle.
  if (!(std::abs(det) > 0)) return false;
  const Eigen::Vector3d q = s.cross(e1);
  double b1 = p.dot(s) / det, b2 = q.dot(dir) / det;
  if (!(std::isfinite(b1) && std::isfinite(b2))) return false;
  b1 = std::clamp(b1, 0.0, 1.0);
  b2 = std::clamp(b2, 0.0, 1.0);
  if (b1 + b2 > 1) {
    const double sum = b1 + b2;
    b1 /= sum;
    b2 /= sum;
  }
  *weights = Eigen::Vector3d(1 - b1 - b2, b1, b2);
  return true;
}

}  // namespace core
}  // namespace laser_raycast
