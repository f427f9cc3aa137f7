#include "drape/ccd/coplanarity.h"

#include "kernels.h"
#include "methods.h"

namespace drape::ccd {
Power3 coplanarity_power(QueryKind kind, const Query& query) {
  const auto order = coplanarity_order(kind);
  const auto x = [&](int i) -> const Vec3& { return query.start[order[i - 1]]; };
  const auto v = [&](int i) -> Vec3 { return query.end[order[i - 1]] - query.start[order[i - 1]]; };
  const Vec3 x21 = x(2) - x(1), x31 = x(3) - x(1), x41 = x(4) - x(1);
  const Vec3 v21 = v(2) - v(1), v31 = v(3) - v(1), v41 = v(4) - v(1);
  const Vec3 mixed = v21.cross(x31) + x21.cross(v31);
  return {x21.cross(x31).dot(x41), mixed.dot(x41) + x21.cross(x31).dot(v41),
          v21.cross(v31).dot(x41) + mixed.dot(v41), v21.cross(v31).dot(v41)};
}

namespace detail {

CoplanarityCubic query_cubic(QueryKind kind, const Query& query) {
  CoplanarityCubic cubic;
  one_query_cubic(kind, query, false, cubic);
  return cubic;
}

bool query_culled(QueryKind kind, const Query& query, CoplanarityCubic& cubic) {
  return one_query_cubic(kind, query, true, cubic);
}

}  // namespace detail
}  // namespace drape::ccd
