// Caster::castBeams and castBeamsSweep: beams off any grid (beam_list.h), one ray at a time. (A
// list that lies on grids, a calibrated spinning lidar's, is cast and swept through the grid's
// walks instead: caster_beam_grid.cpp.)
//
// A grid's walks find the beams each box reaches from the box's view; beams on no grid have no
// such view, so each beam is traced by itself: through each frame's tree of bodies (the scene
// index's top level), then through each body it enters, a mesh's wide BVH (traceWide) with the
// exact triangle test of the cast's method on the triangle moved into the sensor frame, as the mesh
// walk tests it, or a primitive by its analytic test in the body's frame, as the primitives' cast
// does. Each beam keeps the hit that goes first by hit_order.h, so a beam's result depends on
// nothing but its own ray: the same for any thread count and any order of the trees.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "accel/wide_bvh.h"
#include "caster/caster_state.h"
#include "geometry/hit_order.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/primitives.h"
#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Beams per piece of work handed to a thread; the pieces only change the speed.
constexpr int kBeamsPerPiece = 512;
// A cast is split between threads only if each gets at least this many beams.
constexpr int kMinBeamsPerThread = 2048;

// Every frame with bodies relative to the sensor at one time: the group's pose, or invalid, and
// the sphere about its tree's box in the sensor frame (a beam that misses it skips the group).
struct GroupPoses {
  bool sensor_ok = false;
  std::vector<char> valid;                           // by group of the scene index
  std::vector<Eigen::Isometry3d> sensor_from_frame;  // by group, meaningful where valid
  std::vector<Eigen::Vector3d> center;               // by group, sensor frame
  std::vector<double> radius;                        // by group, widened for rounding
};

void placeGroupsAt(const SceneIndex& index, const Eigen::Isometry3d& world_from_sensor,
                   const std::function<bool(int, Eigen::Isometry3d*)>& frame_pose,
                   GroupPoses* out) {
  const auto& groups = index.groups();
  out->sensor_ok = isValidPose(world_from_sensor);
  out->valid.assign(groups.size(), 0);
  out->sensor_from_frame.resize(groups.size());
  out->center.resize(groups.size());
  out->radius.resize(groups.size());
  if (!out->sensor_ok) return;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    Eigen::Isometry3d pose;
    if (!frame_pose(groups[g]->frame, &pose) || !isValidPose(pose)) continue;
    out->valid[g] = 1;
    out->sensor_from_frame[g] = relativePose(world_from_sensor, pose);
    if (groups[g]->wide.empty()) continue;
    const Aabb& box = groups[g]->tree.bounds();
    out->center[g] = out->sensor_from_frame[g] * box.center();
    // The box's corners lie within half its diagonal of its centre; moving the centre rounds by a
    // few ulps of the magnitudes involved, far below this relative slack.
    const double magnitudes = out->center[g].cwiseAbs().maxCoeff() +
                              box.center().cwiseAbs().maxCoeff() +
                              out->sensor_from_frame[g].translation().cwiseAbs().maxCoeff();
    out->radius[g] = (box.extent() * 0.5).norm() * (1 + 1e-9) + 1e-9 * magnitudes;
  }
}

// Whether the ray can meet the box centre +- half (its frame's coordinates) within [tmin, tmax]:
// a slab test on the box widened by a relative margin far above double rounding, so it only culls
// bodies every hit on which lies outside their box, never a hit (a leaf of a frame's tree holds
// several bodies, each otherwise tested exactly).
bool mayEnterBox(const Ray& ray, const Eigen::Vector3d& center, const Eigen::Vector3d& half) {
  const double margin =
      1e-9 * (center.cwiseAbs().maxCoeff() + half.maxCoeff() + ray.origin.cwiseAbs().maxCoeff()) +
      1e-12;
  double lo = ray.tmin, hi = ray.tmax;
  for (int k = 0; k < 3; ++k) {
    const double o = ray.origin[k] - center[k], h = half[k] + margin, d = ray.dir[k];
    if (d == 0) {
      if (std::abs(o) > h) return false;
      continue;
    }
    const double inv = 1 / d;
    double t0 = (-h - o) * inv, t1 = (h - o) * inv;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0 - margin);
    hi = std::min(hi, t1 + margin);
    if (lo > hi) return false;
  }
  return true;
}

