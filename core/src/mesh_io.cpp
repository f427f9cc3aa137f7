#include "drape/core/mesh_io.h"

#include "ply_check.h"
#include "drape/ccd/input_file.h"
#include "drape/core/output_file.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <array>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
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

// The file's extension in lower case (".PLY" -> ".ply").
std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

// Each line of a text (without its '\n') and its number from 1.
template <class F>
void for_each_line(std::string_view text, F&& f) {
  std::size_t number = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    f(text.substr(at, end - at), ++number);
    at = end + 1;
  }
}

// Whether an OBJ line is a vertex ('v') or a face ('f') line: the keyword, then a space or tab.
bool obj_line_is(std::string_view line, char keyword) {
  return line.size() >= 2 && line[0] == keyword && (line[1] == ' ' || line[1] == '\t');
}

// Each corner of an OBJ face line: its text and the text of its vertex index (before any '/').
template <class F>
void for_each_corner(std::string_view line, F&& f) {
  std::size_t p = 2;
  while (p < line.size()) {
    while (p < line.size() && std::isspace(static_cast<unsigned char>(line[p]))) ++p;
    if (p >= line.size()) break;
    const std::size_t token_end = std::min(line.find_first_of(" \t\r", p), line.size());
    const std::string_view corner = line.substr(p, token_end - p);
    p = token_end;
    f(corner, corner.substr(0, corner.find('/')));
  }
}

// An OBJ file's faces checked before assimp reads them, whose messages name no line ("OBJ:
// vertex index out of range"): each corner's vertex index a whole number other than 0, from 1
// to the file's vertex count counting forwards, or from -1 back to the first vertex counting
// backwards from the face's line.
void check_obj_faces(const std::string& bytes, const std::string& name) {
  long total = 0;
  for_each_line(bytes, [&](std::string_view line, std::size_t) { total += obj_line_is(line, 'v'); });
  long vertices = 0;  // so far
  for_each_line(bytes, [&](std::string_view line, std::size_t line_number) {
    if (obj_line_is(line, 'v')) ++vertices;
    if (!obj_line_is(line, 'f')) return;
    for_each_corner(line, [&](std::string_view corner, std::string_view index) {
      long value = 0;
      const auto [ptr, error] = std::from_chars(index.data(), index.data() + index.size(), value);
      const auto fail = [&](const std::string& what) {
        throw MeshFileError(name + ":" + std::to_string(line_number) + ": face corner '" + std::string(corner) + "': " + what);
      };
      if (error != std::errc() || ptr != index.data() + index.size() || value == 0)
        fail("expected a vertex index from 1 to " + std::to_string(total) + " (or from -1 back to -" +
             std::to_string(vertices) + ")");
      if (value > total)
        fail("vertex " + std::to_string(value) + " is out of range: the file gives " + std::to_string(total) + " vertices");
      if (value < -vertices)
        fail("vertex " + std::to_string(value) + " is out of range: the file gives " + std::to_string(vertices) +
             " vertices before this line");
    });
  });
}

