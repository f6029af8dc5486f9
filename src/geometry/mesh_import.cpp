#include "mesh_import.h"

#include <filesystem>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <stdexcept>

namespace magbake::geometry {

TriangleSoup load_triangles(const std::string& path, double scale) {
  // Only regular files of a sane size: a FIFO or device would block or never end.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw std::runtime_error("cannot read mesh '" + path + "': no such file");
  if (!std::filesystem::is_regular_file(status)) throw std::runtime_error("cannot read mesh '" + path + "': not a regular file");
  if (std::filesystem::file_size(path, ec) > kMaxMeshFileBytes) {
    throw std::runtime_error("cannot read mesh '" + path + "': larger than 2 GiB");
  }
  Assimp::Importer importer;
  // Triangulate polygons and merge duplicated vertices; keep the file's coordinates as they are
  // (no normal generation, no re-centring). Node transforms are applied (PreTransformVertices).
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                aiProcess_SortByPType);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->HasMeshes()) {
    const std::string why = importer.GetErrorString();
    throw std::runtime_error("cannot read mesh '" + path + "': " + (why.empty() ? "no meshes in file" : why));
  }
  TriangleSoup soup;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const int base = static_cast<int>(soup.vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      soup.vertices.emplace_back(scale * p.x, scale * p.y, scale * p.z);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      soup.triangles.emplace_back(base + int(face.mIndices[0]), base + int(face.mIndices[1]), base + int(face.mIndices[2]));
    }
  }
  if (soup.triangles.empty()) throw std::runtime_error("mesh '" + path + "' has no triangles");
  return soup;
}

}  // namespace magbake::geometry
