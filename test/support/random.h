// The random generator of every test, and samplers over it. A test makes its own Rng with a fixed
// seed and passes it by reference, so that a failure repeats.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace laser_raycast_test {

// The 32-bit Mersenne Twister: the seeds of the triangle, primitive, watertightness and stress
// tests were chosen with it, and docs/stress.md's figures are its draws.
using Rng = std::mt19937;

inline double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// 10^uniform(lo_exp, hi_exp): a scale spread evenly over the decades.
inline double logUniform(Rng& rng, double lo_exp, double hi_exp) {
  return std::pow(10.0, uniform(rng, lo_exp, hi_exp));
}

inline Eigen::Vector3d uniformInBox(Rng& rng, const Eigen::Vector3d& lo,
                                    const Eigen::Vector3d& hi) {
  return Eigen::Vector3d(uniform(rng, lo.x(), hi.x()), uniform(rng, lo.y(), hi.y()),
                         uniform(rng, lo.z(), hi.z()));
}

inline Eigen::Vector3d uniformInCube(Rng& rng, double half) {
  return uniformInBox(rng, Eigen::Vector3d::Constant(-half), Eigen::Vector3d::Constant(half));
}

// Uniform on the unit sphere (normalised Gaussian vector).
inline Eigen::Vector3d randomUnitVector(Rng& rng) {
  std::normal_distribution<double> normal;
  for (;;) {
    const Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
    const double n = v.norm();
    if (n > 1e-6) return v / n;
  }
}

// Uniform over rotations (normalised Gaussian quaternion).
inline Eigen::Quaterniond randomRotation(Rng& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  q.normalize();
  return q;
}

// A random rotation and a translation uniform in [-max_translation, max_translation]^3.
inline Eigen::Isometry3d randomPose(Rng& rng, double max_translation) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = randomRotation(rng).toRotationMatrix();
  pose.translation() = uniformInCube(rng, max_translation);
  return pose;
}

// Barycentrics (u, v) uniform over the triangle: the point is (1 - u - v) a + u b + v c.
inline Eigen::Vector2d randomBarycentrics(Rng& rng) {
  const double s = std::sqrt(uniform(rng, 0.0, 1.0));
  const double r = uniform(rng, 0.0, 1.0);
  return Eigen::Vector2d(s * (1.0 - r), s * r);
}

}  // namespace laser_raycast_test
