#include "mesh_import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tinyxml2.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "map_image.h"

namespace laser_raycast {
namespace mesh_file {
namespace {

namespace fs = std::filesystem;

// A triangle's material while collecting: none (assimp's default material).
constexpr std::uint32_t kNoMaterial = 0xFFFFFFFFu;

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
  return lowerExtension(path) == ".dae";
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

// ---------------------------------------------------------------------------------------------------
// Surface attributes: per-vertex colours, texture coordinates and normals, and the materials'
// diffuse colours and textures, collected beside the triangles.

// What the sub-meshes gave so far: a per-vertex array is kept only if every sub-mesh has it
// (texture coordinates: if any has them; the others get (0, 0), and their materials' textures are
// then sampled there).
struct SurfaceCollector {
  core::SurfaceAttributes surface;
  bool all_colors = true, all_normals = true, any_uvs = false;
  bool file_materials = true;  // false: the file has none (assimp's materials are its own)
  std::vector<int> material_slot;  // assimp material index -> index in surface.materials, -1: none
};

// An RGB texture from a PNG file (grey and alpha are converted); null if it cannot be read: a
// mesh whose texture is missing or in another format still loads, with its material's colour.
std::shared_ptr<const core::Texture> readTexture(const std::string& mesh_path,
                                                 const aiMaterial& material) {
  aiString name;
  if (material.GetTexture(aiTextureType_DIFFUSE, 0, &name) != AI_SUCCESS) return nullptr;
  std::string file = name.C_Str();
  if (file.empty() || file[0] == '*') return nullptr;  // embedded: not read
  if (file.rfind("file://", 0) == 0) file = file.substr(7);
  fs::path path(file);
  if (path.is_relative()) path = fs::path(mesh_path).parent_path() / path;
  try {
    const map_image::Image image = map_image::read(path.string());
    auto texture = std::make_shared<core::Texture>();
    texture->width = image.width;
    texture->height = image.height;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    texture->rgb.resize(3 * pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < 3; ++c) {
        const int channel = image.colors == 3 ? c : 0;
        const double value = image.samples[p * image.channels() + channel];
        texture->rgb[3 * p + c] =
            static_cast<std::uint8_t>(std::lround(255.0 * value / image.maxval));
      }
    }
    return texture;
  } catch (const SceneLoadError&) {
    return nullptr;
  }
}

// Whether a PLY file's header declares a material element. assimp's PLY importer gives a file
// without one a white material of its own, on every face: the file says nothing of its surface's
// colour, so that is no material (the URDF's colour or default_reflectivity applies).
bool plyHasMaterials(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  // The header ends at end_header; a binary body after it is not read.
  for (int lines = 0; lines < 4096 && std::getline(in, line); ++lines) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") return false;
    std::istringstream words(line);
    std::string keyword, element;
    if (words >> keyword >> element && keyword == "element" && element == "material") return true;
  }
  return false;
}

// The index in surface.materials of assimp's material m, added at its first use; -1 for assimp's
// default material (the file named none).
int materialSlot(const aiScene& scene, unsigned m, const std::string& path,
                 SurfaceCollector* collector) {
  if (m >= scene.mNumMaterials) return -1;
  if (collector->material_slot.size() < scene.mNumMaterials) {
    collector->material_slot.assign(scene.mNumMaterials, -2);
  }
  int& slot = collector->material_slot[m];
  if (slot != -2) return slot;
  if (!collector->file_materials) return slot = -1;
  const aiMaterial& material = *scene.mMaterials[m];
  aiString name;
  if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS &&
      std::string(name.C_Str()) == AI_DEFAULT_MATERIAL_NAME) {
    return slot = -1;
  }
  core::SurfaceMaterial out;
  aiColor3D diffuse;
  if (material.Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == AI_SUCCESS &&
      std::isfinite(diffuse.r) && std::isfinite(diffuse.g) && std::isfinite(diffuse.b)) {
    out.has_diffuse = true;
    out.diffuse = Eigen::Vector3d(diffuse.r, diffuse.g, diffuse.b).cwiseMax(0.0).cwiseMin(1.0);
  }
  out.texture = readTexture(path, material);
  collector->surface.materials.push_back(std::move(out));
  return slot = static_cast<int>(collector->surface.materials.size()) - 1;
}