// importer.ReadFile, but a PLY file is read once, checked (assimp 5.2 hangs or aborts on some
// malformed PLY files: ply_check.h) and handed to assimp from memory; an OBJ file's faces are
// checked first (check_obj_faces).
const aiScene* read_file(Assimp::Importer& importer, const std::filesystem::path& path, unsigned flags) {
  try {
    ccd::check_input_file(path, ccd::MAX_MESH_BYTES, "mesh file");
  } catch (const ccd::InputFileError& e) {
    throw MeshFileError(e.what());
  }
  std::ifstream in(path, std::ios::binary);
  char magic[3] = {};
  in.read(magic, 3);
  if (lower_extension(path) == ".obj") {
    try {
      check_obj_faces(ccd::read_input_file(path, ccd::MAX_MESH_BYTES, "mesh file"), path.string());
    } catch (const ccd::InputFileError& e) {
      throw MeshFileError(e.what());
    }
  }
  if (lower_extension(path) != ".ply" && !looks_like_ply(std::string_view(magic, std::size_t(in.gcount()))))
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

// A Wavefront OBJ of the mesh, every coordinate in the shortest form that reads back as the
// same double (std::to_chars; assimp's exporter writes single precision).
std::string obj_text(const TriangleMesh& mesh) {
  std::string text = "# drape frame: " + std::to_string(mesh.vertices.size()) + " vertices, " +
                     std::to_string(mesh.triangles.size()) + " triangles\n";
  text.reserve(text.size() + mesh.vertices.size() * 72 + mesh.triangles.size() * 24);
  char line[128];
  for (const Vec3& v : mesh.vertices) {
    char* at = line;
    *at++ = 'v';
    for (int k = 0; k < 3; ++k) {
      *at++ = ' ';
      at = std::to_chars(at, line + sizeof line, v[k]).ptr;
    }
    *at++ = '\n';
    text.append(line, std::size_t(at - line));
  }
  for (const Triangle& t : mesh.triangles) {
    const int n = std::snprintf(line, sizeof line, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
    text.append(line, std::size_t(n));
  }
  return text;
}

// The triangles of an OBJ file as corner positions in double precision, in file order: "v"
// lines and "f" lines (a polygon as the fan assimp makes of it); other lines are skipped.
// At most max_triangles are kept (the rest only counted in total, so that a message can say
// how many the file has without holding them) and max_vertices read.
std::vector<std::array<Vec3, 3>> obj_triangles(const std::string& text, const std::string& name,
                                               std::size_t max_triangles, std::size_t max_vertices, std::size_t& total) {
  total = 0;
  std::vector<Vec3> vertices;
  std::vector<std::array<Vec3, 3>> triangles;
  for_each_line(text, [&](std::string_view view, std::size_t line_number) {
    const auto where = [&] { return name + ":" + std::to_string(line_number) + ": "; };
    if (obj_line_is(view, 'v')) {
      const std::string line(view);  // strtod needs the terminating NUL
      double x, y, z;
      char* next = nullptr;
      const char* p = line.c_str() + 2;
      x = std::strtod(p, &next);
      if (next == p) throw MeshFileError(where() + "expected three coordinates after 'v'");
      p = next, y = std::strtod(p, &next);
      if (next == p) throw MeshFileError(where() + "expected three coordinates after 'v'");
      p = next, z = std::strtod(p, &next);
      if (next == p) throw MeshFileError(where() + "expected three coordinates after 'v'");
      if (vertices.size() == max_vertices)
        throw MeshFileError(where() + "more than " + std::to_string(max_vertices) + " vertices for a frame of " +
                            std::to_string(max_triangles) + " triangles");
      vertices.emplace_back(x, y, z);
    } else if (obj_line_is(view, 'f')) {
      std::vector<Vec3> corners;
      for_each_corner(view, [&](std::string_view token, std::string_view number) {
        long index = 0;
        const auto [rest, problem] = std::from_chars(number.data(), number.data() + number.size(), index);
        if (problem != std::errc() || rest != number.data() + number.size() || index == 0)
          throw MeshFileError(where() + "expected a vertex index, found '" + std::string(token) + "'");
        // Negative indices count back from the last vertex read.
        const long resolved = index > 0 ? index - 1 : long(vertices.size()) + index;
        if (resolved < 0 || resolved >= long(vertices.size()))
          throw MeshFileError(where() + "vertex index " + std::string(number) + " refers to no vertex read so far");
        if (corners.size() == max_triangles + 2)
          throw MeshFileError(name + ": expected " + std::to_string(max_triangles) + " triangles, found more");
        corners.push_back(vertices[std::size_t(resolved)]);
      });
      if (corners.size() < 3) return;  // assimp reads these as points and lines
      for (std::size_t k = 1; k + 1 < corners.size(); ++k, ++total)
        if (triangles.size() < max_triangles) triangles.push_back({corners[0], corners[k], corners[k + 1]});
    }
  });
  return triangles;
}

}  // namespace

TriangleMesh load_mesh(const std::filesystem::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = read_file(importer, path, aiProcess_Triangulate | aiProcess_SortByPType);
  return mesh_of(importer, scene, path.string());
}

bool number_as_in_file(TriangleMesh& mesh, const std::filesystem::path& path) {
  if (lower_extension(path) != ".obj") return true;
  std::string bytes;
  try {
    bytes = ccd::read_input_file(path, ccd::MAX_MESH_BYTES, "mesh file");
  } catch (const ccd::InputFileError& e) {
    throw MeshFileError(e.what());
  }
  using Key = std::array<float, 3>;
  std::map<Key, int> vertex_at;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    vertex_at.emplace(Key{float(mesh.vertices[v].x()), float(mesh.vertices[v].y()), float(mesh.vertices[v].z())}, int(v));
  // Failing the same floats (or one unit in the last place away in each coordinate: assimp's
  // parser and strtod may round apart), the nearest vertex within a millionth of the mesh's
  // size and a hundredth of its shortest edge (another parser's rounding of an exponent form).
  Vec3 low = mesh.vertices.front(), high = low;
  for (const Vec3& p : mesh.vertices) low = low.cwiseMin(p), high = high.cwiseMax(p);
  Scalar shortest = std::numeric_limits<Scalar>::infinity();
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      shortest = std::min(shortest, (mesh.vertices[std::size_t(t[std::size_t(k)])] - mesh.vertices[std::size_t(t[std::size_t((k + 1) % 3)])]).norm());
  const Scalar near = std::min(1e-6 * (high - low).norm(), 0.01 * shortest);
  const auto find = [&](const Key& p) {
    if (const auto it = vertex_at.find(p); it != vertex_at.end()) return it->second;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          Key q = p;
          const int d[3] = {dx, dy, dz};
          for (int k = 0; k < 3; ++k)
            if (d[k] != 0) q[std::size_t(k)] = std::nextafter(p[std::size_t(k)], d[k] > 0 ? INFINITY : -INFINITY);
          if (const auto it = vertex_at.find(q); it != vertex_at.end()) return it->second;
        }
    // The vertices whose x is within reach, the nearest of them.
    const Vec3 point(p[0], p[1], p[2]);
    int best = -1;
    Scalar best_distance = near;
    for (auto it = vertex_at.lower_bound(Key{float(point.x() - near), -INFINITY, -INFINITY});
         it != vertex_at.end() && it->first[0] <= point.x() + near; ++it) {
      const Scalar distance = (mesh.vertices[std::size_t(it->second)] - point).norm();
      if (distance <= best_distance) best = it->second, best_distance = distance;
    }
    return best;
  };
  std::vector<int> from_file, order;  // file vertex -> mesh vertex; the mesh's vertices in the file's order
  std::vector<char> placed(mesh.vertices.size(), 0);
  for_each_line(bytes, [&](std::string_view line, std::size_t) {
    if (!obj_line_is(line, 'v')) return;
    const std::string text(line.substr(2));  // strtod needs the terminating NUL
    const char* p = text.c_str();
    std::array<double, 4> numbers{0, 0, 0, 1};
    int count = 0;
    for (; count < 4; ++count) {
      char* next = nullptr;
      const double value = std::strtod(p, &next);
      if (next == p) break;
      numbers[std::size_t(count)] = value, p = next;
    }
    int v = -1;
    if (count >= 3 && std::isfinite(numbers[0]) && std::isfinite(numbers[1]) && std::isfinite(numbers[2])) {
      v = find(Key{float(numbers[0]), float(numbers[1]), float(numbers[2])});
      // A homogeneous "v x y z w": the point may have been read as x/w, y/w, z/w.
      if (v < 0 && count == 4 && std::isfinite(numbers[3]) && numbers[3] != 0)
        v = find(Key{float(numbers[0] / numbers[3]), float(numbers[1] / numbers[3]), float(numbers[2] / numbers[3])});
    }
    from_file.push_back(v);  // -1: no triangle uses it (assimp leaves such vertices out)
    if (v >= 0 && !placed[std::size_t(v)]) placed[std::size_t(v)] = 1, order.push_back(v);
  });
  if (order.size() != mesh.vertices.size()) return false;  // a vertex no "v" line gives: the numbering is not the file's
  std::vector<int> renumbered(mesh.vertices.size());
  TriangleMesh out;
  for (std::size_t k = 0; k < order.size(); ++k) {
    renumbered[std::size_t(order[k])] = int(k);
    out.vertices.push_back(mesh.vertices[std::size_t(order[k])]);
  }
  for (const Triangle& t : mesh.triangles)
    out.triangles.push_back({renumbered[std::size_t(t[0])], renumbered[std::size_t(t[1])], renumbered[std::size_t(t[2])]});
  for (int& v : from_file)
    if (v >= 0) v = renumbered[std::size_t(v)];
  out.from_file = std::move(from_file);
  mesh = std::move(out);
  return true;
}

