#include "ccd_peers.h"

#ifdef DRAPE_HAVE_FCL
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>
#endif
#ifdef DRAPE_HAVE_BULLET
#include <BulletSoftBody/btSoftBodyInternals.h>
#endif

namespace drape::bench {
namespace {

#ifdef DRAPE_HAVE_FCL
using FclIntersect = fcl::detail::Intersect<double>;

// FCL takes the triangle first and the vertex last; the edges as (a0, a1) and (b0, b1).
bool fcl_cubic(ccd::QueryKind kind, const ccd::Query& q) {
  double t = 0;
  fcl::Vector3<double> point;
  if (kind == ccd::QueryKind::VertexFace)
    return FclIntersect::intersect_VF(q.start[1], q.start[2], q.start[3], q.start[0], q.end[1], q.end[2], q.end[3],
                                      q.end[0], &t, &point);
  return FclIntersect::intersect_EE(q.start[0], q.start[1], q.start[2], q.start[3], q.end[0], q.end[1], q.end[2],
                                    q.end[3], &t, &point);
}

bool fcl_filtered(ccd::QueryKind kind, const ccd::Query& q) {
  double t = 0;
  fcl::Vector3<double> point;
  if (kind == ccd::QueryKind::VertexFace)
    return FclIntersect::intersect_VF_filtered(q.start[1], q.start[2], q.start[3], q.start[0], q.end[1], q.end[2],
                                               q.end[3], q.end[0], &t, &point);
  return FclIntersect::intersect_EE_filtered(q.start[0], q.start[1], q.start[2], q.start[3], q.end[0], q.end[1],
                                             q.end[2], q.end[3], &t, &point);
}
#endif

#ifdef DRAPE_HAVE_BULLET
// Bullet's soft-body CCD reads a node's start m_x, velocity m_v and end m_q = m_x + dt m_v, and a
// face's normals at the start (m_n0) and end (m_n1) and m_vn = (v1 - v0) x (v2 - v0) dt^2, as
// btDeformableMultiBodyDynamicsWorld sets them before calling bernsteinCCD; here dt = 1.
bool bullet_bernstein(ccd::QueryKind, const ccd::Query& q) {
  btSoftBody::Node nodes[4];
  for (int i = 0; i < 4; ++i) {
    nodes[i].m_x = btVector3(q.start[i].x(), q.start[i].y(), q.start[i].z());
    nodes[i].m_q = btVector3(q.end[i].x(), q.end[i].y(), q.end[i].z());
    nodes[i].m_v = nodes[i].m_q - nodes[i].m_x;
  }
  btSoftBody::Face face;
  face.m_n[0] = &nodes[1];
  face.m_n[1] = &nodes[2];
  face.m_n[2] = &nodes[3];
  face.m_n0 = (nodes[2].m_x - nodes[1].m_x).cross(nodes[3].m_x - nodes[1].m_x);
  face.m_n1 = (nodes[2].m_q - nodes[1].m_q).cross(nodes[3].m_q - nodes[1].m_q);
  face.m_vn = (nodes[2].m_v - nodes[1].m_v).cross(nodes[3].m_v - nodes[1].m_v);
  btVector3 barycentric;
  return bernsteinCCD(&face, &nodes[0], 1.0, SAFE_EPSILON, barycentric);
}
#endif

}  // namespace

std::vector<Peer> available_peers() {
  std::vector<Peer> peers;
#ifdef DRAPE_HAVE_FCL
  peers.push_back({"fcl-cubic", true, true, fcl_cubic});
  peers.push_back({"fcl-filtered", true, true, fcl_filtered});
#endif
#ifdef DRAPE_HAVE_BULLET
  peers.push_back({"bullet-bernstein", true, false, bullet_bernstein});
#endif
  return peers;
}

}  // namespace drape::bench