// Whether the ray from o along unit d can meet the sphere (center, radius) within [tmin, tmax]:
// radius holds every rounding of how the sphere was found, and the tests here add a relative
// slack above their own, so that a group is skipped only if every point of its box is clear of
// the ray.
bool mayMeetSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                   const Eigen::Vector3d& center, double radius, double tmax) {
  const Eigen::Vector3d oc = center - o;
  const double along = oc.dot(d);
  const double slack = 1e-9 * (oc.cwiseAbs().maxCoeff() + radius);
  if (along - radius > tmax + slack) return false;  // beyond the nearest hit so far
  if (along + radius < -slack) return false;        // behind the origin
  const double r = radius + slack;
  return (oc - along * d).squaredNorm() <= r * r;
}

// The nearest hit of one beam so far, over every body.
struct BeamHit {
  double t = kInf;
  int body = -1;
  int triangle = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

template <TriangleMethod M>
class BeamTracer {
 public:
  BeamTracer(const Scene& scene, const SceneIndex& index, const CastConfig& config)
      : scene_(scene),
        index_(index),
        config_(config),
        placed_(scene.bodies().size()),
        placed_stamp_(scene.bodies().size(), 0) {}

  // The frames' poses for the beams traced next: each body is placed again when first met.
  void setPoses(const GroupPoses& poses) {
    poses_ = &poses;
    ++stamp_;
  }

  // One beam from origin o along unit d (sensor frame) with the frames placed by setPoses.
  BeamHit trace(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    const GroupPoses& poses = *poses_;
    BeamHit hit;
    // The beam's sensor-frame ray, prepared once for every mesh triangle it is tested against.
    Ray sensor_ray;
    sensor_ray.origin = o;
    sensor_ray.dir = d;
    sensor_ray.tmin = config_.tmin;
    const PreparedRay<double, M> prepared(sensor_ray, config_.cull_backfaces);
    const auto& groups = index_.groups();
    for (std::size_t g = 0; g < groups.size(); ++g) {
      if (!poses.valid[g] || groups[g]->wide.empty()) continue;
      if (!mayMeetSphere(o, d, poses.center[g], poses.radius[g], std::min(config_.tmax, hit.t))) {
        continue;
      }
      const SceneIndex::Group& group = *groups[g];
      const Eigen::Isometry3d& sensor_from_frame = poses.sensor_from_frame[g];
      const Eigen::Matrix3d frame_rot = sensor_from_frame.linear().transpose();
      Ray ray;
      ray.origin = frame_rot * (o - sensor_from_frame.translation());
      ray.dir = frame_rot * d;
      ray.tmin = config_.tmin;
      ray.tmax = config_.tmax;
      const WideBoxRay box_ray(ray, group.tree.bounds());
      double tmax = std::min(config_.tmax, hit.t);
      traceWide(group.wide, group.wide.root(), box_ray, &tmax, [&](std::uint32_t slot) {
        const int body = group.bodies[group.tree.triangleIds()[slot]];
        castBody(body, placedBody(body, sensor_from_frame), o, d, prepared, &hit);
        tmax = std::min(config_.tmax, hit.t);
      });
    }
    return hit;
  }

 private:
  // A body relative to the sensor, as placeBody and placeSensorInBody (placed_body.h) place it for
  // the grid's walks: the same bits.
  struct Placed {
    Eigen::Matrix3d rot;  // sensor_from_body
    Eigen::Vector3d trans;
    Eigen::Matrix3d body_rot;  // its transpose: sensor-frame directions into the body frame
    Eigen::Vector3d sensor_in_body;
  };

  // A triangle slot moved into the sensor frame, as the mesh walk moves it (the same bits), through
  // a direct-mapped cache: consecutive beams of a pattern meet the same triangles.
  struct SensorTriangle {
    Eigen::Vector3d a, b, c;
  };
  const SensorTriangle& sensorTriangle(int body, std::uint32_t slot,
                                       const std::array<Eigen::Vector3d, 3>& v,
                                       const Eigen::Matrix3d& rot, const Eigen::Vector3d& trans) {
    const std::uint32_t key = (slot * 2654435761u) ^ (static_cast<std::uint32_t>(body) * 40503u);
    CachedTriangle& e = triangles_[(key >> 20) & (kTriangleCache - 1)];
    if (e.stamp != stamp_ || e.body != body || e.slot != slot) {
      e.stamp = stamp_;
      e.body = body;
      e.slot = slot;
      e.t = SensorTriangle{rot * v[0] + trans, rot * v[1] + trans, rot * v[2] + trans};
    }
    return e.t;
  }

