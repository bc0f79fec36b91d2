#include "bench_peers.h"

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>

#ifdef LASER_RAYCAST_HAVE_EMBREE
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <embree3/rtcore.h>

#include <assimp/Importer.hpp>
#include <chrono>
#endif
#ifdef LASER_RAYCAST_HAVE_BULLET
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#endif

namespace laser_raycast {
namespace bench {
namespace {

[[maybe_unused]] constexpr double kInf = std::numeric_limits<double>::infinity();

#ifdef LASER_RAYCAST_HAVE_EMBREE

// One device for the process, one build thread: the rows time rtcIntersect1 on one thread, and the
// build should not compete with other work on the machine.
RTCDevice embreeDevice() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice("threads=1,set_affinity=0");
    if (!d) throw std::runtime_error("embree: rtcNewDevice failed");
    return d;
  }();
  return device;
}

void checkEmbree(const char* what) {
  const RTCError error = rtcGetDeviceError(embreeDevice());
  if (error != RTC_ERROR_NONE) {
    throw std::runtime_error(std::string("embree: ") + what + " failed (error " +
                             std::to_string(static_cast<int>(error)) + ")");
  }
}

// An Embree scene holding the triangles as one geometry (float vertices, shared indices).
class EmbreeScene {
 public:
  EmbreeScene(const std::vector<Eigen::Vector3d>& vertices,
              const std::vector<core::TriangleIndices>& triangles, bool robust) {
    RTCDevice device = embreeDevice();
    scene_ = rtcNewScene(device);
    rtcSetSceneFlags(scene_, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          vertices.size()));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), triangles.size()));
    checkEmbree("rtcSetNewGeometryBuffer");
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) v[3 * i + k] = static_cast<float>(vertices[i][k]);
    }
    for (std::size_t i = 0; i < triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) idx[3 * i + k] = triangles[i][k];
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene_);
    checkEmbree("building the scene");
  }
  ~EmbreeScene() { rtcReleaseScene(scene_); }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  void pass(const WorkloadRays& w, const std::vector<int>& rays, std::vector<double>* out) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (const int i : rays) {
      const core::RayF& r = w.rays_f[i];
      RTCRayHit rh;
      rh.ray.org_x = r.origin.x();
      rh.ray.org_y = r.origin.y();
      rh.ray.org_z = r.origin.z();
      rh.ray.dir_x = r.dir.x();
      rh.ray.dir_y = r.dir.y();
      rh.ray.dir_z = r.dir.z();
      rh.ray.tnear = r.tmin;
      rh.ray.tfar = r.tmax;
      rh.ray.time = 0;
      rh.ray.mask = 0xFFFFFFFFu;
      rh.ray.id = 0;
      rh.ray.flags = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene_, &context, &rh);
      (*out)[i] = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID
                      ? static_cast<double>(rh.ray.tfar) * w.scale_f[i]
                      : kInf;
    }
  }

 private:
  RTCScene scene_;
};

// Keeps the device's running total of the bytes Embree allocated minus those it freed, as its
// memory monitor reports them, while it lives: installed only while a mesh is measured, so that
// the rows' builds run without it.
class MemoryMonitor {
 public:
  MemoryMonitor() {
    rtcSetDeviceMemoryMonitorFunction(
        embreeDevice(),
        [](void* held, ssize_t bytes, bool) {
          static_cast<std::atomic<std::int64_t>*>(held)->fetch_add(bytes);
          return true;  // never refuse an allocation
        },
        &held_);
  }
  ~MemoryMonitor() { rtcSetDeviceMemoryMonitorFunction(embreeDevice(), nullptr, nullptr); }
  MemoryMonitor(const MemoryMonitor&) = delete;
  MemoryMonitor& operator=(const MemoryMonitor&) = delete;

  std::int64_t held() const { return held_.load(); }

 private:
  std::atomic<std::int64_t> held_{0};
};

#endif  // LASER_RAYCAST_HAVE_EMBREE

#ifdef LASER_RAYCAST_HAVE_BULLET

// Keeps the nearest hit: returning the fraction makes Bullet test later triangles against it.
struct NearestHitCallback : public btTriangleRaycastCallback {
  NearestHitCallback(const btVector3& from, const btVector3& to)
      : btTriangleRaycastCallback(from, to, kF_None) {}
  btScalar reportHit(const btVector3&, btScalar fraction, int, int) override {
    hit = true;
    return fraction;
  }
  bool hit = false;
};

// Bullet's static triangle mesh shape (quantized BVH) over the soup; btScalar is float in Debian's
// build.
class BulletScene {
 public:
  explicit BulletScene(const MeshData& soup) {
    for (const auto& v : soup.vertices) {
      for (int k = 0; k < 3; ++k) vertices_.push_back(static_cast<btScalar>(v[k]));
    }
    for (const auto& t : soup.triangles) {
      for (int k = 0; k < 3; ++k) indices_.push_back(static_cast<int>(t[k]));
    }
    mesh_ = std::make_unique<btTriangleIndexVertexArray>(
        static_cast<int>(soup.triangles.size()), indices_.data(), 3 * sizeof(int),
        static_cast<int>(soup.vertices.size()), vertices_.data(), 3 * sizeof(btScalar));
    shape_ = std::make_unique<btBvhTriangleMeshShape>(mesh_.get(), true, true);
  }

