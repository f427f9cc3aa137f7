#include "drape/core/mesh_io.h"

#include "ply_check.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <string_view>

namespace drape {
namespace {

// assimp's format ids: drape's "obj" is the Wavefront exporter that writes no .mtl file.
std::string assimp_format(const std::string& format) { return format == "obj" ? "objnomtl" : format; }

// Whether assimp may take the bytes for PLY: its magic word in any case (assimp compares
// without case; a file named .ply, or read as "ply", is checked whatever it starts with).
bool looks_like_ply(std::string_view head) {
  if (head.size() < 3) return false;
  for (int i = 0; i < 3; ++i)
    if (std::tolower(static_cast<unsigned char>(head[std::size_t(i)])) != "ply"[i]) return false;
  return true;
}

// importer.ReadFile, but a PLY file is read once, checked (assimp 5.2 hangs or aborts on some
// malformed PLY files: ply_check.h) and handed to assimp from memory.
const aiScene* read_file(Assimp::Importer& importer, const std::filesystem::path& path, unsigned flags) {
  std::ifstream in(path, std::ios::binary);
  char magic[3] = {};
  in.read(magic, 3);
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".ply" && !looks_like_ply(std::string_view(magic, std::size_t(in.gcount()))))
    return importer.ReadFile(path.string(), flags);
  in.clear();
  in.seekg(0);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  check_ply(bytes, path.string());
  return importer.ReadFileFromMemory(bytes.data(), bytes.size(), flags, "ply");
}

// Every triangle of an imported scene into one mesh, welded (load_mesh); name in messages.
TriangleMesh mesh_of(const Assimp::Importer& importer, const aiScene* scene, const std::string& name) {
  if (!scene || !scene->mRootNode) throw MeshFileError(name + ": cannot read the mesh: " + importer.GetErrorString());
  TriangleMesh mesh;
  std::map<std::array<Scalar, 3>, int> welded;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    std::vector<int> index(part->mNumVertices);
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      // A NaN compares equal to anything in the map and would be welded away: keep a
      // non-finite vertex apart, for mesh_problem to report.
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        index[v] = int(mesh.vertices.size());
        mesh.vertices.emplace_back(p.x, p.y, p.z);
        continue;
      }
      const std::array<Scalar, 3> key{p.x, p.y, p.z};
      const auto [it, inserted] = welded.emplace(key, int(mesh.vertices.size()));
      if (inserted) mesh.vertices.emplace_back(p.x, p.y, p.z);
      index[v] = it->second;
    }
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      const aiFace& face = part->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      mesh.triangles.push_back({index[face.mIndices[0]], index[face.mIndices[1]], index[face.mIndices[2]]});
    }
  }
  if (mesh.triangles.empty()) throw MeshFileError(name + ": the file holds no triangles");
  return mesh;
}

}  // namespace

TriangleMesh load_mesh(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw MeshFileError(path.string() + ": no such mesh file");
  Assimp::Importer importer;
  const aiScene* scene = read_file(importer, path, aiProcess_Triangulate | aiProcess_SortByPType);
  return mesh_of(importer, scene, path.string());
}

TriangleMesh parse_mesh(const std::string& bytes, const std::string& format, const std::string& name) {
  if (format == "ply" || looks_like_ply(bytes)) check_ply(bytes, name);
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFileFromMemory(bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_SortByPType, format.c_str());
  return mesh_of(importer, scene, name);
}

std::vector<Vec3> load_frame_positions(const std::filesystem::path& path, const TriangleMesh& topology) {
  Assimp::Importer importer;
  const aiScene* scene = read_file(importer, path, aiProcess_Triangulate);
  if (!scene || !scene->mRootNode) throw MeshFileError(path.string() + ": cannot read the mesh: " + importer.GetErrorString());
  std::vector<Vec3> positions(topology.vertices.size(), Vec3::Zero());
  std::size_t face = 0;  // every triangle of the file is counted, those beyond the topology too
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      if (part->mFaces[f].mNumIndices != 3) continue;  // points and lines
      if (face < topology.triangles.size()) {
        for (int k = 0; k < 3; ++k) {
          const aiVector3D& p = part->mVertices[part->mFaces[f].mIndices[k]];
          positions[topology.triangles[face][k]] = Vec3(p.x, p.y, p.z);
        }
      }
      ++face;
    }
  }
  if (face != topology.triangles.size())
    throw MeshFileError(path.string() + ": expected " + std::to_string(topology.triangles.size()) + " triangles, found " +
                        std::to_string(face));
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite())
      throw MeshFileError(path.string() + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
  return positions;
}

bool mesh_format_supported(const std::string& format) {
  Assimp::Exporter exporter;
  const std::string id = assimp_format(format);
  for (std::size_t i = 0; i < exporter.GetExportFormatCount(); ++i)
    if (id == exporter.GetExportFormatDescription(i)->id) return true;
  return false;
}

std::string mesh_extension(const std::string& format) {
  Assimp::Exporter exporter;
  const std::string id = assimp_format(format);
  for (std::size_t i = 0; i < exporter.GetExportFormatCount(); ++i) {
    const aiExportFormatDesc* d = exporter.GetExportFormatDescription(i);
    if (id == d->id) return std::string(".") + d->fileExtension;
  }
  return "." + format;
}

void save_mesh(const std::filesystem::path& path, const TriangleMesh& mesh, const std::string& format) {
  aiScene scene;  // owns and frees everything attached below
  scene.mRootNode = new aiNode();
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMaterials = 1;
  aiMesh* out = new aiMesh();
  scene.mMeshes = new aiMesh*[1]{out};
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  out->mMaterialIndex = 0;
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = unsigned(mesh.vertices.size());
  out->mVertices = new aiVector3D[mesh.vertices.size()];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    out->mVertices[i] = aiVector3D(ai_real(mesh.vertices[i].x()), ai_real(mesh.vertices[i].y()), ai_real(mesh.vertices[i].z()));
  out->mNumFaces = unsigned(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    out->mFaces[f].mNumIndices = 3;
    out->mFaces[f].mIndices = new unsigned[3]{unsigned(mesh.triangles[f][0]), unsigned(mesh.triangles[f][1]),
                                              unsigned(mesh.triangles[f][2])};
  }
  const std::filesystem::path temporary = path.string() + ".partial";
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, assimp_format(format), temporary.string()) != AI_SUCCESS) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw MeshFileError(path.string() + ": cannot write the mesh: " + exporter.GetErrorString());
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw MeshFileError(path.string() + ": cannot move the finished mesh into place: " + error.message());
}

}  // namespace drape
