#include "mesh_import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tinyxml2.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

namespace laser_raycast {
namespace mesh_file {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------
// The stages of importMeshInProcess, in order: read, check the vertices, post-process, then collect
// the triangles with the node transforms, the Collada unit and the URDF scale.

const aiScene& readScene(Assimp::Importer* importer, const std::string& path) {
  const aiScene* scene = importer->ReadFile(path, 0);
  if (!scene) {
    throw SceneLoadError(std::string("assimp cannot read it: ") + importer->GetErrorString());
  }
  return *scene;
}

// Checked before post-processing: vertex joining compares positions, and NaN breaks that; and
// validation would call an empty mesh just "invalid".
void checkVertices(const aiScene& scene) {
  std::size_t vertex_count = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    if (!mesh.mVertices) continue;  // broken importer output: validation rejects it later
    vertex_count += mesh.mNumVertices;
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
        std::ostringstream msg;
        msg << "vertex " << v << " of sub-mesh " << m << " is not finite (" << p.x << " " << p.y
            << " " << p.z << ")";
        throw SceneLoadError(msg.str());
      }
    }
  }
  if (vertex_count == 0) throw SceneLoadError("it holds no vertices (an empty mesh)");
}

// Validate first: it guards what follows against broken importer output (indices out of range).
// Triangulate polygons; join identical vertices (exact duplicates only: the fan slicer relies on
// shared indices for watertight outlines); sort by primitive type so points and lines, which a ray
// cannot hit, end up in meshes of their own. Nothing that drops or moves triangles
// (FindDegenerates, FindInvalidData, OptimizeMeshes...): core::Mesh handles degenerate ones.
const aiScene& postProcess(Assimp::Importer* importer) {
  const aiScene* scene =
      importer->ApplyPostProcessing(aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                    aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene) {
    throw SceneLoadError(std::string("assimp cannot read it: ") + importer->GetErrorString());
  }
  if (!scene->mRootNode) throw SceneLoadError("assimp found no scene graph in it");
  return *scene;
}

bool isCollada(const aiScene& scene, const std::string& path) {
  aiString format;
  if (scene.mMetaData && scene.mMetaData->Get("SourceAsset_Format", format)) {
    return std::string(format.C_Str()).find("Collada") != std::string::npos;
  }
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".dae";
}

// The Collada <asset><unit meter="..."/>, read from the file as RViz does: assimp puts it into the
// root node's transformation together with the up-axis rotation, and we do not apply that one. No
// <unit> (or no meter attribute) means metres, as the Collada specification says.
double colladaUnit(const std::string& path) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) {
    throw SceneLoadError(std::string("cannot read the Collada <unit>: ") + doc.ErrorStr());
  }
  const tinyxml2::XMLElement* root = doc.RootElement();
  const tinyxml2::XMLElement* asset = root ? root->FirstChildElement("asset") : nullptr;
  const tinyxml2::XMLElement* unit = asset ? asset->FirstChildElement("unit") : nullptr;
  const char* meter = unit ? unit->Attribute("meter") : nullptr;
  if (!meter) return 1.0;
  double value = 0;
  // Written so that NaN fails.
  if (unit->QueryDoubleAttribute("meter", &value) != tinyxml2::XML_SUCCESS ||
      !(std::isfinite(value) && value > 0)) {
    throw SceneLoadError("invalid Collada <unit meter=\"" + std::string(meter) +
                         "\">: must be a finite number > 0");
  }
  return value;
}

// A node's transformation. A projective bottom row has no meaning for a mesh: an error rather than
// silently dropped.
Eigen::Affine3d toAffine(const aiNode& node) {
  const aiMatrix4x4& m = node.mTransformation;
  if (!(m.d1 == 0 && m.d2 == 0 && m.d3 == 0 && m.d4 == 1)) {
    throw SceneLoadError("node '" + std::string(node.mName.C_Str()) +
                         "' has a projective transformation");
  }
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) t(r, c) = m[r][c];
  }
  return t;
}

// The triangles of one node's meshes, placed by to_link, appended to *out.
void appendNodeMeshes(const aiScene& scene, const aiNode& node, const Eigen::Affine3d& to_link,
                      MeshData* out) {
  // A mirroring transform turns triangles inside out: swap two corners to keep the front face.
  const bool flip = to_link.linear().determinant() < 0;
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[i]];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const std::size_t first = out->vertices.size();
    if (first + mesh.mNumVertices > std::numeric_limits<std::uint32_t>::max()) {
      throw SceneLoadError("more vertices than 32-bit indices can address");
    }
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      out->vertices.push_back(to_link * Eigen::Vector3d(p.x, p.y, p.z));
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // a point or a line
      core::TriangleIndices tri;
      for (int k = 0; k < 3; ++k) tri[k] = static_cast<std::uint32_t>(first + face.mIndices[k]);
      if (flip) std::swap(tri[1], tri[2]);
      out->triangles.push_back(tri);
    }
  }
}

// Every node's triangles, depth first over the root's children with an explicit stack (deep graphs
// must not overflow); meshes attached to the root itself get no node transform.
MeshData collectTriangles(const aiScene& scene, const Eigen::Affine3d& scale_unit) {
  MeshData out;
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack;
  for (unsigned c = 0; c < scene.mRootNode->mNumChildren; ++c) {
    stack.emplace_back(scene.mRootNode->mChildren[c], Eigen::Affine3d::Identity());
  }
  appendNodeMeshes(scene, *scene.mRootNode, scale_unit, &out);
  while (!stack.empty()) {
    const auto [node, parent_transform] = stack.back();
    stack.pop_back();
    const Eigen::Affine3d transform = parent_transform * toAffine(*node);
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      stack.emplace_back(node->mChildren[c], transform);
    }
    appendNodeMeshes(scene, *node, scale_unit * transform, &out);
  }
  if (out.triangles.empty()) {
    throw SceneLoadError("it has no triangles (an empty mesh, or only points or lines)");
  }
  return out;
}

}  // namespace

MeshData importMeshInProcess(const std::string& path, const Eigen::Vector3d& scale) {
  Assimp::Importer importer;
  checkVertices(readScene(&importer, path));
  const aiScene& scene = postProcess(&importer);
  const double unit = isCollada(scene, path) ? colladaUnit(path) : 1.0;
  return collectTriangles(scene, Eigen::Affine3d(Eigen::Scaling(Eigen::Vector3d(scale * unit))));
}

}  // namespace mesh_file
}  // namespace laser_raycast
