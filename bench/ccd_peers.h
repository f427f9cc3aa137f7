#pragma once
// Other libraries' elementary CCD tests, behind one signature, for bench/ccd_bench.cpp.

#include <string>
#include <vector>

#include "drape/ccd/query.h"

namespace drape::bench {

struct Peer {
  std::string name;
  bool vertex_face = true;  ///< supports vertex-face queries
  bool edge_edge = true;    ///< supports edge-edge queries
  bool (*test)(ccd::QueryKind kind, const ccd::Query& query);
};

/// The peers this build has: FCL's intersect_VF/EE and their _filtered variants (Debian
/// libfcl-dev), Bullet's vertex-face bernsteinCCD (libbullet-dev, double precision).
std::vector<Peer> available_peers();

}  // namespace drape::bench