// One sub-mesh's per-vertex attributes, normals turned by `turn` (the inverse transpose of the
// placement's linear part).
void appendVertexAttributes(const aiMesh& mesh, const Eigen::Matrix3d& turn,
                            SurfaceCollector* collector) {
  core::SurfaceAttributes& s = collector->surface;
  collector->all_colors = collector->all_colors && mesh.mColors[0];
  collector->all_normals = collector->all_normals && mesh.mNormals;
  collector->any_uvs = collector->any_uvs || mesh.mTextureCoords[0];
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    if (mesh.mColors[0]) {
      const aiColor4D& c = mesh.mColors[0][v];
      s.colors.push_back(Eigen::Vector3f(c.r, c.g, c.b).cwiseMax(0.0f).cwiseMin(1.0f));
    } else {
      s.colors.push_back(Eigen::Vector3f::Ones());
    }
    if (mesh.mTextureCoords[0]) {
      const aiVector3D& t = mesh.mTextureCoords[0][v];
      s.uvs.push_back(Eigen::Vector2f(t.x, t.y));
    } else {
      s.uvs.push_back(Eigen::Vector2f::Zero());
    }
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    if (mesh.mNormals) {
      const aiVector3D& n = mesh.mNormals[v];
      const Eigen::Vector3d turned = turn * Eigen::Vector3d(n.x, n.y, n.z);
      if (turned.allFinite() && turned.norm() > 0) normal = turned.normalized().cast<float>();
    }
    s.normals.push_back(normal);
  }
}

// The attributes, or null if the file has none worth keeping.
std::shared_ptr<core::SurfaceAttributes> finishSurface(SurfaceCollector* collector) {
  core::SurfaceAttributes& s = collector->surface;
  if (!collector->all_colors) s.colors.clear();
  if (!collector->all_normals) s.normals.clear();
  if (!collector->any_uvs) s.uvs.clear();
  const bool any_material = std::any_of(s.triangle_material.begin(), s.triangle_material.end(),
                                        [](std::uint32_t m) { return m != kNoMaterial; });
  if (!any_material) {
    s.triangle_material.clear();
    s.materials.clear();
  } else {
    // Triangles without a material get one without colour.
    const auto none = static_cast<std::uint32_t>(s.materials.size());
    s.materials.emplace_back();
    for (std::uint32_t& m : s.triangle_material) {
      if (m == kNoMaterial) m = none;
    }
  }
  if (s.colors.empty() && s.normals.empty() && s.materials.empty()) return nullptr;
  if (s.materials.empty()) s.uvs.clear();
  return std::make_shared<core::SurfaceAttributes>(std::move(s));
}

// The triangles of one node's meshes, placed by to_link, appended to *out.
void appendNodeMeshes(const aiScene& scene, const aiNode& node, const Eigen::Affine3d& to_link,
                      const std::string& path, SurfaceCollector* collector, MeshData* out) {
  const Eigen::Matrix3d turn = to_link.linear().inverse().transpose();
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
    appendVertexAttributes(mesh, turn, collector);
    const int material = materialSlot(scene, mesh.mMaterialIndex, path, collector);
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // a point or a line
      core::TriangleIndices tri;
      for (int k = 0; k < 3; ++k) tri[k] = static_cast<std::uint32_t>(first + face.mIndices[k]);
      if (flip) std::swap(tri[1], tri[2]);
      out->triangles.push_back(tri);
      collector->surface.triangle_material.push_back(
          material >= 0 ? static_cast<std::uint32_t>(material) : kNoMaterial);
    }
  }
}

// Every node's triangles, depth first over the root's children with an explicit stack (deep graphs
// must not overflow); meshes attached to the root itself get no node transform.
MeshData collectTriangles(const aiScene& scene, const Eigen::Affine3d& scale_unit,
                          const std::string& path) {
  MeshData out;
  SurfaceCollector collector;
  collector.file_materials = lowerExtension(path) != ".ply" || plyHasMaterials(path);
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack;
  for (unsigned c = 0; c < scene.mRootNode->mNumChildren; ++c) {
    stack.emplace_back(scene.mRootNode->mChildren[c], Eigen::Affine3d::Identity());
  }
  appendNodeMeshes(scene, *scene.mRootNode, scale_unit, path, &collector, &out);
  while (!stack.empty()) {
    const auto [node, parent_transform] = stack.back();
    stack.pop_back();
    const Eigen::Affine3d transform = parent_transform * toAffine(*node);
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      stack.emplace_back(node->mChildren[c], transform);
    }
    appendNodeMeshes(scene, *node, scale_unit * transform, path, &collector, &out);
  }
  if (out.triangles.empty()) {
    throw SceneLoadError("it has no triangles (an empty mesh, or only points or lines)");
  }
  out.surface = finishSurface(&collector);
  return out;
}

}  // namespace

MeshData importMeshInProcess(const std::string& path, const Eigen::Vector3d& scale) {
  Assimp::Importer importer;
  checkVertices(readScene(&importer, path));
  const aiScene& scene = postProcess(&importer);
  const double unit = isCollada(scene, path) ? colladaUnit(path) : 1.0;
  return collectTriangles(scene, Eigen::Affine3d(Eigen::Scaling(Eigen::Vector3d(scale * unit))),
                          path);
}

}  // namespace mesh_file
}  // namespace laser_raycast
