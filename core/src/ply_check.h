#pragma once
// Internal to core/: a structural check of PLY files before assimp reads them. assimp 5.2
// (Debian 12) hangs or aborts on some malformed PLY files (found by the mesh fuzzer: no
// end_header line, bytes after end_header on its line, an ASCII row with one number too
// many; tests/data/fuzz-regressions/mesh-ply-*), so drape checks what it hands over.

#include <string>
#include <string_view>

namespace drape {

/// Throws MeshFileError ("<name>: PLY header line N: ..." or "<name>: PLY element E row R: ...")
/// unless data is a well-formed PLY file: the header's grammar (ply, format, comment, obj_info,
/// element NAME COUNT, property TYPE NAME, property list TYPE TYPE NAME, end_header) in
/// printable lines; then every element's rows, one per line with exactly its properties'
/// numbers (ASCII) or within the file's bytes (binary); list lengths up to 65,536; the face
/// element's vertex indices within the vertex element's count.
void check_ply(std::string_view data, const std::string& name);

}  // namespace drape