  const Placed& placedBody(int body, const Eigen::Isometry3d& sensor_from_frame) {
    Placed& p = placed_[body];
    if (placed_stamp_[body] == stamp_) return p;
    placed_stamp_[body] = stamp_;
    const Eigen::Isometry3d sensor_from_body =
        sensor_from_frame * scene_.bodies()[body].frame_from_body;
    p.rot = sensor_from_body.linear();
    p.trans = sensor_from_body.translation();
    p.body_rot = p.rot.transpose();
    p.sensor_in_body = -(p.body_rot * p.trans);
    return p;
  }

  void castBody(int body, const Placed& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                const PreparedRay<double, M>& prepared, BeamHit* hit) {
    const Eigen::Matrix3d& rot = p.rot;
    const Eigen::Vector3d& trans = p.trans;
    Ray body_ray;
    body_ray.origin = o.isZero() ? p.sensor_in_body : Eigen::Vector3d(p.body_rot * (o - trans));
    body_ray.dir = p.body_rot * d;
    body_ray.tmin = config_.tmin;
    body_ray.tmax = std::min(config_.tmax, hit->t);
    if (!mayEnterBox(body_ray, scene_.boxCenter(body), scene_.boxHalf(body))) return;
    const Shape& shape = scene_.bodies()[body].shape;
    if (const auto* mesh_ptr = std::get_if<std::shared_ptr<const Mesh>>(&shape)) {
      castMesh(**mesh_ptr, body, rot, trans, body_ray, prepared, hit);
      return;
    }
    std::visit(
        [&](const auto& s) {
          using S = std::decay_t<decltype(s)>;
          if constexpr (!std::is_same_v<S, std::shared_ptr<const Mesh>>) {
            // The primitives' analytic test, in the body's frame (primitive_cast.cpp's testBeam).
            const std::optional<PrimitiveHit> h = detail::intersectValid(body_ray, s);
            if (h && hitBefore(h->t, body, -1, hit->t, hit->body, hit->triangle)) {
              *hit = BeamHit{h->t, body, -1, rot * h->normal};
            }
          }
        },
        shape);
  }

  // The mesh's wide BVH walked by the beam in the body's frame; each triangle it reaches moved into
  // the sensor frame and tested against the beam's sensor-frame ray (ray), as the mesh walk tests
  // it.
  void castMesh(const Mesh& mesh, int body, const Eigen::Matrix3d& rot,
                const Eigen::Vector3d& trans, const Ray& body_ray, const PreparedRay<double, M>& ray,
                BeamHit* hit) {
    const WideBvh& wide = mesh.wideBvh();
    if (wide.empty()) return;
    const auto& slots = mesh.bvh().triangleVertices();
    const auto& ids = mesh.bvh().triangleIds();
    const WideBoxRay box_ray(body_ray, mesh.bvh().bounds());
    double tmax = body_ray.tmax;
    double best_t = kInf;
    std::uint32_t best_triangle = std::numeric_limits<std::uint32_t>::max();
    traceWide(wide, wide.root(), box_ray, &tmax, [&](std::uint32_t slot) {
      const SensorTriangle& s = sensorTriangle(body, slot, slots[slot], rot, trans);
      const auto h = ray.intersect(s.a, s.b, s.c, tmax);
      if (h && hitBefore(h->t, ids[slot], best_t, best_triangle)) {
        best_t = h->t;
        best_triangle = ids[slot];
        tmax = h->t;
      }
    });
    if (best_triangle == std::numeric_limits<std::uint32_t>::max()) return;
    const int triangle = static_cast<int>(best_triangle);
    if (hitBefore(best_t, body, triangle, hit->t, hit->body, hit->triangle)) {
      *hit = BeamHit{best_t, body, triangle, rot * mesh.normal(best_triangle)};
    }
  }