TriangleMesh parse_mesh(const std::string& bytes, const std::string& format, const std::string& name) {
  if (format == "ply" || looks_like_ply(bytes)) check_ply(bytes, name);
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFileFromMemory(bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_SortByPType, format.c_str());
  return mesh_of(importer, scene, name);
}

namespace {

// The positions of topology's vertices from a file's triangles (corners in file order).
std::vector<Vec3> positions_of(const std::vector<std::array<Vec3, 3>>& triangles, std::size_t total,
                               const TriangleMesh& topology, const std::string& name) {
  if (total != topology.triangles.size())
    throw MeshFileError(name + ": expected " + std::to_string(topology.triangles.size()) + " triangles, found " +
                        std::to_string(total));
  std::vector<Vec3> positions(topology.vertices.size(), Vec3::Zero());
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) positions[std::size_t(topology.triangles[f][k])] = triangles[f][std::size_t(k)];
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite()) throw MeshFileError(name + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
  return positions;
}

}  // namespace

std::vector<Vec3> parse_frame_positions(const std::string& obj_bytes, const std::string& name, const TriangleMesh& topology) {
  // A frame's triangles are the topology's; its vertices at most three a triangle (an exporter
  // may repeat them per face). More is bad input, refused before it can exhaust the memory.
  const std::size_t triangles = topology.triangles.size();
  std::size_t total = 0;
  const auto read = obj_triangles(obj_bytes, name, triangles, 3 * triangles + 1024, total);
  return positions_of(read, total, topology, name);
}

