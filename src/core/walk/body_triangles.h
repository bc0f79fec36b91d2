// A mesh body's triangles as a walk (mesh_walk.cpp) tests them: each slot moved into the sensor
// frame, and the back faces that no beam can meet first (hiddenBackFace), both kept by slot; and
// a hit triangle's normal in its beam's frame.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

#include "beams/column_motion.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/mesh.h"
#include "walk/slot_cache.h"

namespace laser_raycast {
namespace core {

class BodyTriangles {
 public:
  // shift: how far a sweep block's origins lie from the sensor's (0 for a scan from one pose);
  // hide_back_faces: whether the walk asks hidden() (its 3D tests; a planar fan's slices do not).
  BodyTriangles(const Mesh& mesh, const PlacedBody& active, double tmin, double shift,
                bool hide_back_faces)
      : mesh_(mesh),
        slots_(mesh.bvh().triangleVertices()),
        active_(active),
        rot_(active.sensor_from_body.linear()),
        trans_(active.sensor_from_body.translation()),
        tmin_(tmin),
        shift_(shift),
        closed_(hide_back_faces && mesh.hasClosedComponents()) {}

  // A triangle slot moved into the sensor frame. Every 3D test of this body's triangles is the
  // beam's sensor-frame ray against these vertices, however the pair was found (traced,
  // rasterised or tested directly), so shared edges are decided the same way everywhere.
  struct Triangle {
    Eigen::Vector3d a, b, c;
  };
  Triangle sensorTriangle(std::uint32_t slot) const {
    const auto& v = slots_[slot];
    return Triangle{rot_ * v[0] + trans_, rot_ * v[1] + trans_, rot_ * v[2] + trans_};
  }
  // The same through a small cache: the beams traced through one node meet the same leaves.
  const Triangle& cachedTriangle(std::uint32_t slot) {
    return triangles_.get(slot, [&] { return sensorTriangle(slot); });
  }

  Eigen::Vector3d sensorNormal(std::uint32_t triangle) const {
    return rot_ * mesh_.normal(triangle);
  }
  // The triangle's unit normal in the frame of the beam at (row, col): the sensor's, or for a
  // sweep's block the beam's own pose's. The last one is kept: a bundle's sub-rays of one beam
  // that keep hits on one triangle ask for it one after another.
  Eigen::Vector3d beamNormal(int row, int col, std::uint32_t triangle) {
    if (triangle != normal_kept_.triangle || row != normal_kept_.row || col != normal_kept_.col) {
      const Eigen::Vector3d n = sensorNormal(triangle);
      normal_kept_ = {triangle, row, col, active_.motion ? active_.motion->toBeam(row, col, n) : n};
    }
    return normal_kept_.normal;
  }

  // A back face of a closed component that the sensor sees from outside: never the nearest hit of a
  // beam (hiddenBackFace), so never tested. The answer depends on the slot alone for the whole
  // walk, and neighbouring beams ask about the same slots: the last answers are kept by slot.
  bool hidden(std::uint32_t slot) { return closed_ && hiddenClosed(slot); }

 private:
  // Out of line: the tests that ask stay small inline.
  __attribute__((noinline)) bool hiddenClosed(std::uint32_t slot) {
    return hidden_.get(slot, [&] {
      // A sweep's block: hidden from every column's origin, all within the shift.
      return hiddenBackFace(mesh_, slot, active_.sensor_in_body, tmin_, shift_);
    });
  }

  const Mesh& mesh_;
  const SlotVertices<double>& slots_;
  const PlacedBody& active_;
  const Eigen::Matrix3d rot_;
  const Eigen::Vector3d trans_;
  const double tmin_, shift_;
  const bool closed_;  // the mesh has closed components, and the walk hides their back faces
  SlotCache<Triangle, 64> triangles_;
  SlotCache<bool, 256> hidden_;
  struct KeptNormal {
    std::uint32_t triangle = std::numeric_limits<std::uint32_t>::max();
    int row = -1, col = -1;
    Eigen::Vector3d normal;
  } normal_kept_;  // beamNormal's last
};

}  // namespace core
}  // namespace laser_raycast