  const Scene& scene_;
  const SceneIndex& index_;
  const CastConfig& config_;
  const GroupPoses* poses_ = nullptr;
  std::vector<Placed> placed_;  // by body, valid where placed_stamp_ is stamp_
  std::vector<std::uint32_t> placed_stamp_;
  std::uint32_t stamp_ = 0;
  static constexpr std::uint32_t kTriangleCache = 2048;
  struct CachedTriangle {
    std::uint32_t stamp = 0;  // 0: empty (stamps start at 1)
    int body = -1;
    std::uint32_t slot = 0;
    SensorTriangle t;
  };
  std::vector<CachedTriangle> triangles_ = std::vector<CachedTriangle>(kTriangleCache);
};

}  // namespace

void checkFramePoses(const Scene& scene, const FramePoses& poses) {
  const std::size_t frame_count = scene.frames().size();
  if (poses.pose.size() != frame_count || poses.valid.size() != frame_count) {
    std::ostringstream msg;
    msg << "FramePoses has " << poses.pose.size() << " poses for a scene of " << frame_count
        << " frames";
    throw std::invalid_argument(msg.str());
  }
}

int castThreads(const CastConfig& config, int beams, int min_per_thread) {
  return std::max(1, std::min(threadsFor(config.threads), beams / min_per_thread));
}

