// One mesh body sliced by a planar fan's plane, whole and on its own (no BVH walk, no culling, no
// kept slice): the per-beam nearest hit of its segments, with every crossing counted. The
// watertightness and stress tests compare the caster with it; it uses the core's Slicer, so its
// segments are the ones a cast tests.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/scan_pattern.h"
#include "slice/slicer.h"

namespace laser_raycast {
namespace core {

// The per-beam nearest hit so far: distance, body and triangle.
struct DepthBuffer {
  std::vector<double>* range;
  std::vector<int>* body;
  std::vector<int>* triangle;
  // If set, every segment a beam crosses within [tmin, tmax] is counted, nearest or not: a closed
  // mesh's outline is crossed exactly once per beam from inside (the watertightness tests use it).
  std::vector<int>* crossings = nullptr;
  // If set, the hit triangle's front normal (sensor frame) is written with every nearer hit.
  std::vector<Eigen::Vector3d>* normal = nullptr;
};

// Slices one mesh body and keeps, per beam, the nearest hit with t in [tmin, tmax] in buffer.
inline void sliceMesh(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces, int body_index, DepthBuffer buffer) {
  const Slicer slicer(mesh, sensor_from_mesh, fan, tmin, tmax, cull_backfaces);
  const auto& ids = mesh.bvh().triangleIds();
  std::vector<double>& range = *buffer.range;
  const int last = fan.azimuthCount() - 1;
  mesh.visit([&](const Aabb& box) { return slicer.mayCross(box); },
             [&](std::uint32_t slot) {
               slicer.sliceSlot(slot, 0, last, [&](int i, double t) {
                 if (buffer.crossings) ++(*buffer.crossings)[i];
                 if (!(t < range[i])) return;
                 range[i] = t;
                 (*buffer.body)[i] = body_index;
                 (*buffer.triangle)[i] = static_cast<int>(ids[slot]);
                 if (buffer.normal) (*buffer.normal)[i] = slicer.sensorNormal(slot);
               });
             });
}

}  // namespace core
}  // namespace laser_raycast
