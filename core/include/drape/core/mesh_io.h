#pragma once
/// \file
/// Mesh files in and out: assimp for every format, OBJ frames in round-trip double precision.
///
/// Mesh files in and out, through assimp (OBJ, PLY, STL, glTF, Collada, ...). assimp stays
/// behind these two functions.

#include <filesystem>
#include <stdexcept>
#include <string>

#include "drape/core/mesh.h"

namespace drape {

/// A mesh file that cannot be read or written. what() names the file and the problem.
class MeshFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads every triangle of the file into one mesh, welding vertices at identical positions
/// (formats like OBJ repeat a position for each normal or texture coordinate); a vertex with a
/// non-finite coordinate is never welded, so that mesh_problem reports it.
/// Throws MeshFileError; does not validate the mesh (see mesh_problem).
TriangleMesh load_mesh(const std::filesystem::path& path);

/// A mesh read from an OBJ file renumbered in the file's vertex order, with
/// TriangleMesh::from_file set: load_mesh numbers its vertices in the order the faces first
/// use them (assimp gives each face corner its own vertex), so a cloth's frames and a handle's
/// `nodes` would follow the faces, not the file. Each vertex takes the place of the first "v"
/// line at its position (read in single precision, as assimp reads it, or nearest to it
/// within a millionth of the mesh's size); a vertex no face uses is left out. Other formats
/// keep their numbering (true). False, the mesh unchanged, when a vertex of the mesh matches no
/// "v" line: its numbering is then not the file's.
bool number_as_in_file(TriangleMesh& mesh, const std::filesystem::path& path);

/// The positions of a saved frame of a known mesh: the file's triangles, in order, are the
/// mesh's triangles, so each corner gives its vertex's position (no welding, so vertices that
/// happen to coincide stay apart). Throws MeshFileError when the file's triangle count differs
/// from the mesh's ("<file>: expected N triangles, found M") or a coordinate is not finite
/// ("<file>: vertex N has a non-finite coordinate").
/// load_mesh on a file's bytes in memory, format the extension assimp should read it as ("obj",
/// "ply", ...); name stands for the file in messages. The mesh fuzzer's entry point.
TriangleMesh parse_mesh(const std::string& bytes, const std::string& format, const std::string& name);

std::vector<Vec3> load_frame_positions(const std::filesystem::path& path, const TriangleMesh& topology);

/// load_frame_positions on the bytes of an OBJ frame (drape's own reader, double precision:
/// "v" and "f" lines, polygons as fans, other lines skipped); name stands for the file in
/// messages ("<name>:<line>: ..."). The frame fuzzer's entry point.
std::vector<Vec3> parse_frame_positions(const std::string& obj_bytes, const std::string& name, const TriangleMesh& topology);

/// Writes the mesh atomically (a temporary file renamed into place), so a reader never sees a
/// truncated mesh. format: "obj" (without a material file), "ply", "stl", or any assimp export
/// format id. Throws MeshFileError.
void save_mesh(const std::filesystem::path& path, const TriangleMesh& mesh, const std::string& format);

/// The file extension of a save_mesh format ("obj" -> ".obj").
std::string mesh_extension(const std::string& format);

/// Whether assimp can export this format.
bool mesh_format_supported(const std::string& format);

}  // namespace drape
