// What a mesh's surface carries besides its shape, for the reflectance at a hit: per-vertex
// colours, texture coordinates and normals, and per-triangle materials (a diffuse colour and an
// optional texture image). Values at a hit are interpolated with the hit's barycentric
// coordinates, computed from the beam and the hit triangle (surfaceAt).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace laser_raycast {
namespace core {

// An RGB image, row by row from the top row of the picture, 3 bytes a pixel.
struct Texture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  // The colour (each channel in [0, 1]) of the texel that holds (u, v): nearest texel, repeated
  // outside [0, 1) (u = 0 is the left edge, v = 0 the bottom edge, as in OBJ and Collada).
  Eigen::Vector3d sample(double u, double v) const;
};

struct SurfaceMaterial {
  bool has_diffuse = false;
  Eigen::Vector3d diffuse = Eigen::Vector3d::Zero();  // RGB in [0, 1]
  std::shared_ptr<const Texture> texture;             // null: none
};

// Every array is either empty (the mesh has none) or one entry per vertex (colors, uvs, normals)
// or per triangle (triangle_material, an index into materials).
struct SurfaceAttributes {
  std::vector<Eigen::Vector3f> colors;   // RGB in [0, 1]
  std::vector<Eigen::Vector2f> uvs;      // texture coordinates
  std::vector<Eigen::Vector3f> normals;  // unit, mesh frame
  std::vector<std::uint32_t> triangle_material;
  std::vector<SurfaceMaterial> materials;

  // Whether the surface gives a colour at all (else only smooth normals, or nothing).
  bool hasColor() const;
  // Throws std::invalid_argument naming the array and its size if it fits neither rule, a material
  // index out of range, a texture whose size does not match its pixels, or a non-finite value.
  void validate(std::size_t vertices, std::size_t triangles) const;
};

// How a colour becomes a reflectance: scale x relative luminance of the channels as stored
// (0.2126 R + 0.7152 G + 0.0722 B; no gamma decoding), so white is `scale` and black 0.
double reflectanceFromColor(const Eigen::Vector3d& rgb, double scale);

// The barycentric coordinates (1 - b1 - b2, b1, b2) of where the ray origin + t dir meets the
// plane of triangle (a, b, c), by Cramer's rule, clamped into the triangle (a hit found by the
// watertight test lies inside it up to rounding). False for a ray parallel to the plane or a
// degenerate triangle.
bool barycentricAt(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                   const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   Eigen::Vector3d* weights);

}  // namespace core
}  // namespace laser_raycast