namespace {

// Casts every beam with the frames placed by posesAt(time, &poses), on the caster's threads. With
// timed, posesAt is called again wherever a beam's time differs from the one before it in its
// piece; without (every beam from the same poses, whatever the beams' times), once a piece: placing
// the frames anew also places every body and moves every triangle into the sensor frame anew, so a
// calibrated sensor's beams, each at its own firing time, would otherwise pay that at every beam.
void castBeamList(CasterState& state, const Scene& scene, const BeamList& beams,
                  const CastConfig& config, bool timed,
                  const std::function<void(double, GroupPoses*)>& posesAt, ScanResult* result) {
  const SceneIndex& index = state.indexOf(scene);
  const int n = beams.size();
  const int threads = castThreads(config, n, kMinBeamsPerThread);
  // One thread casts every beam as one piece: a piece's tracer starts with an empty cache of
  // bodies and triangles.
  const int piece_beams = threads == 1 ? std::max(n, 1) : kBeamsPerPiece;
  const int pieces = (n + piece_beams - 1) / piece_beams;
  auto castPiece = [&](int p) {
    dispatchTriangleMethod(config.method, [&](auto method) {
      BeamTracer<decltype(method)::value> tracer(scene, index, config);
      GroupPoses poses;
      double placed_time = std::numeric_limits<double>::quiet_NaN();
      for (int i = p * piece_beams; i < std::min(n, (p + 1) * piece_beams); ++i) {
        const double t = timed ? beams.time(i) : 0.0;
        if (!(t == placed_time)) {
          posesAt(t, &poses);
          tracer.setPoses(poses);
          placed_time = t;
        }
        if (!poses.sensor_ok) {
          result->range[i] = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        const BeamHit hit = tracer.trace(beams.origin(i), beams.directions[i]);
        result->range[i] = hit.t;
        result->body[i] = hit.body;
        result->triangle[i] = hit.triangle;
        if (config.compute_incidence && hit.body >= 0) {
          result->normal[i] = hit.normal;
          result->cos_incidence[i] = std::min(1.0, std::abs(beams.directions[i].dot(hit.normal)));
        }
      }
    });
  };
  if (threads == 1) {
    for (int p = 0; p < pieces; ++p) castPiece(p);
  } else {
    if (!state.pool || state.pool->threads() != threads) {
      state.pool = std::make_unique<ThreadPool>(threads);
    }
    state.pool->run(pieces, castPiece);
  }
}

// beams has been checked (CasterState::gridOf). through_grids: the list is cast through its
// grids, whose results are scattered into every beam's range, body and triangle (each beam is in
// one part): those are sized, not filled first (a calibrated head's 28,928 beams, scan after scan).
void startResult(const Scene& scene, const BeamList& beams, const CastConfig& config,
                 bool through_grids, ScanResult* result) {
  config.validate();
  resetResult(beams.size(), static_cast<int>(scene.bodies().size()), true, config.compute_incidence,
              result, through_grids);
  if (config.compute_incidence) result->cos_incidence.assign(beams.size(), 0.0);
}

// The list a caller shares, checked for null.
const BeamList& sharedList(const std::shared_ptr<const BeamList>& beams) {
  if (!beams) throw std::invalid_argument("the beam list is null");
  return *beams;
}

// Caster::castBeams into *result; shared: the caller's shared list beams is, or null.
void castBeamsAt(CasterState& state, const Scene& scene, const FramePoses& poses,
                 const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                 const std::shared_ptr<const BeamList>* shared, const CastConfig& config,
                 ScanResult* result) {
  checkFramePoses(scene, poses);
  state.previous.reset();
  const BeamListGrid* grid = state.gridOf(beams, shared);  // checks beams
  const bool through_grids = grid && isValidPose(world_from_sensor);
  startResult(scene, beams, config, through_grids, result);
  if (through_grids) {
    state.castBeamGrids(scene, poses, world_from_sensor, beams, *grid, config, result);
    return;
  }
  if (state.cellsOf() && isValidPose(world_from_sensor)) {
    state.castBeamCells(scene, poses, world_from_sensor, beams, *state.cellsOf(), config, result);
    return;
  }
  GroupPoses placed;
  placeGroupsAt(
      state.indexOf(scene), world_from_sensor,
      [&](int frame, Eigen::Isometry3d* pose) {
        if (!poses.valid[frame]) return false;
        *pose = poses.pose[frame];
        return true;
      },
      &placed);
  for (std::size_t g = 0; g < placed.valid.size(); ++g) {
    if (!placed.valid[g]) {
      result->stats.bodies_skipped +=
          static_cast<int>(state.indexOf(scene).groups()[g]->bodies.size());
    }
  }
  castBeamList(
      state, scene, beams, config, false, [&](double, GroupPoses* out) { *out = placed; }, result);
}

// Caster::castBeamsSweep into *result; shared as castBeamsAt's.
void castBeamsOver(CasterState& state, const Scene& scene, const PoseSamples& samples,
                   const BeamList& beams, const std::shared_ptr<const BeamList>* shared,
                   const CastConfig& config, ScanResult* result) {
  samples.validate(scene);
  state.previous.reset();
  const BeamListGrid* grid = state.gridOf(beams, shared);  // checks beams
  startResult(scene, beams, config, grid != nullptr, result);
  if (grid) {
    state.castBeamGridsSweep(scene, samples, beams, *grid, config, result);
    return;
  }
  const SceneIndex& index = state.indexOf(scene);
  castBeamList(
      state, scene, beams, config, true,
      [&](double t, GroupPoses* out) {
        placeGroupsAt(
            index, samples.sensorAt(t),
            [&](int frame, Eigen::Isometry3d* pose) {
              return samples.frameAt(t, static_cast<std::size_t>(frame), pose);
            },
            out);
      },
      result);
}

}  // namespace

const ScanResult& Caster::castBeams(const Scene& scene, const FramePoses& poses,
                                    const Eigen::Isometry3d& world_from_sensor,
                                    const BeamList& beams, const CastConfig& config) {
  castBeamsAt(*state_, scene, poses, world_from_sensor, beams, nullptr, config, &result_);
  return result_;
}

const ScanResult& Caster::castBeams(const Scene& scene, const FramePoses& poses,
                                    const Eigen::Isometry3d& world_from_sensor,
                                    const std::shared_ptr<const BeamList>& beams,
                                    const CastConfig& config) {
  castBeamsAt(*state_, scene, poses, world_from_sensor, sharedList(beams), &beams, config,
              &result_);
  return result_;
}

const ScanResult& Caster::castBeamsSweep(const Scene& scene, const PoseSamples& samples,
                                         const BeamList& beams, const CastConfig& config) {
  castBeamsOver(*state_, scene, samples, beams, nullptr, config, &result_);
  return result_;
}

const ScanResult& Caster::castBeamsSweep(const Scene& scene, const PoseSamples& samples,
                                         const std::shared_ptr<const BeamList>& beams,
                                         const CastConfig& config) {
  castBeamsOver(*state_, scene, samples, sharedList(beams), &beams, config, &result_);
  return result_;
}

}  // namespace core
}  // namespace laser_raycast
