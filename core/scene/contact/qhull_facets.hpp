// A thin wrapper around Qhull's reentrant C library. It lives in its own
// translation unit because qhull's headers define macros (True, False,
// fmax_, ...) that must not leak into code that includes Simbody or FCL.
#pragma once

#include <string>
#include <vector>

namespace manibench {
namespace scene_detail {

struct QhullFacet {
  double normal[3];         // outward unit normal
  double offset;            // normal . x = offset on the facet plane
  std::vector<int> points;  // input point indices, unordered
};

enum class QhullStatus { Ok, Flat, Failed };

// Convex hull of `xyz` (3 doubles per point) with coplanar facets merged.
// On Flat (no 3-d hull) or Failed, `message` holds Qhull's explanation.
QhullStatus runQhull(const std::vector<double>& xyz, std::vector<QhullFacet>& facets,
                     std::string& message);

}  // namespace scene_detail
}  // namespace manibench
