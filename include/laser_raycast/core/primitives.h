// URDF primitives, intersected analytically in their own frame (URDF conventions: centred at the
// origin, the cylinder's axis along z with flat caps).
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "laser_raycast/core/ray.h"

namespace laser_raycast {
namespace core {

struct Box {
  Eigen::Vector3d size;  // full edge lengths along x, y, z (m)
};

struct Cylinder {
  double radius;  // m
  double length;  // along z, centred (m)
};

struct Sphere {
  double radius;  // m
};

// The first surface crossing with a finite t in [ray.tmin, ray.tmax] (a t that overflows is no
// hit). Surfaces are surfaces: a ray that starts inside a primitive hits it from the inside, on
// the way out.
struct PrimitiveHit {
  double t;
  Eigen::Vector3d normal;  // outward unit normal at the hit, in the primitive's frame
};

std::optional<PrimitiveHit> intersect(const Ray& ray, const Box& box);
std::optional<PrimitiveHit> intersect(const Ray& ray, const Cylinder& cylinder);
std::optional<PrimitiveHit> intersect(const Ray& ray, const Sphere& sphere);

namespace detail {
// The same for a ray the caller knows to be valid (isValidRay): the caster's beams.
std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Box& box);
std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Cylinder& cylinder);
std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Sphere& sphere);
}  // namespace detail

// Throw std::invalid_argument naming the dimension and its value unless every size is finite and >
// 0.
void validate(const Box& box);
void validate(const Cylinder& cylinder);
void validate(const Sphere& sphere);

}  // namespace core
}  // namespace laser_raycast