std::vector<Vec3> load_frame_positions(const std::filesystem::path& path, const TriangleMesh& topology) {
  // An OBJ is read by drape itself in double precision (assimp reads single precision), any
  // other format through assimp.
  if (lower_extension(path) == ".obj") {
    std::string bytes;
    try {
      bytes = ccd::read_input_file(path, ccd::MAX_MESH_BYTES, "mesh file");
    } catch (const ccd::InputFileError& e) {
      throw MeshFileError(e.what());
    }
    return parse_frame_positions(bytes, path.string(), topology);
  }
  std::vector<std::array<Vec3, 3>> triangles;
  Assimp::Importer importer;
  const aiScene* scene = read_file(importer, path, aiProcess_Triangulate);
  if (!scene || !scene->mRootNode) throw MeshFileError(path.string() + ": cannot read the mesh: " + importer.GetErrorString());
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      if (part->mFaces[f].mNumIndices != 3) continue;  // points and lines
      std::array<Vec3, 3> corners;
      for (int k = 0; k < 3; ++k) {
        const aiVector3D& p = part->mVertices[part->mFaces[f].mIndices[k]];
        corners[std::size_t(k)] = Vec3(p.x, p.y, p.z);
      }
      triangles.push_back(corners);
    }
  }
  return positions_of(triangles, triangles.size(), topology, path.string());
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
  if (format == "obj") {
    try {
      write_file_atomically(path, obj_text(mesh));
    } catch (const OutputError& e) {
      throw MeshFileError(e.what());
    }
    return;
  }
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
  // Exported to memory, then written by drape's checked writer (assimp's file writer does not
  // report a full disk).
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(&scene, assimp_format(format));
  if (!blob) throw MeshFileError(path.string() + ": cannot write the mesh: " + exporter.GetErrorString());
  if (blob->next) throw MeshFileError(path.string() + ": the " + format + " exporter writes more than one file");
  try {
    write_file_atomically(path, std::string_view(static_cast<const char*>(blob->data), blob->size));
  } catch (const OutputError& e) {
    throw MeshFileError(e.what());
  }
}

}  // namespace drape
