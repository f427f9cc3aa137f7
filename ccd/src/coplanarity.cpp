#include "drape/ccd/coplanarity.h"

#include "kernels.h"
#include "methods.h"

namespace drape::ccd {
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