  void pass(const WorkloadRays& w, const std::vector<int>& rays, std::vector<double>* out) const {
    for (const int i : rays) {
      const core::RayF& r = w.rays_f[i];
      const btVector3 from(r.origin.x(), r.origin.y(), r.origin.z());
      const btVector3 to = from + btVector3(r.dir.x(), r.dir.y(), r.dir.z()) * r.tmax;
      NearestHitCallback callback(from, to);
      shape_->performRaycast(&callback, from, to);
      // The fraction is of the segment from -> to as Bullet holds it (in float).
      const double length = std::sqrt(double(to.x() - from.x()) * (to.x() - from.x()) +
                                      double(to.y() - from.y()) * (to.y() - from.y()) +
                                      double(to.z() - from.z()) * (to.z() - from.z()));
      (*out)[i] = callback.hit ? static_cast<double>(callback.m_hitFraction) * length : kInf;
    }
  }

 private:
  std::vector<btScalar> vertices_;
  std::vector<int> indices_;
  std::unique_ptr<btTriangleIndexVertexArray> mesh_;
  std::unique_ptr<btBvhTriangleMeshShape> shape_;
};

#endif  // LASER_RAYCAST_HAVE_BULLET

}  // namespace

std::vector<std::string> peerMethodNames() {
  std::vector<std::string> names;
#ifdef LASER_RAYCAST_HAVE_EMBREE
  names.push_back("embree_default");
  names.push_back("embree_robust");
#endif
#ifdef LASER_RAYCAST_HAVE_BULLET
  names.push_back("bullet");
#endif
  return names;
}

std::string peerVersions() {
  std::string versions;
#ifdef LASER_RAYCAST_HAVE_EMBREE
  versions += "Embree " + std::to_string(RTC_VERSION_MAJOR) + "." +
              std::to_string(RTC_VERSION_MINOR) + "." + std::to_string(RTC_VERSION_PATCH);
#endif
#ifdef LASER_RAYCAST_HAVE_BULLET
  if (!versions.empty()) versions += ", ";
  versions +=
      "Bullet " + std::to_string(btGetVersion() / 100) + "." + std::to_string(btGetVersion() % 100);
#endif
  return versions.empty() ? "none" : versions;
}

std::optional<std::size_t> embreeMeshBytes([[maybe_unused]] const core::Mesh& mesh) {
#ifdef LASER_RAYCAST_HAVE_EMBREE
  const MemoryMonitor monitor;
  // What the scene holds once built: the build's temporary arrays are freed by then, and the
  // buffers made by rtcSetNewGeometryBuffer are counted too (the vertex buffer with the 4 bytes
  // of padding that lets Embree read its last vertex with a 16-byte load).
  const EmbreeScene scene(mesh.vertices().toVector(), mesh.triangles(), false);
  return static_cast<std::size_t>(monitor.held());
#else
  return std::nullopt;
#endif
}

std::optional<double> assimpEmbreeLoadSeconds([[maybe_unused]] const std::string& path) {
#ifdef LASER_RAYCAST_HAVE_EMBREE
  const auto start = std::chrono::steady_clock::now();
  Assimp::Importer importer;
  const aiScene* read =
      importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                  aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!read) throw std::runtime_error("assimp cannot read " + path + ": " + importer.GetErrorString());
  RTCDevice device = embreeDevice();
  const std::unique_ptr<RTCSceneTy, void (*)(RTCScene)> scene(rtcNewScene(device),
                                                               rtcReleaseScene);
  for (unsigned m = 0; m < read->mNumMeshes; ++m) {
    const aiMesh& mesh = *read->mMeshes[m];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.mNumVertices));
    auto* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), mesh.mNumFaces));
    checkEmbree("rtcSetNewGeometryBuffer");
    for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
      v[3 * i] = mesh.mVertices[i].x;
      v[3 * i + 1] = mesh.mVertices[i].y;
      v[3 * i + 2] = mesh.mVertices[i].z;
    }
    for (unsigned i = 0; i < mesh.mNumFaces; ++i) {
      for (unsigned k = 0; k < 3; ++k) idx[3 * i + k] = mesh.mFaces[i].mIndices[k];
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene.get(), geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(scene.get());
  checkEmbree("building the scene");
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
#else
  return std::nullopt;
#endif
}

std::vector<Method> peerMethods([[maybe_unused]] const MeshData& soup,
                                [[maybe_unused]] const MethodFilter& wanted) {
  std::vector<Method> methods;
  [[maybe_unused]] const std::size_t triangles = soup.triangles.size();
#ifdef LASER_RAYCAST_HAVE_EMBREE
  for (const bool robust : {false, true}) {
    const std::string name = robust ? "embree_robust" : "embree_default";
    if (!wanted(name)) continue;
    auto scene = std::make_shared<const EmbreeScene>(soup.vertices, soup.triangles, robust);
    methods.push_back(Method{name, false, false, triangles,
                             [scene](const WorkloadRays& w, const std::vector<int>& rays,
                                     std::vector<double>* out) { scene->pass(w, rays, out); },
                             true});
    methods.back().moving = true;
  }
#endif
#ifdef LASER_RAYCAST_HAVE_BULLET
  if (wanted("bullet")) {
    auto bullet = std::make_shared<const BulletScene>(soup);
    methods.push_back(Method{"bullet", false, false, triangles,
                             [bullet](const WorkloadRays& w, const std::vector<int>& rays,
                                      std::vector<double>* out) { bullet->pass(w, rays, out); }});
  }
#endif
  return methods;
}

}  // namespace bench
}  // namespace laser_raycast
